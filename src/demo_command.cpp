// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail demo`: every algorithm on a generated tentacle.
#include "commands.h"
#include "operations.h"
#include "region_spec.h"

#include <CGAL_ext/generated_shapes.h>

#include <CGAL/number_type_config.h>

#include <cstdio>

namespace point_detail {
namespace {

struct Demo_command
{
  std::string directory = "point-detail-demo", report;
  std::size_t points = 40000;

  void run(const Common_options& common)
  {
    std::error_code ec;
    fs::create_directories(directory, ec);
    if(!fs::is_directory(directory)) throw Cli_error("cannot create directory " + directory);
    const fs::path dir(directory);
    Output_files outputs({});
    const fs::path report_tmp = add_if_given(outputs, report);
    nlohmann::json runs = nlohmann::json::array();
    Progress_printer progress(common.quiet);
    Render_settings render;
    render.view = parse_view("iso");

    // The paper's tentacle (Fig. 8): a bent tube with bumps.
    const auto tube = CGAL_ext::shapes::bumpy_tube<Kernel>(points);
    Point_cloud input;
    input.points = tube.points;
    input.normals = tube.normals;
    write_file(outputs.add(dir / "tentacle.ply"), ply_bytes(input, common.scalar_prefix()));
    write_file(outputs.add(dir / "tentacle.png"), render_png(input.points, input.normals, Coloring(), render));
    std::printf("demo: tentacle of %zu points with exact normals\n", input.points.size());
    for(const char* order : {"linear", "quadric", "cubic"}) {
      Detail_options options;
      options.filter.order = setting_value<CGAL_ext::Detail_order>(order, "order");
      Point_cloud cloud = input;
      Report rep(std::string("demo details ") + order);
      const Coloring coloring = add_details(cloud, options, progress, rep);
      const std::string stem = std::string("details_") + order;
      write_file(outputs.add(dir / (stem + ".ply")), ply_bytes(cloud, common.scalar_prefix()));
      write_file(outputs.add(dir / (stem + ".png")), render_on_base_surface(cloud, coloring, options.k, render, rep));
      std::printf("demo: %-7s details (lambda %.1f, mu %.1f, k %u) in %.3f s -> %s.ply, %s.png\n", order, options.filter.lambda,
                  options.filter.mu, options.k, rep.data()["timings_s"]["details"].get<double>(), stem.c_str(), stem.c_str());
      runs.push_back(rep.data());
    }
    // Detail scaling of the tentacle's middle (paper Fig. 4) and enhancement of the whole tentacle (Fig. 5, 6),
    // quadric order; the pictures are coloured by the displacement along the normal.
    const std::vector<std::size_t> middle = select_points(input.points, {parse_region_spec("sphere:-0.29,0,0.71,0.3")});
    const std::vector<std::size_t> whole = index_range(input.points.size());
    for(const auto& [enhance_binding, factor_binding] :
        {std::pair{false, 0.6}, std::pair{false, 1.2}, std::pair{true, 2.0}, std::pair{true, 3.0}}) {
      const bool enhance = enhance_binding; // C++17 lambdas cannot capture structured bindings
      const double factor = factor_binding;
      const std::string what = enhance ? "enhance" : "scale";
      char stem[64];
      std::snprintf(stem, sizeof stem, "%s_%.1f", what.c_str(), factor);
      Report rep("demo " + std::string(stem));
      Point_cloud out;
      const auto result = rep.time(what, [&] {
        return manipulate(enhance, input, enhance ? whole : middle, nullptr, factor, CGAL_ext::default_laplacian_neighbors,
                          CGAL_ext::Detail_enhancement_settings(), progress.stage(stem), out);
      });
      progress.finish();
      if(!result) throw Cancelled();
      write_file(outputs.add(dir / (std::string(stem) + ".ply")), ply_bytes(out, common.scalar_prefix()));
      write_file(outputs.add(dir / (std::string(stem) + ".png")),
                 render_png(out.points, out.normals, manipulate_coloring(out), render));
      rep.data()["roi_points"] = result.region_size;
      rep.data()["anchors"] = result.anchor_count;
      std::printf("demo: %-7s s = %.1f on %zu points (%zu anchors) in %.3f s -> %s.ply, %s.png\n", what.c_str(), factor,
                  result.region_size, result.anchor_count, rep.data()["timings_s"][what].get<double>(), stem, stem);
      runs.push_back(rep.data());
    }
    // Detail-preserving editing (paper Fig. 8): the tip swings by 50 degrees about the base of the region (the
    // tentacle above z = 0.25; the rest stays). Coloured by the distance each point moved.
    Edit_description bend;
    bend.roi = select_points(input.points, {parse_region_spec("box:-2,-1,0.25,1,1,2")});
    Handle_edit tip;
    tip.points = select_points(input.points, {parse_region_spec("box:-2,-1,-1,-0.85,1,2")});
    const Eigen::Vector3d pivot(0, 0, 0.25);
    tip.rotation = Eigen::AngleAxisd(50 * CGAL_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
    tip.translation = pivot - tip.rotation * pivot;
    bend.handles.push_back(tip);
    for(const char* order : {"linear", "quadric", "cubic"}) {
      bend.settings.filter.order = setting_value<CGAL_ext::Detail_order>(order, "order");
      Report rep(std::string("demo edit ") + order);
      Point_cloud out;
      run_edit(input, bend, progress, rep, out);
      const std::string stem = std::string("edit_") + order;
      write_file(outputs.add(dir / (stem + ".ply")), ply_bytes(out, common.scalar_prefix()));
      write_file(outputs.add(dir / (stem + ".png")), render_png(out.points, out.normals, edit_coloring(out), render));
      const auto& r = rep.data();
      std::printf("demo: %-7s edit, tip swung 50 degrees: %zu SSPs (%zu in the region), SSPs %.3f s, diffusion %.3f s -> %s.ply, %s.png\n",
                  order, r["ssps"].get<std::size_t>(), r["roi_ssps"].get<std::size_t>(), r["table1"]["editing_ssps_s"].get<double>(),
                  r["table1"]["diffusion_s"].get<double>(), stem.c_str(), stem.c_str());
      runs.push_back(r);
    }
    // Up-sampling (paper Sect. 6.3, Fig. 9-10): the tip pulled 1.0 further along the tube stretches the region;
    // what the stretch thinned is filled at the pre-edit spacing. Highlighted: the new points.
    {
      Edit_description pull = bend;
      pull.handles.front().rotation.setIdentity();
      pull.handles.front().translation = Eigen::Vector3d(-1.0, 0, 0);
      Report rep("demo stretch and upsample");
      Point_cloud out;
      run_edit(input, pull, progress, rep, out);
      write_file(outputs.add(dir / "edit_stretch.png"), render_png(out.points, out.normals, edit_coloring(out), render));
      std::vector<std::size_t> moved;
      for(std::size_t i = 0; i < out.points.size(); ++i)
        if((*out.scalar("displacement"))[i] > 0) moved.push_back(i);
      const std::vector<double> spacing_before = local_spacing(input);
      upsample_cloud(out, CGAL_ext::Upsampling_settings(), &moved, &spacing_before, progress, rep);
      write_file(outputs.add(dir / "edit_stretch_upsampled.ply"), ply_bytes(out, common.scalar_prefix()));
      write_file(outputs.add(dir / "edit_stretch_upsampled.png"), render_png(out.points, out.normals, edit_coloring(out), render));
      std::printf("demo: tip pulled by 1.0, then %zu points inserted where the stretch thinned the tentacle -> "
                  "edit_stretch.png, edit_stretch_upsampled.{ply,png}\n", rep.data()["upsampling"]["inserted"].get<std::size_t>());
      runs.push_back(rep.data());
    }
    if(!report.empty()) write_file(report_tmp, nlohmann::json{{"command", "demo"}, {"runs", runs}}.dump(2) + "\n");
    outputs.commit();
    std::printf("demo: wrote %s/{tentacle,details_*,scale_*,enhance_*,edit_*}.{ply,png}\n", directory.c_str());
  }
};

} // namespace

Subcommand add_demo_command(CLI::App& app, const Common_options& common)
{
  auto command = std::make_shared<Demo_command>();
  Demo_command& demo = *command;
  CLI::App* demo_app = app.add_subcommand("demo", "detail colour maps, scaling, enhancement, editing and up-sampling on a generated tentacle");
  demo_app->add_option("-o,--output", demo.directory, "output directory (created)")->capture_default_str();
  demo_app->add_option("--report", demo.report, "write stage timings and counts as JSON");
  demo_app->add_option("--points", demo.points, "number of samples")->check(CLI::Range(1000, 5000000))->capture_default_str();
  return {demo_app, [command, &common] { command->run(common); }};
}

} // namespace point_detail
