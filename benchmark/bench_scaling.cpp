// Benchmark of detail scaling and enhancement (issue: detail scaling and enhancement): the least-squares solve
// per order and solver on the paper's cases (bunny head scaled, Fig. 4; armadillo leg enhanced, Fig. 5/6),
// the 10,000-point region of the targets, and whole-model enhancement.
// Usage: bench_scaling [--quick] [--data DIR] [--out DIR] [--reps N]
// Writes DIR/scaling_results.csv and DIR/scaling_results.md (medians and min-max over repetitions).
#include "bench_support.h"
#include "program_basics.h"
#include "point_io.h"
#include "region_spec.h"

#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/scale_geometric_details.h>

#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numeric>
#include <sstream>

namespace fs = std::filesystem;
using namespace point_detail;

namespace bench_scaling {

struct Case
{
  std::string name;
  const Point_cloud* cloud;
  std::vector<std::size_t> roi; // empty: the whole model
  bool enhance;
};

struct Row
{
  std::string name, order, solver, method;
  std::size_t points, roi, anchors, normal_nonzeros;
  Stats assembly, factor, solve, call;
  int iterations;
  double residual;
};

const char* solver_name(CGAL_ext::Linear_solver s) { return s == CGAL_ext::Linear_solver::cholesky ? "cholesky" : "cg"; }

Row run_case(const Case& c, CGAL_ext::Detail_order order, CGAL_ext::Linear_solver solver, int reps)
{
  CGAL_ext::Detail_enhancement_settings settings(CGAL_ext::Detail_filter{order, 0.8, 1.6});
  settings.least_squares.solver = solver;
  std::vector<std::size_t> all(c.cloud->points.size());
  std::iota(all.begin(), all.end(), std::size_t(0));
  std::vector<double> assembly, factor, solve, call;
  CGAL_ext::Detail_manipulation_result result;
  for(int r = 0; r < reps; ++r) {
    std::vector<Point> moved = c.cloud->points;
    const auto np = CGAL::parameters::point_map(CGAL::make_property_map(moved)).normal_map(CGAL::make_property_map(c.cloud->normals));
    const auto start = std::chrono::steady_clock::now();
    if(c.enhance && c.roi.empty()) result = CGAL_ext::enhance_geometric_details(all, 10, 2.0, settings, np);
    else if(c.enhance) result = CGAL_ext::enhance_geometric_details(all, 10, c.roi, 2.0, settings, np);
    else result = CGAL_ext::scale_geometric_details(all, 10, c.roi, 2.0, settings, np);
    call.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    assembly.push_back(result.least_squares.assembly_seconds);
    factor.push_back(result.least_squares.factor_seconds);
    solve.push_back(result.least_squares.solve_seconds);
  }
  const auto& ls = result.least_squares;
  Row row{c.name, CGAL_ext::Detail_filter::order_name(order), solver_name(solver), ls.method, c.cloud->points.size(),
          result.region_size, result.anchor_count, ls.normal_nonzeros, summarize(assembly), summarize(factor),
          summarize(solve), summarize(call), ls.iterations, ls.relative_residual};
  std::printf("%-22s %-7s %-8s roi %6zu anchors %5zu nnz/row %6.1f  assembly %.3f factor %.3f solve %.3f (it %5d, res %.1e)  call %.3f s\n",
              row.name.c_str(), row.order.c_str(), row.solver.c_str(), row.roi, row.anchors,
              double(row.normal_nonzeros) / double(std::max<std::size_t>(row.roi, 1)), row.assembly.median, row.factor.median,
              row.solve.median, row.iterations, row.residual, row.call.median);
  return row;
}

/// The `count` points nearest to `centre`.
std::vector<std::size_t> nearest(const std::vector<Point>& points, const Point& centre, std::size_t count)
{
  std::vector<std::size_t> idx(points.size());
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  auto closer = [&](std::size_t a, std::size_t b) {
    return CGAL::squared_distance(points[a], centre) < CGAL::squared_distance(points[b], centre);
  };
  std::nth_element(idx.begin(), idx.begin() + std::ptrdiff_t(count), idx.end(), closer);
  idx.resize(count);
  std::sort(idx.begin(), idx.end());
  return idx;
}

/// Mean offset of the balanced-flow base surface along the normals, in mean neighbour spacings (shrinkage check).
double base_surface_offset(const Point_cloud& cloud)
{
  std::vector<Point> base = cloud.points;
  std::vector<std::size_t> all(base.size());
  std::iota(all.begin(), all.end(), std::size_t(0));
  CGAL_ext::balanced_flow_smooth_point_set(all, 10, CGAL_ext::Balanced_flow_settings(),
                                           CGAL::parameters::point_map(CGAL::make_property_map(base))
                                             .normal_map(CGAL::make_property_map(cloud.normals)));
  double offset = 0, rms = 0;
  for(std::size_t i = 0; i < base.size(); ++i) {
    const double d = (base[i] - cloud.points[i]) * cloud.normals[i];
    offset += d;
    rms += d * d;
  }
  return offset / std::sqrt(rms); // mean offset relative to the RMS offset (the size of the removed detail)
}


int run(int argc, char** argv)
{
  tune_process_environment(argv);
  const Bench_options options = parse_bench_options(argc, argv, "bench_scaling", 3);
  if(!options.valid) return 2;
  const bool quick = options.quick;
  const fs::path data = options.data, out = options.out;
  const int reps = options.reps;
  if(!fs::exists(data / "meshes/bunny00.off") || !fs::exists(data / "meshes/armadillo.off")) {
    std::fprintf(stderr, "bench_scaling: needs %s/meshes/{bunny00,armadillo}.off (run scripts/fetch_data.sh)\n", data.string().c_str());
    return 1;
  }
  const Point_cloud bunny = read_point_cloud(data / "meshes/bunny00.off");
  const Point_cloud armadillo = read_point_cloud(data / "meshes/armadillo.off");
  const Point head_centre(-0.33, 0.15, 0.0);
  std::vector<Case> cases = {
    {"bunny head (scale)", &bunny, select_points(bunny.points, {parse_region_spec("sphere:-0.33,0.15,0,0.3")}), false},
    {"armadillo leg (enhance)", &armadillo, select_points(armadillo.points, {parse_region_spec("sphere:-34,-32,10,25")}), true},
    {"10k region (scale)", &bunny, nearest(bunny.points, head_centre, 10000), false},
  };
  if(!quick) cases.push_back({"bunny whole (enhance)", &bunny, {}, true});

  using CGAL_ext::Detail_order;
  std::vector<Row> rows;
  for(const Case& c : cases)
    for(Detail_order order : {Detail_order::linear, Detail_order::quadric, Detail_order::cubic}) {
      rows.push_back(run_case(c, order, CGAL_ext::Linear_solver::cholesky, reps));
      // Conjugate gradients need thousands of iterations on the cubic order: one repetition, the paper's cases only.
      const bool paper_case = c.name.find("bunny head") == 0 || c.name.find("armadillo leg") == 0;
      if(paper_case && !(quick && order == Detail_order::cubic))
        rows.push_back(run_case(c, order, CGAL_ext::Linear_solver::conjugate_gradient, 1));
    }
  const double offset = base_surface_offset(armadillo);
  std::printf("balanced-flow base of the armadillo: mean normal offset = %.3f of the RMS offset\n", offset);

  std::ostringstream csv;
  csv << "case,points,order,solver,roi,anchors,normal_nonzeros,assembly_s,factor_s,solve_s,total_s,call_s,iterations,relative_residual,method\n";
  for(const Row& r : rows)
    csv << '"' << r.name << "\"," << r.points << "," << r.order << "," << r.solver << "," << r.roi << "," << r.anchors << ","
        << r.normal_nonzeros << "," << r.assembly.median << "," << r.factor.median << "," << r.solve.median << ","
        << r.assembly.median + r.factor.median + r.solve.median << "," << r.call.median << "," << r.iterations << ","
        << r.residual << ",\"" << r.method << "\"\n";

  std::string md = "# Detail scaling and enhancement benchmark\n\n" + machine_facts() +
                   format("- k = 10, lambda 0.8, mu 1.6, s = 2, default anchors; medians of %d repetitions for Cholesky "
                          "(min-max of the total beside), 1 for conjugate gradients\n", reps) +
                   "- total = assembly (ROI rows of f(K), normal matrix) + factor + solve (with refinement); call = the whole "
                   "function (kNN, Laplacian, normals given, base surface for enhancement, write-back)\n\n"
                   "| case | order | solver | ROI | anchors | nnz/row of N | assembly s | factor s | solve s | total s (min-max) | iterations | rel. residual | call s |\n"
                   "|---|---|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|\n";
  for(const Row& r : rows) {
    const double total = r.assembly.median + r.factor.median + r.solve.median;
    const double lo = r.assembly.min + r.factor.min + r.solve.min, hi = r.assembly.max + r.factor.max + r.solve.max;
    md += format("| %s | %s | %s | %zu | %zu | %.0f | %.3f | %.3f | %.3f | %.3f (%.3f-%.3f) | %d | %.1e | %.3f |\n",
                 r.name.c_str(), r.order.c_str(), r.solver.c_str(), r.roi, r.anchors,
                 double(r.normal_nonzeros) / double(std::max<std::size_t>(r.roi, 1)), r.assembly.median, r.factor.median,
                 r.solve.median, total, lo, hi, r.iterations, r.residual, r.call.median);
  }
  md += "\nCholesky: " + (rows.empty() ? std::string() : rows.front().method) + ".\n" +
        format("Balanced-flow base surface of the armadillo: mean offset along the normals = %g of the RMS offset (0: no "
               "shrinkage or swelling).\n", offset);
  write_result_file(out, "scaling_results.csv", csv.str());
  write_result_file(out, "scaling_results.md", md);
  return 0;
}

} // namespace bench_scaling

// The project links every benchmark from one library (benchmark/CMakeLists.txt); alone, this file is a program.
#ifndef CGAL_EXT_BENCHMARK_LIBRARY
int main(int argc, char** argv) { return bench_scaling::run(argc, argv); }
#endif
