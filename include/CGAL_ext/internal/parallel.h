// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_PARALLEL_H
#define CGAL_EXT_INTERNAL_PARALLEL_H

#include <CGAL/tags.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <functional>
#include <type_traits>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>
#endif

/*
  Compiled instances. The numerical cores below the public API are templates on the concurrency tag alone, so
  the project's own programs, tests and benchmarks compile them once, in the `CGAL_ext_instances` library,
  instead of once per translation unit (doc/build_time.md). Each header lists its cores in a macro
  `LIST(EXTERN, Tag)` and passes it to `CGAL_EXT_DECLARE_COMPILED_INSTANCES`, which declares them `extern`
  when `CGAL_EXT_COMPILED_INSTANCES` is defined (by linking `CGAL_ext::instances`). A user of the header-only
  library defines nothing and sees no difference.
*/
#ifdef CGAL_LINKED_WITH_TBB
#define CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(LIST, EXTERN) LIST(EXTERN, CGAL::Sequential_tag) LIST(EXTERN, CGAL::Parallel_tag)
#else
#define CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(LIST, EXTERN) LIST(EXTERN, CGAL::Sequential_tag)
#endif
#ifdef CGAL_EXT_COMPILED_INSTANCES
#define CGAL_EXT_DECLARE_COMPILED_INSTANCES(LIST) CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(LIST, extern)
#else
#define CGAL_EXT_DECLARE_COMPILED_INSTANCES(LIST)
#endif
// Where the cores are compiled, a translation unit sees only their declarations and skips the headers their
// definitions need (CGAL's jet fitting and its SVD, the MST orientation, the spatial sort): a third of such a
// unit's parse time. The instances library itself defines CGAL_EXT_DEFINING_INSTANCES.
#if !defined(CGAL_EXT_COMPILED_INSTANCES) || defined(CGAL_EXT_DEFINING_INSTANCES)
#define CGAL_EXT_CORE_DEFINITIONS
#endif

namespace CGAL_ext {
namespace internal {

template <typename ConcurrencyTag>
constexpr bool is_parallel()
{
#ifdef CGAL_LINKED_WITH_TBB
  return std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value;
#else
  static_assert(!std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value,
                "CGAL::Parallel_tag requested but TBB is not linked (define CGAL_LINKED_WITH_TBB)");
  return false;
#endif
}

/// Maps the progress of a sequence of stages onto the caller's `callback` in [0, 1] and remembers a
/// cancellation. Only the calling thread invokes the callback (between chunks of parallel loops).
class Progress
{
public:
  explicit Progress(std::function<bool(double)> callback = {}) : m_callback(std::move(callback)) {}

  /// The following reports cover [begin, end] of the whole run.
  void stage(double begin, double end) { m_begin = begin; m_end = end; }

  /// A stage's span; `at(f)` is the overall progress a fraction f into it (to split a stage into steps).
  struct Range
  {
    double begin, end;
    double at(double f) const { return begin + (end - begin) * f; }
  };
  Range range() const { return {m_begin, m_end}; }

  /// Reports a fraction of the current stage; returns false once the caller has cancelled.
  bool report(double fraction)
  {
    if(m_cancelled) return false;
    if(m_callback && !m_callback(m_begin + (m_end - m_begin) * std::clamp(fraction, 0.0, 1.0)))
      m_cancelled = true;
    return !m_cancelled;
  }

  bool cancelled() const { return m_cancelled; }

private:
  std::function<bool(double)> m_callback;
  double m_begin = 0, m_end = 1;
  std::atomic<bool> m_cancelled{false};
};

/// Runs `body(i)` for i in [begin, end), in parallel when ConcurrencyTag says so.
template <typename ConcurrencyTag, typename Body>
void for_range(std::size_t begin, std::size_t end, const Body& body)
{
#ifdef CGAL_LINKED_WITH_TBB
  if constexpr(is_parallel<ConcurrencyTag>()) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 256),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for(std::size_t i = r.begin(); i != r.end(); ++i) body(i);
                      });
    return;
  }
#endif
  for(std::size_t i = begin; i != end; ++i) body(i);
}

/// Runs `background()` and `foreground()` at the same time when ConcurrencyTag says so, else one after the
/// other: `background` as a task that another thread takes, `foreground` on the calling thread (its parallel
/// loops share whatever threads are free). For work that leaves a core idle, as CHOLMOD's factorisation does
/// (doc/design.md, "A region of a large model"). Returns when both are done; an exception of either is
/// rethrown, the foreground's first.
template <typename ConcurrencyTag, typename Background, typename Foreground>
void run_concurrently(const Background& background, const Foreground& foreground)
{
#ifdef CGAL_LINKED_WITH_TBB
  if constexpr(is_parallel<ConcurrencyTag>()) {
    tbb::task_group group;
    group.run([&] { background(); });
    try {
      foreground();
    } catch(...) {
      try {
        group.wait();
      } catch(...) {
      }
      throw;
    }
    group.wait();
    return;
  }
#endif
  background();
  foreground();
}

/// Runs `body(i)` for i in [0, n) in chunks, reporting progress after each chunk.
/// Returns false (and stops early) when the caller cancels.
template <typename ConcurrencyTag, typename Body>
bool for_each_index(std::size_t n, Progress& progress, const Body& body)
{
  constexpr std::size_t chunk = std::size_t(1) << 16;
  for(std::size_t b = 0; b < n; b += chunk) {
    const std::size_t e = std::min(n, b + chunk);
    for_range<ConcurrencyTag>(b, e, body);
    if(!progress.report(double(e) / double(n))) return false;
  }
  return progress.report(1.0);
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_PARALLEL_H
