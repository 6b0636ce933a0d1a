// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// The compiled part of the Python package `cgal_ext` (`cgal_ext._core`, doc/python.md): the library's algorithms
// and the program's readers, writers and pictures on numpy arrays. float64 (n, 3) arrays are read in place through
// property maps over the caller's memory (C- or F-ordered, any strides); other numbers and nested lists are
// converted once. Results are new arrays, named tuples where there are several. The GIL is released while the
// library computes; a `progress` callable is called from the calling thread with the GIL taken back, and an
// exception it raises (or Ctrl-C) cancels the computation and is raised.
#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/estimate_oriented_normals.h>
#include <CGAL_ext/scale_geometric_details.h>
#include <CGAL_ext/upsample_point_set.h>

#include "cli_support.h"
#include "colors.h"
#include "point_io.h"
#include "render.h"

#include <CGAL/Simple_cartesian.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <boost/property_map/function_property_map.hpp>
#include <boost/range/counting_range.hpp>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace py = pybind11;
using namespace pybind11::literals;

// ---- names the signatures show --------------------------------------------------------------------------------
// Arguments and results are Python objects checked by hand (the messages name the argument); these wrappers only
// give help() and the stub the types a user passes, instead of `object`.
#define CGAL_EXT_PYTHON_TYPE(Type, Name)                                                                      \
  struct Type : py::object                                                                                   \
  {                                                                                                          \
    Type() = default;                                                                                        \
    Type(py::object o) : py::object(std::move(o)) {}                                                         \
  };                                                                                                         \
  namespace pybind11 { namespace detail {                                                                    \
  template <>                                                                                                \
  struct type_caster<Type>                                                                                   \
  {                                                                                                          \
    PYBIND11_TYPE_CASTER(Type, const_name(Name));                                                            \
    bool load(handle source, bool)                                                                           \
    {                                                                                                        \
      value = Type(reinterpret_borrow<object>(source));                                                      \
      return true;                                                                                           \
    }                                                                                                        \
    static handle cast(const Type& source, return_value_policy, handle) { return source.inc_ref(); }         \
  };                                                                                                         \
  }}

CGAL_EXT_PYTHON_TYPE(Array_like, "numpy.typing.ArrayLike")
CGAL_EXT_PYTHON_TYPE(Optional_array_like, "Optional[numpy.typing.ArrayLike]")
CGAL_EXT_PYTHON_TYPE(Optional_progress, "Optional[Callable[[float], object]]")
CGAL_EXT_PYTHON_TYPE(Optional_int, "Optional[int]")
CGAL_EXT_PYTHON_TYPE(Optional_path, "Optional[Union[str, os.PathLike]]")
CGAL_EXT_PYTHON_TYPE(Path_like, "Union[str, os.PathLike]")
CGAL_EXT_PYTHON_TYPE(Ndarray, "numpy.ndarray")
CGAL_EXT_PYTHON_TYPE(Details_result, "Details")
CGAL_EXT_PYTHON_TYPE(Upsampled_result, "Upsampled")
CGAL_EXT_PYTHON_TYPE(Deformed_result, "Deformed")
CGAL_EXT_PYTHON_TYPE(Point_set_result, "PointSet")
CGAL_EXT_PYTHON_TYPE(Sample_points_of, "Union[int, numpy.ndarray]")

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using Index_range = boost::iterator_range<boost::counting_iterator<std::size_t>>;

// ---- arrays -----------------------------------------------------------------------------------------------------

/// An (n, 3) float64 array seen in place: row i, column c at `data + i * row_stride + c * column_stride` bytes.
struct Rows3
{
  char* data = nullptr;
  py::ssize_t rows = 0, row_stride = 0, column_stride = 0;

  double& at(std::size_t i, int c) const
  {
    return *reinterpret_cast<double*>(data + py::ssize_t(i) * row_stride + c * column_stride);
  }
};

/// The span of memory the library read through the points' and normals' maps since `_trace_reads(True)`: how the
/// tests see that an input is read in place, not copied (off by default; one relaxed load per read).
struct Read_trace
{
  std::atomic<bool> on{false};
  std::atomic<std::uintptr_t> lowest{std::numeric_limits<std::uintptr_t>::max()}, highest{0};

  void note(const void* first, const void* last)
  {
    const auto lo = reinterpret_cast<std::uintptr_t>(first), hi = reinterpret_cast<std::uintptr_t>(last);
    for(std::uintptr_t seen = lowest.load(); lo < seen && !lowest.compare_exchange_weak(seen, lo);) {
    }
    for(std::uintptr_t seen = highest.load(); hi > seen && !highest.compare_exchange_weak(seen, hi);) {
    }
  }
};
Read_trace read_trace;

std::string shape_of(const py::array& array)
{
  std::string s = "(";
  for(py::ssize_t d = 0; d < array.ndim(); ++d) s += (d ? ", " : "") + std::to_string(array.shape(d));
  return s + (array.ndim() == 1 ? ",)" : ")");
}

std::string dtype_name(const py::array& array) { return py::str(array.dtype()); }

/// `object` as a numpy array, or a ValueError naming `argument` and `what` it must be.
py::array as_array(const py::handle& object, const char* argument, const std::string& what)
{
  if(py::isinstance<py::array>(object)) return py::reinterpret_borrow<py::array>(object);
  try {
    return py::module_::import("numpy").attr("asarray")(object);
  } catch(py::error_already_set& e) {
    throw py::value_error(std::string(argument) + " must be " + what + " (" + e.what() + ")");
  }
}

/// An (n, 3) array of real numbers as float64: the caller's own array when it is float64 (compared by value, so
/// an array that went through pickle is one too), else one converted copy (float32, integers, nested lists).
py::array float64_rows3(const py::handle& object, const char* argument)
{
  const py::array array = as_array(object, argument, "an (n, 3) array of numbers");
  const char kind = array.dtype().kind();
  if(kind != 'f' && kind != 'i' && kind != 'u')
    throw py::value_error(std::string(argument) + " must hold real numbers (float64, float32 or integers), not dtype " +
                          dtype_name(array));
  if(array.ndim() != 2 || array.shape(1) != 3)
    throw py::value_error(std::string(argument) + " must have shape (n, 3), not " + shape_of(array));
  if(array.dtype().equal(py::dtype::of<double>())) return array;
  return array.attr("astype")(py::dtype::of<double>());
}

Rows3 view_of(const py::array& array)
{
  return Rows3{static_cast<char*>(const_cast<void*>(array.data())), array.shape(0), array.strides(0), array.strides(1)};
}

/// A new C-ordered (rows, 3) float64 array, and its view.
std::pair<py::array_t<double>, Rows3> new_rows3(std::size_t rows)
{
  py::array_t<double> array({py::ssize_t(rows), py::ssize_t(3)});
  return {array, view_of(array)};
}

/// `object` when it is a writable (n, 3) float64 array (checked, ValueError naming `argument`), else a new one.
std::pair<py::array, Rows3> output_rows3(const py::object& object, const char* argument, std::size_t n)
{
  if(object.is_none()) return new_rows3(n);
  if(!py::isinstance<py::array>(object))
    throw py::value_error(std::string(argument) + " must be a numpy array of shape (" + std::to_string(n) +
                          ", 3) and dtype float64");
  const auto array = py::reinterpret_borrow<py::array>(object);
  if(array.ndim() != 2 || array.shape(1) != 3 || std::size_t(array.shape(0)) != n)
    throw py::value_error(std::string(argument) + " must have " + std::to_string(n) + " rows and 3 columns, not shape " +
                          shape_of(array));
  if(!array.dtype().equal(py::dtype::of<double>()))
    throw py::value_error(std::string(argument) + " must have dtype float64, not " + dtype_name(array));
  if(!array.writeable()) throw py::value_error(std::string(argument) + " is not writable");
  return {array, view_of(array)};
}

/// Row i of a `Rows3` as a CGAL property map over indices: points, or vectors (normals, details).
template <typename Value>
struct Rows3_map
{
  using key_type = std::size_t;
  using value_type = Value;
  using reference = Value;
  using category = boost::read_write_property_map_tag;
  Rows3 rows;

  friend Value get(const Rows3_map& m, std::size_t i)
  {
    if(read_trace.on.load(std::memory_order_relaxed)) read_trace.note(&m.rows.at(i, 0), &m.rows.at(i, 2) + 1);
    return Value(m.rows.at(i, 0), m.rows.at(i, 1), m.rows.at(i, 2));
  }
  friend void put(const Rows3_map& m, std::size_t i, const Value& v)
  {
    m.rows.at(i, 0) = v.x();
    m.rows.at(i, 1) = v.y();
    m.rows.at(i, 2) = v.z();
  }
};

/// Element i of a 1-D array as a writable property map.
template <typename T>
struct Array_map
{
  using key_type = std::size_t;
  using value_type = T;
  using reference = T&;
  using category = boost::lvalue_property_map_tag;
  T* data;

  friend T& get(const Array_map& m, std::size_t i) { return m.data[i]; }
  friend void put(const Array_map& m, std::size_t i, const T& v) { m.data[i] = v; }
};

/// Point indices given as a 1-D array or sequence of integers, or as a boolean mask of all `n` points, each
/// checked against `n`.
std::vector<std::size_t> indices(const py::handle& object, std::size_t n, const char* argument)
{
  const py::array array = as_array(object, argument, "a 1-D array of point indices or a boolean mask");
  const char kind = array.dtype().kind();
  if(array.ndim() != 1 || !(kind == 'i' || kind == 'u' || kind == 'b' || array.size() == 0))
    throw py::value_error(std::string(argument) + " must be a 1-D array of integer point indices or a boolean mask, not " +
                          (array.ndim() != 1 ? "shape " + shape_of(array) : "dtype " + dtype_name(array)));
  std::vector<std::size_t> out;
  if(kind == 'b') {
    if(std::size_t(array.size()) != n)
      throw py::value_error(std::string(argument) + ": a boolean mask needs one value per point (" + std::to_string(n) +
                            "), not " + std::to_string(array.size()));
    const auto mask = py::array_t<bool, py::array::forcecast>::ensure(array);
    for(py::ssize_t m = 0; m < mask.size(); ++m)
      if(mask.at(m)) out.push_back(std::size_t(m));
    return out;
  }
  const auto values = py::array_t<long long, py::array::forcecast>::ensure(array);
  out.resize(std::size_t(values.size()));
  for(py::ssize_t m = 0; m < values.size(); ++m) {
    const long long v = values.at(m);
    if(v < 0 || std::size_t(v) >= n)
      throw py::value_error(std::string(argument) + ": index " + std::to_string(v) + " is not a point index (" +
                            std::to_string(n) + " points)");
    out[std::size_t(m)] = std::size_t(v);
  }
  return out;
}

/// A 1-D array of `n` real numbers as float64 values.
std::vector<double> values_of(const py::handle& object, std::size_t n, const char* argument)
{
  const py::array array = as_array(object, argument, "a 1-D array of numbers");
  const char kind = array.dtype().kind();
  if(array.ndim() != 1 || !(kind == 'f' || kind == 'i' || kind == 'u' || kind == 'b'))
    throw py::value_error(std::string(argument) + " must be a 1-D array of numbers, not " +
                          (array.ndim() != 1 ? "shape " + shape_of(array) : "dtype " + dtype_name(array)));
  if(std::size_t(array.size()) != n)
    throw py::value_error(std::string(argument) + " must have one value per point (" + std::to_string(n) + "), not " +
                          std::to_string(array.size()));
  const auto values = py::array_t<double, py::array::forcecast | py::array::c_style>::ensure(array);
  return std::vector<double>(values.data(), values.data() + values.size());
}

/// An (n, 3) array of colours, integers in 0..255.
std::vector<point_detail::Color> colors_of(const py::handle& object, std::size_t n, const char* argument)
{
  const py::array array = as_array(object, argument, "an (n, 3) array of integers in 0..255");
  const char kind = array.dtype().kind();
  if(kind != 'i' && kind != 'u')
    throw py::value_error(std::string(argument) + " must hold integers in 0..255 (uint8), not dtype " + dtype_name(array));
  if(array.ndim() != 2 || array.shape(1) != 3 || std::size_t(array.shape(0)) != n)
    throw py::value_error(std::string(argument) + " must have shape (" + std::to_string(n) + ", 3), not " + shape_of(array));
  const auto values = py::array_t<long long, py::array::forcecast | py::array::c_style>::ensure(array);
  std::vector<point_detail::Color> colors(n);
  for(std::size_t i = 0; i < n; ++i)
    for(int c = 0; c < 3; ++c) {
      const long long v = values.data()[3 * i + std::size_t(c)];
      if(v < 0 || v > 255)
        throw py::value_error(std::string(argument) + ": colour " + std::to_string(v) + " of point " + std::to_string(i) +
                              " is outside 0..255");
      colors[i][std::size_t(c)] = static_cast<unsigned char>(v);
    }
  return colors;
}

Index_range all_points(std::size_t n) { return boost::counting_range(std::size_t(0), n); }

/// Points and, unless None, normals as float64 arrays (kept alive here while the library reads them in place).
struct Point_input
{
  py::array points, normals;
  Rows3 point_rows, normal_rows;
  bool has_normals = false;

  Point_input(const py::handle& point_object, const py::handle& normal_object)
      : points(float64_rows3(point_object, "points")), point_rows(view_of(points))
  {
    if(normal_object.is_none()) return;
    normals = float64_rows3(normal_object, "normals");
    normal_rows = view_of(normals);
    has_normals = true;
    if(normal_rows.rows != point_rows.rows)
      throw py::value_error("normals must have as many rows as points (" + std::to_string(point_rows.rows) + "), not " +
                            std::to_string(normal_rows.rows));
  }

  std::size_t size() const { return std::size_t(point_rows.rows); }
};

/// The named parameters of `input`'s points and, when given, normals, given to `body(np)`.
template <typename Body>
auto with_maps(const Point_input& input, Body&& body)
{
  const auto np = CGAL::parameters::point_map(Rows3_map<Point>{input.point_rows});
  if(!input.has_normals) return body(np);
  return body(np.normal_map(Rows3_map<Vector>{input.normal_rows}));
}

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

// ---- settings -----------------------------------------------------------------------------------------------

/// A setting's value from the name a keyword argument gives (the library's `Setting_names`, shared with the edit
/// files and the program's options).
template <typename Enum>
Enum parse_setting(const std::string& name, const char* setting)
{
  Enum value{};
  if(!CGAL_ext::find_setting(name, value))
    throw py::value_error(std::string(setting) + " must be one of " + CGAL_ext::setting_choices<Enum>() + ", not \"" +
                          name + "\"");
  return value;
}

using namespace CGAL_ext;

Detail_settings detail_settings(const std::string& order, double lam, double mu, const std::string& weights)
{
  Detail_settings s(Detail_filter{parse_setting<Detail_order>(order, "order"), lam, mu});
  s.weights.weighting = parse_setting<Laplacian_weighting>(weights, "weights");
  s.validate();
  return s;
}

/// A count given from Python (k, iterations, sizes); the library checks its own lower bounds.
unsigned int as_count(long long value, const char* argument)
{
  if(value < 0 || value > std::numeric_limits<int>::max())
    throw py::value_error(std::string(argument) + " must be a count >= 0, not " + std::to_string(value));
  return unsigned(value);
}

// ---- named results ----------------------------------------------------------------------------------------------

/// The named tuples of the results, made once at import (kept for the life of the process).
struct Result_types
{
  py::handle details, upsampled, deformed, point_set;
};
Result_types result_types;

py::handle named_tuple(py::module_& m, const char* name, std::vector<std::string> fields, const char* doc)
{
  py::object type = py::module_::import("collections").attr("namedtuple")(name, fields, "module"_a = "cgal_ext");
  type.attr("__doc__") = doc;
  m.attr(name) = type;
  return type.release();
}

/// `body()` with the program's Cli_error (a bad file, a bad view) raised as the ValueError a Python user expects,
/// with the program's message.
template <typename Body>
auto translating_program_errors(Body&& body)
{
  try {
    return body();
  } catch(const point_detail::Cli_error& e) {
    throw py::value_error(e.what());
  }
}

// ---- functions ----------------------------------------------------------------------------------------------

Details_result bound_compute_geometric_details(const Array_like& points, const Optional_array_like& normals, long long k,
                                         const std::string& order, double lam, double mu, const std::string& weights,
                                         const Optional_progress& progress)
{
  const Detail_settings settings = detail_settings(order, lam, mu, weights);
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  auto [details, details_view] = new_rows3(n);
  py::array_t<double> magnitude(static_cast<py::ssize_t>(n));
  Python_progress reporter(progress);
  const Array_map<double> magnitude_map{magnitude.mutable_data()};
  const Rows3_map<Vector> detail_map{details_view};
  const bool done = with_maps(input, [&](const auto& np) {
    return without_gil([&] {
      return CGAL_ext::compute_geometric_details(all_points(n), as_count(k, "k"), settings, detail_map, magnitude_map,
                                                 np.callback(reporter.callback()));
    });
  });
  reporter.raise_if_cancelled(done);
  return py::reinterpret_borrow<py::object>(result_types.details)(details, magnitude);
}

/// Scaling and enhancement: the points moved, as a new array (the library moves a copy of the points in place).
Ndarray manipulate(bool enhance, const Array_like& points, const Optional_array_like& normals, const py::object& roi,
                   double s, const Optional_array_like& anchors, long long k, const std::string& order, double lam,
                   double mu, const std::string& weights, const Optional_progress& progress)
{
  Detail_enhancement_settings settings(detail_settings(order, lam, mu, weights));
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  const std::vector<std::size_t> region = roi.is_none() ? std::vector<std::size_t>() : indices(roi, n, "roi");
  std::vector<char> anchored;
  if(!anchors.is_none()) {
    anchored.assign(n, 0);
    for(std::size_t a : indices(anchors, n, "anchors")) anchored[a] = 1;
  }
  auto [moved, moved_view] = new_rows3(n);
  for(std::size_t i = 0; i < n; ++i)
    for(int c = 0; c < 3; ++c) moved_view.at(i, c) = input.point_rows.at(i, c);
  Python_progress reporter(progress);
  const auto is_anchor = boost::make_function_property_map<std::size_t, bool>([&](std::size_t i) { return anchored[i] != 0; });
  const unsigned int neighbors = as_count(k, "k");
  const auto run = [&](const auto& np) {
    Index_range all = all_points(n);
    return without_gil([&] {
      const auto with_callback = np.callback(reporter.callback());
      if(enhance && anchored.empty())
        return roi.is_none() ? CGAL_ext::enhance_geometric_details(all, neighbors, s, settings, with_callback)
                             : CGAL_ext::enhance_geometric_details(all, neighbors, region, s, settings, with_callback);
      if(enhance)
        return roi.is_none()
                 ? CGAL_ext::enhance_geometric_details(all, neighbors, s, settings, with_callback.point_is_constrained_map(is_anchor))
                 : CGAL_ext::enhance_geometric_details(all, neighbors, region, s, settings,
                                                       with_callback.point_is_constrained_map(is_anchor));
      if(anchored.empty()) return CGAL_ext::scale_geometric_details(all, neighbors, region, s, settings, with_callback);
      return CGAL_ext::scale_geometric_details(all, neighbors, region, s, settings, with_callback.point_is_constrained_map(is_anchor));
    });
  };
  const auto moved_map = CGAL::parameters::point_map(Rows3_map<Point>{moved_view});
  const Detail_manipulation_result result =
    input.has_normals ? run(moved_map.normal_map(Rows3_map<Vector>{input.normal_rows})) : run(moved_map);
  reporter.raise_if_cancelled(result.completed);
  return moved;
}

Ndarray bound_estimate_mean_curvature(const Array_like& points, const Optional_array_like& normals, long long k,
                                const std::string& fitting, const Optional_progress& progress)
{
  const Curvature_fitting method = parse_setting<Curvature_fitting>(fitting, "fitting");
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  py::array_t<double> curvature(static_cast<py::ssize_t>(n));
  Python_progress reporter(progress);
  const Array_map<double> curvature_map{curvature.mutable_data()};
  const bool done = with_maps(input, [&](const auto& np) {
    return without_gil([&] {
      return CGAL_ext::estimate_mean_curvature(all_points(n), as_count(k, "k"), method, curvature_map,
                                               np.callback(reporter.callback()));
    });
  });
  reporter.raise_if_cancelled(done);
  return curvature;
}

Ndarray bound_estimate_oriented_normals(const Array_like& points, long long k, const Optional_progress& progress)
{
  const Point_input input(points, py::none());
  const std::size_t n = input.size();
  auto [normals, normal_rows] = new_rows3(n);
  Python_progress reporter(progress);
  const bool done = with_maps(input, [&, normal_rows = normal_rows](const auto& np) {
    return without_gil([&] {
      return CGAL_ext::estimate_oriented_normals(all_points(n), as_count(k, "k"),
                                                 np.normal_map(Rows3_map<Vector>{normal_rows}).callback(reporter.callback()));
    });
  });
  reporter.raise_if_cancelled(done);
  return normals;
}

Ndarray bound_compute_simplification_sample_points(const Array_like& points, const Optional_array_like& normals,
                                             long long target_count, const Optional_int& max_cluster_size,
                                             double mode_threshold, long long k, const Optional_progress& progress)
{
  Simplification_settings settings;
  if(target_count < 1) throw py::value_error("target_count must be at least 1, not " + std::to_string(target_count));
  settings.target_count = std::size_t(target_count);
  if(!max_cluster_size.is_none()) {
    const long long size = max_cluster_size.cast<long long>();
    if(size < 1) throw py::value_error("max_cluster_size must be at least 1, not " + std::to_string(size));
    settings.max_cluster_size = std::size_t(size);
  }
  settings.mode_spread_threshold = mode_threshold;
  settings.mean_shift_neighbors = as_count(k, "k");
  settings.validate();
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  py::array_t<std::int64_t> labels(static_cast<py::ssize_t>(n));
  static_assert(sizeof(std::int64_t) == sizeof(std::size_t), "labels are written in place as size_t");
  Python_progress reporter(progress);
  const auto samples = with_maps(input, [&](const auto& np) {
    return without_gil([&] {
      return CGAL_ext::compute_simplification_sample_points(
        all_points(n), settings, Array_map<std::size_t>{reinterpret_cast<std::size_t*>(labels.mutable_data())},
        np.callback(reporter.callback()));
    });
  });
  reporter.raise_if_cancelled(samples.completed);
  return labels;
}

Upsampled_result bound_upsample_point_set(const Array_like& points, const Array_like& normals, double spacing,
                                    double max_hole_size, long long k, const Optional_array_like& roi,
                                    const Optional_progress& progress)
{
  if(normals.is_none())
    throw py::value_error("normals are required: hole detection and the new samples' surface come from them");
  Upsampling_settings settings;
  settings.detection.spacing = spacing;
  settings.detection.max_hole_size = max_hole_size;
  settings.neighbors = as_count(k, "k");
  settings.validate();
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  const std::vector<std::size_t> region = roi.is_none() ? std::vector<std::size_t>() : indices(roi, n, "roi");
  std::vector<std::pair<Point, Vector>> added;
  Python_progress reporter(progress);
  const auto result = with_maps(input, [&](const auto& np) {
    return without_gil([&] {
      return roi.is_none()
               ? CGAL_ext::upsample_point_set(all_points(n), settings, std::back_inserter(added), np.callback(reporter.callback()))
               : CGAL_ext::upsample_point_set(all_points(n), region, settings, std::back_inserter(added),
                                              np.callback(reporter.callback()));
    });
  });
  reporter.raise_if_cancelled(result.completed);
  auto [new_points, points_view] = new_rows3(added.size());
  auto [new_normals, normals_view] = new_rows3(added.size());
  for(std::size_t m = 0; m < added.size(); ++m) {
    put(Rows3_map<Point>{points_view}, m, added[m].first);
    put(Rows3_map<Vector>{normals_view}, m, added[m].second);
  }
  return py::reinterpret_borrow<py::object>(result_types.upsampled)(new_points, new_normals);
}

// ---- files and pictures -----------------------------------------------------------------------------------------

namespace fs = std::filesystem;

fs::path path_of(const py::handle& object, const char* argument)
{
  try {
    return fs::path(py::str(py::module_::import("os").attr("fspath")(object)).cast<std::string>());
  } catch(py::error_already_set&) {
    throw py::value_error(std::string(argument) + " must be a path (str or os.PathLike)");
  }
}

/// The elements of `values` as a numpy array that owns them, without a copy: shape (size, extra...), each element
/// `extra_strides` apart inside one value (the values are arrays of doubles or bytes: points, colours).
template <typename Value>
py::array array_owning(std::vector<Value>&& values, std::vector<py::ssize_t> extra_shape, std::vector<py::ssize_t> extra_strides)
{
  using Scalar = std::conditional_t<std::is_same_v<Value, point_detail::Color>, std::uint8_t, double>;
  static_assert(sizeof(Value) % sizeof(Scalar) == 0 && std::is_trivially_copyable_v<Value>, "a value is an array of scalars");
  auto* owned = new std::vector<Value>(std::move(values));
  const py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<Value>*>(p); });
  std::vector<py::ssize_t> shape{py::ssize_t(owned->size())}, strides{py::ssize_t(sizeof(Value))};
  shape.insert(shape.end(), extra_shape.begin(), extra_shape.end());
  strides.insert(strides.end(), extra_strides.begin(), extra_strides.end());
  return py::array_t<Scalar>(shape, strides, reinterpret_cast<const Scalar*>(owned->data()), owner);
}

Point_set_result read_points(const Path_like& path_object)
{
  const fs::path path = path_of(path_object, "path");
  std::error_code ec;
  if(!fs::exists(path, ec)) {
    PyErr_SetString(PyExc_FileNotFoundError, ("cannot read " + path.string() + ": no such file").c_str());
    throw py::error_already_set();
  }
  // What the program's reader checks against the available memory: the arrays returned here, and its own.
  constexpr std::uint64_t bytes_per_point = 160;
  point_detail::Point_cloud cloud = translating_program_errors(
    [&] { return without_gil([&] { return point_detail::read_point_cloud(path, bytes_per_point); }); });
  py::dict properties;
  for(auto& [name, values] : cloud.scalars) properties[py::str(name)] = array_owning(std::move(values), {}, {});
  if(!cloud.colors.empty()) properties["colors"] = array_owning(std::move(cloud.colors), {3}, {1});
  py::object normals = cloud.normals.empty() ? py::object(py::none()) : py::object(array_owning(std::move(cloud.normals), {3}, {8}));
  return py::reinterpret_borrow<py::object>(result_types.point_set)(array_owning(std::move(cloud.points), {3}, {8}),
                                                                    normals, properties);
}

/// The points and normals as the program holds them (its writer and renderer take them so).
point_detail::Point_cloud program_cloud(const Point_input& input)
{
  point_detail::Point_cloud cloud;
  const Rows3 &p = input.point_rows, &v = input.normal_rows;
  cloud.points.resize(input.size());
  cloud.normals.resize(input.has_normals ? input.size() : 0);
  for(std::size_t i = 0; i < input.size(); ++i) {
    cloud.points[i] = point_detail::Point(p.at(i, 0), p.at(i, 1), p.at(i, 2));
    if(input.has_normals) cloud.normals[i] = point_detail::Vector(v.at(i, 0), v.at(i, 1), v.at(i, 2));
  }
  return cloud;
}

void write_ply(const Path_like& path_object, const Array_like& points, const Optional_array_like& normals,
               const Optional_array_like& colors, const Optional_path& input_path, const py::kwargs& scalars)
{
  const fs::path path = path_of(path_object, "path");
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  point_detail::Point_cloud cloud = program_cloud(input);
  if(!colors.is_none()) cloud.colors = colors_of(colors, n, "colors");
  for(const auto& [key, value] : scalars) {
    const std::string name = py::str(key);
    for(const char* taken : {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"})
      if(name == taken)
        throw py::value_error("property '" + name + "' is written from points, normals or colors; name it otherwise");
    cloud.scalars.emplace_back(name, values_of(value, n, name.c_str()));
  }
  std::vector<fs::path> inputs;
  if(!input_path.is_none()) inputs.push_back(path_of(input_path, "input_path"));
  translating_program_errors([&] {
    return without_gil([&] {
      // A temporary beside the destination, renamed once written whole: a failure leaves no partial file.
      point_detail::Output_files outputs(inputs);
      const fs::path temporary = outputs.add(path);
      point_detail::write_file(temporary, point_detail::ply_bytes(cloud));
      outputs.commit();
      return 0;
    });
  });
}

Ndarray colors_by(const std::function<point_detail::Coloring(const std::vector<double>&)>& color_map,
                  const Array_like& values)
{
  const py::array array = as_array(values, "values", "a 1-D array of numbers");
  const std::vector<double> v = values_of(array, std::size_t(array.ndim() == 1 ? array.size() : 0), "values");
  const point_detail::Coloring coloring = color_map(v);
  py::array_t<std::uint8_t> colors({py::ssize_t(v.size()), py::ssize_t(3)});
  std::memcpy(colors.mutable_data(), coloring.colors.data(), v.size() * 3);
  return colors;
}

py::bytes render_png(const Array_like& points, const Optional_array_like& normals, const Optional_array_like& values,
                     const Optional_array_like& colors, const std::string& view, int width, int height,
                     double splat_scale, const std::optional<std::string>& legend)
{
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  if(!values.is_none() && !colors.is_none()) throw py::value_error("give values or colors, not both");
  if(width < 16 || height < 16 || width > 8192 || height > 8192)
    throw py::value_error("width and height must be in 16..8192 pixels");
  if(!(splat_scale > 0) || !std::isfinite(splat_scale)) throw py::value_error("splat_scale must be a number > 0");
  point_detail::Render_settings settings;
  settings.width = width;
  settings.height = height;
  settings.splat_scale = splat_scale;
  settings.view = translating_program_errors([&] { return point_detail::parse_view(view); });
  point_detail::Coloring coloring;
  if(!values.is_none()) coloring = point_detail::colors_for(values_of(values, n, "values"));
  if(!colors.is_none()) coloring.colors = colors_of(colors, n, "colors");
  if(legend) {
    if(values.is_none()) throw py::value_error("legend names the values: give values too");
    for(char c : *legend)
      if(!point_detail::legend_can_write(c))
        throw py::value_error(std::string("legend: the legend's font has no ") +
                              (static_cast<unsigned char>(c) < 128 ? std::string("'") + c + "'" : "non-ASCII letter") +
                              " (it writes letters, digits, spaces and .,-+/()_)");
    coloring.quantity = *legend;
  }
  if(n == 0) throw py::value_error("points is empty: nothing to draw");
  const point_detail::Point_cloud cloud = program_cloud(input);
  const std::string png = translating_program_errors(
    [&] { return without_gil([&] { return point_detail::render_png(cloud.points, cloud.normals, coloring, settings); }); });
  return py::bytes(png);
}

// ---- threads ----------------------------------------------------------------------------------------------------

std::unique_ptr<tbb::global_control> thread_limit;

void set_num_threads(const Optional_int& count)
{
  if(count.is_none()) {
    thread_limit.reset();
    return;
  }
  const long long n = count.cast<long long>();
  if(n < 1) throw py::value_error("the number of threads must be at least 1 (None: every core), not " + std::to_string(n));
  thread_limit.reset(); // one limit at a time: the smallest alive would win
  thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(n));
}

int get_num_threads() { return int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)); }

// ---- editing ------------------------------------------------------------------------------------------------

/// `Detail_preserving_deformation` for Python: the points and normals are copied at construction.
class Deformation
{
public:
  using Settings = Detail_preserving_deformation_settings;

  Deformation(const Array_like& points, const Optional_array_like& normals, const Settings& settings)
  {
    const Point_input input(points, normals);
    const std::size_t n = input.size();
    // The object's progress callback forwards to the one of the call that may preprocess (none at other times).
    const auto forward = [this](double fraction) { return !m_callback || m_callback(fraction); };
    m_deformation = with_maps(input, [&](const auto& np) {
      return without_gil([&] { return std::make_unique<Detail_preserving_deformation<>>(all_points(n), settings, np.callback(forward)); });
    });
  }

  void insert_roi(const Array_like& roi)
  {
    m_deformation->insert_roi_points(indices(roi, size(), "indices"));
    forget_written_arrays(); // the points the edit can move change with the selection
  }

  std::size_t create_handle_group(const Optional_array_like& handle_points)
  {
    const std::vector<std::size_t> handle =
      handle_points.is_none() ? std::vector<std::size_t>() : indices(handle_points, size(), "indices");
    const std::size_t group = m_deformation->create_handle_group();
    m_deformation->insert_handle_points(group, handle);
    forget_written_arrays();
    return group;
  }

  void insert_handle_points(long long group, const Array_like& handle_points)
  {
    const std::vector<std::size_t> handle = indices(handle_points, size(), "indices");
    m_deformation->insert_handle_points(checked_group(group), handle);
    forget_written_arrays();
  }

  void clear_selection()
  {
    m_deformation->clear_selection();
    forget_written_arrays();
  }

  bool preprocess(const Optional_progress& progress)
  {
    return with_progress(progress, [&] { return m_deformation->preprocess(); });
  }

  bool analyse_points(const Optional_progress& progress)
  {
    return with_progress(progress, [&] { return m_deformation->analyse_points(); });
  }

  void set_handle_transform(long long group, const Optional_array_like& rotation, const Optional_array_like& translation,
                            const Optional_array_like& transform, const Optional_array_like& pivot)
  {
    const std::size_t g = checked_group(group);
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    if(!transform.is_none()) {
      if(!rotation.is_none() || !translation.is_none() || !pivot.is_none())
        throw py::value_error("give transform (4, 4) alone, or rotation, translation and pivot");
      const Eigen::Matrix4d T = matrix_of<4, 4>(transform, "transform");
      if(!T.allFinite() || T.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
        throw py::value_error("transform must be a rigid motion [[R, t], [0, 0, 0, 1]]: its last row is not (0, 0, 0, 1)");
      R = T.topLeftCorner<3, 3>();
      t = T.topRightCorner<3, 1>();
    } else {
      if(!rotation.is_none()) R = matrix_of<3, 3>(rotation, "rotation");
      if(!translation.is_none()) t = matrix_of<3, 1>(translation, "translation");
      if(!pivot.is_none()) { // p -> R (p - c) + c + t
        const Eigen::Vector3d c = matrix_of<3, 1>(pivot, "pivot");
        t += c - R * c;
      }
    }
    m_deformation->set_handle_transform(g, R, t); // checks that R is a rotation and that both are finite
  }

  void deform(const Optional_progress& progress)
  {
    with_progress(progress, [&] { return m_deformation->deform(); });
  }

  /// Every point's and normal's deformed position, into `points_out` / `normals_out` when given (writable (n, 3)
  /// float64 arrays, reused from drag to drag), else into new arrays.
  Deformed_result diffuse(const Optional_array_like& points_out, const Optional_array_like& normals_out)
  {
    return results([&] { m_deformation->diffuse(); }, points_out, normals_out);
  }

  Deformed_result restore_details(const Optional_array_like& points_out, const Optional_array_like& normals_out)
  {
    return results([&] { m_deformation->restore_details(); }, points_out, normals_out);
  }

  void reset() { m_deformation->reset(); }

  Sample_points_of sample_point_of(const Array_like& points)
  {
    if(!m_deformation->is_preprocessed())
      throw py::value_error("sample_point_of() needs preprocess() first: the sample points are made there");
    if(py::isinstance<py::int_>(points) && !py::isinstance<py::bool_>(points)) {
      const long long i = points.cast<long long>();
      if(i < 0 || std::size_t(i) >= size())
        throw py::value_error("index " + std::to_string(i) + " is not a point index (" + std::to_string(size()) + " points)");
      return py::int_(m_deformation->sample_point_of(std::size_t(i)));
    }
    const std::vector<std::size_t> rows = indices(points, size(), "points");
    py::array_t<std::int64_t> labels(static_cast<py::ssize_t>(rows.size()));
    for(std::size_t m = 0; m < rows.size(); ++m) labels.mutable_data()[m] = std::int64_t(m_deformation->sample_point_of(rows[m]));
    return labels;
  }

  /// What a renderer that moves the points itself needs once per preprocessing (Detail_preserving_deformation,
  /// "Moving the points elsewhere"), in input order.
  py::dict renderer_setup() const
  {
    if(!m_deformation->is_preprocessed()) throw py::value_error("renderer_setup() needs preprocess() first");
    const Detail_preserving_deformation<>& d = *m_deformation;
    const std::size_t n = size(), m = d.stencil_size();
    if(m > 64) throw py::value_error("renderer_setup() takes at most 64 diffusion_samples, not " + std::to_string(m));
    py::array_t<std::int32_t> samples({py::ssize_t(n), py::ssize_t(m)});
    py::array_t<float> weights({py::ssize_t(n), py::ssize_t(m)});
    py::array_t<std::int8_t> exact_handle{py::ssize_t(n)};
    std::vector<std::int32_t> collar_points, collar_slots;
    std::vector<float> collar_weights;
    without_gil([&, samples_out = samples.mutable_data(), weights_out = weights.mutable_data(),
                 handle_out = exact_handle.mutable_data()] {
      tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        int stencil_samples[64];
        double stencil_weights[64];
        d.stencil(i, stencil_samples, stencil_weights);
        for(std::size_t e = 0; e < m; ++e) {
          samples_out[i * m + e] = stencil_samples[e];
          weights_out[i * m + e] = float(stencil_weights[e]);
        }
        handle_out[i] = d.is_exact_handle_point(i) ? std::int8_t(1) : std::int8_t(0);
      });
      // Two entries per collar point (more only where three groups' collars overlap: the rest are dropped).
      d.for_each_collar_point([&](std::size_t i, const int* slots, const double* w, std::size_t count) {
        collar_points.push_back(std::int32_t(i));
        for(std::size_t e = 0; e < 2; ++e) {
          collar_slots.push_back(e < count ? slots[e] : -1);
          collar_weights.push_back(e < count ? float(w[e]) : 0.0f);
        }
      });
      return 0;
    });
    const py::ssize_t c = py::ssize_t(collar_points.size());
    py::array_t<std::int32_t> slots({c, py::ssize_t(2)});
    py::array_t<float> slot_weights({c, py::ssize_t(2)});
    std::copy(collar_slots.begin(), collar_slots.end(), slots.mutable_data());
    std::copy(collar_weights.begin(), collar_weights.end(), slot_weights.mutable_data());
    return py::dict("stencil_samples"_a = samples, "stencil_weights"_a = weights, "exact_handle"_a = exact_handle,
                    "collar_points"_a = py::array_t<std::int32_t>(c, collar_points.data()),
                    "collar_handles"_a = py::array_t<std::int32_t>(py::ssize_t(d.collar_handle_points().size()),
                                                                  d.collar_handle_points().data()),
                    "collar_slots"_a = slots, "collar_weights"_a = slot_weights,
                    "sample_points"_a = d.number_of_sample_points());
  }

  /// Per drag, after deform(): the sample points' motions (3x4 each, row-major), the handle groups' transforms
  /// (3x4 each) and the collar handle points' steps (position, then normal), as one float32 array.
  py::array_t<float> renderer_frame()
  {
    Detail_preserving_deformation<>& d = *m_deformation;
    if(!d.is_preprocessed()) throw py::value_error("renderer_frame() needs deform() first");
    const std::size_t samples = d.number_of_sample_points(), groups = d.number_of_handle_groups(),
                      collar = d.collar_handle_points().size();
    py::array_t<float> frame(py::ssize_t(12 * (samples + groups) + 6 * collar));
    without_gil([&, out = frame.mutable_data()] {
      d.update_sample_motions();
      for(std::size_t s = 0; s < samples; ++s) {
        const Eigen::Matrix4d& record = d.sample_motion(s);
        for(int r = 0; r < 3; ++r)
          for(int c = 0; c < 4; ++c) out[12 * s + 4 * r + c] = float(record(r, c));
      }
      float* group_out = out + 12 * samples;
      for(std::size_t g = 0; g < groups; ++g) {
        const Eigen::Vector3d t = d.handle_target(g, Eigen::Vector3d::Zero());
        for(int c = 0; c < 3; ++c) {
          const Eigen::Vector3d column = d.handle_target(g, Eigen::Vector3d::Unit(c)) - t;
          for(int r = 0; r < 3; ++r) group_out[12 * g + 4 * r + c] = float(column(r));
        }
        for(int r = 0; r < 3; ++r) group_out[12 * g + 4 * r + 3] = float(t(r));
      }
      float* collar_out = group_out + 12 * groups;
      tbb::parallel_for(std::size_t(0), collar, [&](std::size_t c) { // each a blend of the point's stencil
        Eigen::Vector3d step, normal_step;
        d.collar_handle_step(c, step, normal_step);
        for(int r = 0; r < 3; ++r) collar_out[6 * c + r] = float(step(r)), collar_out[6 * c + 3 + r] = float(normal_step(r));
      });
      return 0;
    });
    return frame;
  }

  py::dict statistics() const
  {
    const Detail_preserving_deformation_statistics& s = m_deformation->statistics();
    return py::dict("points"_a = s.points, "samples"_a = s.samples, "requested_samples"_a = s.requested_samples,
                    "roi_samples"_a = s.roi_samples, "handle_samples"_a = s.handle_samples,
                    "clustering_seconds"_a = s.clustering_seconds, "preprocess_seconds"_a = s.preprocess_seconds,
                    "deform_seconds"_a = s.deform_seconds, "diffuse_seconds"_a = s.diffuse_seconds,
                    "restore_seconds"_a = s.restore_seconds, "restore_iterations"_a = s.restore_iterations,
                    "restore_residual"_a = s.restore_residual, "rigid_iterations"_a = s.rigid_iterations,
                    "displacement_ratio"_a = s.displacement_ratio, "factor_seconds"_a = s.least_squares.factor_seconds,
                    "operator_nonzeros"_a = s.least_squares.operator_nonzeros,
                    "normal_nonzeros"_a = s.least_squares.normal_nonzeros,
                    "solve_seconds"_a = s.least_squares.solve_seconds, "solve_iterations"_a = s.least_squares.iterations,
                    "relative_residual"_a = s.least_squares.relative_residual);
  }

  /// The settings under their keyword names, as the constructor takes them.
  static py::dict settings_dict(const Settings& s)
  {
    return py::dict(
      "order"_a = setting_name(s.filter.order), "lam"_a = s.filter.lambda, "mu"_a = s.filter.mu,
      "k"_a = s.sample_neighbors, "handle_weight"_a = s.handle_weight,
      "rotations"_a = setting_name(s.rotations), "rigid_iterations"_a = s.rigid_iterations,
      "rigid_rotation_smoothing"_a = s.rigid_rotation_smoothing,
      "rigid_rotation_smoothing_scale"_a = setting_name(s.rigid_rotation_smoothing_scale),
      "rigid_edge_weights"_a = setting_name(s.rigid_edge_weights),
      "strength_distance"_a = setting_name(s.strength_distance), "target_count"_a = s.simplification.target_count,
      "max_cluster_size"_a = s.simplification.max_cluster_size ? py::object(py::int_(*s.simplification.max_cluster_size))
                                                                  : py::object(py::none()),
      "diffusion_samples"_a = s.diffusion_samples, "diffusion_origin"_a = setting_name(s.diffusion_origin),
      "diffusion_turn"_a = setting_name(s.diffusion_turn), "detail_iterations"_a = s.detail_iterations,
      "detail_tolerance"_a = s.detail_tolerance, "detail_anchor"_a = s.detail_anchor);
  }

  py::dict settings() const { return settings_dict(m_deformation->settings()); }

  std::size_t size() const { return m_deformation->number_of_points(); }
  std::size_t number_of_handle_groups() const { return m_deformation->number_of_handle_groups(); }
  std::size_t number_of_sample_points() const { return m_deformation->number_of_sample_points(); }
  bool is_preprocessed() const { return m_deformation->is_preprocessed(); }

  std::string repr() const
  {
    std::string s = "<cgal_ext.Deformation of " + std::to_string(size()) + " points, " +
                    std::to_string(number_of_handle_groups()) + " handle group(s), ";
    if(!is_preprocessed()) return s + "not preprocessed>";
    return s + std::to_string(number_of_sample_points()) + " sample points (" +
           std::to_string(m_deformation->number_of_roi_sample_points()) + " in the region), rotations " +
           setting_name(m_deformation->settings().rotations) + ">";
  }

private:
  std::size_t checked_group(long long group) const
  {
    if(group < 0 || std::size_t(group) >= number_of_handle_groups())
      throw py::value_error("there is no handle group " + std::to_string(group) + " (" +
                            std::to_string(number_of_handle_groups()) + " groups; create_handle_group() adds one)");
    return std::size_t(group);
  }

  template <int Rows, int Columns>
  static Eigen::Matrix<double, Rows, Columns> matrix_of(const py::handle& object, const char* argument)
  {
    const py::array array = as_array(object, argument, "an array of numbers");
    const char kind = array.dtype().kind();
    const bool vector = Columns == 1 && array.ndim() == 1 && array.shape(0) == Rows;
    const bool matrix = array.ndim() == 2 && array.shape(0) == Rows && array.shape(1) == Columns;
    if(!(kind == 'f' || kind == 'i' || kind == 'u') || !(vector || matrix))
      throw py::value_error(std::string(argument) + " must be " +
                            (Columns == 1 ? "3 numbers" : "a (" + std::to_string(Rows) + ", " + std::to_string(Columns) + ") array") +
                            ", not shape " + shape_of(array) + " of dtype " + dtype_name(array));
    const auto values = py::array_t<double, py::array::forcecast | py::array::c_style>::ensure(array);
    Eigen::Matrix<double, Rows, Columns> m;
    for(int r = 0; r < Rows; ++r)
      for(int c = 0; c < Columns; ++c) m(r, c) = values.data()[r * Columns + c];
    if(!m.allFinite()) throw py::value_error(std::string(argument) + " is not finite");
    return m;
  }

  /// `step()` (a call that may preprocess) with `progress` reported and its exception or Ctrl-C raised.
  template <typename Step>
  bool with_progress(const Optional_progress& progress, const Step& step)
  {
    Python_progress reporter(progress);
    m_callback = reporter.callback();
    bool done = false;
    try {
      done = without_gil(step);
    } catch(...) {
      m_callback = nullptr;
      throw;
    }
    m_callback = nullptr;
    reporter.raise_if_cancelled(done);
    return done;
  }

  /// Runs `step`, then writes every point's and normal's deformed position in the caller's order: the whole
  /// arrays, or, when they are the very arrays written whole since the last preprocessing, only the points the
  /// edit can move (Detail_preserving_deformation::for_each_deformed_point).
  template <typename Step>
  Deformed_result results(const Step& step, const Optional_array_like& points_out, const Optional_array_like& normals_out)
  {
    const std::size_t n = size();
    auto [points, point_view] = output_rows3(points_out, "points_out", n);
    auto [normals, normal_view] = output_rows3(normals_out, "normals_out", n);
    // The same array objects (held here, so their memory cannot pass to other arrays meanwhile).
    const bool movable_only = m_deformation->is_preprocessed() && !points_out.is_none() && !normals_out.is_none() &&
                              points_out.is(m_written_points) && normals_out.is(m_written_normals);
    without_gil([&, point_view = point_view, normal_view = normal_view] {
      const auto write = [&](std::size_t i, const double* p, const double* v) {
        for(int c = 0; c < 3; ++c) {
          point_view.at(i, c) = p[c];
          normal_view.at(i, c) = v[c];
        }
      };
      step();
      m_deformation->for_each_deformed_point(write, movable_only);
      return 0;
    });
    // Caller's arrays written whole: the next drag into them writes only what it can move.
    m_written_points = points_out.is_none() || normals_out.is_none() ? py::object() : py::object(points_out);
    m_written_normals = points_out.is_none() || normals_out.is_none() ? py::object() : py::object(normals_out);
    return py::reinterpret_borrow<py::object>(result_types.deformed)(points, normals);
  }

  /// The caller's arrays last written whole, until the selection changes.
  void forget_written_arrays()
  {
    m_written_points = py::object();
    m_written_normals = py::object();
  }
  py::object m_written_points, m_written_normals;

  std::unique_ptr<Detail_preserving_deformation<>> m_deformation;
  std::function<bool(double)> m_callback;
};

// ---- docstrings -------------------------------------------------------------------------------------------------

const char* const points_doc = R"(points : (n, 3) array_like
    The points. float64 arrays are read in place (any memory layout); float32, integers and nested lists are
    converted to float64 once, a copy.)";
const char* const normals_doc = R"(normals : (n, 3) array_like, optional
    Unit normals, read as points are. None estimates them (jet fitting and a consistent orientation).)";
const char* const progress_doc = R"(progress : callable, optional
    Called as progress(fraction), fraction in [0, 1], from the calling thread. An exception raised in it
    cancels the computation, which then raises it; Ctrl-C does the same with KeyboardInterrupt.)";
const char* const filter_doc = R"(k : int
    Neighbours of the point-set Laplacian (each point's k nearest, itself not counted; fewer than the points).
order : {"linear", "quadric", "cubic"}
    The transfer function f(K) of the details (Miao et al. 2007, Sect. 3).
lam, mu : float
    Its pass-band and highest frequencies, 0 < lam < mu (mu unused by "linear").
weights : {"uniform", "distance"}
    The Laplacian's weights: uniform, or inverse distance.)";
const char* const raises_doc = R"(Raises
------
ValueError
    A bad argument (shape, dtype, index, setting) or input the library refuses, with its message.
RuntimeError
    A numerical failure (a factorisation that fails), with the library's message.)";

std::string doc(const std::string& summary, const std::vector<std::string>& parameters, const std::string& returns,
                bool raises = true)
{
  std::string text = summary + "\n\nParameters\n----------\n";
  for(const std::string& p : parameters) text += p + "\n";
  if(!returns.empty()) text += "\nReturns\n-------\n" + returns + "\n";
  if(raises) text += std::string("\n") + raises_doc + "\n";
  return text;
}

} // namespace

PYBIND11_MODULE(_core, m)
{
  m.doc() = "The compiled part of cgal_ext: high-frequency geometric details of point-sampled surfaces (Miao et al. "
            "2007) on numpy arrays.";
  m.attr("__version__") = CGAL_EXT_VERSION;
  // The library's exceptions: Invalid_input is a std::invalid_argument (ValueError), Numerical_failure a
  // std::runtime_error (RuntimeError); pybind11 translates both with their messages.
  result_types.details = named_tuple(m, "Details", {"details", "magnitude"},
                                     "Details(details, magnitude): the detail vector of every point (n, 3) and its "
                                     "oriented magnitude (n,), positive where the detail stands out along the normal.");
  result_types.upsampled = named_tuple(m, "Upsampled", {"points", "normals"},
                                       "Upsampled(points, normals): the new samples (m, 3) and their normals (m, 3).");
  result_types.deformed = named_tuple(m, "Deformed", {"points", "normals"},
                                      "Deformed(points, normals): every point's and normal's deformed position (n, 3), "
                                      "in the input order.");
  result_types.point_set = named_tuple(m, "PointSet", {"points", "normals", "properties"},
                                       "PointSet(points, normals, properties): the points (n, 3) float64, their normals "
                                       "(n, 3) or None, and the other per-point properties by name (float64 arrays; "
                                       "colours as 'colors', (n, 3) uint8).");

  const Detail_filter filter;
  const unsigned int laplacian_k = default_laplacian_neighbors;
  const std::string default_order = setting_name(filter.order);
  const std::string default_weights = setting_name(Laplacian_weights().weighting);

  m.def("compute_geometric_details", &bound_compute_geometric_details, "points"_a, "normals"_a = py::none(), py::kw_only(),
        "k"_a = laplacian_k, "order"_a = default_order, "lam"_a = filter.lambda, "mu"_a = filter.mu,
        "weights"_a = default_weights, "progress"_a = py::none(),
        doc("The detail vector delta = f(K) p of every point and its oriented magnitude +-|delta| (the sign of "
            "delta . n); K = I - W is the point-set Laplacian (doc/geometric_details.md).",
            {points_doc, normals_doc, filter_doc, progress_doc},
            "Details\n    (details (n, 3), magnitude (n,)), new float64 arrays.")
          .c_str());
  const std::string region_doc = R"(roi : array_like of int or bool
    The region of interest: point indices, or a boolean mask of all the points.)";
  const std::string anchors_doc = R"(anchors : array_like of int or bool, optional
    Points held where they are (indices or a mask); None lets the function anchor the region's border.)";
  m.def("scale_geometric_details",
        [](const Array_like& points, const Optional_array_like& normals, const Array_like& roi, double s,
           const Optional_array_like& anchors, long long k, const std::string& order, double lam, double mu,
           const std::string& weights, const Optional_progress& progress) {
          return manipulate(false, points, normals, roi, s, anchors, k, order, lam, mu, weights, progress);
        },
        "points"_a, "normals"_a = py::none(), py::kw_only(), "roi"_a, "s"_a, "anchors"_a = py::none(), "k"_a = laplacian_k,
        "order"_a = default_order, "lam"_a = filter.lambda, "mu"_a = filter.mu, "weights"_a = default_weights,
        "progress"_a = py::none(),
        doc("The points with the details of a region scaled by s (Miao et al. 2007, Sect. 4): a least-squares "
            "solve that keeps the rest of the shape (doc/detail_scaling.md).",
            {points_doc, normals_doc, region_doc, "s : float\n    The scale of the details: 0 removes them, 1 keeps the points, 2 doubles them.",
             anchors_doc, filter_doc, progress_doc},
            "numpy.ndarray\n    The moved points (n, 3), a new array (the points are read once into it; the input is "
            "not changed).")
          .c_str());
  m.def("enhance_geometric_details",
        [](const Array_like& points, const Optional_array_like& normals, double s, const Optional_array_like& roi,
           const Optional_array_like& anchors, long long k, const std::string& order, double lam, double mu,
           const std::string& weights, const Optional_progress& progress) {
          return manipulate(true, points, normals, roi, s, anchors, k, order, lam, mu, weights, progress);
        },
        "points"_a, "normals"_a = py::none(), py::kw_only(), "s"_a, "roi"_a = py::none(), "anchors"_a = py::none(),
        "k"_a = laplacian_k, "order"_a = default_order, "lam"_a = filter.lambda, "mu"_a = filter.mu,
        "weights"_a = default_weights, "progress"_a = py::none(),
        doc("The points with their details against a smooth base surface (the balanced curvature flow) enhanced by "
            "s (Miao et al. 2007, Sect. 4; doc/detail_scaling.md).",
            {points_doc, normals_doc, "s : float\n    The enhancement: 1 keeps the points, 2 doubles the details.",
             "roi : array_like of int or bool, optional\n    The region enhanced (indices or a mask); None: every point.",
             anchors_doc, filter_doc, progress_doc},
            "numpy.ndarray\n    The moved points (n, 3), a new array (the points are read once into it).")
          .c_str());
  m.def("estimate_mean_curvature", &bound_estimate_mean_curvature, "points"_a, "normals"_a = py::none(), py::kw_only(),
        "k"_a = default_curvature_neighbors, "fitting"_a = setting_name(Curvature_fitting::closed_form),
        "progress"_a = py::none(),
        doc("The signed mean curvature of every point: a sphere with outward normals has +1/r (doc/curvature.md).",
            {points_doc, normals_doc, "k : int\n    Neighbours of each local fit (itself not counted).",
             "fitting : {\"closed_form\", \"monge\"}\n    A closed-form degree-2 fit, or CGAL's Monge jet fitting.",
             progress_doc},
            "numpy.ndarray\n    (n,) float64.")
          .c_str());
  const Simplification_settings simplification;
  m.def("compute_simplification_sample_points", &bound_compute_simplification_sample_points, "points"_a,
        "normals"_a = py::none(), py::kw_only(), "target_count"_a = simplification.target_count,
        "max_cluster_size"_a = py::none(), "mode_threshold"_a = simplification.mode_spread_threshold,
        "k"_a = default_mean_shift_neighbors, "progress"_a = py::none(),
        doc("The simplification sample point (SSP) of every point: a 7D mean shift over position, normal and "
            "curvature, and clusters that are dense where the surface bends (doc/simplification.md).",
            {points_doc, normals_doc, "target_count : int\n    About how many sample points to make.",
             "max_cluster_size : int, optional\n    The most points a sample point may have, instead of target_count.",
             "mode_threshold : float\n    How far apart (in the mean shift's range units) two modes must be to split a "
             "cluster.",
             "k : int\n    Neighbours of the mean shift (itself not counted).", progress_doc},
            "numpy.ndarray\n    (n,) int64, the sample point of each point, 0 .. number of sample points - 1.")
          .c_str());
  const Upsampling_settings upsampling;
  m.def("upsample_point_set", &bound_upsample_point_set, "points"_a, "normals"_a, py::kw_only(),
        "spacing"_a = upsampling.detection.spacing, "max_hole_size"_a = upsampling.detection.max_hole_size,
        "k"_a = upsampling.neighbors, "roi"_a = py::none(), "progress"_a = py::none(),
        doc("New samples that fill the holes and sparse parts of an oriented point set (doc/upsampling.md).",
            {points_doc, "normals : (n, 3) array_like\n    Unit normals (required: the holes and the new samples' surface "
             "come from them).",
             "spacing : float\n    The spacing of the new samples; 0: each point's local spacing.",
             "max_hole_size : float\n    The widest hole filled, in spacings.",
             "k : int\n    Neighbours of the principal axes and of the local surface fits (at least 6).",
             "roi : array_like of int or bool, optional\n    Only holes next to these points are filled.",
             progress_doc},
            "Upsampled\n    (points (m, 3), normals (m, 3)), the new samples only.")
          .c_str());

  m.def("read_points", &read_points, "path"_a,
        doc("Reads a PLY, OFF, XYZ or PWN point set with the point-detail program's readers: the header is checked "
            "before anything is allocated, and a file larger than the memory, truncated or malformed is refused with "
            "the program's message (doc/bad_input.md); non-finite coordinates of a binary file are read as they are "
            "(the algorithms refuse them). A mesh's normals are its faces' area-weighted vertex normals.",
            {"path : str or os.PathLike\n    The file; its extension names the format."},
            "PointSet\n    (points (n, 3) float64, normals (n, 3) or None, properties: dict of the other per-point "
            "properties, float64 (n,) each, colours as 'colors' (n, 3) uint8).",
            false)
            .append("\nRaises\n------\nFileNotFoundError\n    No such file.\nValueError\n    A file the readers "
                    "refuse, with their message.\n")
          .c_str());
  m.def("write_ply", &write_ply, "path"_a, "points"_a, "normals"_a = py::none(), "colors"_a = py::none(), py::kw_only(),
        "input_path"_a = py::none(),
        doc("Writes a binary little-endian PLY as the program does (x y z, nx ny nz, the scalars as doubles, red "
            "green blue): into a temporary file beside it, renamed once whole, so a failure leaves no partial "
            "file. Any extra keyword argument is a per-point scalar property of that name.",
            {"path : str or os.PathLike\n    The file to write.", points_doc,
             "normals : (n, 3) array_like, optional\n    Written as nx ny nz.",
             "colors : (n, 3) array_like of int, optional\n    Written as red green blue, integers in 0..255.",
             "input_path : str or os.PathLike, optional\n    The file the points were read from: writing over it is "
             "refused.",
             "**scalars : (n,) array_like\n    Per-point values, written as double properties in the order given."},
            "", true)
          .c_str());
  m.def("estimate_oriented_normals", &bound_estimate_oriented_normals, "points"_a, py::kw_only(),
        "k"_a = default_normal_neighbors, "progress"_a = py::none(),
        doc("Unit normals by jet fitting, oriented consistently along a minimum spanning tree (as the program "
            "estimates them for an input without normals).",
            {points_doc, "k : int\n    Neighbours of each point's fit, the point itself counted; at most the number of points.",
             progress_doc},
            "numpy.ndarray\n    (n, 3) float64 normals.")
          .c_str());
  m.def("sequential_colors", [](const Array_like& values) { return colors_by(point_detail::sequential_colors, values); },
        "values"_a,
        doc("The program's sequential colour map (the edit's distance moved), from the 2nd to the 98th "
            "percentile of the values.",
            {"values : (n,) array_like\n    The values, e.g. each point's displacement."},
            "numpy.ndarray\n    (n, 3) uint8 colours.")
          .c_str());
  m.def("diverging_colors",
        [](const Array_like& values, std::optional<double> limit) {
          if(!limit) return colors_by([](const std::vector<double>& v) { return point_detail::diverging_colors(v); }, values);
          if(!(*limit > 0) || !std::isfinite(*limit))
            throw std::invalid_argument("diverging_colors: limit must be positive and finite, not " +
                                        std::to_string(*limit));
          return colors_by([&](const std::vector<double>& v) { return point_detail::diverging_colors(v, *limit); },
                           values);
        },
        "values"_a, py::kw_only(), "limit"_a = py::none(),
        doc("The program's blue-white-red colour map of signed values, symmetric about zero and saturating at the "
            "98th percentile of the non-zero magnitudes (doc/geometric_details.md, \"Colour maps\").",
            {"values : (n,) array_like\n    The values, e.g. the details' magnitude.",
             "limit : float, optional\n    Saturate at +-limit instead (the tiled runs pass the whole scan's)."},
            "numpy.ndarray\n    (n, 3) uint8 colours.")
          .c_str());
  const point_detail::Render_settings render;
  m.def("render_png", &render_png, "points"_a, "normals"_a = py::none(), py::kw_only(), "values"_a = py::none(),
        "colors"_a = py::none(), "view"_a = "front", "width"_a = render.width, "height"_a = render.height,
        "splat_scale"_a = render.splat_scale, "legend"_a = py::none(),
        doc("A PNG picture of the points as the program draws it (splats with a depth buffer, shaded by the "
            "normals), e.g. for IPython.display.Image.",
            {points_doc, "normals : (n, 3) array_like, optional\n    Shade by them; None: flat shading.",
             "values : (n,) array_like, optional\n    Colour by these values (a diverging map when both signs occur, "
             "else a sequential one) with a legend of their range.",
             "colors : (n, 3) array_like of int, optional\n    Colour by these colours (0..255) instead.",
             "view : str\n    front, back, left, right, top, bottom, iso, or \"AZIMUTH,ELEVATION\" in degrees.",
             "width, height : int\n    The picture's size in pixels.",
             "splat_scale : float\n    Scales the splats' radius.",
             "legend : str, optional\n    What the values are and their unit, written over the legend's bar (e.g. "
             "\"displacement, model units\"; letters, digits, spaces and .,-+/()_)."},
            "bytes\n    The PNG file's bytes.")
          .c_str());
  m.def("set_num_threads", &set_num_threads, "count"_a,
        doc("Limits the library's worker threads (TBB's max_allowed_parallelism), as the program's --threads does. "
            "cgal_ext.threads(n) does the same for a with-block.",
            {"count : int or None\n    At least 1; None lifts the limit (every core)."},
            "", false)
          .c_str());
  m.def("get_num_threads", &get_num_threads, "The number of worker threads the library may use now.");
  m.def("_trace_reads", [](bool on) {
    read_trace.lowest = std::numeric_limits<std::uintptr_t>::max();
    read_trace.highest = 0;
    read_trace.on = on;
  }, "on"_a, "Tests only: start (True) or stop recording the memory the library reads through points and normals.");
  m.def("_read_span", [] { return py::make_tuple(read_trace.lowest.load(), read_trace.highest.load()); },
        "Tests only: the lowest and one past the highest address read since _trace_reads(True).");

  const Deformation::Settings defaults;
  py::class_<Deformation>(m, "Deformation",
                          doc("Detail-preserving editing of a point set (Miao et al. 2007, Sect. 6), shaped like CGAL's "
                              "Surface_mesh_deformation: select a region of interest and handle groups, preprocess(), "
                              "then per frame of a drag set_handle_transform(), deform() and diffuse(), and "
                              "restore_details() once the drag ends (doc/editing.md). The points and normals are "
                              "copied at construction. The settings are keyword-only; `settings` reads them back.",
                              {points_doc, normals_doc,
                               "order, lam, mu : str, float, float\n    The detail transfer function, as in compute_geometric_details.",
                               "k : int\n    Neighbours of the sample points' Laplacian.",
                               "handle_weight : float\n    inf: handles are hard constraints; else their weight in the "
                               "least squares.",
                               "rotations : {\"propagate\", \"arap\", \"none\"}\n    How the details turn: by the strength "
                               "field, fitted as rigid as possible, or not.",
                               "rigid_iterations : int\n    Local/global iterations per step in \"arap\" mode.",
                               "rigid_rotation_smoothing : float\n    SRE-ARAP's smooth-rotation weight (0: plain ARAP).",
                               "rigid_rotation_smoothing_scale : {\"edge_lengths\", \"surface_area\"}\n    How that weight "
                               "is scaled.",
                               "rigid_edge_weights : {\"uniform\", \"cotangent\"}\n    Edge weights of the \"arap\" energy.",
                               "strength_distance : {\"euclidean\", \"geodesic\"}\n    The distance of the strength "
                               "field.",
                               "target_count : int\n    About how many sample points to make.",
                               "max_cluster_size : int, optional\n    The most points per sample point, instead.",
                               "diffusion_samples : int\n    Sample points blended per point by the diffusion.",
                               "diffusion_origin : {\"own\", \"nearest\"}\n    Where each point's offset is taken from.",
                               "diffusion_turn : {\"affine\", \"fitted\", \"frames\"}\n    How each sample point carries "
                               "its points.",
                               "detail_iterations : int\n    The most conjugate-gradient iterations of restore_details().",
                               "detail_tolerance : float\n    Its relative residual to stop at.",
                               "detail_anchor : float\n    How strongly it keeps the diffusion's coarse shape.",
                               "strength : str, optional\n    The older spelling of strength_distance, still read."},
                              "", true)
                            .c_str())
    .def(py::init([](const Array_like& points, const Optional_array_like& normals, const std::string& order, double lam,
                     double mu, long long k, double handle_weight, const std::string& rotations, long long rigid_iterations,
                     double rigid_rotation_smoothing, const std::string& rigid_rotation_smoothing_scale,
                     const std::string& rigid_edge_weights, const std::string& strength_distance, long long target_count,
                     const Optional_int& max_cluster_size, long long diffusion_samples, const std::string& diffusion_origin,
                     const std::string& diffusion_turn, long long detail_iterations, double detail_tolerance,
                     double detail_anchor, const std::optional<std::string>& strength) {
           Deformation::Settings s;
           s.filter = Detail_filter{parse_setting<Detail_order>(order, "order"), lam, mu};
           s.sample_neighbors = as_count(k, "k");
           s.handle_weight = handle_weight;
           s.rotations = parse_setting<Detail_rotation>(rotations, "rotations");
           s.rigid_iterations = as_count(rigid_iterations, "rigid_iterations");
           s.rigid_rotation_smoothing = rigid_rotation_smoothing;
           s.rigid_rotation_smoothing_scale =
             parse_setting<Rotation_smoothing_scale>(rigid_rotation_smoothing_scale, "rigid_rotation_smoothing_scale");
           s.rigid_edge_weights = parse_setting<Rigid_edge_weights>(rigid_edge_weights, "rigid_edge_weights");
           if(strength && strength_distance != setting_name(Deformation::Settings().strength_distance))
             throw py::value_error("give strength_distance (strength is its older spelling), not both");
           s.strength_distance = strength ? parse_setting<Strength_distance>(*strength, "strength")
                                          : parse_setting<Strength_distance>(strength_distance, "strength_distance");
           if(target_count < 1) throw py::value_error("target_count must be at least 1, not " + std::to_string(target_count));
           s.simplification.target_count = std::size_t(target_count);
           if(!max_cluster_size.is_none()) {
             const long long size = max_cluster_size.cast<long long>();
             if(size < 1) throw py::value_error("max_cluster_size must be at least 1, not " + std::to_string(size));
             s.simplification.max_cluster_size = std::size_t(size);
           }
           s.diffusion_samples = as_count(diffusion_samples, "diffusion_samples");
           s.diffusion_origin = parse_setting<Diffusion_origin>(diffusion_origin, "diffusion_origin");
           s.diffusion_turn = parse_setting<Sample_turn>(diffusion_turn, "diffusion_turn");
           s.detail_iterations = as_count(detail_iterations, "detail_iterations");
           s.detail_tolerance = detail_tolerance;
           s.detail_anchor = detail_anchor;
           s.validate();
           return std::make_unique<Deformation>(points, normals, s);
         }),
         "points"_a, "normals"_a = py::none(), py::kw_only(), "order"_a = setting_name(defaults.filter.order),
         "lam"_a = defaults.filter.lambda, "mu"_a = defaults.filter.mu, "k"_a = defaults.sample_neighbors,
         "handle_weight"_a = defaults.handle_weight, "rotations"_a = setting_name(defaults.rotations),
         "rigid_iterations"_a = defaults.rigid_iterations, "rigid_rotation_smoothing"_a = defaults.rigid_rotation_smoothing,
         "rigid_rotation_smoothing_scale"_a = setting_name(defaults.rigid_rotation_smoothing_scale),
         "rigid_edge_weights"_a = setting_name(defaults.rigid_edge_weights),
         "strength_distance"_a = setting_name(defaults.strength_distance),
         "target_count"_a = defaults.simplification.target_count, "max_cluster_size"_a = py::none(),
         "diffusion_samples"_a = defaults.diffusion_samples,
         "diffusion_origin"_a = setting_name(defaults.diffusion_origin),
         "diffusion_turn"_a = setting_name(defaults.diffusion_turn),
         "detail_iterations"_a = defaults.detail_iterations, "detail_tolerance"_a = defaults.detail_tolerance,
         "detail_anchor"_a = defaults.detail_anchor, "strength"_a = py::none())
    .def("insert_roi", &Deformation::insert_roi, "indices"_a,
         doc("Adds points to the region of interest (the part that deforms).",
             {"indices : array_like of int or bool\n    Point indices, or a boolean mask of all the points."}, "", true)
           .c_str())
    .def("create_handle_group", &Deformation::create_handle_group, "indices"_a = py::none(),
         doc("Adds a handle group (points moved together by one rigid transform; they must lie in the region).",
             {"indices : array_like of int or bool, optional\n    Its points (indices or a mask); more can be added with "
              "insert_handle_points()."},
             "int\n    The group's number.", true)
           .c_str())
    .def("insert_handle_points", &Deformation::insert_handle_points, "group"_a, "indices"_a,
         doc("Adds points to a handle group.",
             {"group : int\n    A group create_handle_group() returned.",
              "indices : array_like of int or bool\n    Point indices, or a boolean mask of all the points."},
             "", true)
           .c_str())
    .def("clear_selection", &Deformation::clear_selection,
         "Empties the region of interest and removes every handle group (the next deform() preprocesses again).")
    .def("preprocess", &Deformation::preprocess, py::kw_only(), "progress"_a = py::none(),
         doc("Makes the sample points of the selection, their Laplacian and details, the strength field and the "
             "diffusion stencils, and factors the least squares; deform() calls it when the selection changed.",
             {progress_doc}, "bool\n    True (a cancelled call raises instead).", true)
           .c_str())
    .def("analyse_points", &Deformation::analyse_points, py::kw_only(), "progress"_a = py::none(),
         doc("Computes now what preprocess() needs whatever the selection (the points' mean-shift modes, the "
             "clustering's most costly part), so that it can run while a user selects; preprocess() computes it "
             "when it has not been. Safe to call in another thread while the selection is changed.",
             {progress_doc}, "bool\n    True (a cancelled run raises).")
           .c_str())
    .def("set_handle_transform", &Deformation::set_handle_transform, "group"_a, "rotation"_a = py::none(),
         "translation"_a = py::none(), py::kw_only(), "transform"_a = py::none(), "pivot"_a = py::none(),
         doc("Sets the rigid motion of a handle group: p -> R (p - c) + c + t (c = pivot, 0 when not given), or the "
             "4x4 matrix [[R, t], [0, 0, 0, 1]].",
             {"group : int\n    The handle group.", "rotation : (3, 3) array_like, optional\n    R, a rotation "
              "(orthonormal within 1e-6, determinant +1); None: the identity.",
              "translation : (3,) array_like, optional\n    t; None: zero.",
              "transform : (4, 4) array_like, optional\n    The whole rigid motion instead of rotation, translation and "
              "pivot.",
              "pivot : (3,) array_like, optional\n    The point the rotation turns about."},
             "", true)
           .c_str())
    .def("deform", &Deformation::deform, py::kw_only(), "progress"_a = py::none(),
         doc("Solves the sample points' new positions for the handles' transforms (preprocessing first when the "
             "selection changed): one back-substitution per call.",
             {progress_doc}, "", true)
           .c_str())
    .def("diffuse", &Deformation::diffuse, "points_out"_a = py::none(), "normals_out"_a = py::none(),
         doc("Carries the sample points' deformation to every point and normal.",
             {"points_out : (n, 3) float64 ndarray, optional\n    Written in place (reuse it from drag to drag); None: a "
              "new array.",
              "normals_out : (n, 3) float64 ndarray, optional\n    The same for the normals."},
             "Deformed\n    (points, normals) in the input order: points_out and normals_out when given.", true)
           .c_str())
    .def("restore_details", &Deformation::restore_details, "points_out"_a = py::none(), "normals_out"_a = py::none(),
         doc("After diffuse(): puts back the fine details the diffusion smoothed (conjugate gradients, at most "
             "detail_iterations; call it once a drag ends), then returns the points and normals as diffuse() does.",
             {"points_out : (n, 3) float64 ndarray, optional\n    Written in place; None: a new array.",
              "normals_out : (n, 3) float64 ndarray, optional\n    The same for the normals."},
             "Deformed\n    (points, normals) in the input order.", true)
           .c_str())
    .def("reset", &Deformation::reset,
         "Handle transforms back to the identity and every point back to its input position; the preprocessing is kept.")
    .def("sample_point_of", &Deformation::sample_point_of, "points"_a,
         doc("The sample point of points (after preprocess()).",
             {"points : int or array_like of int or bool\n    A point index, or indices or a boolean mask."},
             "int or numpy.ndarray\n    The sample point of each, int64.", true)
           .c_str())
    .def("number_of_handle_groups", &Deformation::number_of_handle_groups, "The number of handle groups.")
    .def("number_of_sample_points", &Deformation::number_of_sample_points,
         "The number of sample points (0 before preprocess()).")
    .def("is_preprocessed", &Deformation::is_preprocessed, "Whether preprocess() ran since the selection last changed.")
    .def("renderer_setup", &Deformation::renderer_setup,
         "What a renderer that moves the points itself (a GPU) needs once per preprocessing, in input order: each\n"
         "point's stencil (``stencil_samples`` (n, m) int32 and ``stencil_weights`` (n, m) float32), ``exact_handle``\n"
         "(n,) int8, and the collar: ``collar_points`` (c,), their ``collar_slots`` and ``collar_weights`` (c, 2)\n"
         "(slot -1: none) into ``collar_handles``, the handle points whose steps the collar spreads.")
    .def("renderer_frame", &Deformation::renderer_frame,
         "Per drag, after deform(): one float32 array of each sample point's motion (3x4, row-major: a point p it\n"
         "carries alone moves by M (p, 1)), each handle group's transform (3x4) and each collar handle point's\n"
         "step (position, then normal; 6 numbers). O(sample points): what a renderer's shader blends per point.")
    .def("statistics", &Deformation::statistics, "Sizes and timings of the last calls, as a dict.")
    .def_property_readonly("settings", &Deformation::settings, "The settings, under the constructor's keyword names.")
    .def("__len__", &Deformation::size)
    .def("__repr__", &Deformation::repr);
}
