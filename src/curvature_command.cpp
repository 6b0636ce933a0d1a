// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail curvature`: signed mean curvature of every point.
#include "commands.h"
#include "subcommand_options.h"

#include <CGAL_ext/estimate_mean_curvature.h>

#include <algorithm>

namespace point_detail {
namespace {

/// `curvature`: signed mean curvature per point (positive where the surface bends away from its normal).
struct Curvature_command
{
  std::string input, output, png, report, view = "front";
  CGAL_ext::Curvature_fitting fitting = CGAL_ext::Curvature_fitting::monge_jet_fitting;
  unsigned int k = CGAL_ext::default_curvature_neighbors;
  Render_settings render;

  void run(const Common_options& common)
  {
    Point_outputs written({input}, output, png, report);
    render.view = parse_view(view);
    Progress_printer progress(common.quiet);
    Report rep("curvature");
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, k, bytes_per_point::curvature, rep);
    ensure_normals(cloud, progress, rep);
    const std::size_t n = cloud.points.size();
    std::vector<double> H(n);
    const bool done = rep.time("curvature", [&] {
      return CGAL_ext::estimate_mean_curvature(
        index_range(n), k, fitting,
        CGAL::make_property_map(H),
        CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
          .normal_map(CGAL::make_property_map(cloud.normals))
          .callback(progress.stage("curvature")));
    });
    progress.finish();
    if(!done) throw Cancelled();
    std::vector<double> sorted = H;
    std::sort(sorted.begin(), sorted.end());
    auto& r = rep.data();
    r["points"] = n;
    r["k"] = k;
    r["fitting"] = CGAL_ext::setting_name(fitting);
    r["curvature_percentiles"] = {{"p02", sorted[n / 50]}, {"p50", sorted[n / 2]}, {"p98", sorted[n - 1 - n / 50]}};
    Coloring coloring = diverging_colors(H);
    coloring.quantity = quantity_of("mean_curvature");
    cloud.colors = coloring.colors;
    cloud.set_scalar("mean_curvature", std::move(H));
    rep.time("write", [&] { write_file(written.ply, ply_bytes(cloud, common.scalar_prefix())); });
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] { return render_png(cloud.points, cloud.normals, coloring, render); }));
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
  }
};

} // namespace

Subcommand add_curvature_command(CLI::App& app, const Common_options& common)
{
  auto command = std::make_shared<Curvature_command>();
  Curvature_command& curvature = *command;
  CLI::App* curvature_app = app.add_subcommand("curvature", "signed mean curvature of every point (jet fitting), as a PLY property and a colour map");
  curvature_app
    ->add_option("-i,--input", curvature.input, "input points (.ply, .off, .xyz, .pwn, .pcd, .pts, .ptx, .las)")
    ->required();
  curvature_app->add_option("-o,--output", curvature.output, "output binary PLY with mean_curvature and colours")->required();
  add_neighbor_count_option(*curvature_app, curvature.k, "degree-2 fit", 5);
  add_setting_option(*curvature_app, "--fitting", curvature.fitting,
                     "monge (CGAL::Monge_via_jet_fitting, default) or closed_form (faster)");
  curvature_app->add_option("--png", curvature.png, "also render the curvature colour map (red: bends away from the normal)");
  curvature_app->add_option("--report", curvature.report, "write stage timings and curvature percentiles as JSON");
  add_render_options(*curvature_app, curvature.render, curvature.view);
  return {curvature_app, [command, &common] { command->run(common); }};
}

} // namespace point_detail
