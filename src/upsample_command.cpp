// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail upsample`: fills holes and stretched parts.
#include "commands.h"
#include "operations.h"

#include <cstdio>

namespace point_detail {
namespace {

/// `upsample`: fills the holes of an oriented point set (paper Sect. 6.3).
struct Upsample_command
{
  std::string input, output, png, report, view = "front";
  double spacing = 0;
  CGAL_ext::Upsampling_settings settings;
  Render_settings render;

  void run(const Common_options& common)
  {
    Point_outputs written({input}, output, png, report);
    render.view = parse_view(view);
    settings.detection.spacing = spacing;
    settings.validate();
    Progress_printer progress(common.quiet);
    Report rep("upsample");
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, settings.neighbors, bytes_per_point::upsample, rep);
    ensure_normals(cloud, progress, rep);
    const std::size_t n = cloud.points.size();
    upsample_cloud(cloud, settings, nullptr, nullptr, progress, rep);
    rep.data()["points"] = n;
    rep.time("write", [&] { write_file(written.ply, ply_bytes(cloud, common.scalar_prefix())); });
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] {
        Coloring coloring = flag_colors(*cloud.scalar("inserted"));
        coloring.quantity = quantity_of("inserted");
        return render_png(cloud.points, cloud.normals, coloring, render);
      }));
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
    if(!common.quiet)
      std::fprintf(stderr, "upsample: %zu points + %zu new at spacing %g\n", n, cloud.points.size() - n,
                   rep.data()["upsampling"]["spacing"].get<double>());
  }
};

} // namespace

Subcommand add_upsample_command(CLI::App& app, const Common_options& common)
{
  auto command = std::make_shared<Upsample_command>();
  Upsample_command& upsample = *command;
  CLI::App* upsample_app = app.add_subcommand("upsample", "fill holes and stretched parts with new samples, relaxed on the surface (paper Sect. 6.3)");
  upsample_app->add_option("-i,--input", upsample.input, "input points with normals (.ply, .off, .xyz, .pwn, .pcd)")
    ->required();
  upsample_app->add_option("-o,--output", upsample.output, "output binary PLY: the input, then the new points (inserted = 1)")->required();
  upsample_app->add_option("--spacing", upsample.spacing, "target spacing everywhere (0: each point's local spacing, so that only what is sparse for its surroundings is filled)")->capture_default_str();
  upsample_app->add_option("--max-hole-size", upsample.settings.detection.max_hole_size, "widest gap filled, in spacings (open borders are never grown)")->capture_default_str();
  add_neighbor_count_option(*upsample_app, upsample.settings.neighbors, "tangent axes and surface fits", 6);
  upsample_app->add_option("--png", upsample.png, "also render the result, new points highlighted");
  upsample_app->add_option("--report", upsample.report, "write counts, spacing and timings as JSON");
  add_render_options(*upsample_app, upsample.render, upsample.view);
  return {upsample_app, [command, &common] { command->run(common); }};
}

} // namespace point_detail
