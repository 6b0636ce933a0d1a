// Benchmark of mean-curvature estimation (issue: curvature, mean shift and SSPs): CGAL's Monge jet fitting and
// the closed-form fit, on CGAL's scans and a 1M-point sampling of the armadillo, sequentially and in parallel,
// beside CGAL's jet_estimate_normals in the same run; CGAL's Monge path and the closed form against the
// analytic curvature of a sphere, a cylinder and a torus, time beside accuracy. Then normal estimation for scans without normals
// (issue: raw million-point scans): CGAL_ext::estimate_oriented_normals against CGAL's jet_estimate_normals +
// mst_orient_normals, time and the fraction of normals pointing away from the mesh's, on every model under
// DATA/meshes (vertices, and 100k samples of the surface) and on 1M samples of the armadillo.
// Usage: bench_curvature [--quick] [--data DIR] [--out DIR] [--reps N]
// Writes DIR/curvature_results.{csv,md}, DIR/curvature_accuracy.csv and DIR/normals_results.{csv,md}.
#include "bench_support.h"
#include "program_basics.h"
#include "point_io.h"

#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/estimate_oriented_normals.h>

#include <CGAL/jet_estimate_normals.h>
#include <CGAL/mst_orient_normals.h>

#include <tbb/info.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <random>
#include <tuple>

namespace fs = std::filesystem;
using namespace point_detail;

namespace bench_curvature {

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

struct Accuracy_row
{
  std::string shape, method;
  std::size_t points;
  Stats time;
  double median_error, p95_error; // |H - H_true| / |H_true|
};

/// Samples of analytic surfaces with exact outward normals and their mean curvature (positive where the surface
/// bends away from the normal): a unit sphere, a cylinder of radius 0.5 and height 4 (H = 1; points within 0.2 of
/// its open ends are not scored) and a torus R = 1, r = 0.4 (H = (R + 2 r cos v) / (2 r (R + r cos v))),
/// sampled uniformly by area.
struct Analytic_shape
{
  std::string name;
  Point_cloud cloud;
  std::vector<double> curvature; // NaN: not scored
};

std::vector<Analytic_shape> analytic_shapes(std::size_t n)
{
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double pi = CGAL_PI;
  std::vector<Analytic_shape> shapes(3);
  shapes[0].name = "sphere r 1";
  shapes[1].name = "cylinder r 0.5";
  shapes[2].name = "torus R 1, r 0.4";
  for(std::size_t i = 0; i < n; ++i) {
    const double z = 1 - 2 * unit(rng), phi = 2 * pi * unit(rng), s = std::sqrt(1 - z * z);
    shapes[0].cloud.points.emplace_back(s * std::cos(phi), s * std::sin(phi), z);
    shapes[0].cloud.normals.emplace_back(s * std::cos(phi), s * std::sin(phi), z);
    shapes[0].curvature.push_back(1.0);
    const double a = 2 * pi * unit(rng), h = 4 * unit(rng) - 2;
    shapes[1].cloud.points.emplace_back(0.5 * std::cos(a), 0.5 * std::sin(a), h);
    shapes[1].cloud.normals.emplace_back(std::cos(a), std::sin(a), 0);
    shapes[1].curvature.push_back(std::abs(h) < 1.8 ? 1.0 : std::nan(""));
  }
  const double R = 1, r = 0.4;
  while(shapes[2].cloud.points.size() < n) {
    const double u = 2 * pi * unit(rng), v = 2 * pi * unit(rng);
    if(unit(rng) * (R + r) > R + r * std::cos(v)) continue; // area element (R + r cos v)
    const double ring = R + r * std::cos(v);
    shapes[2].cloud.points.emplace_back(ring * std::cos(u), ring * std::sin(u), r * std::sin(v));
    shapes[2].cloud.normals.emplace_back(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
    shapes[2].curvature.push_back((R + 2 * r * std::cos(v)) / (2 * r * ring));
  }
  return shapes;
}

/// CGAL's mean-curvature path (CGAL::Monge_via_jet_fitting, through `Curvature_fitting::monge_jet_fitting`) and
/// the closed-form fit at the same k = 15, in parallel: time and error against the analytic curvature.
void bench_accuracy(std::size_t n, int reps, std::vector<Accuracy_row>& rows)
{
  for(const Analytic_shape& shape : analytic_shapes(n)) {
    std::vector<std::size_t> idx(n);
    std::iota(idx.begin(), idx.end(), std::size_t(0));
    const auto np = CGAL::parameters::point_map(CGAL::make_property_map(shape.cloud.points))
                      .normal_map(CGAL::make_property_map(shape.cloud.normals));
    for(const auto& [method, fitting] : {std::pair{"CGAL Monge_via_jet_fitting", CGAL_ext::Curvature_fitting::monge_jet_fitting},
                                         std::pair{"CGAL_ext closed form", CGAL_ext::Curvature_fitting::closed_form}}) {
      std::vector<double> H(n);
      const Stats time = measure(reps, [&] {
        CGAL_ext::estimate_mean_curvature<CGAL::Parallel_tag>(idx, 15, fitting, CGAL::make_property_map(H), np);
      });
      std::vector<double> error;
      for(std::size_t i = 0; i < n; ++i)
        if(!std::isnan(shape.curvature[i])) error.push_back(std::abs(H[i] - shape.curvature[i]) / std::abs(shape.curvature[i]));
      std::sort(error.begin(), error.end());
      rows.push_back({shape.name, method, n, time, error[error.size() / 2], error[error.size() * 95 / 100]});
      std::printf("%-18s %-28s %8zu pts  %8.3f s  relative error median %.2e, 95th %.2e\n", shape.name.c_str(), method, n,
                  time.median, rows.back().median_error, rows.back().p95_error);
    }
  }
}

struct Normals_row
{
  std::string model, method;
  std::size_t points;
  Stats time;
  double flipped; // fraction of normals at more than 90 degrees from the mesh's
};

/// Fraction of `normals` pointing away from the reference `truth`.
double flipped_fraction(const std::vector<Vector>& normals, const std::vector<Vector>& truth)
{
  std::size_t flipped = 0;
  for(std::size_t i = 0; i < normals.size(); ++i)
    if(normals[i] * truth[i] < 0) ++flipped;
  return double(flipped) / double(normals.size());
}

void bench_normals(const std::string& name, const Point_cloud& cloud, int reps, std::vector<Normals_row>& rows)
{
  const std::size_t n = cloud.points.size();
  if(n <= CGAL_ext::default_normal_neighbors) return;
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  auto add = [&](const std::string& method, Stats s, double flipped) {
    rows.push_back({name, method, n, s, flipped});
    std::printf("%-28s %-40s %8zu pts  %8.3f s (min %.3f, max %.3f)  flipped %.4f %%\n", name.c_str(), method.c_str(), n,
                s.median, s.min, s.max, 100 * flipped);
  };
  std::vector<Vector> ours(n);
  const Stats time = measure(reps, [&] {
    CGAL_ext::estimate_oriented_normals<CGAL::Parallel_tag>(
      idx, CGAL_ext::default_normal_neighbors,
      CGAL::parameters::point_map(CGAL::make_property_map(cloud.points)).normal_map(CGAL::make_property_map(ours)));
  });
  add("CGAL_ext estimate_oriented_normals", time, flipped_fraction(ours, cloud.normals));

  // CGAL's orientation reorders its range: the items carry their index.
  using Item = std::tuple<Point, Vector, std::size_t>;
  std::vector<Item> items;
  const Stats cgal = measure(reps, [&] {
    items.clear();
    for(std::size_t i = 0; i < n; ++i) items.emplace_back(cloud.points[i], Vector(0, 0, 0), i);
    const auto np = CGAL::parameters::point_map(CGAL::Nth_of_tuple_property_map<0, Item>())
                      .normal_map(CGAL::Nth_of_tuple_property_map<1, Item>());
    // CGAL's k counts the point itself: k + 1 fits the same jets.
    CGAL::jet_estimate_normals<CGAL::Parallel_tag>(items, CGAL_ext::default_normal_neighbors + 1, np);
    CGAL::mst_orient_normals(items, CGAL_ext::default_normal_neighbors + 1, np);
  });
  std::vector<Vector> theirs(n);
  for(const Item& item : items) theirs[std::get<2>(item)] = std::get<1>(item);
  add("CGAL jet_estimate_normals + mst_orient_normals", cgal, flipped_fraction(theirs, cloud.normals));
}

void write_normals_results(const fs::path& out, const std::vector<Normals_row>& rows, int reps)
{
  std::string csv = "model,points,method,median_s,min_s,max_s,flipped_fraction\n";
  for(const Normals_row& r : rows)
    csv += format("%s,%zu,\"%s\",%g,%g,%g,%g\n", r.model.c_str(), r.points, r.method.c_str(), r.time.median, r.time.min,
                  r.time.max, r.flipped);
  std::string md = "# Normal estimation for scans without normals\n\n" + machine_facts() +
                   format("- medians of %d runs; 18 neighbours\n", reps) +
                   "- flipped: normals more than 90 degrees from the mesh's (its area-weighted vertex normals for the "
                   "vertices, the sampled face's normal for the samples)\n\n"
                   "| model | points | CGAL_ext s | CGAL s | CGAL_ext flipped | CGAL flipped |\n|---|---:|---:|---:|---:|---:|\n";
  for(std::size_t i = 0; i + 1 < rows.size(); i += 2)
    md += format("| %s | %zu | %.3f | %.3f | %.3f %% | %.3f %% |\n", rows[i].model.c_str(), rows[i].points,
                 rows[i].time.median, rows[i + 1].time.median, 100 * rows[i].flipped, 100 * rows[i + 1].flipped);
  write_result_file(out, "normals_results.csv", csv);
  write_result_file(out, "normals_results.md", md);
}

int run(int argc, char** argv)
{
  tune_process_environment(argv);
  const Bench_options options = parse_bench_options(argc, argv, "bench_curvature", 3);
  if(!options.valid) return 2;
  const bool quick = options.quick;
  const fs::path data = options.data, out = options.out;
  const int reps = options.reps;
  Models models = load_scans(data, quick);
  if(models.empty()) { std::fprintf(stderr, "bench_curvature: no model under %s/meshes (run scripts/fetch_data.sh)\n", data.string().c_str()); return 1; }
  if(!quick) add_armadillo_sampling(models, data, quick); // the quick run only keeps the harness working
  std::vector<Row> rows;
  for(const auto& [name, cloud] : models) {
    bench_model<CGAL::Sequential_tag>(name, cloud, reps, rows);
    bench_model<CGAL::Parallel_tag>(name, cloud, reps, rows);
  }
  std::string csv = "model,points,method,k,mode,median_s,min_s,max_s,peak_rss_mib,median_abs_difference_to_monge\n";
  std::string md = "# Mean-curvature benchmark\n\n" + machine_facts() +
                   format("- medians of %d runs; normals given (mesh faces or sampled faces)\n", reps) +
                   "- times include the kNN graph; |dH| is the median absolute difference to the Monge fit at k = 15\n\n"
                   "| model | points | method | k | mode | median s | min-max s | median abs dH | peak MiB |\n|---|---:|---|---:|---|---:|---|---:|---:|\n";
  for(const Row& r : rows) {
    csv += format("%s,%zu,\"%s\",%u,%s,%g,%g,%g,%g,%g\n", r.model.c_str(), r.points, r.method.c_str(), r.k, r.mode.c_str(),
                  r.time.median, r.time.min, r.time.max, r.peak_mib, r.error);
    md += format("| %s | %zu | %s | %u | %s | %.3f | %.3f-%.3f | %.2e | %.0f |\n", r.model.c_str(), r.points,
                 r.method.c_str(), r.k, r.mode.c_str(), r.time.median, r.time.min, r.time.max, r.error, r.peak_mib);
  }

  std::vector<Accuracy_row> accuracy;
  bench_accuracy(quick ? 20000 : 200000, reps, accuracy);
  std::string accuracy_csv = "shape,points,method,k,median_s,min_s,max_s,median_relative_error,p95_relative_error\n";
  md += "\n## Against the analytic curvature, beside CGAL's Monge_via_jet_fitting\n\n"
        "Random samples (uniform by area) with exact normals, k = 15 for both, parallel; error |H - H_true| / |H_true| "
        "(the cylinder without its ends).\n\n"
        "| shape | points | method | median s | median error | 95th pct error |\n|---|---:|---|---:|---:|---:|\n";
  for(const Accuracy_row& r : accuracy) {
    accuracy_csv += format("\"%s\",%zu,\"%s\",15,%g,%g,%g,%g,%g\n", r.shape.c_str(), r.points, r.method.c_str(),
                           r.time.median, r.time.min, r.time.max, r.median_error, r.p95_error);
    md += format("| %s | %zu | %s | %.3f | %.2e | %.2e |\n", r.shape.c_str(), r.points, r.method.c_str(), r.time.median,
                 r.median_error, r.p95_error);
  }
  write_result_file(out, "curvature_results.csv", csv);
  write_result_file(out, "curvature_accuracy.csv", accuracy_csv);
  write_result_file(out, "curvature_results.md", md);

  std::vector<Normals_row> normal_rows;
  std::vector<fs::path> meshes;
  for(const auto& entry : fs::directory_iterator(data / "meshes"))
    if(entry.path().extension() == ".off") meshes.push_back(entry.path());
  std::sort(meshes.begin(), meshes.end());
  for(const fs::path& mesh : meshes) {
    const std::string name = mesh.stem().string();
    bench_normals(name + " (vertices)", read_point_cloud(mesh), reps, normal_rows);
    bench_normals(name + " (100k samples)", sample_mesh(mesh, 100000), reps, normal_rows);
    if(quick) break;
  }
  if(!quick) bench_normals("armadillo (1M samples)", sample_mesh(data / "meshes/armadillo.off", 1000000), reps, normal_rows);
  write_normals_results(out, normal_rows, reps);
  return 0;
}

} // namespace bench_curvature

// The project links every benchmark from one library (benchmark/CMakeLists.txt); alone, this file is a program.
#ifndef CGAL_EXT_BENCHMARK_LIBRARY
int main(int argc, char** argv) { return bench_curvature::run(argc, argv); }
#endif
