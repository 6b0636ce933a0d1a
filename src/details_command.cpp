// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail details`: geometric details of every point and their colour map.
#include "commands.h"
#include "operations.h"

namespace point_detail {
namespace {

struct Details_command
{
  std::string input, output, png, report, view = "front";
  Detail_options detail;
  Render_settings render;

  void run(const Common_options& common)
  {
    Point_outputs written({input}, output, png, report);
    render.view = parse_view(view);
    detail.settings().validate(); // before the (possibly long) read

    Progress_printer progress(common.quiet);
    Report rep("details");
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, detail.k, bytes_per_point::details, rep);
    ensure_normals(cloud, progress, rep);
    const Coloring coloring = add_details(cloud, detail, progress, rep);
    rep.time("write", [&] { write_file(written.ply, ply_bytes(cloud, common.scalar_prefix())); });
    if(!png.empty()) write_file(written.png, render_on_base_surface(cloud, coloring, detail.k, render, rep));
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
  }
};

} // namespace

Subcommand add_details_command(CLI::App& app, const Common_options& common)
{
  auto command = std::make_shared<Details_command>();
  Details_command& details = *command;
  CLI::App* details_app = app.add_subcommand("details", "geometric details of every point, as PLY properties and a colour map");
  details_app->add_option("-i,--input", details.input, "input points (.ply, .off, .xyz, .pwn, .pcd, .pts, .ptx, .las)")
    ->required();
  details_app->add_option("-o,--output", details.output, "output binary PLY")->required();
  details_app->add_option("--png", details.png, "also render the colour map on the base surface");
  details_app->add_option("--color-by", details.detail.color_by, "colour map (and PLY colours): detail_normal (delta . n, the "
                          "relief on any sampling) or detail_magnitude (the paper's signed |delta|)")
    ->check(CLI::IsMember({"detail_normal", "detail_magnitude"}))->capture_default_str();
  details_app->add_option("--report", details.report, "write stage timings and counts as JSON");
  add_detail_options(*details_app, details.detail);
  add_render_options(*details_app, details.render, details.view);
  return {details_app, [command, &common] { command->run(common); }};
}

} // namespace point_detail
