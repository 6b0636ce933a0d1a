// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_PARALLEL_H
#define CGAL_EXT_INTERNAL_PARALLEL_H

// Parallel loops over the concurrency tag (TBB where CGAL has it), with progress and cancellation.

#include <CGAL_ext/internal/progress.h>

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

/// Runs `body(i)` for i in [begin, end), in parallel when ConcurrencyTag says so, in tasks of at least `grain`
/// (when there are that many).
template <typename ConcurrencyTag, typename Body>
void for_range(std::size_t begin, std::size_t end, const Body& body, std::size_t grain = 256)
{
#ifdef CGAL_LINKED_WITH_TBB
  if constexpr(is_parallel<ConcurrencyTag>()) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, grain),
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
