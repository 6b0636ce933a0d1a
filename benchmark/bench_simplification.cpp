// Benchmark of the mean shift and the simplification sample points (issue: curvature, mean shift and SSPs):
// each stage timed on its own (kNN graph, curvature, mean shift, clustering) and the whole public call, on CGAL's
// scans and a 1M-point sampling of the armadillo, sequentially and in parallel, beside
// CGAL::hierarchy_simplify_point_set (size 50) and CGAL::grid_simplify_point_set in the same run; and the
// number of sample points against the mode-spread threshold.
// Usage: bench_simplification [--quick] [--data DIR] [--out DIR] [--reps N]
// Writes DIR/simplification_results.csv and DIR/simplification_results.md.
#include "bench_support.h"
#include "program_basics.h"
#include "point_io.h"

#include <CGAL_ext/compute_simplification_sample_points.h>

#include <CGAL/grid_simplify_point_set.h>
#include <CGAL/hierarchy_simplify_point_set.h>

#include <tbb/info.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numeric>

namespace fs = std::filesystem;
using namespace point_detail;
namespace internal = CGAL_ext::internal;

namespace bench_simplification {

struct Row
{
  std::string model, stage, mode;
  std::size_t points;
  Stats time;
  std::size_t count;  // sample points or clusters; 0 where it does not apply
  double iterations;  // mean-shift steps per point; 0 where it does not apply
  double peak_mib;
};

constexpr std::size_t cluster_size = 50;

template <typename Tag>
void bench_model(const std::string& name, const Point_cloud& input, int reps, std::vector<Row>& rows)
{
  const char* mode = std::is_same<Tag, CGAL::Sequential_tag>::value ? "sequential" : "parallel";
  const std::size_t n = input.points.size();
  auto add = [&](const std::string& stage, Stats s, std::size_t count, double iterations) {
    rows.push_back({name, stage, mode, n, s, count, iterations, peak_rss_mib()});
    std::printf("%-16s %-44s %-10s %8zu pts  %8.3f s (min %.3f, max %.3f)  count %7zu  steps %.2f  peak %.0f MiB\n",
                name.c_str(), stage.c_str(), mode, n, s.median, s.min, s.max, count, iterations, rows.back().peak_mib);
  };
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  const auto point_map = CGAL::make_property_map(input.points);
  const auto np = CGAL::parameters::point_map(point_map).normal_map(CGAL::make_property_map(input.normals));

  // The stages one by one, through the same internal calls as the public function.
  const internal::Spatial_point_cloud cloud = internal::make_spatial_point_cloud<Tag>(idx, point_map, "bench");
  const internal::Matrix_n3 normals = internal::gather_normals(idx, CGAL::make_property_map(input.normals), cloud, "bench");
  internal::Progress progress;
  const unsigned k = CGAL_ext::default_mean_shift_neighbors;
  internal::Mean_shift_analysis a;
  add("kNN graph (k = 15)", measure(reps, [&] { a.candidates = internal::k_nearest_neighbor_graph<Tag>(cloud.positions, k, progress); }), 0, 0);
  add("curvature (closed form, k = 15)", measure(reps, [&] {
        internal::mean_curvatures<Tag>(cloud, normals, a.candidates, CGAL_ext::Curvature_fitting::closed_form, progress, a.curvature);
      }), 0, 0);
  const CGAL_ext::Mean_shift_settings shift = CGAL_ext::Simplification_settings().mean_shift; // stopped by the range part
  a.scales = internal::resolve_scales(shift, cloud.positions, a.candidates, a.curvature);
  const internal::Matrix_n7 features = internal::mean_shift_features(cloud.positions, normals, a.curvature, a.scales);
  const Stats shift_time = measure(reps, [&] { internal::mean_shift_modes<Tag>(features, a.candidates, shift, progress, a.modes, a.iterations); });
  add("mean shift (Gaussian)", shift_time, 0, internal::summarize(a, shift).mean_iterations);
  CGAL_ext::Simplification_sample_points<Kernel> samples;
  internal::Cluster_split_rule rule;
  rule.max_size = cluster_size;
  rule.modes = &a.modes;
  rule.spread_threshold = CGAL_ext::Simplification_settings().mode_spread_threshold;
  const Stats clustering = measure(reps, [&] {
    std::vector<int> order;
    const std::vector<int> leaves = internal::split_into_clusters<Tag>(cloud.positions, rule, order);
    internal::make_surfels<Kernel, Tag>(cloud, normals, order, leaves, samples);
  });
  add("clustering (splits and surfels, size 50)", clustering, samples.size(), 0);

  CGAL_ext::Simplification_settings settings;
  settings.max_cluster_size = cluster_size;
  std::vector<std::size_t> sample_of(n);
  std::size_t count = 0;
  const Stats whole = measure(reps, [&] {
    count = CGAL_ext::compute_simplification_sample_points<Tag>(idx, settings, CGAL::make_property_map(sample_of), np).size();
  });
  add("compute_simplification_sample_points (all)", whole, count, 0);

  // CGAL's peers on the same points (they remove points from a copy; the copy is timed too, ~1 % of the run).
  const double spacing = a.scales.spatial_bandwidth;
  const Stats hierarchy = measure(reps, [&] {
    std::vector<Point> copy = input.points;
    count = std::size_t(std::distance(copy.begin(), CGAL::hierarchy_simplify_point_set(copy, CGAL::parameters::size(cluster_size))));
  });
  add("CGAL hierarchy_simplify_point_set (size 50)", hierarchy, count, 0);
  const Stats grid = measure(reps, [&] {
    std::vector<Point> copy = input.points;
    count = std::size_t(std::distance(copy.begin(), CGAL::grid_simplify_point_set(copy, 3 * spacing)));
  });
  add("CGAL grid_simplify_point_set (cell 3 spacings)", grid, count, 0);
}

/// Sample points against the mode-spread threshold (parallel, size 50).
void sweep_threshold(const std::string& name, const Point_cloud& input, std::vector<Row>& rows)
{
  const std::size_t n = input.points.size();
  std::vector<std::size_t> idx(n), sample_of(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(input.points)).normal_map(CGAL::make_property_map(input.normals));
  for(double threshold : {0.5, 1.0, 1.5, 2.0, 3.0, std::numeric_limits<double>::infinity()}) {
    CGAL_ext::Simplification_settings settings;
    settings.max_cluster_size = cluster_size;
    settings.mode_spread_threshold = threshold;
    std::size_t count = 0;
    const Stats s = measure(1, [&] {
      count = CGAL_ext::compute_simplification_sample_points(idx, settings, CGAL::make_property_map(sample_of), np).size();
    });
    char stage[96];
    std::snprintf(stage, sizeof stage, "threshold sweep: mode spread %g", threshold);
    rows.push_back({name, stage, "parallel", n, s, count, 0, peak_rss_mib()});
    std::printf("%-16s %-44s %8zu sample points (%.1f points each)\n", name.c_str(), stage, count, double(n) / double(count));
  }
}


int run(int argc, char** argv)
{
  tune_process_environment(argv);
  const Bench_options options = parse_bench_options(argc, argv, "bench_simplification", 3);
  if(!options.valid) return 2;
  const bool quick = options.quick;
  const fs::path data = options.data, out = options.out;
  Models models = load_scans(data, quick);
  if(models.empty()) { std::fprintf(stderr, "bench_simplification: no model under %s/meshes (run scripts/fetch_data.sh)\n", data.string().c_str()); return 1; }
  add_armadillo_sampling(models, data, quick);
  std::vector<Row> rows;
  for(const auto& [name, cloud] : models) {
    bench_model<CGAL::Sequential_tag>(name, cloud, options.reps, rows);
    bench_model<CGAL::Parallel_tag>(name, cloud, options.reps, rows);
  }
  sweep_threshold(models.front().first, models.front().second, rows);

  std::string csv = "model,points,stage,mode,median_s,min_s,max_s,count,mean_shift_steps,peak_rss_mib\n";
  std::string md = "# Mean shift and simplification sample points benchmark\n\n" + machine_facts() +
                   format("- medians of %d runs (the threshold sweep: one run); normals given (mesh faces or sampled faces)\n", options.reps) +
                   "- stages: kNN graph, closed-form curvature, Gaussian mean shift (default bandwidths, stopped by the range part), clustering with "
                   "maximum size 50 and mode-spread threshold 1; the whole call includes the spatial sort and all stages\n"
                   "- count: sample points (ours, CGAL's hierarchy) or points kept (grid); steps: mean-shift steps per point\n\n"
                   "| model | points | stage | mode | median s | min-max s | count | steps | peak MiB |\n|---|---:|---|---|---:|---|---:|---:|---:|\n";
  for(const Row& r : rows) {
    csv += format("%s,%zu,\"%s\",%s,%g,%g,%g,%zu,%g,%g\n", r.model.c_str(), r.points, r.stage.c_str(), r.mode.c_str(),
                  r.time.median, r.time.min, r.time.max, r.count, r.iterations, r.peak_mib);
    md += format("| %s | %zu | %s | %s | %.3f | %.3f-%.3f | %zu | %.2f | %.0f |\n", r.model.c_str(), r.points,
                 r.stage.c_str(), r.mode.c_str(), r.time.median, r.time.min, r.time.max, r.count, r.iterations, r.peak_mib);
  }
  write_result_file(out, "simplification_results.csv", csv);
  write_result_file(out, "simplification_results.md", md);
  return 0;
}

} // namespace bench_simplification

// The project links every benchmark from one library (benchmark/CMakeLists.txt); alone, this file is a program.
#ifndef CGAL_EXT_BENCHMARK_LIBRARY
int main(int argc, char** argv) { return bench_simplification::run(argc, argv); }
#endif
