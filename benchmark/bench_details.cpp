// Benchmark of the details pipeline (issue: package foundation): kNN graph, symmetrisation, Laplacian assembly,
// detail filters of the three orders, and the whole compute_geometric_details call (normals given), on CGAL's
// scans and on a 1M-point sampling of the armadillo surface, sequentially and with the machine's threads.
// Usage: bench_details [--quick] [--data DIR] [--out DIR] [--reps N]
// Writes DIR/details_results.csv and DIR/details_results.md (medians, min-max, peak memory).
#include "bench_support.h"
#include "program_basics.h"
#include "point_io.h"

#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_point_set_laplacian.h>

#include <CGAL/IO/polygon_soup_io.h>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <sys/resource.h>
#include <sys/utsname.h>

namespace fs = std::filesystem;
using namespace point_detail;
namespace ci = CGAL_ext::internal;

namespace bench_details {

struct Row
{
  std::string model, stage, mode;
  std::size_t points;
  int threads;
  Stats time;
  double peak_mib;
};

template <typename Tag>
void bench_model(const std::string& name, const Point_cloud& cloud, int reps, int threads, std::vector<Row>& rows)
{
  const char* mode = std::is_same<Tag, CGAL::Sequential_tag>::value ? "sequential" : "parallel";
  const unsigned k = CGAL_ext::default_laplacian_neighbors;
  const std::size_t n = cloud.points.size();
  auto add = [&](const std::string& stage, Stats s) {
    rows.push_back({name, stage, mode, n, threads, s, peak_rss_mib()});
    std::printf("%-18s %-9s %-10s %8zu pts  %8.4f s (min %.4f, max %.4f)  peak %.0f MiB\n", name.c_str(), stage.c_str(), mode,
                n, s.median, s.min, s.max, rows.back().peak_mib);
  };
  ci::Spatial_point_cloud sc;
  add("sort", measure(reps, [&] { sc = ci::make_spatial_point_cloud<Tag>(cloud.points, CGAL::Identity_property_map<const Point>(), "bench"); }));
  ci::Progress progress;
  ci::Neighbor_graph directed, graph;
  add("knn", measure(reps, [&] { directed = ci::k_nearest_neighbor_graph<Tag>(sc.positions, k, progress); }));
  add("symmetrise", measure(reps, [&] { graph = ci::symmetrize<Tag>(directed); }));
  ci::Sparse_row_matrix K;
  add("laplacian", measure(reps, [&] { K = ci::laplacian_matrix<Tag>(sc.positions, graph, {}); }));
  for(auto order : {CGAL_ext::Detail_order::linear, CGAL_ext::Detail_order::quadric, CGAL_ext::Detail_order::cubic}) {
    ci::Matrix_n3 d;
    add(std::string("filter_") + CGAL_ext::Detail_filter::order_name(order),
        measure(reps, [&] { d = ci::apply_detail_filter<Tag>(K, CGAL_ext::Detail_filter{order, 0.8, 1.6}, sc.positions); }));
  }
  std::vector<Vector> details(n);
  std::vector<double> magnitude(n);
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  add("pipeline", measure(reps, [&] {
        CGAL_ext::compute_geometric_details<Tag>(idx, k, CGAL_ext::Detail_filter{}, CGAL::make_property_map(details),
                                                 CGAL::make_property_map(magnitude),
                                                 CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
                                                   .normal_map(CGAL::make_property_map(cloud.normals)));
      }));
}

int run(int argc, char** argv)
{
  tune_process_environment(argv);
  const Bench_options options = parse_bench_options(argc, argv, "bench_details", 5);
  if(!options.valid) return 2;
  const bool quick = options.quick;
  const fs::path data = options.data, out = options.out;
  const int reps = options.reps;
  const int threads = tbb::info::default_concurrency();
  std::vector<Row> rows;
  Models models = load_scans(data, quick);
  add_armadillo_sampling(models, data, quick);
  if(models.empty()) {
    std::fprintf(stderr, "bench_details: no model found under %s/meshes (run scripts/fetch_data.sh)\n", data.string().c_str());
    return 1;
  }
  for(const auto& [name, cloud] : models) {
    bench_model<CGAL::Sequential_tag>(name, cloud, name == "armadillo_1M" ? std::min(reps, 3) : reps, 1, rows);
    bench_model<CGAL::Parallel_tag>(name, cloud, name == "armadillo_1M" ? std::min(reps, 3) : reps, threads, rows);
  }
  std::string csv = "model,points,stage,mode,threads,median_s,min_s,max_s,peak_rss_mib\n";
  std::string md = "# Details pipeline benchmark\n\n" + machine_facts() +
                   "- k = 10 (symmetrised), uniform weights, lambda 0.8, mu 1.6; pipeline = compute_geometric_details "
                   "with normals given\n" +
                   format("- repetitions: %d (3 at 1M points); peak memory is the process's peak RSS when the stage "
                          "finished\n\n", reps) +
                   "| model | points | stage | mode | median s | min-max s | peak MiB |\n|---|---:|---|---|---:|---|---:|\n";
  for(const Row& r : rows) {
    csv += format("%s,%zu,%s,%s,%d,%g,%g,%g,%g\n", r.model.c_str(), r.points, r.stage.c_str(), r.mode.c_str(),
                  r.threads, r.time.median, r.time.min, r.time.max, r.peak_mib);
    md += format("| %s | %zu | %s | %s (%d) | %.4f | %.4f-%.4f | %.0f |\n", r.model.c_str(), r.points, r.stage.c_str(),
                 r.mode.c_str(), r.threads, r.time.median, r.time.min, r.time.max, r.peak_mib);
  }
  write_result_file(out, "details_results.csv", csv);
  write_result_file(out, "details_results.md", md);
  return 0;
}

} // namespace bench_details

// The project links every benchmark from one library (benchmark/CMakeLists.txt); alone, this file is a program.
#ifndef CGAL_EXT_BENCHMARK_LIBRARY
int main(int argc, char** argv) { return bench_details::run(argc, argv); }
#endif
