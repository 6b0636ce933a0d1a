// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail edit`: detail-preserving editing by handles.
#include "commands.h"
#include "operations.h"

#include <cstdio>
#include <functional>
#include <type_traits>
#include <utility>
#include <vector>

namespace point_detail {
namespace {

/// Above this ratio of the largest sample-point displacement to the handles' largest, `edit` warns.
constexpr double swing_warning_ratio = 2.0;

/// `edit`: detail-preserving editing of a region by handles (paper Sect. 6).
struct Edit_command
{
  using Settings = CGAL_ext::Detail_preserving_deformation_settings;
  std::string input, output, edit, sel, def, png, report, view = "front";
  Settings options; // the settings the command line gives
  // Each setting option, and how it overrides the edit file's setting when given.
  std::vector<std::pair<CLI::Option*, std::function<void(Settings&, const Settings&)>>> overrides;
  bool upsample = false;
  Render_settings render;

  /// The edit with the command line's settings over the file's, checked.
  Edit_description with_overrides(Edit_description description) const
  {
    for(const auto& [option, apply] : overrides)
      if(option->count() > 0) apply(description.settings, options);
    description.settings.validate();
    return description;
  }

  /// Runs the steps of `chain` on `cloud` (which has normals), each on the result of the one before (doc/editing.md,
  /// "Chains of steps"). The result holds the points and normals, each input point's distance from where it
  /// started (`displacement`), `status` and `ssp_index` of the last edit step and, after a fill, `inserted`.
  Point_cloud run_chain(const Point_cloud& cloud, const std::vector<Edit_step>& chain, Progress_printer& progress,
                        Report& rep) const
  {
    Point_cloud state;
    state.points = cloud.points;
    state.normals = cloud.normals;
    std::vector<double> status, sample; // of the last edit step
    std::vector<std::size_t> moved;     // the points the last edit step moved
    std::vector<double> spacing_before; // and their spacing before it
    bool filled = false;
    for(std::size_t s = 0; s < chain.size(); ++s) {
      const Edit_step& step = chain[s];
      if(step.kind == Edit_step::Kind::edit) {
        const Edit_description description = with_overrides(step.edit(state.points));
        if(s + 1 < chain.size() && chain[s + 1].kind == Edit_step::Kind::fill) spacing_before = local_spacing(state);
        Point_cloud out;
        run_edit(state, description, progress, rep, out);
        const std::vector<double>& displacement = *out.scalar("displacement");
        moved.clear();
        for(std::size_t i = 0; i < displacement.size(); ++i)
          if(displacement[i] > 0) moved.push_back(i);
        status = *out.scalar("status");
        sample = *out.scalar("ssp_index");
        if(rep.data().contains("restore_details"))
          rep.data()["restore_details"]["tolerance"] = description.settings.detail_tolerance;
        state.points = std::move(out.points);
        state.normals = std::move(out.normals);
      } else if(step.kind == Edit_step::Kind::fill) {
        Point_cloud grown;
        grown.points = state.points;
        grown.normals = state.normals;
        upsample_cloud(grown, CGAL_ext::Upsampling_settings(), &moved, &spacing_before, progress, rep);
        state = std::move(grown);
        filled = true;
      } else {
        const bool enhance = step.kind == Edit_step::Kind::enhance;
        const std::vector<std::size_t> region = step.region(state.points);
        if(step.k >= state.points.size())
          throw Cli_error(step.where + ": k = " + std::to_string(step.k) +
                          " must be smaller than the number of points (" + std::to_string(state.points.size()) + ")");
        CGAL_ext::Detail_enhancement_settings settings{CGAL_ext::Detail_settings(step.filter)};
        settings.validate();
        Point_cloud out;
        const char* name = enhance ? "enhance" : "scale";
        const bool done = rep.time(name, [&] {
          return bool(
            manipulate(enhance, state, region, nullptr, step.factor, step.k, settings, progress.stage(name), out));
        });
        progress.finish();
        if(!done) throw Cancelled();
        state.points = std::move(out.points);
        state.normals = std::move(out.normals);
      }
    }
    const std::size_t n = state.points.size(), input_size = cloud.points.size();
    std::vector<double> displacement(n, 0.0);
    for(std::size_t i = 0; i < input_size; ++i)
      displacement[i] = std::sqrt(CGAL::squared_distance(state.points[i], cloud.points[i]));
    state.colors =
      sequential_colors(std::vector<double>(displacement.begin(), displacement.begin() + std::ptrdiff_t(input_size)))
        .colors;
    state.colors.resize(n, flag_color);
    state.set_scalar("displacement", std::move(displacement));
    if(!status.empty()) {
      status.resize(n, 0.0);
      sample.resize(n, 0.0);
      state.set_scalar("status", std::move(status));
      state.set_scalar("ssp_index", std::move(sample));
    }
    if(filled) {
      std::vector<double> inserted(n, 0.0);
      std::fill(inserted.begin() + std::ptrdiff_t(input_size), inserted.end(), 1.0);
      state.set_scalar("inserted", std::move(inserted));
    }
    rep.data()["steps"] = chain.size();
    return state;
  }

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
    Point_cloud cloud = read_input(input, bytes_per_point::edit, rep);
    if(cloud.points.size() < 2) throw Cli_error(input + " has fewer than 2 points");
    std::vector<Edit_step> chain;
    if(edit.empty()) {
      chain.emplace_back();
      chain.back().where = sel;
      chain.back().edit = [d = read_botsch_sorkine(sel, def, cloud.points.size())](const std::vector<Point>&) {
        return d;
      };
    } else {
      chain = read_edit_chain(edit);
    }
    if(upsample) {
      if(chain.back().kind != Edit_step::Kind::edit)
        throw Cli_error("--upsample fills what the last edit step stretched, but " + chain.back().where +
                        " is not an edit");
      chain.emplace_back();
      chain.back().kind = Edit_step::Kind::fill;
    }
    for(const Edit_step& step : chain) // the command line's settings over each edit's, checked before any step runs
      if(step.kind == Edit_step::Kind::edit) {
        Edit_description settings_only;
        settings_only.settings = step.settings;
        with_overrides(settings_only);
      }
    ensure_normals(cloud, progress, rep);
    const Point_cloud out = run_chain(cloud, chain, progress, rep);
    rep.time("write", [&] { write_file(written.ply, ply_bytes(out, common.scalar_prefix())); });
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] { return render_png(out.points, out.normals, edit_coloring(out), render); }));
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
    if(!common.quiet && rep.data().contains("ssps")) {
      const auto& r = rep.data();
      std::fprintf(stderr, "edit: %zu points, %zu SSPs (%zu in the region): editing the SSPs %.3f s, diffusion %.3f s\n",
                   r["points"].get<std::size_t>(), r["ssps"].get<std::size_t>(), r["roi_ssps"].get<std::size_t>(),
                   r["table1"]["editing_ssps_s"].get<double>(), r["table1"]["diffusion_s"].get<double>());
      if(r["requested_ssps"].get<std::size_t>() > r["ssps"].get<std::size_t>())
        std::fprintf(stderr, "edit: the mode-spread rule asked for %zu SSPs; the budget kept %zu\n",
                     r["requested_ssps"].get<std::size_t>(), r["ssps"].get<std::size_t>());
    }
    // Printed even with --quiet: the result is probably not what the user wanted.
    if(rep.data().value("displacement_ratio", 0.0) > swing_warning_ratio)
      std::fprintf(stderr, "point-detail: warning: parts of the region moved %.1f times as far as any handle (the solve "
                   "swings them; try --order quadric or --rotations arap)\n", rep.data()["displacement_ratio"].get<double>());
    if(rep.data().contains("restore_details") && rep.data()["restore_details"]["residual"].get<double>() >
                                                   rep.data()["restore_details"]["tolerance"].get<double>())
      std::fprintf(stderr,
                   "point-detail: warning: putting back the fine details stopped after %u steps at a residual "
                   "of %.2g (tolerance %.2g); raise --detail-iterations\n",
                   rep.data()["restore_details"]["iterations"].get<unsigned>(),
                   rep.data()["restore_details"]["residual"].get<double>(),
                   rep.data()["restore_details"]["tolerance"].get<double>());
  }
};

} // namespace

Subcommand add_edit_command(CLI::App& app, const Common_options& common)
{
  auto command = std::make_shared<Edit_command>();
  Edit_command& edit = *command;
  CLI::App* edit_app = app.add_subcommand("edit", "detail-preserving editing by handles on simplification sample points (paper Sect. 6)");
  edit_app->add_option("-i,--input", edit.input, "input points (.ply, .off, .xyz, .pwn, .pcd, .pts, .ptx, .las)")
    ->required();
  edit_app->add_option("-o,--output", edit.output, "output binary PLY: deformed points and normals, displacement, status, ssp_index")->required();
  auto* edit_json = edit_app->add_option("--edit", edit.edit, "edit description (JSON: roi, handles with transforms, settings; doc/editing.md)");
  auto* edit_sel = edit_app->add_option("--sel", edit.sel, "Botsch-Sorkine selection: one status per point (0 fixed, 1 deformable, 2 handle)");
  auto* edit_def = edit_app->add_option("--def", edit.def, "Botsch-Sorkine handle transform: a 4x4 matrix");
  edit_json->excludes(edit_sel)->excludes(edit_def);
  edit_sel->needs(edit_def);
  edit_def->needs(edit_sel);
  edit_app->add_option("--png", edit.png, "also render the result, coloured by the distance each point moved");
  edit_app->add_option("--report", edit.report, "write the paper's Table 1 fields, stage timings and solver figures as JSON");
  using Settings = Edit_command::Settings;
  using CGAL_ext::Detail_filter;
  using CGAL_ext::Simplification_settings;
  Settings& o = edit.options;
  // When `option` is given, its value (the member at `path` of the command line's settings) overrides the edit
  // file's.
  const auto overriding = [&edit](CLI::Option* option, auto... path) {
    edit.overrides.emplace_back(option, [=](Settings& s, const Settings& c) { (s .* ... .* path) = (c .* ... .* path); });
    return option;
  };
  // The option of the setting at `path`: an enum's by the names of its values, any other as given.
  const auto setting = [&](const std::string& name, const std::string& description, auto... path) {
    auto& value = (o .* ... .* path);
    if constexpr(std::is_enum_v<std::decay_t<decltype(value)>>)
      return overriding(add_setting_option(*edit_app, name, value, description), path...);
    else
      return overriding(edit_app->add_option(name, value, description), path...);
  };
  // The settings' own names (doc/editing.md, "Edit files"); the names after a comma are older spellings.
  setting("--order", "transfer function (overrides the edit file)", &Settings::filter, &Detail_filter::order);
  setting("--lambda", "pass-band frequency (> 0)", &Settings::filter, &Detail_filter::lambda);
  setting("--mu", "highest frequency (> lambda; quadric and cubic)", &Settings::filter, &Detail_filter::mu);
  overriding(add_neighbor_count_option(*edit_app, o.sample_neighbors, "Laplacian row", 1, "sample point"),
             &Settings::sample_neighbors);
  setting("--strength-distance,--strength", "distances of the strength field: euclidean (the paper's) or geodesic",
          &Settings::strength_distance);
  setting("--diffusion-samples", "sample points that carry each point", &Settings::diffusion_samples);
  setting("--diffusion-origin", "own (p - ssp_i in frame i, default) or nearest (the paper's p - ssp_0)",
          &Settings::diffusion_origin);
  setting("--diffusion-turn",
          "affine (each SSP's best linear map of its neighbourhood, default), fitted (its best rotation) or frames "
          "(the paper's local frames)",
          &Settings::diffusion_turn);
  setting("--handle-weight", "weight of soft handle constraints (the paper's, e.g. 1); default: exact handles",
          &Settings::handle_weight);
  setting("--max-cluster-size", "largest number of points per SSP", &Settings::simplification,
          &Simplification_settings::max_cluster_size);
  setting("--target-count,--target",
          "SSP count the clustering aims at, at most 1.5 times it with the mode-spread rule (default 3000)",
          &Settings::simplification, &Simplification_settings::target_count);
  setting("--rotations", "how the details turn: none, propagate (the paper's), arap (as rigid as possible)",
          &Settings::rotations);
  setting("--rigid-iterations", "with --rotations arap: rotation fits and solves", &Settings::rigid_iterations)
    ->check(CLI::Range(1u, 1000u));
  setting("--rigid-rotation-smoothing,--rigid-smoothing",
          "with --rotations arap: weight of SRE-ARAP's smooth-rotation term (about 1: near CGAL's SRE_ARAP, with "
          "--rigid-iterations 10 or more; default 0)",
          &Settings::rigid_rotation_smoothing)
    ->check(CLI::NonNegativeNumber);
  setting("--rigid-rotation-smoothing-scale,--rigid-smoothing-scale",
          "with --rigid-rotation-smoothing: what its weight is relative to, edge_lengths (default: the same at every "
          "density) or surface_area (CGAL's SRE_ARAP: --rigid-rotation-smoothing 0.02 with --rigid-edge-weights "
          "cotangent is its energy)",
          &Settings::rigid_rotation_smoothing_scale);
  setting("--rigid-edge-weights,--rigid-weights",
          "with --rotations arap: weights of the SSP graph's edges, uniform (default) or cotangent (from each SSP's "
          "Voronoi cell in its tangent plane: nearer a mesh ARAP on large bends)",
          &Settings::rigid_edge_weights);
  setting("--detail-iterations",
          "at most this many steps to put back the fine details the diffusion smoothed (default 100, 0: none)",
          &Settings::detail_iterations)
    ->check(CLI::Range(0u, 100000u));
  edit_app->add_flag("--upsample", edit.upsample, "fill what the edit stretched, from the points it moved, at each point's pre-edit local spacing (new points: inserted = 1)");
  add_render_options(*edit_app, edit.render, edit.view);
  return {edit_app, [command, &common] { command->run(common); }};
}

} // namespace point_detail
