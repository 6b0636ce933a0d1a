// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// The functions: details, scaling and enhancement, curvature, normals, sample points, up-sampling; files, pictures and threads.
// A part of cgal_ext_module.cpp, the package's one translation unit, which includes its parts in order.
#ifndef CGAL_EXT_PYTHON_FUNCTIONS_H
#define CGAL_EXT_PYTHON_FUNCTIONS_H

namespace {

// ---- functions ----------------------------------------------------------------------------------------------

Details_result bound_compute_geometric_details(const Array_like& points, const Optional_array_like& normals,
                                               long long k, const std::string& order, double lam, double mu,
                                               const std::string& weights, const Optional_progress& progress,
                                               const py::object& neighbor_radius)
{
  const Detail_settings settings = detail_settings(order, lam, mu, weights);
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  double* const radius = output_values(neighbor_radius, "neighbor_radius", n);
  auto [details, details_view] = new_rows3(n);
  py::array_t<double> magnitude(static_cast<py::ssize_t>(n));
  Python_progress reporter(progress);
  const Array_map<double> magnitude_map{magnitude.mutable_data()};
  const Rows3_map<Vector> detail_map{details_view};
  const unsigned int neighbors = as_count(k, "k");
  const bool done = with_maps(input, [&](const auto& np) {
    return without_gil([&] {
      const auto with_callback = np.callback(reporter.callback());
      if(radius)
        return CGAL_ext::compute_geometric_details(
          all_points(n), neighbors, settings, detail_map, magnitude_map,
          CGAL_ext::parameters::neighbor_radius_map(Array_map<double>{radius}, with_callback));
      return CGAL_ext::compute_geometric_details(all_points(n), neighbors, settings, detail_map, magnitude_map,
                                                 with_callback);
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
  settings.target_count = as_size(target_count, "target_count");
  if(!max_cluster_size.is_none())
    settings.max_cluster_size = as_size(max_cluster_size.cast<long long>(), "max_cluster_size");
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
                                          const Optional_array_like& spacing_before, const Optional_progress& progress)
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
  if(!spacing_before.is_none() && roi.is_none())
    throw py::value_error("spacing_before needs roi: the points whose spacing before an edit it gives");
  std::vector<double> before =
    spacing_before.is_none() ? std::vector<double>() : values_of(spacing_before, n, "spacing_before");
  std::vector<std::pair<Point, Vector>> added;
  Python_progress reporter(progress);
  const auto result = with_maps(input, [&](const auto& np) {
    return without_gil([&] {
      const auto with_callback = np.callback(reporter.callback());
      if(roi.is_none())
        return CGAL_ext::upsample_point_set(all_points(n), settings, std::back_inserter(added), with_callback);
      if(before.empty())
        return CGAL_ext::upsample_point_set(all_points(n), region, settings, std::back_inserter(added), with_callback);
      return CGAL_ext::upsample_point_set(all_points(n), region, Array_map<double>{before.data()}, settings,
                                          std::back_inserter(added), with_callback);
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

py::tuple bound_compute_neighbor_graph(const Array_like& points, long long k, bool symmetric,
                                       const Optional_progress& progress)
{
  const Point_input input(points, py::none());
  const std::size_t n = input.size();
  Python_progress reporter(progress);
  CGAL_ext::Neighbor_lists lists = with_maps(input, [&](const auto& np) {
    return without_gil([&] {
      return CGAL_ext::compute_neighbor_graph(all_points(n), as_count(k, "k"), np.callback(reporter.callback()));
    });
  });
  reporter.raise_if_cancelled(lists.offsets.size() == n + 1);
  if(symmetric) {
    without_gil([&] {
      CGAL_ext::internal::Neighbor_graph directed;
      directed.offsets.assign(lists.offsets.begin(), lists.offsets.end());
      directed.indices.assign(lists.neighbors.begin(), lists.neighbors.end());
      const CGAL_ext::internal::Neighbor_graph both =
        CGAL_ext::internal::symmetrize<CGAL::Parallel_if_available_tag>(directed);
      lists.offsets.assign(both.offsets.begin(), both.offsets.end());
      lists.neighbors.assign(both.indices.begin(), both.indices.end());
      return 0;
    });
  }
  py::array_t<std::int64_t> offsets(static_cast<py::ssize_t>(lists.offsets.size()));
  py::array_t<std::int64_t> neighbors(static_cast<py::ssize_t>(lists.neighbors.size()));
  std::copy(lists.offsets.begin(), lists.offsets.end(), offsets.mutable_data());
  std::copy(lists.neighbors.begin(), lists.neighbors.end(), neighbors.mutable_data());
  return py::make_tuple(offsets, neighbors);
}

py::array_t<double> bound_compute_local_spacing(const Array_like& points)
{
  const Point_input input(points, py::none());
  const std::size_t n = input.size();
  py::array_t<double> spacing(static_cast<py::ssize_t>(n));
  const Array_map<double> spacing_map{spacing.mutable_data()};
  with_maps(input, [&](const auto& np) {
    return without_gil([&] { return CGAL_ext::compute_local_spacing(all_points(n), spacing_map, np); });
  });
  return spacing;
}

Ndarray bound_refit_normals(const Array_like& points, const Array_like& normals, const Array_like& moved, long long k)
{
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  const std::vector<std::size_t> refit = indices(moved, n, "moved");
  auto [out, out_rows] = new_rows3(n);
  for(std::size_t i = 0; i < n; ++i)
    for(int c = 0; c < 3; ++c) out_rows.at(i, c) = input.normal_rows.at(i, c);
  const unsigned int neighbors = as_count(k, "k");
  if(!refit.empty())
    without_gil([&, out_rows = out_rows] {
      return CGAL_ext::refit_normals(
        all_points(n), refit, neighbors,
        CGAL::parameters::point_map(Rows3_map<Point>{input.point_rows}).normal_map(Rows3_map<Vector>{out_rows}));
    });
  return out;
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

/// The record layout of a binary PCD or LAS file (point_detail::record_layout) as a dict, for the tiled runs'
/// readers.
py::dict record_layout(const Path_like& path_object)
{
  const fs::path path = path_of(path_object, "path");
  const point_detail::Record_layout layout =
    translating_program_errors([&] { return point_detail::record_layout(path); });
  py::list fields;
  for(const auto& f : layout.fields)
    fields.append(py::make_tuple(f.name, f.offset, std::string(1, f.kind) + std::to_string(f.bytes)));
  py::dict out;
  out["points"] = layout.points;
  out["data_offset"] = layout.data_offset;
  out["record_bytes"] = layout.record_bytes;
  out["fields"] = fields;
  out["coordinates"] = py::make_tuple(layout.coordinates[0], layout.coordinates[1], layout.coordinates[2]);
  out["normals"] = layout.normals[0].empty()
                     ? py::object(py::none())
                     : py::object(py::make_tuple(layout.normals[0], layout.normals[1], layout.normals[2]));
  out["scale"] = py::make_tuple(layout.scale[0], layout.scale[1], layout.scale[2]);
  out["shift"] = py::make_tuple(layout.shift[0], layout.shift[1], layout.shift[2]);
  return out;
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
                  const Array_like& values, const char* argument = "values")
{
  const py::array array = as_array(values, argument, "a 1-D array of numbers");
  const std::vector<double> v = values_of(array, std::size_t(array.ndim() == 1 ? array.size() : 0), argument);
  const point_detail::Coloring coloring = color_map(v);
  py::array_t<std::uint8_t> colors({py::ssize_t(v.size()), py::ssize_t(3)});
  std::memcpy(colors.mutable_data(), coloring.colors.data(), v.size() * 3);
  return colors;
}

/// The program's cluster colours (simplify --clusters) of integer labels.
Ndarray label_colors(const Array_like& labels)
{
  return colors_by(
    [](const std::vector<double>& v) {
      std::vector<std::size_t> integers(v.size());
      for(std::size_t i = 0; i < v.size(); ++i) {
        if(!(v[i] >= 0 && v[i] <= 9007199254740992.0 && v[i] == std::floor(v[i])))
          throw py::value_error("labels must be integers >= 0; label #" + std::to_string(i) + " is " +
                                std::to_string(v[i]));
        integers[i] = std::size_t(v[i]);
      }
      return point_detail::label_colors(integers);
    },
    labels, "labels");
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

} // namespace

#endif // CGAL_EXT_PYTHON_FUNCTIONS_H
