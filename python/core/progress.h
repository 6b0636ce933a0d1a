// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// Progress callables, Ctrl-C and the GIL around the library's calls.
// A part of cgal_ext_module.cpp, the package's one translation unit, which includes its parts in order.
#ifndef CGAL_EXT_PYTHON_PROGRESS_H
#define CGAL_EXT_PYTHON_PROGRESS_H

namespace {

// ---- progress and cancellation ------------------------------------------------------------------------------

/// The library's progress callback for a Python caller: with the GIL taken back, it checks for Ctrl-C and calls
/// `progress(fraction)` when given; an exception from either cancels the run, and `raise_if_cancelled` raises
/// it once the library has returned.
class Python_progress
{
public:
  explicit Python_progress(py::object progress) : m_progress(std::move(progress))
  {
    if(!m_progress.is_none() && !PyCallable_Check(m_progress.ptr()))
      throw py::value_error("progress must be a callable taking the progress in [0, 1], or None");
  }

  std::function<bool(double)> callback()
  {
    return [this](double fraction) {
      py::gil_scoped_acquire gil;
      try {
        if(PyErr_CheckSignals() != 0) throw py::error_already_set();
        if(!m_progress.is_none()) m_progress(fraction);
        return true;
      } catch(py::error_already_set& e) {
        m_error = std::make_unique<py::error_already_set>(std::move(e));
        return false;
      }
    };
  }

  /// Raises what cancelled the run (the GIL held): the callback's exception.
  void raise_if_cancelled(bool completed)
  {
    if(m_error) {
      py::error_already_set error = std::move(*m_error);
      m_error.reset();
      throw error;
    }
    if(!completed) throw std::runtime_error("cancelled");
  }

private:
  py::object m_progress;
  std::unique_ptr<py::error_already_set> m_error;
};

/// `body()` with the GIL released.
template <typename Body>
auto without_gil(Body&& body)
{
  py::gil_scoped_release release;
  return body();
}

} // namespace

#endif // CGAL_EXT_PYTHON_PROGRESS_H
