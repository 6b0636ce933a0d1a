// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// point-detail: high-frequency geometric details of point-sampled surfaces from the command line.
#include "cli_support.h"
#include "point_io.h"
#include "region_spec.h"
#include "render.h"

#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/estimate_oriented_normals.h>
#include <CGAL_ext/scale_geometric_details.h>

#include <CLI/CLI.hpp>

#include <boost/property_map/function_property_map.hpp>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#include <tbb/info.h>
#endif

#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
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
  std::string weights = "uniform", neighbors = "knn";

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
    s.neighborhood = neighbors == "mean-shift" ? CGAL_ext::Laplacian_neighborhood::mean_shift
                                               : CGAL_ext::Laplacian_neighborhood::k_nearest;
    return s;
  }
};

void add_detail_options(CLI::App& app, Detail_options& o)
{
  app.add_option("--order", o.order, "transfer function")->check(CLI::IsMember({"linear", "quadric", "cubic"}))->capture_default_str();
  app.add_option("--lambda", o.lambda, "pass-band frequency (> 0)")->capture_default_str();
  app.add_option("--mu", o.mu, "highest frequency (> lambda; quadric and cubic)")->capture_default_str();
  app.add_option("-k,--neighbor-count", o.k, "nearest neighbours of the Laplacian, the point itself not counted")->capture_default_str();
  app.add_option("--neighbors", o.neighbors, "Laplacian neighbourhoods: knn (symmetrised k nearest) or mean-shift (the k "
                                             "nearest whose mean-shift modes agree, so rows stop at creases)")
    ->check(CLI::IsMember({"knn", "mean-shift"}))->capture_default_str();
  app.add_option("--weights", o.weights, "Laplacian weights: uniform (1/valence) or distance (|p_i - p_j|^-1)")
    ->check(CLI::IsMember({"uniform", "distance"}))->capture_default_str();
}

std::vector<std::size_t> index_range(std::size_t n)
{
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  return idx;
}

/// The temporary file to write an optional output to, or an empty path when the option was not given.
fs::path add_if_given(Output_files& outputs, const std::string& destination)
{
  return destination.empty() ? fs::path() : outputs.add(destination);
}

/// Reads `input` (timed in the report) and checks that it has more than `k` points.
Point_cloud read_for_neighbors(const std::string& input, unsigned int k, Report& rep)
{
  Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input); });
  if(cloud.points.size() <= k)
    throw Cli_error(input + " has " + std::to_string(cloud.points.size()) + " points: -k " + std::to_string(k) +
                    " needs more than k points");
  return cloud;
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
  r["neighbors"] = options.neighbors;
  r["color_range"] = range;
}

/// The detail colours shown on the balanced-flow base surface (paper Fig. 3).
std::string render_on_base_surface(const Point_cloud& cloud, unsigned int k, const Render_settings& render,
                                   Report& report)
{
  std::vector<Point> base = cloud.points;
  std::vector<std::size_t> indices = index_range(base.size());
  report.time("base_surface", [&] {
    CGAL_ext::balanced_flow_smooth_point_set(indices, k, CGAL_ext::Balanced_flow_settings(),
                                             CGAL::parameters::point_map(CGAL::make_property_map(base))
                                               .normal_map(CGAL::make_property_map(cloud.normals)));
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
    const fs::path png_tmp = add_if_given(outputs, png);
    const fs::path report_tmp = add_if_given(outputs, report);
    render.view = parse_view(view);
    detail.settings().validate(); // before the (possibly long) read

    Progress_printer progress(common.quiet);
    Report rep("details");
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, detail.k, rep);
    ensure_normals(cloud, progress, rep);
    add_details(cloud, detail, progress, rep);
    rep.time("write", [&] { write_file(ply_tmp, ply_bytes(cloud)); });
    if(!png.empty()) write_file(png_tmp, render_on_base_surface(cloud, detail.k, render, rep));
    if(!report.empty()) write_file(report_tmp, rep.dump());
    outputs.commit();
  }
};

/// Scales (or enhances) the details of `region` of `cloud` (which has normals) by `factor`; `out` receives the
/// moved points with the input's normals, their displacement along the normal and the region flag.
CGAL_ext::Detail_manipulation_result manipulate(bool enhance, const Point_cloud& cloud, const std::vector<std::size_t>& region,
                                                const std::vector<std::size_t>* anchors, double factor, unsigned int k,
                                                const CGAL_ext::Detail_enhancement_settings& settings,
                                                const std::function<bool(double)>& callback, Point_cloud& out)
{
  std::vector<Point> moved = cloud.points;
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(moved))
                    .normal_map(CGAL::make_property_map(cloud.normals))
                    .callback(callback);
  std::vector<std::size_t> all = index_range(moved.size());
  CGAL_ext::Detail_manipulation_result result;
  if(enhance && anchors) {
    std::vector<char> anchored(moved.size(), 0);
    for(std::size_t a : *anchors) anchored[a] = 1;
    const auto is_anchor = boost::make_function_property_map<std::size_t, bool>([&](std::size_t i) { return anchored[i] != 0; });
    result = CGAL_ext::enhance_geometric_details(all, k, region, factor, settings, np.point_is_constrained_map(is_anchor));
  } else if(enhance) {
    result = CGAL_ext::enhance_geometric_details(all, k, region, factor, settings, np);
  } else if(anchors) {
    result = CGAL_ext::scale_geometric_details(all, k, region, *anchors, factor, settings, np);
  } else {
    result = CGAL_ext::scale_geometric_details(all, k, region, factor, settings, np);
  }
  if(!result) return result;
  std::vector<double> displacement(moved.size()), in_roi(moved.size(), 0.0);
  for(std::size_t i = 0; i < moved.size(); ++i) displacement[i] = (moved[i] - cloud.points[i]) * cloud.normals[i];
  for(std::size_t i : region) in_roi[i] = 1.0;
  out = Point_cloud();
  out.points = std::move(moved);
  out.normals = cloud.normals;
  out.set_scalar("displacement", std::move(displacement));
  out.set_scalar("in_roi", std::move(in_roi));
  return result;
}

/// `scale` and `enhance`: move a region so that its details become s times larger (paper Sect. 4).
struct Manipulate_command
{
  bool enhance = false;
  std::string input, output, png, report, view = "front", solver = "cholesky";
  double factor = 1;
  std::vector<std::string> roi, anchors;
  std::string border = "auto";
  Detail_options detail;
  Render_settings render;

  void run(const Common_options& common)
  {
    const char* name = enhance ? "enhance" : "scale";
    Output_files outputs({input});
    const fs::path ply_tmp = outputs.add(output);
    const fs::path png_tmp = add_if_given(outputs, png);
    const fs::path report_tmp = add_if_given(outputs, report);
    render.view = parse_view(view);
    std::vector<Region_spec> roi_specs, anchor_specs;
    for(const std::string& t : roi) roi_specs.push_back(parse_region_spec(t));
    for(const std::string& t : anchors) anchor_specs.push_back(parse_region_spec(t));
    CGAL_ext::Detail_enhancement_settings settings(detail.settings());
    settings.least_squares.solver = solver == "cg" ? CGAL_ext::Linear_solver::conjugate_gradient : CGAL_ext::Linear_solver::cholesky;
    settings.border_anchoring = border == "anchored" ? CGAL_ext::Border_anchoring::anchored
                                : border == "free"   ? CGAL_ext::Border_anchoring::free
                                                     : CGAL_ext::Border_anchoring::automatic;
    settings.validate();

    Progress_printer progress(common.quiet);
    Report rep(name);
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, detail.k, rep);
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
    rep.time("write", [&] { write_file(ply_tmp, ply_bytes(out)); });
    if(!png.empty())
      write_file(png_tmp, rep.time("render", [&] {
        return render_png(out.points, out.normals, diverging_colors(*out.scalar("displacement")), render);
      }));
    auto& r = rep.data();
    r["points"] = out.points.size();
    r["factor"] = factor;
    r["order"] = detail.order;
    r["neighbors"] = detail.neighbors;
    r["roi_points"] = result.region_size;
    r["anchors"] = result.anchor_count;
    r["default_anchors"] = result.default_anchors;
    const CGAL_ext::Least_squares_statistics& ls = result.least_squares;
    r["solver"] = {{"method", ls.method}, {"operator_nonzeros", ls.operator_nonzeros}, {"normal_nonzeros", ls.normal_nonzeros},
                   {"assembly_s", ls.assembly_seconds}, {"factor_s", ls.factor_seconds}, {"solve_s", ls.solve_seconds},
                   {"iterations", ls.iterations}, {"relative_residual", ls.relative_residual}};
    if(!report.empty()) write_file(report_tmp, rep.dump());
    outputs.commit();
  }
};

/// `curvature`: signed mean curvature per point (positive where the surface bends away from its normal).
struct Curvature_command
{
  std::string input, output, png, report, view = "front", fitting = "monge";
  unsigned int k = CGAL_ext::default_curvature_neighbors;
  Render_settings render;

  void run(const Common_options& common)
  {
    Output_files outputs({input});
    const fs::path ply_tmp = outputs.add(output);
    const fs::path png_tmp = add_if_given(outputs, png);
    const fs::path report_tmp = add_if_given(outputs, report);
    render.view = parse_view(view);
    Progress_printer progress(common.quiet);
    Report rep("curvature");
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, k, rep);
    ensure_normals(cloud, progress, rep);
    const std::size_t n = cloud.points.size();
    std::vector<double> H(n);
    const bool done = rep.time("curvature", [&] {
      return CGAL_ext::estimate_mean_curvature(
        index_range(n), k, fitting == "closed-form" ? CGAL_ext::Curvature_fitting::closed_form : CGAL_ext::Curvature_fitting::monge_jet_fitting,
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
    r["fitting"] = fitting;
    r["curvature_percentiles"] = {{"p02", sorted[n / 50]}, {"p50", sorted[n / 2]}, {"p98", sorted[n - 1 - n / 50]}};
    cloud.colors = diverging_colors(H);
    cloud.set_scalar("mean_curvature", std::move(H));
    rep.time("write", [&] { write_file(ply_tmp, ply_bytes(cloud)); });
    if(!png.empty())
      write_file(png_tmp, rep.time("render", [&] { return render_png(cloud.points, cloud.normals, cloud.colors, render); }));
    if(!report.empty()) write_file(report_tmp, rep.dump());
    outputs.commit();
  }
};

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
    Output_files outputs({input});
    const fs::path ply_tmp = outputs.add(output);
    const fs::path png_tmp = add_if_given(outputs, png);
    const fs::path clusters_tmp = add_if_given(outputs, clusters);
    const fs::path report_tmp = add_if_given(outputs, report);
    render.view = parse_view(view);
    if(max_cluster_size_option->count() > 0) settings.max_cluster_size = max_cluster_size;
    settings.validate();

    Progress_printer progress(common.quiet);
    Report rep("simplify");
    rep.data()["input"] = input;
    Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input); });
    if(cloud.points.empty()) throw Cli_error(input + " has no points");
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
    rep.time("write", [&] { write_file(ply_tmp, ply_bytes(surfels)); });
    cloud.colors = label_colors(sample_of);
    if(!clusters.empty()) {
      std::vector<double> ssp_index(sample_of.begin(), sample_of.end());
      cloud.set_scalar("ssp_index", std::move(ssp_index));
      write_file(clusters_tmp, ply_bytes(cloud));
    }
    if(!png.empty())
      write_file(png_tmp, rep.time("render", [&] { return render_png(cloud.points, cloud.normals, cloud.colors, render); }));

    auto& r = rep.data();
    r["points"] = n;
    r["ssps"] = ssps.size();
    r["points_per_ssp"] = double(n) / double(ssps.size());
    r["max_cluster_size"] = ssps.max_cluster_size;
    r["mode_threshold"] = std::isfinite(settings.mode_spread_threshold) ? nlohmann::json(settings.mode_spread_threshold)
                                                                        : nlohmann::json("inf");
    const CGAL_ext::Mean_shift_result& ms = ssps.mean_shift;
    if(ms.completed)
      r["mean_shift"] = {{"spatial_bandwidth", ms.spatial_bandwidth}, {"range_bandwidth", ms.range_bandwidth},
                         {"curvature_scale", ms.curvature_scale}, {"mean_iterations", ms.mean_iterations},
                         {"max_iterations", ms.max_iterations}, {"points_at_cap", ms.points_at_cap}};
    if(!report.empty()) write_file(report_tmp, rep.dump());
    outputs.commit();
    if(!common.quiet)
      std::fprintf(stderr, "simplify: %zu points -> %zu SSPs (%.1f points each, at most %zu)\n", n, ssps.size(),
                   double(n) / double(ssps.size()), ssps.max_cluster_size);
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
    const fs::path report_tmp = add_if_given(outputs, report);
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
    // Detail scaling of the tentacle's middle (paper Fig. 4) and enhancement of the whole tentacle (Fig. 5, 6),
    // quadric order; the pictures are coloured by the displacement along the normal.
    const std::vector<std::size_t> middle = select_points(input.points, {parse_region_spec("sphere:-0.29,0,0.71,0.3")});
    const std::vector<std::size_t> whole = index_range(input.points.size());
    for(const auto& [enhance, factor] : {std::pair{false, 0.6}, std::pair{false, 1.2}, std::pair{true, 2.0}, std::pair{true, 3.0}}) {
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
      write_file(outputs.add(dir / (std::string(stem) + ".ply")), ply_bytes(out));
      write_file(outputs.add(dir / (std::string(stem) + ".png")),
                 render_png(out.points, out.normals, diverging_colors(*out.scalar("displacement")), render));
      rep.data()["roi_points"] = result.region_size;
      rep.data()["anchors"] = result.anchor_count;
      std::printf("demo: %-7s s = %.1f on %zu points (%zu anchors) in %.3f s -> %s.ply, %s.png\n", what.c_str(), factor,
                  result.region_size, result.anchor_count, rep.data()["timings_s"][what].get<double>(), stem, stem);
      runs.push_back(rep.data());
    }
    if(!report.empty()) write_file(report_tmp, nlohmann::json{{"command", "demo"}, {"runs", runs}}.dump(2) + "\n");
    outputs.commit();
    std::printf("demo: wrote %s/{tentacle,details_*,scale_*,enhance_*}.{ply,png}\n", directory.c_str());
  }
};

} // namespace

int main(int argc, char** argv)
{
  use_huge_pages(argv);
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

  Manipulate_command scale, enhance;
  enhance.enhance = true;
  CLI::App* scale_app = app.add_subcommand("scale", "scale the geometric details of a region by a factor (paper Sect. 4.1)");
  CLI::App* enhance_app = app.add_subcommand("enhance", "enhance the details against the balanced-flow base surface (paper Sect. 4.2)");
  for(auto [sub, command] : {std::pair{scale_app, &scale}, std::pair{enhance_app, &enhance}}) {
    sub->add_option("-i,--input", command->input, "input points (.ply, .off, .xyz, .pwn)")->required();
    sub->add_option("-o,--output", command->output, "output binary PLY: moved points, normals, displacement, in_roi")->required();
    sub->add_option("-s,--factor", command->factor, "scale factor s (1: unchanged)")->required();
    auto* roi_option = sub->add_option("--roi", command->roi,
      "region of interest, repeatable (union): sphere:x,y,z,r | box:xmin,ymin,zmin,xmax,ymax,zmax | indices:FILE"
      + std::string(command->enhance ? " (default: the whole model)" : ""));
    if(!command->enhance) roi_option->required();
    sub->add_option("--anchors", command->anchors, "anchored points, same syntax (default: the region's border, or for the "
                                                    "whole model in enhance a uniform 1 % at the exact solution)");
    sub->add_option("--border", command->border, "default anchors of a partial region: its border (anchored), none (free: the "
                                                  "surroundings hold it), or auto (anchored except for the cubic order)")
      ->check(CLI::IsMember({"auto", "anchored", "free"}))->capture_default_str();
    sub->add_option("--solver", command->solver, "cholesky (factor once) or cg (conjugate gradients, the paper's)")
      ->check(CLI::IsMember({"cholesky", "cg"}))->capture_default_str();
    sub->add_option("--png", command->png, "also render the result, coloured by the displacement along the normal");
    sub->add_option("--report", command->report, "write stage timings, region and solver figures as JSON");
    add_detail_options(*sub, command->detail);
    add_render_options(*sub, command->render, command->view);
  }

  Curvature_command curvature;
  CLI::App* curvature_app = app.add_subcommand("curvature", "signed mean curvature of every point (jet fitting), as a PLY property and a colour map");
  curvature_app->add_option("-i,--input", curvature.input, "input points (.ply, .off, .xyz, .pwn)")->required();
  curvature_app->add_option("-o,--output", curvature.output, "output binary PLY with mean_curvature and colours")->required();
  curvature_app->add_option("-k,--neighbor-count", curvature.k, "neighbours of the degree-2 fit (>= 5)")->capture_default_str();
  curvature_app->add_option("--fitting", curvature.fitting, "monge (CGAL::Monge_via_jet_fitting) or closed-form (faster)")
    ->check(CLI::IsMember({"monge", "closed-form"}))->capture_default_str();
  curvature_app->add_option("--png", curvature.png, "also render the curvature colour map (red: bends away from the normal)");
  curvature_app->add_option("--report", curvature.report, "write stage timings and curvature percentiles as JSON");
  add_render_options(*curvature_app, curvature.render, curvature.view);

  Simplify_command simplify;
  CLI::App* simplify_app = app.add_subcommand("simplify", "simplification sample points: clusters split until small and of one mean-shift mode (paper Sect. 5)");
  simplify_app->add_option("-i,--input", simplify.input, "input points (.ply, .off, .xyz, .pwn)")->required();
  simplify_app->add_option("-o,--output", simplify.output, "output binary PLY of the SSP surfels: position, normal, radius, member_count")->required();
  simplify.max_cluster_size_option = simplify_app->add_option("--max-cluster-size", simplify.max_cluster_size,
    "largest number of points per SSP (default: ceil(points / target))");
  simplify_app->add_option("--target", simplify.settings.target_count, "SSP count that sets the default cluster size")->capture_default_str();
  simplify_app->add_option("--mode-threshold", simplify.settings.mode_spread_threshold,
    "split while the members' modes spread more than this many range bandwidths (inf: by size only)")->capture_default_str();
  simplify_app->add_option("-k,--neighbor-count", simplify.settings.mean_shift_neighbors, "neighbours of the mean shift (>= 5)")->capture_default_str();
  simplify_app->add_option("--kernel", simplify.settings.mean_shift.kernel, "mean-shift kernel")
    ->transform(CLI::CheckedTransformer(std::map<std::string, CGAL_ext::Mean_shift_kernel>{
      {"gaussian", CGAL_ext::Mean_shift_kernel::gaussian}, {"epanechnikov", CGAL_ext::Mean_shift_kernel::epanechnikov}}));
  simplify_app->add_option("--spatial-bandwidth", simplify.settings.mean_shift.spatial_bandwidth, "h_s (0: the average spacing)")->capture_default_str();
  simplify_app->add_option("--range-bandwidth", simplify.settings.mean_shift.range_bandwidth, "h_r over normal and scaled curvature")->capture_default_str();
  simplify_app->add_option("--clusters", simplify.clusters, "also write the input with its ssp_index and cluster colours (PLY)");
  simplify_app->add_option("--png", simplify.png, "also render the input coloured by cluster (paper Fig. 7)");
  simplify_app->add_option("--report", simplify.report, "write stage timings, SSP counts and mean-shift figures as JSON");
  add_render_options(*simplify_app, simplify.render, simplify.view);

  Render_command render;
  CLI::App* render_app = app.add_subcommand("render", "headless PNG picture of a point set");
  render_app->add_option("-i,--input", render.input, "input points")->required();
  render_app->add_option("-o,--output", render.output, "output PNG")->required();
  render_app->add_option("--color-by", render.color_by, "rgb, none or a scalar property (default: rgb, else detail_magnitude)");
  render_app->add_option("--report", render.report, "write stage timings and counts as JSON");
  add_render_options(*render_app, render.render, render.view);

  Demo_command demo;
  CLI::App* demo_app = app.add_subcommand("demo", "detail colour maps, scaling and enhancement on a generated tentacle");
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
    if(*scale_app) scale.run(common);
    if(*curvature_app) curvature.run(common);
    if(*enhance_app) enhance.run(common);
    if(*simplify_app) simplify.run(common);
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
