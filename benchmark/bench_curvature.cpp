// Benchmark of mean-curvature estimation (issue: curvature, mean shift and SSPs): CGAL's Monge jet fitting and
// the closed-form fit, on CGAL's scans and a 1M-point sampling of the armadillo, sequentially and in parallel,
// beside CGAL's jet_estimate_normals in the same run.
// Usage: bench_curvature [--quick] [--data DIR] [--out DIR] [--reps N]
// Writes DIR/curvature_results.csv and DIR/curvature_results.md.
#include "bench_support.h"
#include "cli_support.h"
#include "point_io.h"

#include <CGAL_ext/estimate_mean_curvature.h>

#include <CGAL/jet_estimate_normals.h>

#include <tbb/info.h>

#include <cstdio>
#include <fstream>
#include <numeric>

namespace fs = std::filesystem;
using namespace point_detail;

namespace {

struct Row
{
  std::string model, method, mode;
  std::size_t points;
  unsigned k;
  Stats time;
  double peak_mib, error; // error: median |H| difference to the Monge fit at k = 15 (0 for the Monge rows)
};

template <typename Tag>
void bench_model(const std::string& name, const Point_cloud& cloud, int reps, std::vector<Row>& rows)
{
  const char* mode = std::is_same<Tag, CGAL::Sequential_tag>::value ? "sequential" : "parallel";
  const std::size_t n = cloud.points.size();
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(cloud.points)).normal_map(CGAL::make_property_map(cloud.normals));
  std::vector<double> reference(n), H(n);
  auto add = [&](const std::string& method, unsigned k, Stats s, double error) {
    rows.push_back({name, method, mode, n, k, s, peak_rss_mib(), error});
    std::printf("%-16s %-22s k %2u %-10s %8zu pts  %8.3f s (min %.3f, max %.3f)  median |dH| %.2e  peak %.0f MiB\n", name.c_str(),
                method.c_str(), k, mode, n, s.median, s.min, s.max, error, rows.back().peak_mib);
  };
  auto median_difference = [&] {
    std::vector<double> d(n);
    for(std::size_t i = 0; i < n; ++i) d[i] = std::abs(H[i] - reference[i]);
    return summarize(d).median;
  };
  // Timings first, then the comparison (an argument list would not order them).
  const Stats monge = measure(reps, [&] {
    CGAL_ext::estimate_mean_curvature<Tag>(idx, 15, CGAL_ext::Curvature_fitting::monge_jet_fitting, CGAL::make_property_map(reference), np);
  });
  add("monge_jet_fitting", 15, monge, 0.0);
  for(unsigned k : {15u, 10u}) {
    const Stats closed = measure(reps, [&] {
      CGAL_ext::estimate_mean_curvature<Tag>(idx, k, CGAL_ext::Curvature_fitting::closed_form, CGAL::make_property_map(H), np);
    });
    add("closed_form", k, closed, median_difference());
  }
  std::vector<Point> points = cloud.points;
  std::vector<Vector> normals(n);
  const Stats jet = measure(reps, [&] {
    CGAL::jet_estimate_normals<Tag>(idx, 18, CGAL::parameters::point_map(CGAL::make_property_map(points)).normal_map(CGAL::make_property_map(normals)));
  });
  add("CGAL jet_estimate_normals", 18, jet, 0.0);
}

} // namespace

int main(int argc, char** argv)
{
  use_huge_pages(argv);
  const Bench_options options = parse_bench_options(argc, argv, "bench_curvature", 3);
  if(!options.valid) return 2;
  const bool quick = options.quick;
  const fs::path data = options.data, out = options.out;
  const int reps = options.reps;
  std::vector<std::pair<std::string, Point_cloud>> models;
  for(const char* m : {"armadillo", "bunny00", "refined_elephant", "camel"}) {
    const fs::path file = data / "meshes" / (std::string(m) + ".off");
    if(!fs::exists(file)) continue;
    models.emplace_back(m, read_point_cloud(file));
    if(quick) break;
  }
  if(models.empty()) { std::fprintf(stderr, "bench_curvature: no model under %s/meshes (run scripts/fetch_data.sh)\n", data.string().c_str()); return 1; }
  models.emplace_back(quick ? "armadillo_100k" : "armadillo_1M", sample_mesh(data / "meshes/armadillo.off", quick ? 100000 : 1000000));
  std::vector<Row> rows;
  for(const auto& [name, cloud] : models) {
    bench_model<CGAL::Sequential_tag>(name, cloud, reps, rows);
    bench_model<CGAL::Parallel_tag>(name, cloud, reps, rows);
  }
  fs::create_directories(out);
  std::ofstream csv(out / "curvature_results.csv");
  csv << "model,points,method,k,mode,median_s,min_s,max_s,peak_rss_mib,median_abs_difference_to_monge\n";
  for(const Row& r : rows)
    csv << r.model << "," << r.points << ",\"" << r.method << "\"," << r.k << "," << r.mode << "," << r.time.median << ","
        << r.time.min << "," << r.time.max << "," << r.peak_mib << "," << r.error << "\n";
  std::ofstream md(out / "curvature_results.md");
  md << "# Mean-curvature benchmark\n\n- " << tbb::info::default_concurrency() << " threads in parallel runs; malloc: " << malloc_pages()
     << "; medians of " << reps << " runs; normals given (mesh faces or sampled faces)\n"
     << "- times include the kNN graph; |dH| is the median absolute difference to the Monge fit at k = 15\n\n"
     << "| model | points | method | k | mode | median s | min-max s | median abs dH | peak MiB |\n|---|---:|---|---:|---|---:|---|---:|---:|\n";
  char buf[320];
  for(const Row& r : rows) {
    std::snprintf(buf, sizeof buf, "| %s | %zu | %s | %u | %s | %.3f | %.3f-%.3f | %.2e | %.0f |\n", r.model.c_str(), r.points,
                  r.method.c_str(), r.k, r.mode.c_str(), r.time.median, r.time.min, r.time.max, r.error, r.peak_mib);
    md << buf;
  }
  std::printf("wrote %s and %s\n", (out / "curvature_results.md").string().c_str(), (out / "curvature_results.csv").string().c_str());
  return 0;
}
