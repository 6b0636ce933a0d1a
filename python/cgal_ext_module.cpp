// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// The Python module `cgal_ext`: the library's algorithms on numpy arrays (doc/python.md). Points and normals are
// read in place through property maps over the caller's arrays (C- or F-ordered, any strides); results are new
// arrays. The GIL is released while the library computes; a `progress` callable is called from the calling
// thread with the GIL taken back, and an exception it raises (or Ctrl-C) cancels the computation and is raised.
#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/scale_geometric_details.h>
#include <CGAL_ext/upsample_point_set.h>

#include <CGAL/Simple_cartesian.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <boost/property_map/function_property_map.hpp>
#include <boost/range/counting_range.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using Index_range = boost::iterator_range<boost::counting_iterator<std::size_t>>;

// ---- arrays in place ----------------------------------------------------------------------------------------

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

std::string shape_of(const py::array& array)
{
  std::string s = "(";
  for(py::ssize_t d = 0; d < array.ndim(); ++d) s += (d ? ", " : "") + std::to_string(array.shape(d));
  return s + (array.ndim() == 1 ? ",)" : ")");
}

/// Checks that `object` is an (n, 3) float64 numpy array and views it in place; a ValueError names `argument`.
Rows3 rows3(const py::handle& object, const char* argument)
{
  if(!py::isinstance<py::array>(object))
    throw py::value_error(std::string(argument) + " must be a numpy array of shape (n, 3) and dtype float64, not " +
                          std::string(py::str(object.get_type().attr("__name__"))));
  const auto array = py::reinterpret_borrow<py::array>(object);
  if(array.ndim() != 2 || array.shape(1) != 3)
    throw py::value_error(std::string(argument) + " must have shape (n, 3), not " + shape_of(array));
  if(!array.dtype().is(py::dtype::of<double>()))
    throw py::value_error(std::string(argument) + " must have dtype float64, not " + std::string(py::str(array.dtype())));
  return Rows3{static_cast<char*>(const_cast<void*>(array.data())), array.shape(0), array.strides(0), array.strides(1)};
}

/// A new C-ordered (rows, 3) float64 array, and its view.
std::pair<py::array_t<double>, Rows3> new_rows3(std::size_t rows)
{
  py::array_t<double> array({py::ssize_t(rows), py::ssize_t(3)});
  const Rows3 view{reinterpret_cast<char*>(array.mutable_data()), array.shape(0), array.strides(0), array.strides(1)};
  return {std::move(array), view};
}

/// `object` when it is a writable (n, 3) float64 array (checked, ValueError naming `argument`), else a new one.
std::pair<py::object, Rows3> output_rows3(const py::object& object, const char* argument, std::size_t n)
{
  if(object.is_none()) {
    auto [array, view] = new_rows3(n);
    return {std::move(array), view};
  }
  const Rows3 view = rows3(object, argument);
  if(std::size_t(view.rows) != n)
    throw py::value_error(std::string(argument) + " must have " + std::to_string(n) + " rows, not " + std::to_string(view.rows));
  if(!py::reinterpret_borrow<py::array>(object).writeable()) throw py::value_error(std::string(argument) + " is not writable");
  return {object, view};
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

  friend Value get(const Rows3_map& m, std::size_t i) { return Value(m.rows.at(i, 0), m.rows.at(i, 1), m.rows.at(i, 2)); }
  friend void put(const Rows3_map& m, std::size_t i, const Value& v)
  {
    m.rows.at(i, 0) = v.x();
    m.rows.at(i, 1) = v.y();
    m.rows.at(i, 2) = v.z();
  }
};

/// Element i of a new 1-D array as a writable property map.
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

/// Indices given as a 1-D integer array or a sequence of integers, each checked against `n`.
std::vector<std::size_t> indices(const py::handle& object, std::size_t n, const char* argument)
{
  py::array array;
  try {
    array = py::array::ensure(object);
  } catch(const py::error_already_set&) {
  }
  if(!array || array.ndim() != 1 || !(array.dtype().kind() == 'i' || array.dtype().kind() == 'u' || array.size() == 0))
    throw py::value_error(std::string(argument) + " must be a 1-D array of integer indices");
  const auto values = py::array_t<long long, py::array::forcecast>::ensure(array);
  std::vector<std::size_t> out(std::size_t(values.size()));
  for(py::ssize_t m = 0; m < values.size(); ++m) {
    const long long v = values.at(m);
    if(v < 0 || std::size_t(v) >= n)
      throw py::value_error(std::string(argument) + ": index " + std::to_string(v) + " is not a point index (" +
                            std::to_string(n) + " points)");
    out[std::size_t(m)] = std::size_t(v);
  }
  return out;
}

Index_range all_points(std::size_t n) { return boost::counting_range(std::size_t(0), n); }

/// The named parameters of `points` and, unless None, `normals`, given to `body(n, np)`.
template <typename Body>
auto with_points(const py::handle& points, const py::handle& normals, Body&& body)
{
  const Rows3 p = rows3(points, "points");
  if(normals.is_none()) return body(std::size_t(p.rows), CGAL::parameters::point_map(Rows3_map<Point>{p}));
  const Rows3 n = rows3(normals, "normals");
  if(n.rows != p.rows)
    throw py::value_error("normals must have as many rows as points (" + std::to_string(p.rows) + "), not " +
                          std::to_string(n.rows));
  return body(std::size_t(p.rows), CGAL::parameters::point_map(Rows3_map<Point>{p}).normal_map(Rows3_map<Vector>{n}));
}

// ---- progress and cancellation ------------------------------------------------------------------------------

/// The library's progress callback for a Python caller: with the GIL taken back, it checks for Ctrl-C and calls
/// `progress(fraction)` when given; an exception from either cancels the run, and `raise_if_cancelled` raises
/// it once the library has returned.
class Python_progress
{
public:
  explicit Python_progress(py::object progress) : m_progress(std::move(progress)) {}

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

CGAL_ext::Detail_order order_named(const std::string& name)
{
  for(CGAL_ext::Detail_order order : {CGAL_ext::Detail_order::linear, CGAL_ext::Detail_order::quadric, CGAL_ext::Detail_order::cubic})
    if(name == CGAL_ext::Detail_filter::order_name(order)) return order;
  throw py::value_error("order must be \"linear\", \"quadric\" or \"cubic\", not \"" + name + "\"");
}

CGAL_ext::Detail_settings detail_settings(const std::string& order, double lam, double mu, const std::string& weights)
{
  CGAL_ext::Detail_settings s(CGAL_ext::Detail_filter{order_named(order), lam, mu});
  if(weights == "distance") s.weights.weighting = CGAL_ext::Laplacian_weighting::distance_power;
  else if(weights != "uniform") throw py::value_error("weights must be \"uniform\" or \"distance\", not \"" + weights + "\"");
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

// ---- functions ----------------------------------------------------------------------------------------------

py::tuple compute_geometric_details(const py::object& points, const py::object& normals, long long k,
                                    const std::string& order, double lam, double mu, const std::string& weights,
                                    const py::object& progress)
{
  const CGAL_ext::Detail_settings settings = detail_settings(order, lam, mu, weights);
  return with_points(points, normals, [&](std::size_t n, const auto& np) {
    auto [details, details_view] = new_rows3(n);
    py::array_t<double> magnitude(static_cast<py::ssize_t>(n));
    Python_progress reporter(progress);
    const Array_map<double> magnitude_map{magnitude.mutable_data()};
    const bool done = without_gil([&, details_view = details_view] {
      return CGAL_ext::compute_geometric_details(all_points(n), as_count(k, "k"), settings, Rows3_map<Vector>{details_view},
                                                 magnitude_map, np.callback(reporter.callback()));
    });
    reporter.raise_if_cancelled(done);
    return py::make_tuple(details, magnitude);
  });
}

/// Scaling and enhancement: the points moved, as a new array.
py::array_t<double> manipulate(bool enhance, const py::object& points, const py::object& roi, double s,
                               const py::object& normals, const py::object& anchors, long long k, const std::string& order,
                               double lam, double mu, const std::string& weights, const py::object& progress)
{
  CGAL_ext::Detail_enhancement_settings settings(detail_settings(order, lam, mu, weights));
  const Rows3 input = rows3(points, "points");
  const std::size_t n = std::size_t(input.rows);
  const std::vector<std::size_t> region = roi.is_none() ? std::vector<std::size_t>() : indices(roi, n, "roi");
  std::vector<char> anchored;
  if(!anchors.is_none()) {
    anchored.assign(n, 0);
    for(std::size_t a : indices(anchors, n, "anchors")) anchored[a] = 1;
  }
  // The result starts as a copy of the points: the library moves it in place.
  auto [moved, moved_view] = new_rows3(n);
  for(std::size_t i = 0; i < n; ++i)
    for(int c = 0; c < 3; ++c) moved_view.at(i, c) = input.at(i, c);
  Python_progress reporter(progress);
  const auto is_anchor = boost::make_function_property_map<std::size_t, bool>([&](std::size_t i) { return anchored[i] != 0; });
  const auto run = [&](const auto& np) {
    Index_range all = all_points(n);
    return without_gil([&] {
      const auto with_callback = np.callback(reporter.callback());
      if(enhance && anchored.empty())
        return roi.is_none() ? CGAL_ext::enhance_geometric_details(all, as_count(k, "k"), s, settings, with_callback)
                             : CGAL_ext::enhance_geometric_details(all, as_count(k, "k"), region, s, settings, with_callback);
      if(enhance)
        return roi.is_none()
                 ? CGAL_ext::enhance_geometric_details(all, as_count(k, "k"), s, settings, with_callback.point_is_constrained_map(is_anchor))
                 : CGAL_ext::enhance_geometric_details(all, as_count(k, "k"), region, s, settings,
                                                       with_callback.point_is_constrained_map(is_anchor));
      if(anchored.empty()) return CGAL_ext::scale_geometric_details(all, as_count(k, "k"), region, s, settings, with_callback);
      return CGAL_ext::scale_geometric_details(all, as_count(k, "k"), region, s, settings,
                                               with_callback.point_is_constrained_map(is_anchor));
    });
  };
  const Rows3_map<Point> moved_map{moved_view};
  CGAL_ext::Detail_manipulation_result result;
  if(normals.is_none()) {
    result = run(CGAL::parameters::point_map(moved_map));
  } else {
    const Rows3 given = rows3(normals, "normals");
    if(std::size_t(given.rows) != n)
      throw py::value_error("normals must have as many rows as points (" + std::to_string(n) + "), not " + std::to_string(given.rows));
    result = run(CGAL::parameters::point_map(moved_map).normal_map(Rows3_map<Vector>{given}));
  }
  reporter.raise_if_cancelled(result.completed);
  return moved;
}

py::array_t<double> estimate_mean_curvature(const py::object& points, const py::object& normals, long long k,
                                            const std::string& fitting, const py::object& progress)
{
  CGAL_ext::Curvature_fitting method;
  if(fitting == "closed_form") method = CGAL_ext::Curvature_fitting::closed_form;
  else if(fitting == "monge") method = CGAL_ext::Curvature_fitting::monge_jet_fitting;
  else throw py::value_error("fitting must be \"closed_form\" or \"monge\", not \"" + fitting + "\"");
  return with_points(points, normals, [&](std::size_t n, const auto& np) {
    py::array_t<double> curvature(static_cast<py::ssize_t>(n));
    Python_progress reporter(progress);
    const Array_map<double> curvature_map{curvature.mutable_data()};
    const bool done = without_gil([&] {
      return CGAL_ext::estimate_mean_curvature(all_points(n), as_count(k, "k"), method, curvature_map,
                                               np.callback(reporter.callback()));
    });
    reporter.raise_if_cancelled(done);
    return curvature;
  });
}

py::array_t<long long> compute_simplification_sample_points(const py::object& points, const py::object& normals,
                                                            long long target_count, const py::object& max_cluster_size,
                                                            double mode_threshold, long long k, const py::object& progress)
{
  CGAL_ext::Simplification_settings settings;
  if(target_count < 1) throw py::value_error("target_count must be at least 1");
  settings.target_count = std::size_t(target_count);
  if(!max_cluster_size.is_none()) {
    const long long size = max_cluster_size.cast<long long>();
    if(size < 1) throw py::value_error("max_cluster_size must be at least 1");
    settings.max_cluster_size = std::size_t(size);
  }
  settings.mode_spread_threshold = mode_threshold;
  settings.mean_shift_neighbors = as_count(k, "k");
  settings.validate();
  return with_points(points, normals, [&](std::size_t n, const auto& np) {
    std::vector<std::size_t> sample_of(n);
    Python_progress reporter(progress);
    const auto samples = without_gil([&] {
      return CGAL_ext::compute_simplification_sample_points(all_points(n), settings, Array_map<std::size_t>{sample_of.data()},
                                                            np.callback(reporter.callback()));
    });
    reporter.raise_if_cancelled(samples.completed);
    py::array_t<long long> labels(static_cast<py::ssize_t>(n));
    for(std::size_t i = 0; i < n; ++i) labels.mutable_at(py::ssize_t(i)) = (long long)sample_of[i];
    return labels;
  });
}

py::tuple upsample_point_set(const py::object& points, const py::object& normals, double spacing, double max_hole_size,
                             long long k, const py::object& roi, const py::object& progress)
{
  if(normals.is_none()) throw py::value_error("normals are required: hole detection and the new samples' surface come from them");
  CGAL_ext::Upsampling_settings settings;
  settings.detection.spacing = spacing;
  settings.detection.max_hole_size = max_hole_size;
  settings.neighbors = as_count(k, "k");
  settings.validate();
  return with_points(points, normals, [&](std::size_t n, const auto& np) {
    const std::vector<std::size_t> region = roi.is_none() ? std::vector<std::size_t>() : indices(roi, n, "roi");
    std::vector<std::pair<Point, Vector>> added;
    Python_progress reporter(progress);
    const auto result = without_gil([&] {
      return roi.is_none()
               ? CGAL_ext::upsample_point_set(all_points(n), settings, std::back_inserter(added), np.callback(reporter.callback()))
               : CGAL_ext::upsample_point_set(all_points(n), region, settings, std::back_inserter(added),
                                              np.callback(reporter.callback()));
    });
    reporter.raise_if_cancelled(result.completed);
    auto [new_points, points_view] = new_rows3(added.size());
    auto [new_normals, normals_view] = new_rows3(added.size());
    for(std::size_t m = 0; m < added.size(); ++m) {
      put(Rows3_map<Point>{points_view}, m, added[m].first);
      put(Rows3_map<Vector>{normals_view}, m, added[m].second);
    }
    return py::make_tuple(new_points, new_normals);
  });
}

// ---- editing ------------------------------------------------------------------------------------------------

/// `Detail_preserving_deformation` for Python: the points and normals are copied at construction.
class Deformation
{
public:
  Deformation(const py::object& points, const py::object& normals, const py::kwargs& options)
  {
    const CGAL_ext::Detail_preserving_deformation_settings settings = settings_from(options);
    // The object's progress callback forwards to the one `preprocess` sets (none at other times).
    with_points(points, normals, [&](std::size_t n, const auto& np) {
      const auto forward = [this](double fraction) { return !m_callback || m_callback(fraction); };
      m_deformation = without_gil([&] {
        return std::make_unique<CGAL_ext::Detail_preserving_deformation<>>(all_points(n), settings, np.callback(forward));
      });
      return 0;
    });
  }

  void insert_roi(const py::object& roi) { m_deformation->insert_roi_points(indices(roi, size(), "roi")); }

  std::size_t create_handle_group(const py::object& handle_points)
  {
    const std::vector<std::size_t> handle = indices(handle_points, size(), "indices");
    const std::size_t group = m_deformation->create_handle_group();
    m_deformation->insert_handle_points(group, handle);
    return group;
  }

  bool preprocess(const py::object& progress)
  {
    Python_progress reporter(progress);
    m_callback = reporter.callback();
    const bool done = without_gil([&] { return m_deformation->preprocess(); });
    m_callback = nullptr;
    reporter.raise_if_cancelled(done);
    return done;
  }

  void set_handle_transform(std::size_t group, const py::object& rotation, const py::object& translation)
  {
    const auto R = py::array_t<double, py::array::forcecast>::ensure(rotation);
    const auto t = py::array_t<double, py::array::forcecast>::ensure(translation);
    if(!R || R.ndim() != 2 || R.shape(0) != 3 || R.shape(1) != 3) throw py::value_error("rotation must be a (3, 3) array");
    if(!t || t.size() != 3) throw py::value_error("translation must be an array of 3 numbers");
    Eigen::Matrix3d rotation_matrix;
    for(int r = 0; r < 3; ++r)
      for(int c = 0; c < 3; ++c) rotation_matrix(r, c) = R.at(r, c);
    m_deformation->set_handle_transform(group, rotation_matrix, Eigen::Vector3d(t.data()[0], t.data()[1], t.data()[2]));
  }

  void deform()
  {
    const bool done = without_gil([&] { return m_deformation->deform(); });
    if(!done) throw std::runtime_error("cancelled");
  }

  /// Every point's and normal's deformed position, into `points_out` / `normals_out` when given (writable (n, 3)
  /// float64 arrays, reused from drag to drag), else into new arrays.
  py::tuple diffuse(const py::object& points_out, const py::object& normals_out)
  {
    return results([&] { m_deformation->diffuse(); }, points_out, normals_out);
  }

  /// restore_details(), then the points and normals as diffuse() gives them.
  py::tuple restore_details(const py::object& points_out, const py::object& normals_out)
  {
    return results([&] { m_deformation->restore_details(); }, points_out, normals_out);
  }

  /// Runs `step`, then copies every point's and normal's deformed position out.
  template <typename Step>
  py::tuple results(const Step& step, const py::object& points_out, const py::object& normals_out)
  {
    const std::size_t n = size();
    auto [points, points_view] = output_rows3(points_out, "points_out", n);
    auto [normals, normals_view] = output_rows3(normals_out, "normals_out", n);
    without_gil([&, points_view = points_view, normals_view = normals_view] {
      step();
      // Out of the object's spatial order into the caller's, in parallel.
      CGAL_ext::internal::for_range<CGAL::Parallel_if_available_tag>(0, n, [&](std::size_t i) {
        const Eigen::Vector3d p = m_deformation->deformed_point(i), v = m_deformation->deformed_normal(i);
        for(int c = 0; c < 3; ++c) {
          points_view.at(i, c) = p(c);
          normals_view.at(i, c) = v(c);
        }
      });
      return 0;
    });
    return py::make_tuple(points, normals);
  }

  py::dict statistics() const
  {
    const CGAL_ext::Detail_preserving_deformation_statistics& s = m_deformation->statistics();
    return py::dict("points"_a = s.points, "samples"_a = s.samples, "requested_samples"_a = s.requested_samples,
                    "roi_samples"_a = s.roi_samples, "handle_samples"_a = s.handle_samples,
                    "clustering_seconds"_a = s.clustering_seconds, "preprocess_seconds"_a = s.preprocess_seconds,
                    "deform_seconds"_a = s.deform_seconds, "diffuse_seconds"_a = s.diffuse_seconds,
                    "restore_seconds"_a = s.restore_seconds, "restore_iterations"_a = s.restore_iterations,
                    "restore_residual"_a = s.restore_residual,
                    "rigid_iterations"_a = s.rigid_iterations, "displacement_ratio"_a = s.displacement_ratio,
                    "factor_seconds"_a = s.least_squares.factor_seconds,
                    "relative_residual"_a = s.least_squares.relative_residual);
  }

  std::size_t size() const { return m_deformation->number_of_points(); }

private:
  static CGAL_ext::Detail_preserving_deformation_settings settings_from(const py::kwargs& options)
  {
    CGAL_ext::Detail_preserving_deformation_settings s;
    for(const auto& [key_handle, value] : options) {
      const std::string key = py::str(key_handle);
      if(key == "order") s.filter.order = order_named(value.cast<std::string>());
      else if(key == "lam") s.filter.lambda = value.cast<double>();
      else if(key == "mu") s.filter.mu = value.cast<double>();
      else if(key == "k") s.sample_neighbors = as_count(value.cast<long long>(), "k");
      else if(key == "handle_weight") s.handle_weight = value.cast<double>();
      else if(key == "rotations") {
        const std::string r = value.cast<std::string>();
        if(r == "none") s.rotations = CGAL_ext::Detail_rotation::none;
        else if(r == "propagate") s.rotations = CGAL_ext::Detail_rotation::propagated;
        else if(r == "arap") s.rotations = CGAL_ext::Detail_rotation::as_rigid_as_possible;
        else throw py::value_error("rotations must be \"none\", \"propagate\" or \"arap\", not \"" + r + "\"");
      } else if(key == "rigid_iterations") s.rigid_iterations = as_count(value.cast<long long>(), "rigid_iterations");
      else if(key == "rigid_rotation_smoothing") s.rigid_rotation_smoothing = value.cast<double>();
      else if(key == "rigid_rotation_smoothing_scale") {
        const std::string w = value.cast<std::string>();
        if(w == "edge_lengths") s.rigid_rotation_smoothing_scale = CGAL_ext::Rotation_smoothing_scale::edge_lengths;
        else if(w == "surface_area") s.rigid_rotation_smoothing_scale = CGAL_ext::Rotation_smoothing_scale::surface_area;
        else throw py::value_error("rigid_rotation_smoothing_scale must be \"edge_lengths\" or \"surface_area\", not \"" + w + "\"");
      }
      else if(key == "rigid_edge_weights") {
        const std::string w = value.cast<std::string>();
        if(w == "uniform") s.rigid_edge_weights = CGAL_ext::Rigid_edge_weights::uniform;
        else if(w == "cotangent") s.rigid_edge_weights = CGAL_ext::Rigid_edge_weights::cotangent;
        else throw py::value_error("rigid_edge_weights must be \"uniform\" or \"cotangent\", not \"" + w + "\"");
      }
      else if(key == "strength") {
        const std::string d = value.cast<std::string>();
        if(d == "euclidean") s.strength_distance = CGAL_ext::Strength_distance::euclidean;
        else if(d == "geodesic") s.strength_distance = CGAL_ext::Strength_distance::geodesic;
        else throw py::value_error("strength must be \"euclidean\" or \"geodesic\", not \"" + d + "\"");
      } else if(key == "target_count") s.simplification.target_count = as_count(value.cast<long long>(), "target_count");
      else if(key == "max_cluster_size") s.simplification.max_cluster_size = as_count(value.cast<long long>(), "max_cluster_size");
      else if(key == "diffusion_samples") s.diffusion_samples = as_count(value.cast<long long>(), "diffusion_samples");
      else if(key == "detail_iterations") s.detail_iterations = as_count(value.cast<long long>(), "detail_iterations");
      else if(key == "detail_tolerance") s.detail_tolerance = value.cast<double>();
      else if(key == "detail_anchor") s.detail_anchor = value.cast<double>();
      else if(key == "diffusion_origin") {
        const std::string o = value.cast<std::string>();
        if(o == "own") s.diffusion_origin = CGAL_ext::Diffusion_origin::own_sample;
        else if(o == "nearest") s.diffusion_origin = CGAL_ext::Diffusion_origin::nearest_sample;
        else throw py::value_error("diffusion_origin must be \"own\" or \"nearest\", not \"" + o + "\"");
      } else if(key == "diffusion_turn") {
        const std::string t = value.cast<std::string>();
        if(t == "affine") s.diffusion_turn = CGAL_ext::Sample_turn::affine;
        else if(t == "fitted") s.diffusion_turn = CGAL_ext::Sample_turn::fitted;
        else if(t == "frames") s.diffusion_turn = CGAL_ext::Sample_turn::frames;
        else throw py::value_error("diffusion_turn must be \"affine\", \"fitted\" or \"frames\", not \"" + t + "\"");
      }
      else throw py::value_error("unknown setting '" + key + "' (see help(cgal_ext.Deformation))");
    }
    s.validate();
    return s;
  }

  std::unique_ptr<CGAL_ext::Detail_preserving_deformation<>> m_deformation;
  std::function<bool(double)> m_callback;
};

} // namespace

PYBIND11_MODULE(cgal_ext, m)
{
  m.doc() = "High-frequency geometric details of point-sampled surfaces (Miao et al. 2007) on numpy arrays";
  // The library's exceptions: Invalid_input is a std::invalid_argument (ValueError), Numerical_failure a
  // std::runtime_error (RuntimeError); pybind11 translates both with their messages.

  m.def("compute_geometric_details", &compute_geometric_details, "points"_a, "normals"_a = py::none(),
        "k"_a = CGAL_ext::default_laplacian_neighbors, "order"_a = "quadric", "lam"_a = 0.8, "mu"_a = 1.6,
        "weights"_a = "uniform", "progress"_a = py::none(),
        "The detail vector delta = f(K) p of every point and its oriented magnitude: (details (n, 3), magnitude (n,)).");
  m.def("scale_geometric_details",
        [](const py::object& points, const py::object& roi, double s, const py::object& normals, const py::object& anchors,
           long long k, const std::string& order, double lam, double mu, const std::string& weights, const py::object& progress) {
          return manipulate(false, points, roi, s, normals, anchors, k, order, lam, mu, weights, progress);
        },
        "points"_a, "roi"_a, "s"_a, "normals"_a = py::none(), "anchors"_a = py::none(),
        "k"_a = CGAL_ext::default_laplacian_neighbors, "order"_a = "quadric", "lam"_a = 0.8, "mu"_a = 1.6,
        "weights"_a = "uniform", "progress"_a = py::none(),
        "The points with the details of the region `roi` (indices) scaled by s: a new (n, 3) array.");
  m.def("enhance_geometric_details",
        [](const py::object& points, double s, const py::object& roi, const py::object& normals, const py::object& anchors,
           long long k, const std::string& order, double lam, double mu, const std::string& weights, const py::object& progress) {
          return manipulate(true, points, roi, s, normals, anchors, k, order, lam, mu, weights, progress);
        },
        "points"_a, "s"_a, "roi"_a = py::none(), "normals"_a = py::none(), "anchors"_a = py::none(),
        "k"_a = CGAL_ext::default_laplacian_neighbors, "order"_a = "quadric", "lam"_a = 0.8, "mu"_a = 1.6,
        "weights"_a = "uniform", "progress"_a = py::none(),
        "The points with their details against the balanced-flow base surface enhanced by s (all of them, or the "
        "region `roi`): a new (n, 3) array.");
  m.def("estimate_mean_curvature", &estimate_mean_curvature, "points"_a, "normals"_a = py::none(),
        "k"_a = CGAL_ext::default_curvature_neighbors, "fitting"_a = "closed_form", "progress"_a = py::none(),
        "The signed mean curvature of every point (positive where the surface bends away from its normal): (n,).");
  m.def("compute_simplification_sample_points", &compute_simplification_sample_points, "points"_a,
        "normals"_a = py::none(), "target_count"_a = 4000, "max_cluster_size"_a = py::none(), "mode_threshold"_a = 1.0,
        "k"_a = CGAL_ext::default_mean_shift_neighbors, "progress"_a = py::none(),
        "The simplification sample point of every point: labels (n,), int64.");
  m.def("upsample_point_set", &upsample_point_set, "points"_a, "normals"_a, "spacing"_a = 0.0, "max_hole_size"_a = 6.0,
        "k"_a = 12, "roi"_a = py::none(), "progress"_a = py::none(),
        "The new samples that fill the holes of an oriented point set: (points (m, 3), normals (m, 3)).");

  py::class_<Deformation>(m, "Deformation",
                          "Detail-preserving editing (Miao et al. 2007, Sect. 6). Settings: order, lam, mu, k, "
                          "handle_weight, rotations ('propagate', 'arap', 'none'), rigid_iterations, rigid_rotation_smoothing, "
                          "rigid_rotation_smoothing_scale ('edge_lengths', 'surface_area'), "
                          "rigid_edge_weights ('uniform', 'cotangent'), strength "
                          "('euclidean', 'geodesic'), target_count, max_cluster_size, diffusion_samples, detail_iterations, "
                          "detail_tolerance, detail_anchor, diffusion_origin "
                          "('own', 'nearest'), diffusion_turn ('affine', 'fitted', 'frames').")
    .def(py::init<const py::object&, const py::object&, const py::kwargs&>(), "points"_a, "normals"_a = py::none())
    .def("insert_roi", &Deformation::insert_roi, "indices"_a)
    .def("create_handle_group", &Deformation::create_handle_group, "indices"_a)
    .def("preprocess", &Deformation::preprocess, "progress"_a = py::none())
    .def("set_handle_transform", &Deformation::set_handle_transform, "group"_a, "rotation"_a, "translation"_a)
    .def("deform", &Deformation::deform)
    .def("diffuse", &Deformation::diffuse, "points_out"_a = py::none(), "normals_out"_a = py::none(),
         "The deformed points and normals (n, 3), written into points_out / normals_out when given.")
    .def("restore_details", &Deformation::restore_details, "points_out"_a = py::none(), "normals_out"_a = py::none(),
         "After diffuse(): puts back the fine details the diffusion smoothed (conjugate gradients, at most "
         "detail_iterations; call it once a drag ends), then returns the points and normals as diffuse() does.")
    .def("statistics", &Deformation::statistics)
    .def("__len__", &Deformation::size);
}
