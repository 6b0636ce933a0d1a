// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// The editing class Deformation over Detail_preserving_deformation.
// A part of cgal_ext_module.cpp, the package's one translation unit, which includes its parts in order.
#ifndef CGAL_EXT_PYTHON_EDITING_H
#define CGAL_EXT_PYTHON_EDITING_H

namespace {

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
    return results([&] { m_deformation->diffuse(); }, points_out, normals_out, true);
  }

  Deformed_result restore_details(const Optional_array_like& points_out, const Optional_array_like& normals_out)
  {
    return results(
      [&] {
        // It works on the library's own result of the diffusion, which the last diffuse() may have left elsewhere.
        if(m_diffused_in_place) m_deformation->diffuse();
        m_deformation->restore_details();
      },
      points_out, normals_out);
  }

  void reset()
  {
    m_deformation->reset();
    m_diffused_in_place = false;
  }

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

  /// What a renderer that moves the points itself needs once per preprocessing (Diffusion_view), in input order.
  py::dict renderer_setup() const
  {
    if(!m_deformation->is_preprocessed()) throw py::value_error("renderer_setup() needs preprocess() first");
    const Diffusion_view d = m_deformation->diffusion_view();
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
                    "sample_points"_a = m_deformation->number_of_sample_points());
  }

  /// Per drag, after deform(): the sample points' motions (3x4 each, row-major), the handle groups' transforms
  /// (3x4 each) and the collar handle points' steps (position, then normal), as one float32 array.
  py::array_t<float> renderer_frame()
  {
    Detail_preserving_deformation<>& d = *m_deformation;
    if(!d.is_preprocessed()) throw py::value_error("renderer_frame() needs deform() first");
    const Diffusion_view view = d.diffusion_view();
    const std::size_t samples = d.number_of_sample_points(), groups = d.number_of_handle_groups(),
                      collar = view.collar_handle_points().size();
    py::array_t<float> frame(py::ssize_t(12 * (samples + groups) + 6 * collar));
    without_gil([&, out = frame.mutable_data()] {
      d.update_sample_motions();
      for(std::size_t s = 0; s < samples; ++s) {
        const Eigen::Matrix4d record = view.sample_motion(s);
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
        view.collar_handle_step(c, step, normal_step);
        for(int r = 0; r < 3; ++r) collar_out[6 * c + r] = float(step(r)), collar_out[6 * c + 3 + r] = float(normal_step(r));
      });
      return 0;
    });
    return frame;
  }

  /// After deform(): the sample points' side of the drag (Diffusion_view::state()), for diffuse_points() here or
  /// in another process.
  py::dict diffusion_state()
  {
    Detail_preserving_deformation<>& d = *m_deformation;
    if(!d.is_preprocessed()) throw py::value_error("diffusion_state() needs deform() first");
    Diffusion_state state;
    without_gil([&] {
      d.update_sample_motions();
      state = d.diffusion_view().state();
      return 0;
    });
    const py::ssize_t s = py::ssize_t(state.number_of_sample_points());
    py::array_t<double> positions({s, py::ssize_t(3)}), deformed({s, py::ssize_t(3)}),
      motions({s, py::ssize_t(3), py::ssize_t(4)});
    std::copy(state.sample_positions.begin(), state.sample_positions.end(), positions.mutable_data());
    std::copy(state.deformed_sample_positions.begin(), state.deformed_sample_positions.end(), deformed.mutable_data());
    std::copy(state.motions.begin(), state.motions.end(), motions.mutable_data());
    py::array_t<double> transforms({py::ssize_t(state.number_of_handle_groups()), py::ssize_t(7)});
    std::copy(state.handle_transforms.begin(), state.handle_transforms.end(), transforms.mutable_data());
    return py::dict("sample_positions"_a = positions, "deformed_sample_positions"_a = deformed, "motions"_a = motions,
                    "region_samples"_a = py::array_t<std::uint8_t>(s, state.region_samples.data()),
                    "handle_transforms"_a = transforms, "stencil_size"_a = state.stencil_size,
                    "origin"_a = setting_name(state.origin), "portable"_a = state.portable,
                    "exact_handles"_a = state.exact_handles, "collar_reach"_a = state.collar_reach,
                    "detail_anchor"_a = state.detail_anchor, "detail_iterations"_a = state.detail_iterations,
                    "detail_tolerance"_a = state.detail_tolerance,
                    "detail_steps"_a = CGAL_ext::internal::Detail_relaxation::steps(
                      state.detail_anchor, state.detail_iterations, state.detail_tolerance));
  }

  py::dict statistics() const
  {
    const Detail_preserving_deformation_statistics& s = m_deformation->statistics();
    return py::dict(
      "points"_a = s.points, "samples"_a = s.samples, "requested_samples"_a = s.requested_samples,
      "roi_samples"_a = s.roi_samples, "handle_samples"_a = s.handle_samples,
      "clustering_seconds"_a = s.clustering_seconds, "preprocess_seconds"_a = s.preprocess_seconds,
      "deform_seconds"_a = s.deform_seconds, "diffuse_seconds"_a = s.diffuse_seconds,
      "diffuse_bytes"_a = s.diffuse_bytes, "restore_seconds"_a = s.restore_seconds,
      "restore_iterations"_a = s.restore_iterations, "restore_residual"_a = s.restore_residual,
      "rigid_iterations"_a = s.rigid_iterations, "displacement_ratio"_a = s.displacement_ratio,
      "factor_seconds"_a = s.least_squares.factor_seconds, "operator_nonzeros"_a = s.least_squares.operator_nonzeros,
      "normal_nonzeros"_a = s.least_squares.normal_nonzeros, "solve_seconds"_a = s.least_squares.solve_seconds,
      "solve_iterations"_a = s.least_squares.iterations, "relative_residual"_a = s.least_squares.relative_residual);
  }

  py::dict settings() const { return deformation_settings_dict(m_deformation->settings()); }

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
    const auto values = py::array_t<double, py::array::forcecast | py::array::c_style | aligned_copy>::ensure(array);
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
  /// edit can move (Detail_preserving_deformation::for_each_deformed_point). A diffusion (`is_diffusion`) into
  /// such arrays, when they are C-contiguous, writes them in place instead, walking the points in the caller's
  /// order (Detail_preserving_deformation::diffuse_in_input_order): the same results, without their copy.
  template <typename Step>
  Deformed_result results(const Step& step, const Optional_array_like& points_out,
                          const Optional_array_like& normals_out, bool is_diffusion = false)
  {
    const std::size_t n = size();
    auto [points, point_view] = output_rows3(points_out, "points_out", n);
    auto [normals, normal_view] = output_rows3(normals_out, "normals_out", n);
    // The same array objects (held here, so their memory cannot pass to other arrays meanwhile).
    const bool movable_only = m_deformation->is_preprocessed() && !points_out.is_none() && !normals_out.is_none() &&
                              points_out.is(m_written_points) && normals_out.is(m_written_normals);
    const bool in_place = is_diffusion && movable_only && is_c_contiguous(point_view) && is_c_contiguous(normal_view);
    without_gil([&, point_view = point_view, normal_view = normal_view] {
      if(in_place) {
        m_deformation->diffuse_in_input_order(&point_view.at(0, 0), &normal_view.at(0, 0));
        return 0;
      }
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
    m_diffused_in_place = in_place;
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
    m_diffused_in_place = false;
  }
  py::object m_written_points, m_written_normals;
  bool m_diffused_in_place = false; // the last diffuse() wrote the caller's arrays in place, not the library's

  std::unique_ptr<Detail_preserving_deformation<>> m_deformation;
  std::function<bool(double)> m_callback;
};

/// The program's reading of an edit JSON (`point-detail edit --edit FILE`) with its selections evaluated on
/// `points`: the region's and each handle group's point indices, the groups' transforms and the settings under
/// Deformation's keywords. The tiled edit reads its file so, on the subsample its client deforms.
py::dict read_edit(const Path_like& path_object, const Array_like& points)
{
  const fs::path path = path_of(path_object, "path");
  const Point_input input(points, py::none());
  std::vector<point_detail::Point> copy;
  copy.reserve(input.size());
  for(std::size_t i = 0; i < input.size(); ++i)
    copy.emplace_back(input.point_rows.at(i, 0), input.point_rows.at(i, 1), input.point_rows.at(i, 2));
  const point_detail::Edit_description edit =
    translating_program_errors([&] { return point_detail::read_edit_json(path, copy); });
  const auto as_array = [](const std::vector<std::size_t>& indices) {
    py::array_t<std::int64_t> out(py::ssize_t(indices.size()));
    std::copy(indices.begin(), indices.end(), out.mutable_data());
    return out;
  };
  py::list handles;
  for(const point_detail::Handle_edit& h : edit.handles) {
    py::array_t<double> rotation({py::ssize_t(3), py::ssize_t(3)}), translation(py::ssize_t(3));
    for(int r = 0; r < 3; ++r) {
      translation.mutable_data()[r] = h.translation(r);
      for(int c = 0; c < 3; ++c) rotation.mutable_data()[3 * r + c] = h.rotation(r, c);
    }
    handles.append(py::dict("points"_a = as_array(h.points), "rotation"_a = rotation, "translation"_a = translation));
  }
  return py::dict("roi"_a = as_array(edit.roi), "handles"_a = handles,
                  "settings"_a = deformation_settings_dict(edit.settings));
}

/// diffuse_points() with a Deformation.diffusion_state() dict: the moved points and normals, new arrays.
Deformed_result bound_diffuse_points(const Array_like& points, const Array_like& normals, const py::dict& state,
                                     const Optional_array_like& selection, bool restore_details,
                                     const py::object& neighbor_radius)
{
  const auto entry = [&](const char* key) -> py::object {
    if(!state.contains(key)) throw py::value_error(std::string("the diffusion state has no '") + key + "'");
    return state[key];
  };
  // The array `key` of shape (any, tail...), as doubles.
  const auto values = [&](const char* key, std::vector<py::ssize_t> tail) {
    const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(entry(key));
    bool shaped = array && array.ndim() == py::ssize_t(1 + tail.size());
    for(std::size_t d = 0; shaped && d < tail.size(); ++d) shaped = array.shape(py::ssize_t(1 + d)) == tail[d];
    if(!shaped) {
      std::string shape = "(s";
      for(py::ssize_t d : tail) shape += ", " + std::to_string(d);
      throw py::value_error(std::string("the diffusion state's '") + key + "' must be a float array of shape " + shape +
                            ")");
    }
    return std::vector<double>(array.data(), array.data() + array.size());
  };
  Diffusion_state parsed;
  parsed.sample_positions = values("sample_positions", {3});
  parsed.deformed_sample_positions = values("deformed_sample_positions", {3});
  parsed.motions = values("motions", {3, 4});
  for(double flag : values("region_samples", {})) parsed.region_samples.push_back(flag != 0 ? 1 : 0);
  parsed.handle_transforms = values("handle_transforms", {7});
  parsed.stencil_size = as_count(entry("stencil_size").cast<long long>(), "stencil_size");
  parsed.origin = parse_setting<Diffusion_origin>(entry("origin").cast<std::string>(), "origin");
  parsed.portable = entry("portable").cast<bool>();
  parsed.exact_handles = entry("exact_handles").cast<bool>();
  parsed.collar_reach = entry("collar_reach").cast<double>();
  parsed.detail_anchor = entry("detail_anchor").cast<double>();
  parsed.detail_iterations = unsigned(as_count(entry("detail_iterations").cast<long long>(), "detail_iterations"));
  parsed.detail_tolerance = entry("detail_tolerance").cast<double>();
  const Point_input input(points, normals);
  const std::size_t n = input.size();
  std::vector<int> selected;
  if(!selection.is_none()) {
    const auto array = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(selection);
    if(!array || array.ndim() != 1 || std::size_t(array.shape(0)) != n)
      throw py::value_error("selection must be an integer array of shape (" + std::to_string(n) + ",)");
    const long long groups = (long long)parsed.number_of_handle_groups();
    for(py::ssize_t i = 0; i < array.shape(0); ++i) {
      const long long value = array.data()[i];
      if(value < Diffusion_state::fixed || value >= groups)
        throw py::value_error("selection of point " + std::to_string(i) + " is " + std::to_string(value) +
                              ": -2 (fixed), -1 (region) or a handle group (" + std::to_string(groups) +
                              " in the state)");
      selected.push_back(int(value));
    }
  }
  double* const radius = output_values(neighbor_radius, "neighbor_radius", n);
  auto [moved, moved_rows] = new_rows3(n);
  auto [moved_normals, moved_normal_rows] = new_rows3(n);
  for(std::size_t i = 0; i < n; ++i)
    for(int c = 0; c < 3; ++c) {
      moved_rows.at(i, c) = input.point_rows.at(i, c);
      moved_normal_rows.at(i, c) = input.normal_rows.at(i, c);
    }
  without_gil([&, moved_rows = moved_rows, moved_normal_rows = moved_normal_rows] {
    Index_range all = all_points(n);
    const auto np = CGAL_ext::parameters::restore_details(
      restore_details,
      CGAL::parameters::point_map(Rows3_map<Point>{moved_rows}).normal_map(Rows3_map<Vector>{moved_normal_rows}));
    // The selection map and the radius map, each when given.
    const auto with_selection = [&](const auto& with) {
      if(selection.is_none())
        CGAL_ext::diffuse_points(all, parsed, with);
      else
        CGAL_ext::diffuse_points(all, parsed,
                                 CGAL_ext::parameters::selection_map(Array_map<int>{selected.data()}, with));
    };
    if(radius)
      with_selection(CGAL_ext::parameters::neighbor_radius_map(Array_map<double>{radius}, np));
    else
      with_selection(np);
    return 0;
  });
  return py::reinterpret_borrow<py::object>(result_types.deformed)(moved, moved_normals);
}

} // namespace

#endif // CGAL_EXT_PYTHON_EDITING_H
