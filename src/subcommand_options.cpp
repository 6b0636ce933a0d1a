// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "subcommand_options.h"

#include <CGAL_ext/estimate_oriented_normals.h>

#include <algorithm>
#include <cstdio>
#include <numeric>

namespace point_detail {

void add_detail_options(CLI::App& app, Detail_options& o)
{
  add_setting_option(app, "--order", o.filter.order, std::string("transfer function (default ") +
                                                      CGAL_ext::setting_name(o.filter.order) + ")");
  app.add_option("--lambda", o.filter.lambda, "pass-band frequency (> 0)")->capture_default_str();
  app.add_option("--mu", o.filter.mu, "highest frequency (> lambda; quadric and cubic)")->capture_default_str();
  add_neighbor_count_option(app, o.k, "Laplacian row", 1);
  add_setting_option(app, "--neighbors", o.neighbors, "Laplacian neighbourhoods: knn (symmetrised k nearest, default) or "
                                                      "mean_shift (the k nearest whose mean-shift modes agree, so rows "
                                                      "stop at creases)");
  add_setting_option(app, "--weights", o.weights, "Laplacian weights: uniform (1/valence, default) or distance "
                                                  "(|p_i - p_j|^-1)");
}

CLI::Option* add_neighbor_count_option(CLI::App& app, unsigned int& k, const std::string& of, unsigned int minimum,
                                       const std::string& point)
{
  return app.add_option("-k,--neighbor-count", k, "each " + point + "'s k nearest neighbours (itself not counted) form its " + of +
                        "; " + std::to_string(minimum) + " <= k < the number of " + point + "s, an error otherwise")
    ->capture_default_str();
}

void add_render_options(CLI::App& app, Render_settings& r, std::string& view)
{
  app.add_option("--view", view, "front|back|left|right|top|bottom|iso or AZIMUTH,ELEVATION (degrees)")->capture_default_str();
  app.add_option("--width", r.width, "picture width in pixels")->check(CLI::Range(16, 8192))->capture_default_str();
  app.add_option("--height", r.height, "picture height in pixels")->check(CLI::Range(16, 8192))->capture_default_str();
  app.add_option("--splat", r.splat_scale, "splat size relative to the sample spacing")->check(CLI::Range(0.1, 10.0))->capture_default_str();
}

std::vector<std::size_t> index_range(std::size_t n)
{
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  return idx;
}

fs::path add_if_given(Output_files& outputs, const std::string& destination)
{
  return destination.empty() ? fs::path() : outputs.add(destination);
}

Point_cloud read_input(const std::string& input, std::uint64_t bytes, Report& rep)
{
  Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input, bytes); });
  if(cloud.points_without_position > 0) {
    rep.data()["points_without_position"] = cloud.points_without_position;
    std::fprintf(stderr,
                 "point-detail: note: %zu points of %s have no position (NaN in a PCD file, 0 0 0 in a PTX file) "
                 "and are left out; the outputs hold the other points in file order\n",
                 cloud.points_without_position, input.c_str());
  }
  return cloud;
}

Point_cloud read_for_neighbors(const std::string& input, unsigned int k, std::uint64_t bytes, Report& rep)
{
  Point_cloud cloud = read_input(input, bytes, rep);
  if(cloud.points.size() <= k)
    throw Cli_error(input + " has " + std::to_string(cloud.points.size()) + " points: -k " + std::to_string(k) +
                    " needs more than k points");
  return cloud;
}

void ensure_normals(Point_cloud& cloud, Progress_printer& progress, Report& report)
{
  report.data()["normal_source"] = cloud.normals.empty() ? "estimated" : cloud.normal_source;
  if(!cloud.normals.empty() && cloud.vertices_without_normal == 0) return;
  if(cloud.points.size() < 6) throw Cli_error("normal estimation needs at least 6 points (a jet fit has 6 coefficients)");
  if(cloud.unread_triangle_strips)
    std::fprintf(stderr, "point-detail: warning: the faces of this PLY file are triangle strips, which are not read; "
                         "its normals are estimated from the points\n");
  std::vector<Vector> estimated(cloud.points.size());
  report.time("normals", [&] {
    if(!CGAL_ext::estimate_oriented_normals(
         index_range(cloud.points.size()),
         std::min<unsigned int>(CGAL_ext::default_normal_neighbors, unsigned(cloud.points.size() - 1)),
         CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
           .normal_map(CGAL::make_property_map(estimated))
           .callback(progress.stage("normals"))))
      throw Cancelled();
  });
  progress.finish();
  if(cloud.normals.empty()) {
    cloud.normals = std::move(estimated);
    cloud.normal_source = "estimated";
    return;
  }
  double agreement = 0;
  for(std::size_t i = 0; i < estimated.size(); ++i) agreement += estimated[i] * cloud.normals[i];
  for(std::size_t i = 0; i < estimated.size(); ++i)
    if(cloud.normals[i] == CGAL::NULL_VECTOR) cloud.normals[i] = agreement < 0 ? -estimated[i] : estimated[i];
  report.data()["estimated_normals"] = cloud.vertices_without_normal;
  cloud.vertices_without_normal = 0;
}

} // namespace point_detail
