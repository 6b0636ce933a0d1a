// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_PROGRESS_H
#define CGAL_EXT_INTERNAL_PROGRESS_H

#include <algorithm>
#include <atomic>
#include <functional>
#include <utility>

namespace CGAL_ext {
namespace internal {

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

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_PROGRESS_H
