// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// point-detail: high-frequency geometric details of point-sampled surfaces from the command line.
#include "cli_support.h"
#include "point_io.h"
#include "render.h"

#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_point_set_laplacian.h>
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/estimate_oriented_normals.h>
#include <CGAL_ext/internal/taubin_smoothing.h>

#include <CLI/CLI.hpp>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#include <tbb/info.h>
#endif

#include <cstdio>
#include <iostream>
#include <memory>
#include <numeric>

namespace fs = std::filesystem;
using namespace point_detail;

namespace {

struct Common_options
{
  int threads = 0; // 0: all cores
  bool quiet = false;
};

struct Detail_options
{
  std::string order = "quadric";
  double lambda = CGAL_ext::Detail_filter().lambda, mu = CGAL_ext::Detail_filter().mu;
  unsigned int k = CGAL_ext::default_laplacian_neighbors;
  std::string weights = "uniform";

  CGAL_ext::Detail_settings settings() const
  {
    CGAL_ext::Detail_settings s;
    s.filter.order = order == "linear" ? CGAL_ext::Detail_order::linear
                     : order == "cubic" ? CGAL_ext::Detail_order::cubic
                                        : CGAL_ext::Detail_order::quadric;
    s.filter.lambda = lambda;
    s.filter.mu = mu;
    s.weights.weighting = weights == "distance" ? CGAL_ext::Laplacian_weighting::distance_power
                                                : CGAL_ext::Laplacian_weighting::uniform;
    return s;
  }
};

void add_detail_options(CLI::App& app, Detail_options& o)
{
  app.add_option("--order", o.order, "transfer function")->check(CLI::IsMember({"linear", "quadric", "cubic"}))->capture_default_str();
  app.add_option("--lambda", o.lambda, "pass-band frequency (> 0)")->capture_default_str();
  app.add_option("--mu", o.mu, "highest frequency (> lambda; quadric and cubic)")->capture_default_str();
  app.add_option("-k,--neighbors", o.k, "nearest neighbours of the Laplacian, the point itself not counted")->capture_default_str();
  app.add_option("--weights", o.weights, "Laplacian weights: uniform (1/valence) or distance (|p_i - p_j|^-1)")
    ->check(CLI::IsMember({"uniform", "distance"}))->capture_default_str();
}

std::vector<std::size_t> index_range(std::size_t n)
{
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  return idx;
}

/// Gives the cloud normals when it has none: CGAL jet estimation and MST orientation.
void ensure_normals(Point_cloud& cloud, Progress_printer& progress, Report& report)
{
  report.data()["normal_source"] = cloud.normals.empty() ? "estimated" : cloud.normal_source;
  if(!cloud.normals.empty()) return;
  report.time("normals", [&] {
    const auto spatial = CGAL_ext::internal::make_spatial_point_cloud<CGAL::Parallel_if_available_tag>(
      cloud.points, CGAL::Identity_property_map<const Point>(), "normal estimation");
    if(spatial.size() < 3) throw Cli_error("normal estimation needs at least 3 points");
    CGAL_ext::internal::Progress p(progress.stage("normals"));
    CGAL_ext::internal::Matrix_n3 normals;
    if(!CGAL_ext::internal::estimate_oriented_normals<CGAL::Parallel_if_available_tag>(
         spatial, CGAL_ext::default_normal_neighbors, p, normals))
      throw Cancelled();
    cloud.normals.resize(cloud.points.size());
    for(std::size_t s = 0; s < spatial.size(); ++s)
      cloud.normals[std::size_t(spatial.input_index[s])] = Vector(normals(Eigen::Index(s), 0), normals(Eigen::Index(s), 1), normals(Eigen::Index(s), 2));
    cloud.normal_source = "estimated";
  });
}

/// Adds detail_x/y/z, detail_magnitude and the colour map to `cloud` (which has normals).
void add_details(Point_cloud& cloud, const Detail_options& options, Progress_printer& progress, Report& report)
{
  const std::size_t n = cloud.points.size();
  std::vector<Vector> details(n);
  std::vector<double> magnitude(n);
  const auto settings = options.settings();
  const bool done = report.time("details", [&] {
    return CGAL_ext::compute_geometric_details(
      index_range(n), options.k, settings, CGAL::make_property_map(details), CGAL::make_property_map(magnitude),
      CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
        .normal_map(CGAL::make_property_map(cloud.normals))
        .callback(progress.stage("details")));
  });
  progress.finish();
  if(!done) throw Cancelled();
  std::vector<double> dx(n), dy(n), dz(n);
  for(std::size_t i = 0; i < n; ++i) { dx[i] = details[i].x(); dy[i] = details[i].y(); dz[i] = details[i].z(); }
  cloud.set_scalar("detail_x", std::move(dx));
  cloud.set_scalar("detail_y", std::move(dy));
  cloud.set_scalar("detail_z", std::move(dz));
  double range = 0;
  cloud.colors = diverging_colors(magnitude, &range);
  cloud.set_scalar("detail_magnitude", std::move(magnitude));
  auto& r = report.data();
  r["points"] = n;
  r["k"] = options.k;
  r["order"] = options.order;
  r["lambda"] = options.lambda;
  if(settings.filter.order != CGAL_ext::Detail_order::linear) r["mu"] = options.mu;
  r["weights"] = options.weights;
  r["color_range"] = range;
}

/// The detail colours shown on a low-pass base surface (paper Fig. 3).
std::string render_on_base_surface(const Point_cloud& cloud, unsigned int k, const Render_settings& render,
                                   Report& report)
{
  const std::vector<Point> base = report.time("base_surface", [&] {
    Eigen::SparseMatrix<double, Eigen::RowMajor, int> K;
    CGAL_ext::compute_point_set_laplacian(cloud.points, k, {}, K);
    CGAL_ext::internal::Matrix_n3 X(Eigen::Index(cloud.points.size()), 3);
    for(std::size_t i = 0; i < cloud.points.size(); ++i) X.row(Eigen::Index(i)) << cloud.points[i].x(), cloud.points[i].y(), cloud.points[i].z();
    X = CGAL_ext::internal::taubin_smoothing<CGAL::Parallel_if_available_tag>(K, X);
    std::vector<Point> out(cloud.points.size());
    for(std::size_t i = 0; i < out.size(); ++i) out[i] = Point(X(Eigen::Index(i), 0), X(Eigen::Index(i), 1), X(Eigen::Index(i), 2));
    return out;
  });
  return report.time("render", [&] { return render_png(base, cloud.normals, cloud.colors, render); });
}

void add_render_options(CLI::App& app, Render_settings& r, std::string& view)
{
  app.add_option("--view", view, "front|back|left|right|top|bottom|iso or AZIMUTH,ELEVATION (degrees)")->capture_default_str();
  app.add_option("--width", r.width, "picture width in pixels")->check(CLI::Range(16, 8192))->capture_default_str();
  app.add_option("--height", r.height, "picture height in pixels")->check(CLI::Range(16, 8192))->capture_default_str();
  app.add_option("--splat", r.splat_scale, "splat size relative to the sample spacing")->check(CLI::Range(0.1, 10.0))->capture_default_str();
}

// ---- subcommands -------------------------------------------------------------------------------------------

struct Details_command
{
  std::string input, output, png, report, view = "front";
  Detail_options detail;
  Render_settings render;

  void run(const Common_options& common)
  {
    Output_files outputs({input});
    const fs::path ply_tmp = outputs.add(output);
    const fs::path png_tmp = png.empty() ? fs::path() : outputs.add(png);
    const fs::path report_tmp = report.empty() ? fs::path() : outputs.add(report);
    render.view = parse_view(view);
    detail.settings().validate(); // before the (possibly long) read

    Progress_printer progress(common.quiet);
    Report rep("details");
    rep.data()["input"] = input;
    Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input); });
    if(cloud.points.size() <= detail.k)
      throw Cli_error(input + " has " + std::to_string(cloud.points.size()) + " points: -k " + std::to_string(detail.k) +
                      " needs more than k points");
    ensure_normals(cloud, progress, rep);
    add_details(cloud, detail, progress, rep);
    rep.time("write", [&] { write_file(ply_tmp, ply_bytes(cloud)); });
    if(!png.empty()) write_file(png_tmp, render_on_base_surface(cloud, detail.k, render, rep));
    if(!report.empty()) write_file(report_tmp, rep.dump());
    outputs.commit();
  }
};

struct Render_command
{
  std::string input, output, color_by, report, view = "front";
  Render_settings render;

  void run(const Common_options&)
  {
    Output_files outputs({input});
    const fs::path png_tmp = outputs.add(output);
    const fs::path report_tmp = report.empty() ? fs::path() : outputs.add(report);
    render.view = parse_view(view);
    Report rep("render");
    rep.data()["input"] = input;
    const Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input); });
    rep.data()["points"] = cloud.points.size();
    std::vector<Color> colors;
    std::string by = color_by;
    if(by.empty()) by = !cloud.colors.empty() ? "rgb" : cloud.scalar("detail_magnitude") ? "detail_magnitude" : "none";
    if(by == "rgb") {
      if(cloud.colors.empty()) throw Cli_error(input + " has no red/green/blue properties to colour by");
      colors = cloud.colors;
    } else if(by != "none") {
      const std::vector<double>* values = cloud.scalar(by);
      if(!values) {
        std::string names;
        for(const auto& s : cloud.scalars) names += " " + s.first;
        throw Cli_error(input + " has no property '" + by + "' (it has:" + (names.empty() ? " none" : names) + "; or use rgb, none)");
      }
      const auto [lo, hi] = std::minmax_element(values->begin(), values->end());
      colors = (*lo < 0 && *hi > 0) ? diverging_colors(*values) : sequential_colors(*values);
    }
    rep.data()["color_by"] = by;
    write_file(png_tmp, rep.time("render", [&] { return render_png(cloud.points, cloud.normals, colors, render); }));
    if(!report.empty()) write_file(report_tmp, rep.dump());
    outputs.commit();
  }
};

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
    const fs::path report_tmp = report.empty() ? fs::path() : outputs.add(report);
    nlohmann::json runs = nlohmann::json::array();
    Progress_printer progress(common.quiet);
    Render_settings render;
    render.view = parse_view("iso");

    // The paper's tentacle (Fig. 8): a bent tube with bumps.
    const auto tube = CGAL_ext::shapes::bumpy_tube<Kernel>(points);
    Point_cloud input;
    input.points = tube.points;
    input.normals = tube.normals;
    write_file(outputs.add(dir / "tentacle.ply"), ply_bytes(input));
    write_file(outputs.add(dir / "tentacle.png"), render_png(input.points, input.normals, {}, render));
    std::printf("demo: tentacle of %zu points with exact normals\n", input.points.size());
    for(const char* order : {"linear", "quadric", "cubic"}) {
      Detail_options options;
      options.order = order;
      Point_cloud cloud = input;
      Report rep(std::string("demo details ") + order);
      add_details(cloud, options, progress, rep);
      const std::string stem = std::string("details_") + order;
      write_file(outputs.add(dir / (stem + ".ply")), ply_bytes(cloud));
      write_file(outputs.add(dir / (stem + ".png")), render_on_base_surface(cloud, options.k, render, rep));
      std::printf("demo: %-7s details (lambda %.1f, mu %.1f, k %u) in %.3f s -> %s.ply, %s.png\n", order, options.lambda,
                  options.mu, options.k, rep.data()["timings_s"]["details"].get<double>(), stem.c_str(), stem.c_str());
      runs.push_back(rep.data());
    }
    if(!report.empty()) write_file(report_tmp, nlohmann::json{{"command", "demo"}, {"runs", runs}}.dump(2) + "\n");
    outputs.commit();
    std::printf("demo: wrote %s/{tentacle,details_linear,details_quadric,details_cubic}.{ply,png}\n", directory.c_str());
  }
};

} // namespace

int main(int argc, char** argv)
{
  CLI::App app{"point-detail: high-frequency geometric details of point-sampled surfaces (Miao et al. 2007)"};
  app.require_subcommand(1);
  Common_options common;
  app.add_option("--threads", common.threads, "worker threads (0: all cores)")->check(CLI::NonNegativeNumber);
  app.add_flag("-q,--quiet", common.quiet, "no progress on stderr");

  Details_command details;
  CLI::App* details_app = app.add_subcommand("details", "geometric details of every point, as PLY properties and a colour map");
  details_app->add_option("-i,--input", details.input, "input points (.ply, .off, .xyz, .pwn)")->required();
  details_app->add_option("-o,--output", details.output, "output binary PLY")->required();
  details_app->add_option("--png", details.png, "also render the colour map on the base surface");
  details_app->add_option("--report", details.report, "write stage timings and counts as JSON");
  add_detail_options(*details_app, details.detail);
  add_render_options(*details_app, details.render, details.view);

  Render_command render;
  CLI::App* render_app = app.add_subcommand("render", "headless PNG picture of a point set");
  render_app->add_option("-i,--input", render.input, "input points")->required();
  render_app->add_option("-o,--output", render.output, "output PNG")->required();
  render_app->add_option("--color-by", render.color_by, "rgb, none or a scalar property (default: rgb, else detail_magnitude)");
  render_app->add_option("--report", render.report, "write stage timings and counts as JSON");
  add_render_options(*render_app, render.render, render.view);

  Demo_command demo;
  CLI::App* demo_app = app.add_subcommand("demo", "colour maps of the three detail orders on a generated tentacle");
  demo_app->add_option("-o,--output", demo.directory, "output directory (created)")->capture_default_str();
  demo_app->add_option("--report", demo.report, "write stage timings and counts as JSON");
  demo_app->add_option("--points", demo.points, "number of samples")->check(CLI::Range(1000, 5000000))->capture_default_str();

  CLI11_PARSE(app, argc, argv);
  install_interrupt_handler();
#ifdef CGAL_LINKED_WITH_TBB
  std::unique_ptr<tbb::global_control> threads;
  if(common.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(common.threads));
#endif
  try {
    if(*details_app) details.run(common);
    if(*render_app) render.run(common);
    if(*demo_app) demo.run(common);
  } catch(const Cancelled&) {
    std::fprintf(stderr, "\npoint-detail: cancelled; nothing written\n");
    return 130;
  } catch(const Cli_error& e) {
    std::fprintf(stderr, "point-detail: error: %s\n", e.what());
    return 1;
  } catch(const CGAL_ext::Invalid_input& e) {
    std::fprintf(stderr, "point-detail: invalid input: %s\n", e.what());
    return 1;
  } catch(const std::exception& e) {
    std::fprintf(stderr, "point-detail: failed: %s\n", e.what());
    return 3;
  }
  return 0;
}
