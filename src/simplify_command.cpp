// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// `point-detail simplify`: simplification sample points.
#include "commands.h"
#include "subcommand_options.h"

#include <CGAL_ext/compute_simplification_sample_points.h>

#include <cmath>
#include <cstdio>

namespace point_detail {
namespace {

/// `simplify`: simplification sample points (SSPs) by recursive splits guided by the mean-shift modes (paper Sect. 5).
struct Simplify_command
{
  std::string input, output, png, clusters, report, view = "front";
  CGAL_ext::Simplification_settings settings;
  std::size_t max_cluster_size = 0; // taken only when the option was given
  CLI::Option* max_cluster_size_option = nullptr;
  Render_settings render;

  void run(const Common_options& common)
  {
    Point_outputs written({input}, output, png, report);
    const fs::path clusters_tmp = add_if_given(written.files, clusters);
    render.view = parse_view(view);
    if(max_cluster_size_option->count() > 0) settings.max_cluster_size = max_cluster_size;
    settings.validate();

    Progress_printer progress(common.quiet);
    Report rep("simplify");
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, settings.mean_shift_neighbors, bytes_per_point::simplify, rep);
    ensure_normals(cloud, progress, rep);
    const std::size_t n = cloud.points.size();
    std::vector<std::size_t> sample_of(n);
    const auto ssps = rep.time("simplify", [&] {
      return CGAL_ext::compute_simplification_sample_points(
        index_range(n), settings, CGAL::make_property_map(sample_of),
        CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
          .normal_map(CGAL::make_property_map(cloud.normals))
          .callback(progress.stage("simplify")));
    });
    progress.finish();
    if(!ssps) throw Cancelled();

    Point_cloud surfels;
    std::vector<double> radius, member_count;
    for(const auto& ssp : ssps.samples) {
      surfels.points.push_back(ssp.centroid);
      surfels.normals.push_back(ssp.normal);
      radius.push_back(ssp.radius);
      member_count.push_back(double(ssp.member_count));
    }
    surfels.set_scalar("radius", std::move(radius));
    surfels.set_scalar("member_count", std::move(member_count));
    rep.time("write", [&] { write_file(written.ply, ply_bytes(surfels, common.scalar_prefix())); });
    const Coloring coloring = label_colors(sample_of);
    cloud.colors = coloring.colors;
    if(!clusters.empty()) {
      std::vector<double> ssp_index(sample_of.begin(), sample_of.end());
      cloud.set_scalar("ssp_index", std::move(ssp_index));
      write_file(clusters_tmp, ply_bytes(cloud, common.scalar_prefix()));
    }
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] { return render_png(cloud.points, cloud.normals, coloring, render); }));

    auto& r = rep.data();
    r["points"] = n;
    r["ssps"] = ssps.size();
    r["points_per_ssp"] = double(n) / double(ssps.size());
    r["max_cluster_size"] = ssps.max_cluster_size;
    r["size_split_ssps"] = ssps.size_split_count;
    r["requested_ssps"] = ssps.requested_count;
    r["mode_threshold"] = std::isfinite(settings.mode_spread_threshold) ? nlohmann::json(settings.mode_spread_threshold)
                                                                        : nlohmann::json("inf");
    const CGAL_ext::Mean_shift_result& ms = ssps.mean_shift;
    if(ms.completed)
      r["mean_shift"] = {{"spatial_bandwidth", ms.spatial_bandwidth}, {"range_bandwidth", ms.range_bandwidth},
                         {"curvature_scale", ms.curvature_scale}, {"mean_iterations", ms.mean_iterations},
                         {"max_iterations", ms.max_iterations}, {"points_at_cap", ms.points_at_cap}};
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
    if(!common.quiet)
      std::fprintf(stderr, "simplify: %zu points -> %zu SSPs (%.1f points each, at most %zu)\n", n, ssps.size(),
                   double(n) / double(ssps.size()), ssps.max_cluster_size);
  }
};

} // namespace

Subcommand add_simplify_command(CLI::App& app, const Common_options& common)
{
  auto command = std::make_shared<Simplify_command>();
  Simplify_command& simplify = *command;
  CLI::App* simplify_app = app.add_subcommand("simplify", "simplification sample points: clusters split until small and of one mean-shift mode (paper Sect. 5)");
  simplify_app
    ->add_option("-i,--input", simplify.input, "input points (.ply, .off, .xyz, .pwn, .pcd, .pts, .ptx, .las)")
    ->required();
  simplify_app->add_option("-o,--output", simplify.output, "output binary PLY of the SSP surfels: position, normal, radius, member_count")->required();
  simplify.max_cluster_size_option = simplify_app->add_option("--max-cluster-size", simplify.max_cluster_size,
    "largest number of points per SSP (default: ceil(points / target))");
  simplify_app->add_option("--target-count,--target", simplify.settings.target_count, "SSP count the clustering aims at: the largest clusters split to it, then the mode-spread rule adds at most half as many again")->capture_default_str();
  simplify_app->add_option("--mode-threshold", simplify.settings.mode_spread_threshold,
    "split while the members' modes spread more than this many range bandwidths (inf: by size only)")->capture_default_str();
  add_neighbor_count_option(*simplify_app, simplify.settings.mean_shift_neighbors, "mean-shift candidates", 5);
  add_setting_option(*simplify_app, "--kernel", simplify.settings.mean_shift.kernel, "mean-shift kernel");
  simplify_app->add_option("--spatial-bandwidth", simplify.settings.mean_shift.spatial_bandwidth, "h_s (0: the average spacing)")->capture_default_str();
  simplify_app->add_option("--range-bandwidth", simplify.settings.mean_shift.range_bandwidth, "h_r over normal and scaled curvature")->capture_default_str();
  simplify_app->add_option("--clusters", simplify.clusters, "also write the input with its ssp_index and cluster colours (PLY)");
  simplify_app->add_option("--png", simplify.png, "also render the input coloured by cluster (paper Fig. 7)");
  simplify_app->add_option("--report", simplify.report, "write stage timings, SSP counts and mean-shift figures as JSON");
  add_render_options(*simplify_app, simplify.render, simplify.view);
  return {simplify_app, [command, &common] { command->run(common); }};
}

} // namespace point_detail
