// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail edit`: detail-preserving editing by handles.
#include "commands.h"
#include "operations.h"

#include <cstdio>
#include <map>

namespace point_detail {
namespace {

/// Above this ratio of the largest sample-point displacement to the handles' largest, `edit` warns.
constexpr double swing_warning_ratio = 2.0;

/// `edit`: detail-preserving editing of a region by handles (paper Sect. 6).
struct Edit_command
{
  std::string input, output, edit, sel, def, png, report, view = "front";
  std::string order, strength, origin, turn;
  double lambda = 0, mu = 0, handle_weight = 0, rigid_smoothing = 0;
  unsigned int k = CGAL_ext::default_laplacian_neighbors;
  std::size_t max_cluster_size = 0, target = 0;
  unsigned int rigid_iterations = 0, detail_iterations = 0;
  std::string rotations, rigid_weights, rigid_smoothing_scale;
  bool upsample = false;
  std::map<std::string, CLI::Option*> given;
  Render_settings render;

  bool has(const std::string& name) const { return given.at(name)->count() > 0; }

  void run(const Common_options& common)
  {
    if(edit.empty() && sel.empty()) throw Cli_error("edit needs --edit EDIT.json or --sel S --def D");
    std::vector<fs::path> inputs{input};
    for(const std::string& f : {edit, sel, def})
      if(!f.empty()) inputs.push_back(f);
    Point_outputs written(inputs, output, png, report);
    render.view = parse_view(view);

    Progress_printer progress(common.quiet);
    Report rep("edit");
    rep.data()["input"] = input;
    Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input, bytes_per_point::edit); });
    if(cloud.points.size() < 2) throw Cli_error(input + " has fewer than 2 points");
    Edit_description description = edit.empty() ? read_botsch_sorkine(sel, def, cloud.points.size())
                                                 : read_edit_json(edit, cloud.points);
    // Options given on the command line override the edit file's settings.
    auto& s = description.settings;
    if(has("--order"))
      s.filter.order = detail_order(order, "--order");
    if(has("--lambda")) s.filter.lambda = lambda;
    if(has("--mu")) s.filter.mu = mu;
    if(has("-k")) s.sample_neighbors = k;
    if(has("--strength")) s.strength_distance = strength == "geodesic" ? CGAL_ext::Strength_distance::geodesic : CGAL_ext::Strength_distance::euclidean;
    if(has("--diffusion-origin")) s.diffusion_origin = origin == "nearest" ? CGAL_ext::Diffusion_origin::nearest_sample : CGAL_ext::Diffusion_origin::own_sample;
    if(has("--diffusion-turn"))
      s.diffusion_turn = turn == "frames" ? CGAL_ext::Sample_turn::frames : turn == "fitted" ? CGAL_ext::Sample_turn::fitted : CGAL_ext::Sample_turn::affine;
    if(has("--handle-weight")) s.handle_weight = handle_weight;
    if(has("--max-cluster-size")) s.simplification.max_cluster_size = max_cluster_size;
    if(has("--target")) s.simplification.target_count = target;
    if(has("--rotations")) s.rotations = detail_rotation(rotations, "--rotations");
    if(has("--rigid-iterations")) s.rigid_iterations = rigid_iterations;
    if(has("--rigid-smoothing")) s.rigid_rotation_smoothing = rigid_smoothing;
    if(has("--rigid-weights")) s.rigid_edge_weights = rigid_edge_weights(rigid_weights, "--rigid-weights");
    if(has("--rigid-smoothing-scale"))
      s.rigid_rotation_smoothing_scale = rotation_smoothing_scale(rigid_smoothing_scale, "--rigid-smoothing-scale");
    if(has("--detail-iterations")) s.detail_iterations = detail_iterations;
    s.validate();
    ensure_normals(cloud, progress, rep);

    Point_cloud out;
    run_edit(cloud, description, progress, rep, out);
    // What the edit stretched is filled at the spacing the model had before it, from the points it moved.
    if(upsample) {
      const std::vector<double>& moved = *out.scalar("displacement");
      std::vector<std::size_t> region;
      for(std::size_t i = 0; i < moved.size(); ++i)
        if(moved[i] > 0) region.push_back(i);
      const std::vector<double> spacing_before = local_spacing(cloud);
      upsample_cloud(out, CGAL_ext::Upsampling_settings(), &region, &spacing_before, progress, rep);
    }
    rep.time("write", [&] { write_file(written.ply, ply_bytes(out)); });
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] { return render_png(out.points, out.normals, edit_coloring(out), render); }));
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
    if(!common.quiet) {
      const auto& r = rep.data();
      std::fprintf(stderr, "edit: %zu points, %zu SSPs (%zu in the region): editing the SSPs %.3f s, diffusion %.3f s\n",
                   r["points"].get<std::size_t>(), r["ssps"].get<std::size_t>(), r["roi_ssps"].get<std::size_t>(),
                   r["table1"]["editing_ssps_s"].get<double>(), r["table1"]["diffusion_s"].get<double>());
      if(r["requested_ssps"].get<std::size_t>() > r["ssps"].get<std::size_t>())
        std::fprintf(stderr, "edit: the mode-spread rule asked for %zu SSPs; the budget kept %zu\n",
                     r["requested_ssps"].get<std::size_t>(), r["ssps"].get<std::size_t>());
    }
    // Printed even with --quiet: the result is probably not what the user wanted.
    if(rep.data()["displacement_ratio"].get<double>() > swing_warning_ratio)
      std::fprintf(stderr, "point-detail: warning: parts of the region moved %.1f times as far as any handle (the solve "
                   "swings them; try --order quadric or --rotations arap)\n", rep.data()["displacement_ratio"].get<double>());
    if(rep.data().contains("restore_details") &&
       rep.data()["restore_details"]["residual"].get<double>() > description.settings.detail_tolerance)
      std::fprintf(stderr, "point-detail: warning: putting back the fine details stopped after %u iterations at a residual "
                   "of %.2g (tolerance %.2g); raise --detail-iterations\n",
                   rep.data()["restore_details"]["iterations"].get<unsigned>(),
                   rep.data()["restore_details"]["residual"].get<double>(), description.settings.detail_tolerance);
  }
};

} // namespace

Subcommand add_edit_command(CLI::App& app, const Common_options& common)
{
  auto command = std::make_shared<Edit_command>();
  Edit_command& edit = *command;
  CLI::App* edit_app = app.add_subcommand("edit", "detail-preserving editing by handles on simplification sample points (paper Sect. 6)");
  edit_app->add_option("-i,--input", edit.input, "input points (.ply, .off, .xyz, .pwn)")->required();
  edit_app->add_option("-o,--output", edit.output, "output binary PLY: deformed points and normals, displacement, status, ssp_index")->required();
  auto* edit_json = edit_app->add_option("--edit", edit.edit, "edit description (JSON: roi, handles with transforms, settings; doc/editing.md)");
  auto* edit_sel = edit_app->add_option("--sel", edit.sel, "Botsch-Sorkine selection: one status per point (0 fixed, 1 deformable, 2 handle)");
  auto* edit_def = edit_app->add_option("--def", edit.def, "Botsch-Sorkine handle transform: a 4x4 matrix");
  edit_json->excludes(edit_sel)->excludes(edit_def);
  edit_sel->needs(edit_def);
  edit_def->needs(edit_sel);
  edit_app->add_option("--png", edit.png, "also render the result, coloured by the distance each point moved");
  edit_app->add_option("--report", edit.report, "write the paper's Table 1 fields, stage timings and solver figures as JSON");
  edit.given["--order"] = edit_app->add_option("--order", edit.order, "transfer function (overrides the edit file)")
                            ->check(CLI::IsMember({"linear", "quadric", "cubic"}));
  edit.given["--lambda"] = edit_app->add_option("--lambda", edit.lambda, "pass-band frequency (> 0)");
  edit.given["--mu"] = edit_app->add_option("--mu", edit.mu, "highest frequency (> lambda; quadric and cubic)");
  edit.given["-k"] = add_neighbor_count_option(*edit_app, edit.k, "Laplacian row", 1, "sample point");
  edit.given["--strength"] = edit_app->add_option("--strength", edit.strength, "distances of the strength field: euclidean (the paper's) or geodesic")
                               ->check(CLI::IsMember({"euclidean", "geodesic"}));
  edit.given["--diffusion-origin"] = edit_app->add_option("--diffusion-origin", edit.origin, "own (p - ssp_i in frame i, default) or nearest (the paper's p - ssp_0)")
                                       ->check(CLI::IsMember({"own", "nearest"}));
  edit.given["--diffusion-turn"] = edit_app->add_option("--diffusion-turn", edit.turn, "affine (each SSP's best linear map of its neighbourhood, default), fitted (its best rotation) or frames (the paper's local frames)")
                                     ->check(CLI::IsMember({"affine", "fitted", "frames"}));
  edit.given["--handle-weight"] = edit_app->add_option("--handle-weight", edit.handle_weight, "weight of soft handle constraints (the paper's, e.g. 1); default: exact handles");
  edit.given["--max-cluster-size"] = edit_app->add_option("--max-cluster-size", edit.max_cluster_size, "largest number of points per SSP");
  edit.given["--target"] = edit_app->add_option("--target", edit.target, "SSP count the clustering aims at, at most 1.5 times it with the mode-spread rule (default 3000)");
  edit.given["--rotations"] = edit_app->add_option("--rotations", edit.rotations, "how the details turn: none, propagate (the paper's), arap (as rigid as possible)")
    ->check(CLI::IsMember({"none", "propagate", "arap"}));
  edit.given["--rigid-iterations"] = edit_app->add_option("--rigid-iterations", edit.rigid_iterations, "with --rotations arap: rotation fits and solves")
    ->check(CLI::Range(1u, 1000u));
  edit.given["--rigid-smoothing"] = edit_app->add_option("--rigid-smoothing", edit.rigid_smoothing, "with --rotations arap: weight of SRE-ARAP's smooth-rotation term (about 1: near CGAL's SRE_ARAP, with --rigid-iterations 10 or more; default 0)")
    ->check(CLI::NonNegativeNumber);
  edit.given["--rigid-smoothing-scale"] = edit_app->add_option("--rigid-smoothing-scale", edit.rigid_smoothing_scale, "with --rigid-smoothing: what its weight is relative to, edge_lengths (default: the same at every density) or surface_area (CGAL's SRE_ARAP: --rigid-smoothing 0.02 with --rigid-weights cotangent is its energy)")
    ->check(CLI::IsMember({"edge_lengths", "surface_area"}));
  edit.given["--rigid-weights"] = edit_app->add_option("--rigid-weights", edit.rigid_weights, "with --rotations arap: weights of the SSP graph's edges, uniform (default) or cotangent (from each SSP's Voronoi cell in its tangent plane: nearer a mesh ARAP on large bends)")
    ->check(CLI::IsMember({"uniform", "cotangent"}));
  edit.given["--detail-iterations"] = edit_app->add_option("--detail-iterations", edit.detail_iterations, "at most this many iterations to put back the fine details the diffusion smoothed (default 100, 0: none)")
    ->check(CLI::Range(0u, 100000u));
  edit_app->add_flag("--upsample", edit.upsample, "fill what the edit stretched, from the points it moved, at each point's pre-edit local spacing (new points: inserted = 1)");
  add_render_options(*edit_app, edit.render, edit.view);
  return {edit_app, [command, &common] { command->run(common); }};
}

} // namespace point_detail
