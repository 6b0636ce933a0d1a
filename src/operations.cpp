// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "operations.h"

#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/detect_sparse_directions.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/refit_normals.h>
#include <CGAL_ext/scale_geometric_details.h>
#include <CGAL_ext/upsample_point_set.h>

#include <boost/property_map/function_property_map.hpp>

#include <cmath>

namespace point_detail {

Coloring add_details(Point_cloud& cloud, const Detail_options& options, Progress_printer& progress, Report& report)
{
  const std::size_t n = cloud.points.size();
  std::vector<Vector> details(n);
  std::vector<double> magnitude(n);
  const auto settings = options.settings();
  const bool done = report.time("details", [&] {
    return CGAL_ext::compute_geometric_details(
      index_range(n), options.k, settings, CGAL::make_property_map(details), CGAL::make_property_map(magnitude),
      CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
        .normal_map(CGAL::make_property_map(cloud.normals))
        .callback(progress.stage("details")));
  });
  progress.finish();
  if(!done) throw Cancelled();
  std::vector<double> dx(n), dy(n), dz(n), along_normal(n);
  for(std::size_t i = 0; i < n; ++i) {
    dx[i] = details[i].x();
    dy[i] = details[i].y();
    dz[i] = details[i].z();
    along_normal[i] = details[i] * cloud.normals[i] / std::sqrt(cloud.normals[i].squared_length());
  }
  cloud.set_scalar("detail_x", std::move(dx));
  cloud.set_scalar("detail_y", std::move(dy));
  cloud.set_scalar("detail_z", std::move(dz));
  cloud.set_scalar("detail_magnitude", std::move(magnitude));
  cloud.set_scalar("detail_normal", std::move(along_normal));
  Coloring coloring = diverging_colors(*cloud.scalar(options.color_by));
  coloring.quantity = quantity_of(options.color_by);
  cloud.colors = coloring.colors;
  auto& r = report.data();
  r["points"] = n;
  r["k"] = options.k;
  r["order"] = CGAL_ext::setting_name(settings.filter.order);
  r["lambda"] = settings.filter.lambda;
  if(settings.filter.order != CGAL_ext::Detail_order::linear) r["mu"] = settings.filter.mu;
  r["weights"] = CGAL_ext::setting_name(settings.weights.weighting);
  r["neighbors"] = CGAL_ext::setting_name(settings.neighborhood);
  r["color_by"] = options.color_by;
  r["color_range"] = coloring.hi;
  return coloring;
}

std::string render_on_base_surface(const Point_cloud& cloud, const Coloring& coloring, unsigned int k,
                                   const Render_settings& render, Report& report)
{
  std::vector<Point> base = cloud.points;
  std::vector<std::size_t> indices = index_range(base.size());
  report.time("base_surface", [&] {
    CGAL_ext::balanced_flow_smooth_point_set(indices, k, CGAL_ext::Balanced_flow_settings(),
                                             CGAL::parameters::point_map(CGAL::make_property_map(base))
                                               .normal_map(CGAL::make_property_map(cloud.normals)));
  });
  return report.time("render", [&] { return render_png(base, cloud.normals, coloring, render); });
}

CGAL_ext::Detail_manipulation_result manipulate(bool enhance, const Point_cloud& cloud, const std::vector<std::size_t>& region,
                                                const std::vector<std::size_t>* anchors, double factor, unsigned int k,
                                                const CGAL_ext::Detail_enhancement_settings& settings,
                                                const std::function<bool(double)>& callback, Point_cloud& out)
{
  std::vector<Point> moved = cloud.points;
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(moved))
                    .normal_map(CGAL::make_property_map(cloud.normals))
                    .callback(callback);
  std::vector<std::size_t> all = index_range(moved.size());
  CGAL_ext::Detail_manipulation_result result;
  if(enhance && anchors) {
    std::vector<char> anchored(moved.size(), 0);
    for(std::size_t a : *anchors) anchored[a] = 1;
    const auto is_anchor = boost::make_function_property_map<std::size_t, bool>([&](std::size_t i) { return anchored[i] != 0; });
    result = CGAL_ext::enhance_geometric_details(all, k, region, factor, settings, np.point_is_constrained_map(is_anchor));
  } else if(enhance) {
    result = CGAL_ext::enhance_geometric_details(all, k, region, factor, settings, np);
  } else if(anchors) {
    result = CGAL_ext::scale_geometric_details(all, k, region, *anchors, factor, settings, np);
  } else {
    result = CGAL_ext::scale_geometric_details(all, k, region, factor, settings, np);
  }
  if(!result) return result;
  std::vector<double> displacement(moved.size()), in_roi(moved.size(), 0.0);
  for(std::size_t i = 0; i < moved.size(); ++i) displacement[i] = (moved[i] - cloud.points[i]) * cloud.normals[i];
  for(std::size_t i : region) in_roi[i] = 1.0;
  out = Point_cloud();
  out.points = std::move(moved);
  out.normals = cloud.normals;
  std::vector<std::size_t> displaced;
  for(std::size_t i = 0; i < out.points.size(); ++i)
    if(out.points[i] != cloud.points[i]) displaced.push_back(i);
  if(!displaced.empty())
    CGAL_ext::refit_normals(index_range(out.points.size()), displaced,
                            std::min<unsigned int>(CGAL_ext::default_normal_neighbors, unsigned(out.points.size() - 1)),
                            CGAL::parameters::point_map(CGAL::make_property_map(out.points))
                              .normal_map(CGAL::make_property_map(out.normals)));
  out.set_scalar("displacement", std::move(displacement));
  out.set_scalar("in_roi", std::move(in_roi));
  return result;
}

std::vector<double> local_spacing(const Point_cloud& cloud)
{
  std::vector<double> spacing(cloud.points.size());
  CGAL_ext::compute_local_spacing(index_range(cloud.points.size()), CGAL::make_property_map(spacing),
                                  CGAL::parameters::point_map(CGAL::make_property_map(cloud.points)));
  return spacing;
}

void upsample_cloud(Point_cloud& cloud, const CGAL_ext::Upsampling_settings& settings, const std::vector<std::size_t>* region,
                    const std::vector<double>* spacing_before, Progress_printer& progress, Report& rep)
{
  std::vector<std::pair<Point, Vector>> added;
  const std::size_t n = cloud.points.size();
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
                    .normal_map(CGAL::make_property_map(cloud.normals))
                    .callback(progress.stage("upsample"));
  const CGAL_ext::Upsampling_result result = rep.time("upsample", [&] {
    if(region && spacing_before)
      return CGAL_ext::upsample_point_set(index_range(n), *region, CGAL::make_property_map(*spacing_before), settings,
                                          std::back_inserter(added), np);
    return region ? CGAL_ext::upsample_point_set(index_range(n), *region, settings, std::back_inserter(added), np)
                  : CGAL_ext::upsample_point_set(index_range(n), settings, std::back_inserter(added), np);
  });
  progress.finish();
  if(!result) throw Cancelled();
  for(auto& [name, values] : cloud.scalars) values.resize(n + added.size(), 0.0);
  if(!cloud.colors.empty()) cloud.colors.resize(n + added.size(), flag_color);
  std::vector<double> inserted(n + added.size(), 0.0);
  for(std::size_t m = 0; m < added.size(); ++m) {
    cloud.points.push_back(added[m].first);
    cloud.normals.push_back(added[m].second);
    inserted[n + m] = 1;
  }
  cloud.set_scalar("inserted", std::move(inserted));
  rep.data()["upsampling"] = {{"spacing", result.spacing}, {"inserted", result.inserted}, {"rounds", result.rounds},
                              {"hole_boundary_points", result.hole_boundary_points}};
}

void run_edit(const Point_cloud& cloud, const Edit_description& edit, Progress_printer& progress, Report& rep, Point_cloud& out)
{
  const std::size_t n = cloud.points.size();
  std::vector<std::size_t> all = index_range(n);
  CGAL_ext::Detail_preserving_deformation<> deformation(
    all, edit.settings,
    CGAL::parameters::point_map(CGAL::make_property_map(cloud.points)).normal_map(CGAL::make_property_map(cloud.normals))
      .callback(progress.stage("preprocess")));
  deformation.insert_roi_points(edit.roi);
  for(const Handle_edit& handle : edit.handles) {
    const std::size_t group = deformation.create_handle_group();
    deformation.insert_handle_points(group, handle.points);
    deformation.set_handle_transform(group, handle.rotation, handle.translation);
  }
  const bool done = rep.time("preprocess", [&] { return deformation.preprocess(); });
  progress.finish();
  if(!done) throw Cancelled();
  rep.time("deform", [&] { deformation.deform(); });
  out = Point_cloud();
  out.points.resize(n);
  out.normals.resize(n);
  rep.time("diffuse", [&] {
    deformation.diffuse(all, CGAL::parameters::point_map(CGAL::make_property_map(out.points))
                                   .normal_map(CGAL::make_property_map(out.normals)));
  });
  if(edit.settings.detail_iterations > 0)
    rep.time("restore_details", [&] {
      deformation.restore_details(all, CGAL::parameters::point_map(CGAL::make_property_map(out.points)));
    });
  std::vector<double> moved(n), status(n, 0.0), sample(n);
  for(std::size_t i = 0; i < n; ++i) {
    moved[i] = std::sqrt(CGAL::squared_distance(out.points[i], cloud.points[i]));
    sample[i] = double(deformation.sample_point_of(i));
  }
  for(std::size_t i : edit.roi) status[i] = 1;
  for(const Handle_edit& handle : edit.handles)
    for(std::size_t i : handle.points) status[i] = 2;
  out.colors = sequential_colors(moved).colors;
  out.set_scalar("displacement", std::move(moved));
  out.set_scalar("status", std::move(status));
  out.set_scalar("ssp_index", std::move(sample));

  // Handle points against their targets (zero to rounding with exact handles).
  double handle_error = 0;
  for(std::size_t g = 0; g < edit.handles.size(); ++g)
    for(std::size_t i : edit.handles[g].points)
      handle_error = std::max(handle_error, (deformation.deformed_point(i) - deformation.handle_target(g, deformation.point(i))).norm());
  const CGAL_ext::Detail_preserving_deformation_statistics& st = deformation.statistics();
  const CGAL_ext::Least_squares_statistics& ls = st.least_squares;
  auto& r = rep.data();
  r["points"] = st.points;
  r["ssps"] = st.samples;
  r["requested_ssps"] = st.requested_samples;
  r["roi_ssps"] = st.roi_samples;
  r["handle_ssps"] = st.handle_samples;
  r["handle_groups"] = edit.handles.size();
  r["order"] = CGAL_ext::Detail_filter::order_name(edit.settings.filter.order);
  r["lambda"] = edit.settings.filter.lambda;
  if(edit.settings.filter.order != CGAL_ext::Detail_order::linear) r["mu"] = edit.settings.filter.mu;
  // The paper's Table 1: time for editing the SSPs (operator, normal matrix, factorisation, solve) and for diffusion.
  r["table1"] = {{"editing_ssps_s", ls.assembly_seconds + ls.factor_seconds + st.deform_seconds},
                 {"diffusion_s", st.diffuse_seconds}};
  r["clustering_s"] = st.clustering_seconds;
  r["solver"] = {{"method", ls.method}, {"normal_nonzeros", ls.normal_nonzeros}, {"assembly_s", ls.assembly_seconds},
                 {"factor_s", ls.factor_seconds}, {"solve_s", ls.solve_seconds}, {"refinement_steps", ls.iterations},
                 {"relative_residual", ls.relative_residual}};
  r["handle_constraints"] = std::isinf(edit.settings.handle_weight) ? nlohmann::json("exact") : nlohmann::json(edit.settings.handle_weight);
  r["max_handle_point_error"] = handle_error;
  r["displacement_ratio"] = st.displacement_ratio;
  if(edit.settings.rotations == CGAL_ext::Detail_rotation::as_rigid_as_possible) {
    r["rigid_iterations"] = st.rigid_iterations;
    r["rigid_edge_weights"] = CGAL_ext::setting_name(edit.settings.rigid_edge_weights);
    r["rigid_rotation_smoothing"] = edit.settings.rigid_rotation_smoothing;
    r["rigid_rotation_smoothing_scale"] = CGAL_ext::setting_name(edit.settings.rigid_rotation_smoothing_scale);
  }
  if(edit.settings.detail_iterations > 0)
    r["restore_details"] = {{"iterations", st.restore_iterations}, {"residual", st.restore_residual}};
}

Coloring manipulate_coloring(const Point_cloud& out)
{
  Coloring coloring = diverging_colors(*out.scalar("displacement"));
  coloring.quantity = "displacement along the normal, model units";
  return coloring;
}

Coloring edit_coloring(const Point_cloud& out)
{
  Coloring coloring = sequential_colors(*out.scalar("displacement"));
  coloring.quantity = "distance moved, model units";
  if(const std::vector<double>* inserted = out.scalar("inserted")) emphasize(coloring, *inserted, "new");
  return coloring;
}

} // namespace point_detail
