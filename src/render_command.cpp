// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail render`: a headless picture of a point set.
#include "commands.h"
#include "subcommand_options.h"

namespace point_detail {
namespace {

struct Render_command
{
  std::string input, output, color_by, legend, report, view = "front";
  Render_settings render;

  void run(const Common_options& common)
  {
    Output_files outputs({input});
    const fs::path png_tmp = outputs.add(output);
    const fs::path report_tmp = add_if_given(outputs, report);
    render.view = parse_view(view);
    Report rep("render");
    rep.data()["input"] = input;
    Point_cloud cloud = read_input(input, bytes_per_point::render, rep);
    rep.data()["points"] = cloud.points.size();
    if(cloud.points.size() >= 6) { // shaded pictures: normals from the points when the file has none
      Progress_printer progress(common.quiet);
      ensure_normals(cloud, progress, rep);
    }
    Coloring colors;
    std::string by = color_by;
    if(by.empty())
      by = !cloud.colors.empty()                ? "rgb"
           : cloud.scalar("detail_normal")      ? "detail_normal"
           : cloud.scalar("detail_magnitude")   ? "detail_magnitude"
                                                : "none";
    if(by == "rgb") {
      if(cloud.colors.empty()) throw Cli_error(input + " has no red/green/blue properties to colour by");
      colors.colors = cloud.colors;
    } else if(by != "none") {
      const std::vector<double>* values = cloud.scalar(by);
      if(!values) {
        std::string names;
        for(const auto& s : cloud.scalars) names += " " + s.first;
        throw Cli_error(input + " has no property '" + by + "' (it has:" + (names.empty() ? " none" : names) + "; or use rgb, none)");
      }
      colors = colors_for(*values);
      colors.quantity = legend.empty() ? quantity_of(by) : legend;
    }
    rep.data()["color_by"] = by;
    write_file(png_tmp, rep.time("render", [&] { return render_png(cloud.points, cloud.normals, colors, render); }));
    if(!report.empty()) write_file(report_tmp, rep.dump());
    outputs.commit();
  }
};

} // namespace

Subcommand add_render_command(CLI::App& app, const Common_options& common)
{
  auto command = std::make_shared<Render_command>();
  Render_command& render = *command;
  CLI::App* render_app = app.add_subcommand("render", "headless PNG picture of a point set");
  render_app->add_option("-i,--input", render.input, "input points")->required();
  render_app->add_option("-o,--output", render.output, "output PNG")->required();
  render_app->add_option("--color-by", render.color_by, "rgb, none or a scalar property: 0/1 flags (inserted, in_roi) are highlighted, signed values get a diverging map, others a sequential one (default: rgb, else detail_normal, else detail_magnitude)");
  render_app->add_option("--legend", render.legend,
                          "what the colours show and their unit, over the legend's bar (default: the property's name "
                          "for the program's own, e.g. detail_normal: \"detail along the normal, model units\")")
    ->check([](const std::string& text) {
      for(char c : text)
        if(!legend_can_write(c)) return std::string("the legend's font writes letters, digits, spaces and .,-+/()_ only");
      return std::string();
    });
  render_app->add_option("--report", render.report, "write stage timings and counts as JSON");
  add_render_options(*render_app, render.render, render.view);
  return {render_app, [command, &common] { command->run(common); }};
}

} // namespace point_detail
