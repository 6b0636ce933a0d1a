// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// point-detail: high-frequency geometric details of point-sampled surfaces from the command line.
#include "cli_support.h"
#include "edit_spec.h"
#include "point_io.h"
#include "region_spec.h"
#include "render.h"

#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/estimate_oriented_normals.h>
#include <CGAL_ext/refit_normals.h>
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/scale_geometric_details.h>
#include <CGAL_ext/upsample_point_set.h>

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
  std::string color_by = "detail_normal"; // the relief on any sampling (doc/geometric_details.md, "Colour maps")

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

/// The outputs of a subcommand that writes points, with an optional picture and report: each checked (never an
/// input; its directory exists) and written to a temporary until `files.commit()`, so outputs are whole or absent.
struct Point_outputs
{
  Output_files files;
  fs::path ply, png, report; // the temporaries (empty when not asked for)

  Point_outputs(std::vector<fs::path> inputs, const std::string& output, const std::string& png_destination,
                const std::string& report_destination)
    : files(std::move(inputs)), ply(files.add(output)), png(add_if_given(files, png_destination)),
      report(add_if_given(files, report_destination))
  {}
};

/// What each subcommand needs per input point, reading and writing included: its peak memory on a raw scan of
/// 1M points (normals estimated; benchmark/raw_scan_results.md, upsample and render on the same points with
/// normals) plus a quarter. The check before reading asks the machine for this much. A region's factorisation
/// needs more, by the region's size; CHOLMOD running out of memory then is an error of its own.
namespace bytes_per_point {
constexpr std::uint64_t details = 704;   // measured 550
constexpr std::uint64_t curvature = 416; // 327
constexpr std::uint64_t simplify = 448;  // 355
constexpr std::uint64_t manipulate = 800; // 632 (whole-model enhancement)
constexpr std::uint64_t edit = 640;      // 492
constexpr std::uint64_t upsample = 512;  // 400
constexpr std::uint64_t render = 416;    // 185 with normals; estimating them, as curvature
} // namespace bytes_per_point

/// Reads `input` (timed in the report), asking the machine for `bytes` per point, and checks that it has more
/// than `k` points.
Point_cloud read_for_neighbors(const std::string& input, unsigned int k, std::uint64_t bytes, Report& rep)
{
  Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input, bytes); });
  if(cloud.points.size() <= k)
    throw Cli_error(input + " has " + std::to_string(cloud.points.size()) + " points: -k " + std::to_string(k) +
                    " needs more than k points");
  return cloud;
}

/// Gives the cloud normals when it has none (CGAL_ext::estimate_oriented_normals), and the vertices of a mesh
/// that lie on no face theirs: estimated normals turned, as a whole, to the side of the mesh's.
void ensure_normals(Point_cloud& cloud, Progress_printer& progress, Report& report)
{
  report.data()["normal_source"] = cloud.normals.empty() ? "estimated" : cloud.normal_source;
  if(!cloud.normals.empty() && cloud.vertices_without_normal == 0) return;
  if(cloud.points.size() < 6) throw Cli_error("normal estimation needs at least 6 points (a jet fit has 6 coefficients)");
  if(cloud.unread_triangle_strips)
    std::fprintf(stderr, "point-detail: warning: the faces of this PLY file are triangle strips, which are not read; "
                         "its normals are estimated from the points\n");
  std::vector<Vector> estimated(cloud.points.size());
  report.time("normals", [&] {
    if(!CGAL_ext::estimate_oriented_normals(
         index_range(cloud.points.size()),
         std::min<unsigned int>(CGAL_ext::default_normal_neighbors, unsigned(cloud.points.size())),
         CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
           .normal_map(CGAL::make_property_map(estimated))
           .callback(progress.stage("normals"))))
      throw Cancelled();
  });
  progress.finish();
  if(cloud.normals.empty()) {
    cloud.normals = std::move(estimated);
    cloud.normal_source = "estimated";
    return;
  }
  double agreement = 0;
  for(std::size_t i = 0; i < estimated.size(); ++i) agreement += estimated[i] * cloud.normals[i];
  for(std::size_t i = 0; i < estimated.size(); ++i)
    if(cloud.normals[i] == CGAL::NULL_VECTOR) cloud.normals[i] = agreement < 0 ? -estimated[i] : estimated[i];
  report.data()["estimated_normals"] = cloud.vertices_without_normal;
  cloud.vertices_without_normal = 0;
}

/// Adds detail_x/y/z, detail_magnitude (the paper's signed |delta|), detail_normal (delta . n) and the colour
/// map of `options.color_by` to `cloud` (which has normals); returns that map.
Coloring add_details(Point_cloud& cloud, const Detail_options& options, Progress_printer& progress, Report& report)
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
  std::vector<double> dx(n), dy(n), dz(n), along_normal(n);
  for(std::size_t i = 0; i < n; ++i) {
    dx[i] = details[i].x();
    dy[i] = details[i].y();
    dz[i] = details[i].z();
    along_normal[i] = details[i] * cloud.normals[i] / std::sqrt(cloud.normals[i].squared_length());
  }
  cloud.set_scalar("detail_x", std::move(dx));
  cloud.set_scalar("detail_y", std::move(dy));
  cloud.set_scalar("detail_z", std::move(dz));
  cloud.set_scalar("detail_magnitude", std::move(magnitude));
  cloud.set_scalar("detail_normal", std::move(along_normal));
  Coloring coloring = diverging_colors(*cloud.scalar(options.color_by));
  cloud.colors = coloring.colors;
  auto& r = report.data();
  r["points"] = n;
  r["k"] = options.k;
  r["order"] = options.order;
  r["lambda"] = options.lambda;
  if(settings.filter.order != CGAL_ext::Detail_order::linear) r["mu"] = options.mu;
  r["weights"] = options.weights;
  r["neighbors"] = options.neighbors;
  r["color_by"] = options.color_by;
  r["color_range"] = coloring.hi;
  return coloring;
}

/// The detail colours shown on the balanced-flow base surface (paper Fig. 3).
std::string render_on_base_surface(const Point_cloud& cloud, const Coloring& coloring, unsigned int k,
                                   const Render_settings& render, Report& report)
{
  std::vector<Point> base = cloud.points;
  std::vector<std::size_t> indices = index_range(base.size());
  report.time("base_surface", [&] {
    CGAL_ext::balanced_flow_smooth_point_set(indices, k, CGAL_ext::Balanced_flow_settings(),
                                             CGAL::parameters::point_map(CGAL::make_property_map(base))
                                               .normal_map(CGAL::make_property_map(cloud.normals)));
  });
  return report.time("render", [&] { return render_png(base, cloud.normals, coloring, render); });
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
    Point_outputs written({input}, output, png, report);
    render.view = parse_view(view);
    detail.settings().validate(); // before the (possibly long) read

    Progress_printer progress(common.quiet);
    Report rep("details");
    rep.data()["input"] = input;
    Point_cloud cloud = read_for_neighbors(input, detail.k, bytes_per_point::details, rep);
    ensure_normals(cloud, progress, rep);
    const Coloring coloring = add_details(cloud, detail, progress, rep);
    rep.time("write", [&] { write_file(written.ply, ply_bytes(cloud)); });
    if(!png.empty()) write_file(written.png, render_on_base_surface(cloud, coloring, detail.k, render, rep));
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
  }
};

/// Scales (or enhances) the details of `region` of `cloud` (which has normals) by `factor`; `out` receives the
/// moved points with normals re-fitted where they moved, their displacement along the input normal and the
/// region flag.
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
  std::vector<std::size_t> displaced;
  for(std::size_t i = 0; i < out.points.size(); ++i)
    if(out.points[i] != cloud.points[i]) displaced.push_back(i);
  if(!displaced.empty())
    CGAL_ext::refit_normals(index_range(out.points.size()), displaced,
                            std::min<unsigned int>(CGAL_ext::default_normal_neighbors, unsigned(out.points.size())),
                            CGAL::parameters::point_map(CGAL::make_property_map(out.points))
                              .normal_map(CGAL::make_property_map(out.normals)));
  out.set_scalar("displacement", std::move(displacement));
  out.set_scalar("in_roi", std::move(in_roi));
  return result;
}

/// How far a region stands out from the surface its border spans, relative to its size: the median distance
/// its points moved divided by |s - 1| (the detail scaling is affine in s, so this is the deviation the region's
/// details have in all), over the region's RMS radius. Measured: the demo tentacle's bumpy middle 0.074, a ball
/// around the armadillo's head 0.10 (doc/detail_scaling.md). 0 at s = 1.
double region_deviation(const std::vector<Point>& before, const std::vector<Point>& after,
                        const std::vector<std::size_t>& region, double factor)
{
  if(factor == 1 || region.empty()) return 0;
  std::vector<double> moved;
  Vector centroid(0, 0, 0);
  for(std::size_t i : region) {
    moved.push_back(std::sqrt(CGAL::squared_distance(before[i], after[i])));
    centroid = centroid + (before[i] - CGAL::ORIGIN) / double(region.size());
  }
  double radius = 0;
  for(std::size_t i : region) radius += (before[i] - (CGAL::ORIGIN + centroid)).squared_length() / double(region.size());
  std::nth_element(moved.begin(), moved.begin() + std::ptrdiff_t(moved.size() / 2), moved.end());
  return radius > 0 ? moved[moved.size() / 2] / std::abs(factor - 1) / std::sqrt(radius) : 0;
}

/// Above this region deviation, `scale` warns that it reshapes a feature rather than its details.
constexpr double feature_deviation = 0.1;

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
    Point_outputs written({input}, output, png, report);
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
    Point_cloud cloud = read_for_neighbors(input, detail.k, bytes_per_point::manipulate, rep);
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
    const double deviation = enhance ? 0.0 : region_deviation(cloud.points, out.points, region, factor);
    rep.time("write", [&] { write_file(written.ply, ply_bytes(out)); });
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] {
        return render_png(out.points, out.normals, diverging_colors(*out.scalar("displacement")), render);
      }));
    auto& r = rep.data();
    r["points"] = out.points.size();
    r["factor"] = factor;
    r["order"] = detail.order;
    r["neighbors"] = detail.neighbors;
    r["roi_points"] = result.region_size;
    r["computed_points"] = result.computed_points;
    r["anchors"] = result.anchor_count;
    r["default_anchors"] = result.default_anchors;
    if(!enhance) r["region_deviation"] = deviation;
    const CGAL_ext::Least_squares_statistics& ls = result.least_squares;
    r["solver"] = {{"method", ls.method}, {"operator_nonzeros", ls.operator_nonzeros}, {"normal_nonzeros", ls.normal_nonzeros},
                   {"assembly_s", ls.assembly_seconds}, {"factor_s", ls.factor_seconds}, {"solve_s", ls.solve_seconds},
                   {"iterations", ls.iterations}, {"relative_residual", ls.relative_residual}};
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
    // Printed even with --quiet: the result is probably not what the user wanted.
    if(deviation > feature_deviation)
      std::fprintf(stderr, "point-detail: warning: the region stands out from the surface its border spans by %.0f %% of "
                   "its size: scale reshapes all of it, not only its small details (for those, use enhance)\n", 100 * deviation);
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
    const Coloring coloring = diverging_colors(H);
    cloud.colors = coloring.colors;
    cloud.set_scalar("mean_curvature", std::move(H));
    rep.time("write", [&] { write_file(written.ply, ply_bytes(cloud)); });
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] { return render_png(cloud.points, cloud.normals, coloring, render); }));
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
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
    Point_outputs written({input}, output, png, report);
    const fs::path clusters_tmp = add_if_given(written.files, clusters);
    render.view = parse_view(view);
    if(max_cluster_size_option->count() > 0) settings.max_cluster_size = max_cluster_size;
    settings.validate();

    Progress_printer progress(common.quiet);
    Report rep("simplify");
    rep.data()["input"] = input;
    Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input, bytes_per_point::simplify); });
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
    rep.time("write", [&] { write_file(written.ply, ply_bytes(surfels)); });
    const Coloring coloring = label_colors(sample_of);
    cloud.colors = coloring.colors;
    if(!clusters.empty()) {
      std::vector<double> ssp_index(sample_of.begin(), sample_of.end());
      cloud.set_scalar("ssp_index", std::move(ssp_index));
      write_file(clusters_tmp, ply_bytes(cloud));
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

/// Every point's local spacing (CGAL_ext::compute_local_spacing): what an edit keeps.
std::vector<double> local_spacing(const Point_cloud& cloud)
{
  std::vector<double> spacing(cloud.points.size());
  CGAL_ext::compute_local_spacing(index_range(cloud.points.size()), CGAL::make_property_map(spacing),
                                  CGAL::parameters::point_map(CGAL::make_property_map(cloud.points)));
  return spacing;
}

/// Fills the holes of `cloud` (which has normals), looking for gaps from the points `region` only (all when
/// null), at the spacing each point had before an edit (`spacing_before`, with `region`) or else that of the
/// settings (0: local): the new points are appended with the flag `inserted` = 1, 0 in the other scalars and
/// `flag_color` (when the cloud has colours); the report gets the figures.
void upsample_cloud(Point_cloud& cloud, const CGAL_ext::Upsampling_settings& settings, const std::vector<std::size_t>* region,
                    const std::vector<double>* spacing_before, Progress_printer& progress, Report& rep)
{
  std::vector<std::pair<Point, Vector>> added;
  const std::size_t n = cloud.points.size();
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
                    .normal_map(CGAL::make_property_map(cloud.normals))
                    .callback(progress.stage("upsample"));
  const CGAL_ext::Upsampling_result result = rep.time("upsample", [&] {
    if(region && spacing_before)
      return CGAL_ext::upsample_point_set(index_range(n), *region, CGAL::make_property_map(*spacing_before), settings,
                                          std::back_inserter(added), np);
    return region ? CGAL_ext::upsample_point_set(index_range(n), *region, settings, std::back_inserter(added), np)
                  : CGAL_ext::upsample_point_set(index_range(n), settings, std::back_inserter(added), np);
  });
  progress.finish();
  if(!result) throw Cancelled();
  for(auto& [name, values] : cloud.scalars) values.resize(n + added.size(), 0.0);
  if(!cloud.colors.empty()) cloud.colors.resize(n + added.size(), flag_color);
  std::vector<double> inserted(n + added.size(), 0.0);
  for(std::size_t m = 0; m < added.size(); ++m) {
    cloud.points.push_back(added[m].first);
    cloud.normals.push_back(added[m].second);
    inserted[n + m] = 1;
  }
  cloud.set_scalar("inserted", std::move(inserted));
  rep.data()["upsampling"] = {{"spacing", result.spacing}, {"inserted", result.inserted}, {"rounds", result.rounds},
                              {"hole_boundary_points", result.hole_boundary_points}};
}

/// Runs an edit on `cloud` (which has normals): preprocess, deform, diffuse. `out` receives the deformed points
/// and normals, the distance each point moved, its status (0 fixed, 1 region, 2 handle) and its sample point;
/// the report gets the paper's Table 1 fields.
void run_edit(const Point_cloud& cloud, const Edit_description& edit, Progress_printer& progress, Report& rep, Point_cloud& out)
{
  const std::size_t n = cloud.points.size();
  std::vector<std::size_t> all = index_range(n);
  CGAL_ext::Detail_preserving_deformation<> deformation(
    all, edit.settings,
    CGAL::parameters::point_map(CGAL::make_property_map(cloud.points)).normal_map(CGAL::make_property_map(cloud.normals))
      .callback(progress.stage("preprocess")));
  deformation.insert_roi_points(edit.roi);
  for(const Handle_edit& handle : edit.handles) {
    const std::size_t group = deformation.create_handle_group();
    deformation.insert_handle_points(group, handle.points);
    deformation.set_handle_transform(group, handle.rotation, handle.translation);
  }
  const bool done = rep.time("preprocess", [&] { return deformation.preprocess(); });
  progress.finish();
  if(!done) throw Cancelled();
  rep.time("deform", [&] { deformation.deform(); });
  out = Point_cloud();
  out.points.resize(n);
  out.normals.resize(n);
  rep.time("diffuse", [&] {
    deformation.diffuse(all, CGAL::parameters::point_map(CGAL::make_property_map(out.points))
                                   .normal_map(CGAL::make_property_map(out.normals)));
  });
  std::vector<double> moved(n), status(n, 0.0), sample(n);
  for(std::size_t i = 0; i < n; ++i) {
    moved[i] = std::sqrt(CGAL::squared_distance(out.points[i], cloud.points[i]));
    sample[i] = double(deformation.sample_point_of(i));
  }
  for(std::size_t i : edit.roi) status[i] = 1;
  for(const Handle_edit& handle : edit.handles)
    for(std::size_t i : handle.points) status[i] = 2;
  out.colors = sequential_colors(moved).colors;
  out.set_scalar("displacement", std::move(moved));
  out.set_scalar("status", std::move(status));
  out.set_scalar("ssp_index", std::move(sample));

  // Handle points against their targets (zero to rounding with exact handles).
  double handle_error = 0;
  for(std::size_t g = 0; g < edit.handles.size(); ++g)
    for(std::size_t i : edit.handles[g].points)
      handle_error = std::max(handle_error, (deformation.deformed_point(i) - deformation.handle_target(g, deformation.point(i))).norm());
  const CGAL_ext::Detail_preserving_deformation_statistics& st = deformation.statistics();
  const CGAL_ext::Least_squares_statistics& ls = st.least_squares;
  auto& r = rep.data();
  r["points"] = st.points;
  r["ssps"] = st.samples;
  r["requested_ssps"] = st.requested_samples;
  r["roi_ssps"] = st.roi_samples;
  r["handle_ssps"] = st.handle_samples;
  r["handle_groups"] = edit.handles.size();
  r["order"] = CGAL_ext::Detail_filter::order_name(edit.settings.filter.order);
  r["lambda"] = edit.settings.filter.lambda;
  if(edit.settings.filter.order != CGAL_ext::Detail_order::linear) r["mu"] = edit.settings.filter.mu;
  // The paper's Table 1: time for editing the SSPs (operator, normal matrix, factorisation, solve) and for diffusion.
  r["table1"] = {{"editing_ssps_s", ls.assembly_seconds + ls.factor_seconds + st.deform_seconds},
                 {"diffusion_s", st.diffuse_seconds}};
  r["clustering_s"] = st.clustering_seconds;
  r["solver"] = {{"method", ls.method}, {"normal_nonzeros", ls.normal_nonzeros}, {"assembly_s", ls.assembly_seconds},
                 {"factor_s", ls.factor_seconds}, {"solve_s", ls.solve_seconds}, {"refinement_steps", ls.iterations},
                 {"relative_residual", ls.relative_residual}};
  r["handle_constraints"] = std::isinf(edit.settings.handle_weight) ? nlohmann::json("exact") : nlohmann::json(edit.settings.handle_weight);
  r["max_handle_point_error"] = handle_error;
  r["displacement_ratio"] = st.displacement_ratio;
  if(edit.settings.rotations == CGAL_ext::Detail_rotation::as_rigid_as_possible) r["rigid_iterations"] = st.rigid_iterations;
}

/// An edit's picture: the distance each point moved, and the points an up-sampling added, flagged.
Coloring edit_coloring(const Point_cloud& out)
{
  Coloring coloring = sequential_colors(*out.scalar("displacement"));
  if(const std::vector<double>* inserted = out.scalar("inserted")) emphasize(coloring, *inserted);
  return coloring;
}

/// Above this ratio of the largest sample-point displacement to the handles' largest, `edit` warns.
constexpr double swing_warning_ratio = 2.0;

/// `edit`: detail-preserving editing of a region by handles (paper Sect. 6).
struct Edit_command
{
  std::string input, output, edit, sel, def, png, report, view = "front";
  std::string order, strength, origin;
  double lambda = 0, mu = 0, handle_weight = 0;
  unsigned int k = 0;
  std::size_t max_cluster_size = 0, target = 0;
  unsigned int rigid_iterations = 0;
  std::string rotations;
  bool upsample = false;
  std::map<std::string, CLI::Option*> given;
  Render_settings render;

  bool has(const std::string& name) const { return given.at(name)->count() > 0; }

  void run(const Common_options& common)
  {
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
      s.filter.order = order == "linear" ? CGAL_ext::Detail_order::linear
                       : order == "cubic" ? CGAL_ext::Detail_order::cubic : CGAL_ext::Detail_order::quadric;
    if(has("--lambda")) s.filter.lambda = lambda;
    if(has("--mu")) s.filter.mu = mu;
    if(has("-k")) s.sample_neighbors = k;
    if(has("--strength")) s.strength_distance = strength == "geodesic" ? CGAL_ext::Strength_distance::geodesic : CGAL_ext::Strength_distance::euclidean;
    if(has("--diffusion-origin")) s.diffusion_origin = origin == "nearest" ? CGAL_ext::Diffusion_origin::nearest_sample : CGAL_ext::Diffusion_origin::own_sample;
    if(has("--handle-weight")) s.handle_weight = handle_weight;
    if(has("--max-cluster-size")) s.simplification.max_cluster_size = max_cluster_size;
    if(has("--target")) s.simplification.target_count = target;
    if(has("--rotations")) s.rotations = detail_rotation(rotations, "--rotations");
    if(has("--rigid-iterations")) s.rigid_iterations = rigid_iterations;
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
  }
};

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
    rep.time("write", [&] { write_file(written.ply, ply_bytes(cloud)); });
    if(!png.empty())
      write_file(written.png, rep.time("render", [&] {
        return render_png(cloud.points, cloud.normals, flag_colors(*cloud.scalar("inserted")), render);
      }));
    if(!report.empty()) write_file(written.report, rep.dump());
    written.files.commit();
    if(!common.quiet)
      std::fprintf(stderr, "upsample: %zu points + %zu new at spacing %g\n", n, cloud.points.size() - n,
                   rep.data()["upsampling"]["spacing"].get<double>());
  }
};

struct Render_command
{
  std::string input, output, color_by, report, view = "front";
  Render_settings render;

  void run(const Common_options& common)
  {
    Output_files outputs({input});
    const fs::path png_tmp = outputs.add(output);
    const fs::path report_tmp = add_if_given(outputs, report);
    render.view = parse_view(view);
    Report rep("render");
    rep.data()["input"] = input;
    Point_cloud cloud = rep.time("read", [&] { return read_point_cloud(input, bytes_per_point::render); });
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
    write_file(outputs.add(dir / "tentacle.png"), render_png(input.points, input.normals, Coloring(), render));
    std::printf("demo: tentacle of %zu points with exact normals\n", input.points.size());
    for(const char* order : {"linear", "quadric", "cubic"}) {
      Detail_options options;
      options.order = order;
      Point_cloud cloud = input;
      Report rep(std::string("demo details ") + order);
      const Coloring coloring = add_details(cloud, options, progress, rep);
      const std::string stem = std::string("details_") + order;
      write_file(outputs.add(dir / (stem + ".ply")), ply_bytes(cloud));
      write_file(outputs.add(dir / (stem + ".png")), render_on_base_surface(cloud, coloring, options.k, render, rep));
      std::printf("demo: %-7s details (lambda %.1f, mu %.1f, k %u) in %.3f s -> %s.ply, %s.png\n", order, options.lambda,
                  options.mu, options.k, rep.data()["timings_s"]["details"].get<double>(), stem.c_str(), stem.c_str());
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
      write_file(outputs.add(dir / (std::string(stem) + ".ply")), ply_bytes(out));
      write_file(outputs.add(dir / (std::string(stem) + ".png")),
                 render_png(out.points, out.normals, diverging_colors(*out.scalar("displacement")), render));
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
    tip.rotation = Eigen::AngleAxisd(50 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
    tip.translation = pivot - tip.rotation * pivot;
    bend.handles.push_back(tip);
    for(const char* order : {"linear", "quadric", "cubic"}) {
      bend.settings.filter.order = std::string(order) == "linear" ? CGAL_ext::Detail_order::linear
                                   : std::string(order) == "cubic" ? CGAL_ext::Detail_order::cubic
                                                                   : CGAL_ext::Detail_order::quadric;
      Report rep(std::string("demo edit ") + order);
      Point_cloud out;
      run_edit(input, bend, progress, rep, out);
      const std::string stem = std::string("edit_") + order;
      write_file(outputs.add(dir / (stem + ".ply")), ply_bytes(out));
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
      write_file(outputs.add(dir / "edit_stretch_upsampled.ply"), ply_bytes(out));
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
  details_app->add_option("--color-by", details.detail.color_by, "colour map (and PLY colours): detail_normal (delta . n, the "
                          "relief on any sampling) or detail_magnitude (the paper's signed |delta|)")
    ->check(CLI::IsMember({"detail_normal", "detail_magnitude"}))->capture_default_str();
  details_app->add_option("--report", details.report, "write stage timings and counts as JSON");
  add_detail_options(*details_app, details.detail);
  add_render_options(*details_app, details.render, details.view);

  Manipulate_command scale, enhance;
  enhance.enhance = true;
  CLI::App* scale_app = app.add_subcommand("scale", "scale a region's deviation from the surface its border spans by a factor "
    "(paper Sect. 4.1): all of it, so a region around a whole feature (a head) reshapes the feature; for only the "
    "small details, use enhance");
  CLI::App* enhance_app = app.add_subcommand("enhance", "enhance the details against the balanced-flow base surface (paper Sect. 4.2)");
  for(auto [sub, command] : {std::pair{scale_app, &scale}, std::pair{enhance_app, &enhance}}) {
    sub->add_option("-i,--input", command->input, "input points (.ply, .off, .xyz, .pwn)")->required();
    sub->add_option("-o,--output", command->output, "output binary PLY: moved points, their normals (re-fitted where they moved), displacement, in_roi")->required();
    sub->add_option("-s,--factor", command->factor, "scale factor s (1: unchanged)")->required();
    auto* roi_option = sub->add_option("--roi", command->roi,
      "region of interest, repeatable (union): sphere:x,y,z,r | box:xmin,ymin,zmin,xmax,ymax,zmax | indices:FILE"
      + std::string(command->enhance ? " (default: the whole model)" : ""));
    if(!command->enhance) roi_option->required();
    sub->add_option("--anchors", command->anchors, "anchored points, same syntax (default: the region's border; enhance "
                                                    "of the whole model needs none: its exact solution is written)");
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
  simplify_app->add_option("--target", simplify.settings.target_count, "SSP count the clustering aims at: the largest clusters split to it, then the mode-spread rule adds at most half as many again")->capture_default_str();
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

  Edit_command edit;
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
  edit.given["-k"] = edit_app->add_option("-k,--neighbor-count", edit.k, "neighbours of a sample point in their Laplacian (default 10)");
  edit.given["--strength"] = edit_app->add_option("--strength", edit.strength, "distances of the strength field: euclidean (the paper's) or geodesic")
                               ->check(CLI::IsMember({"euclidean", "geodesic"}));
  edit.given["--diffusion-origin"] = edit_app->add_option("--diffusion-origin", edit.origin, "own (p - ssp_i in frame i, default) or nearest (the paper's p - ssp_0)")
                                       ->check(CLI::IsMember({"own", "nearest"}));
  edit.given["--handle-weight"] = edit_app->add_option("--handle-weight", edit.handle_weight, "weight of soft handle constraints (the paper's, e.g. 1); default: exact handles");
  edit.given["--max-cluster-size"] = edit_app->add_option("--max-cluster-size", edit.max_cluster_size, "largest number of points per SSP");
  edit.given["--target"] = edit_app->add_option("--target", edit.target, "SSP count the clustering aims at, at most 1.5 times it with the mode-spread rule (default 3000)");
  edit.given["--rotations"] = edit_app->add_option("--rotations", edit.rotations, "how the details turn: none, propagate (the paper's), arap (as rigid as possible)")
    ->check(CLI::IsMember({"none", "propagate", "arap"}));
  edit.given["--rigid-iterations"] = edit_app->add_option("--rigid-iterations", edit.rigid_iterations, "with --rotations arap: rotation fits and solves")
    ->check(CLI::Range(1u, 1000u));
  edit_app->add_flag("--upsample", edit.upsample, "fill what the edit stretched, from the points it moved, at each point's pre-edit local spacing (new points: inserted = 1)");
  add_render_options(*edit_app, edit.render, edit.view);

  Upsample_command upsample;
  CLI::App* upsample_app = app.add_subcommand("upsample", "fill holes and stretched parts with new samples, relaxed on the surface (paper Sect. 6.3)");
  upsample_app->add_option("-i,--input", upsample.input, "input points with normals (.ply, .off, .xyz, .pwn)")->required();
  upsample_app->add_option("-o,--output", upsample.output, "output binary PLY: the input, then the new points (inserted = 1)")->required();
  upsample_app->add_option("--spacing", upsample.spacing, "target spacing everywhere (0: each point's local spacing, so that only what is sparse for its surroundings is filled)")->capture_default_str();
  upsample_app->add_option("--max-hole-size", upsample.settings.detection.max_hole_size, "widest gap filled, in spacings (open borders are never grown)")->capture_default_str();
  upsample_app->add_option("-k,--neighbor-count", upsample.settings.neighbors, "neighbours of the tangent axes and surface fits (>= 6)")->capture_default_str();
  upsample_app->add_option("--png", upsample.png, "also render the result, new points highlighted");
  upsample_app->add_option("--report", upsample.report, "write counts, spacing and timings as JSON");
  add_render_options(*upsample_app, upsample.render, upsample.view);

  Render_command render;
  CLI::App* render_app = app.add_subcommand("render", "headless PNG picture of a point set");
  render_app->add_option("-i,--input", render.input, "input points")->required();
  render_app->add_option("-o,--output", render.output, "output PNG")->required();
  render_app->add_option("--color-by", render.color_by, "rgb, none or a scalar property: 0/1 flags (inserted, in_roi) are highlighted, signed values get a diverging map, others a sequential one (default: rgb, else detail_normal, else detail_magnitude)");
  render_app->add_option("--report", render.report, "write stage timings and counts as JSON");
  add_render_options(*render_app, render.render, render.view);

  Demo_command demo;
  CLI::App* demo_app = app.add_subcommand("demo", "detail colour maps, scaling, enhancement, editing and up-sampling on a generated tentacle");
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
    if(*edit_app) {
      if(edit.edit.empty() && edit.sel.empty()) throw Cli_error("edit needs --edit EDIT.json or --sel S --def D");
      edit.run(common);
    }
    if(*upsample_app) upsample.run(common);
    if(*render_app) render.run(common);
    if(*demo_app) demo.run(common);
  } catch(const Cancelled&) {
    std::fprintf(stderr, "\npoint-detail: cancelled; nothing written\n");
    return 130;
  } catch(const Cli_error& e) {
    std::fprintf(stderr, "point-detail: error: %s\n", e.what());
    return 1;
  } catch(const CGAL_ext::Invalid_input& e) {
    std::fprintf(stderr, "point-detail: error: %s\n", e.what());
    return 1;
  } catch(const CGAL_ext::Numerical_failure& e) {
    std::fprintf(stderr, "point-detail: error: %s\n", e.what());
    return 3;
  } catch(const std::bad_alloc&) {
    std::fprintf(stderr, "point-detail: error: out of memory; free memory, raise the process's memory limit or "
                         "work on a smaller region\n");
    return 3;
  } catch(const std::exception& e) {
    std::fprintf(stderr, "point-detail: failed: %s\n", e.what());
    return 3;
  }
  return 0;
}
