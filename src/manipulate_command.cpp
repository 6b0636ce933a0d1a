// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail scale` and `point-detail enhance`: a region's details made s times larger.
#include "commands.h"
#include "operations.h"
#include "region_spec.h"

#include <cmath>
#include <cstdio>

namespace point_detail {
namespace {

/// How far a region stands out from the surface its border spans, relative to its size: the median distance
/// its points moved divided by |s - 1| (the detail scaling is affine in s, so this is the deviation the region's
/// details have in all), over the region's RMS radius. Measured: the demo tentacle's bumpy middle 0.074, a ball
/// around the armadillo's head 0.10 (doc/detail_scaling.md). 0 at s = 1.
double region_deviation(const std::vector<Point>& before, const std::vector<Point>& after,
                        const std::vector<std::size_t>& region, double factor)
{
  if(factor == 1 || region.empty()) return 0;
  std::vector<double> moved;
  Vector centroid(0, 0, 0);
  for(std::size_t i : region) {
    moved.push_back(std::sqrt(CGAL::squared_distance(before[i], after[i])));
    centroid = centroid + (before[i] - CGAL::ORIGIN) / double(region.size());
  }
  double radius = 0;
  for(std::size_t i : region) radius += (before[i] - (CGAL::ORIGIN + centroid)).squared_length() / double(region.size());
  std::nth_element(moved.begin(), moved.begin() + std::ptrdiff_t(moved.size() / 2), moved.end());
  return radius > 0 ? moved[moved.size() / 2] / std::abs(factor - 1) / std::sqrt(radius) : 0;
}

/// Above this region deviation, `scale` warns that it reshapes a feature rather than its details.
constexpr double feature_deviation = 0.1;

/// `scale` and `enhance`: move a region so that its details become s times larger (paper Sect. 4).
struct Manipulate_command
{
  bool enhance = false;
  std::string input, output, png, report, view = "front";
  CGAL_ext::Linear_solver solver = CGAL_ext::Least_squares_settings().solver;
  double factor = 1;
  std::vector<std::string> roi, anchors;
  CGAL_ext::Border_anchoring border = CGAL_ext::Detail_enhancement_settings().border_anchoring;
  Detail_options detail;
  Render_settings render;

  void run(const Common_options& common)
  {
    const char* name = enhance ? "enhance" : "scale";
    Point_outputs written({input}, output, png, report);
    render.view = parse_view(view);
    std::vector<Region_spec> roi_specs, anchor_specs;
    for(const std::string& t : roi) roi_specs.push_back(parse_region_spec(t));
    for(const std::string& t : anchors) anchor_specs.push_back(parse_region_spec(t));
    CGAL_ext::Detail_enhancement_settings settings(detail.settings());
    settings.least_squares.solver = solver;
    settings.border_anchoring = border;
    settings.validate();

    Progress_printer progress(common.quiet);
    Report rep(name);
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, detail.k, bytes_per_point::manipulate, rep);
    const std::vector<std::size_t> region = roi_specs.empty() ? index_range(cloud.points.size()) : select_points(cloud.points, roi_specs);
    if(region.empty()) throw Cli_error("the region of interest (--roi) contains none of the " + std::to_string(cloud.points.size()) + " points");
    std::vector<std::size_t> anchor_indices;
    if(!anchor_specs.empty()) {
      anchor_indices = select_points(cloud.points, anchor_specs);
      if(anchor_indices.empty()) throw Cli_error("--anchors selects none of the points");
    }
    ensure_normals(cloud, progress, rep);

    Point_cloud out;
    const CGAL_ext::Detail_manipulation_result result = rep.time(name, [&] {
      return manipulate(enhance, cloud, region, anchor_specs.empty() ? nullptr : &anchor_indices, factor, detail.k,
                        settings, progress.stage(name), out);
    });
    progress.finish();
    if(!result) throw Cancelled();
    const double deviation = enhance ? 0.0 : region_deviation(cloud.points, out.points, region, factor);
    rep.time("write", [&] { write_file(written.ply, ply_bytes(out, common.scalar_prefix())); });
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] {
        return render_png(out.points, out.normals, manipulate_coloring(out), render);
      }));
    auto& r = rep.data();
    r["points"] = out.points.size();
    r["factor"] = factor;
    r["order"] = CGAL_ext::setting_name(detail.filter.order);
    r["neighbors"] = CGAL_ext::setting_name(detail.neighbors);
    r["roi_points"] = result.region_size;
    r["computed_points"] = result.computed_points;
    r["anchors"] = result.anchor_count;
    r["default_anchors"] = result.default_anchors;
    if(!enhance) r["region_deviation"] = deviation;
    const CGAL_ext::Least_squares_statistics& ls = result.least_squares;
    r["solver"] = {{"method", ls.method}, {"operator_nonzeros", ls.operator_nonzeros}, {"normal_nonzeros", ls.normal_nonzeros},
                   {"assembly_s", ls.assembly_seconds}, {"factor_s", ls.factor_seconds}, {"solve_s", ls.solve_seconds},
                   {"iterations", ls.iterations}, {"relative_residual", ls.relative_residual}};
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
    // Printed even with --quiet: the result is probably not what the user wanted.
    if(deviation > feature_deviation)
      std::fprintf(stderr, "point-detail: warning: the region stands out from the surface its border spans by %.0f %% of "
                   "its size: scale reshapes all of it, not only its small details (for those, use enhance)\n", 100 * deviation);
  }
};

} // namespace

std::vector<Subcommand> add_manipulate_commands(CLI::App& app, const Common_options& common)
{
  auto scale_command = std::make_shared<Manipulate_command>(), enhance_command = std::make_shared<Manipulate_command>();
  Manipulate_command &scale = *scale_command, &enhance = *enhance_command;
  enhance.enhance = true;
  CLI::App* scale_app = app.add_subcommand("scale", "scale a region's deviation from the surface its border spans by a factor "
    "(paper Sect. 4.1): all of it, so a region around a whole feature (a head) reshapes the feature; for only the "
    "small details, use enhance");
  CLI::App* enhance_app = app.add_subcommand("enhance", "enhance the details against the balanced-flow base surface (paper Sect. 4.2)");
  for(auto [sub, command] : {std::pair{scale_app, &scale}, std::pair{enhance_app, &enhance}}) {
    sub->add_option("-i,--input", command->input, "input points (.ply, .off, .xyz, .pwn, .pcd, .pts, .ptx, .las)")
      ->required();
    sub->add_option("-o,--output", command->output, "output binary PLY: moved points, their normals (re-fitted where they moved), displacement, in_roi")->required();
    sub->add_option("-s,--factor", command->factor, "scale factor s (1: unchanged)")->required();
    auto* roi_option = sub->add_option("--roi", command->roi,
      "region of interest, repeatable (union): sphere:x,y,z,r | box:xmin,ymin,zmin,xmax,ymax,zmax | indices:FILE"
      + std::string(command->enhance ? " (default: the whole model)" : ""));
    if(!command->enhance) roi_option->required();
    sub->add_option("--anchors", command->anchors, "anchored points, same syntax (default: the region's border; enhance "
                                                    "of the whole model needs none: its exact solution is written)");
    add_setting_option(*sub, "--border", command->border,
                       "default anchors of a partial region: its border (anchored), none (free: the surroundings hold "
                       "it), or auto (anchored except for the cubic order; default)");
    add_setting_option(*sub, "--solver", command->solver,
                       "cholesky (factor once; default) or cg (conjugate gradients, the paper's)");
    sub->add_option("--png", command->png, "also render the result, coloured by the displacement along the normal");
    sub->add_option("--report", command->report, "write stage timings, region and solver figures as JSON");
    add_detail_options(*sub, command->detail);
    add_render_options(*sub, command->render, command->view);
  }
  return {{scale_app, [scale_command, &common] { scale_command->run(common); }},
          {enhance_app, [enhance_command, &common] { enhance_command->run(common); }}};
}

} // namespace point_detail
