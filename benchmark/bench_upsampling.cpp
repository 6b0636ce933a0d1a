// Benchmark of up-sampling after an edit (issue: up-sampling and relaxation): the armadillo's arm pulled far out
// by a detail-preserving edit, then filled by upsample_point_set and by CGAL::edge_aware_upsample_point_set asked
// for the same number of output points, in the same run: points added, time, covering radius of the edited
// surface before and after, and the distance of the new points to that surface (the mesh with its vertices
// moved by the same edit). The same on a 1M-point sampling of the mesh, edited together with its vertices.
// Usage: bench_upsampling [--quick] [--data DIR] [--out DIR] [--reps N]
// Writes DIR/upsampling_results.csv and DIR/upsampling_results.md.
#include "bench_support.h"
#include "program_basics.h"
#include "point_io.h"

#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/upsample_point_set.h>

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/edge_aware_upsample_point_set.h>

#include <tbb/info.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <numeric>

namespace fs = std::filesystem;
using namespace point_detail;
namespace internal = CGAL_ext::internal;
using Mesh = CGAL::Surface_mesh<Point>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_face_graph_triangle_primitive<Mesh>>>;
using Inserted = std::vector<std::pair<Point, Vector>>;

namespace bench_upsampling {

Markdown_report report;
std::ofstream csv;

/// The largest distance from the reference samples to their nearest point of `samples`.
double covering_radius(const std::vector<Point>& samples, const std::vector<Point>& reference)
{
  const internal::Matrix_n3 s = to_matrix(samples), q = to_matrix(reference);
  const internal::Neighbor_graph nearest = internal::k_nearest_samples<CGAL::Parallel_tag>(s, q, 1);
  double radius = 0;
  for(Eigen::Index i = 0; i < q.rows(); ++i) radius = std::max(radius, (q.row(i) - s.row(nearest.indices[std::size_t(i)])).norm());
  return radius;
}

/// The arm nearest +x pulled out by 25 % of the diagonal: region within 40 % of the diagonal from the extreme
/// point, handle within 6 %, as in the editing benchmark. Returns the deformed points and normals.
Point_cloud pull_arm(const Point_cloud& cloud, double diagonal)
{
  std::size_t extreme = 0;
  for(std::size_t i = 1; i < cloud.points.size(); ++i)
    if(cloud.points[i].x() > cloud.points[extreme].x()) extreme = i;
  std::vector<std::size_t> all(cloud.points.size());
  std::iota(all.begin(), all.end(), std::size_t(0));
  CGAL_ext::Detail_preserving_deformation<CGAL::Parallel_tag> edit(
    all, CGAL_ext::Detail_preserving_deformation_settings(),
    CGAL::parameters::point_map(CGAL::make_property_map(cloud.points)).normal_map(CGAL::make_property_map(cloud.normals)));
  const std::size_t hand = edit.create_handle_group();
  for(std::size_t i = 0; i < cloud.points.size(); ++i) {
    const double d = std::sqrt(CGAL::squared_distance(cloud.points[i], cloud.points[extreme]));
    if(d < 0.4 * diagonal) edit.insert_roi_point(i);
    if(d < 0.06 * diagonal) edit.insert_handle_point(hand, i);
  }
  edit.set_handle_transform(hand, Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.25 * diagonal, 0, 0));
  edit.deform();
  Point_cloud out;
  out.points.resize(cloud.points.size());
  out.normals.resize(cloud.points.size());
  edit.diffuse(all, CGAL::parameters::point_map(CGAL::make_property_map(out.points)).normal_map(CGAL::make_property_map(out.normals)));
  return out;
}

/// `input` is the mesh's vertices, or another sampling of its surface that the edit moves together with them
/// (`samples_are_vertices` false): either way the mesh with its vertices moved is the edited surface.
void bench(const std::string& name, const Point_cloud& input, const Mesh& mesh, const Point_cloud& vertices,
           bool samples_are_vertices, int reps)
{
  const double diagonal = diagonal_of(input.points);
  Point_cloud edited_vertices, stretched;
  if(samples_are_vertices) {
    stretched = edited_vertices = pull_arm(input, diagonal);
  } else {
    Point_cloud both = vertices;
    both.points.insert(both.points.end(), input.points.begin(), input.points.end());
    both.normals.insert(both.normals.end(), input.normals.begin(), input.normals.end());
    const Point_cloud edited = pull_arm(both, diagonal);
    const auto split = std::ptrdiff_t(vertices.points.size());
    edited_vertices.points.assign(edited.points.begin(), edited.points.begin() + split);
    stretched.points.assign(edited.points.begin() + split, edited.points.end());
    stretched.normals.assign(edited.normals.begin() + split, edited.normals.end());
  }
  const std::size_t n = stretched.points.size();
  std::vector<std::size_t> all(n);
  std::iota(all.begin(), all.end(), std::size_t(0));
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(stretched.points))
                    .normal_map(CGAL::make_property_map(stretched.normals));

  // The target spacing is the model's before the edit.
  const internal::Matrix_n3 before = to_matrix(input.points);
  const internal::Position_tree input_tree(before, CGAL::Parallel_tag());
  CGAL_ext::Upsampling_settings settings;
  settings.detection.spacing = internal::typical_spacing<CGAL::Parallel_tag>(before, input_tree);

  Inserted ours, theirs;
  const Stats ours_time = measure(reps, [&] {
    ours.clear();
    CGAL_ext::upsample_point_set<CGAL::Parallel_tag>(all, settings, std::back_inserter(ours), np);
  });
  const Stats their_time = measure(1, [&] {
    theirs.clear();
    CGAL::edge_aware_upsample_point_set<CGAL::Parallel_tag>(
      all, std::back_inserter(theirs), np.number_of_output_points(n + std::max<std::size_t>(ours.size(), 1)));
  });

  // The reference: the mesh with its vertices moved by the same edit, sampled densely.
  Mesh deformed = mesh;
  for(Mesh::Vertex_index v : deformed.vertices()) deformed.point(v) = edited_vertices.points[v.idx()];
  const fs::path off = fs::temp_directory_path() / "bench_upsampling_reference.off";
  CGAL::IO::write_polygon_mesh(off.string(), deformed, CGAL::parameters::stream_precision(17));
  const std::vector<Point> reference = sample_mesh(off, std::min<std::size_t>(20 * n, 4000000)).points;
  fs::remove(off);
  const auto tree = std::make_unique<Tree>(faces(deformed).first, faces(deformed).second, deformed);
  const double h = settings.detection.spacing;
  // The edited input itself lies off the reference where the mesh's flat triangles cannot follow the edit:
  // the floor under which no new point's distance means anything. Where the edit stretched a triangle past a
  // few spacings, its chord strays from the curved edited surface, so distances are also reported where the
  // nearest triangle has no edge longer than 4 h.
  auto distance_to_reference = [&](const Point& p, bool& short_triangle) {
    const auto [closest, face] = tree->closest_point_and_primitive(p);
    double longest = 0;
    for(Mesh::Halfedge_index e : halfedges_around_face(halfedge(face, deformed), deformed))
      longest = std::max(longest, std::sqrt(CGAL::squared_distance(deformed.point(source(e, deformed)), deformed.point(target(e, deformed)))));
    short_triangle = longest <= 4 * h;
    return std::sqrt(CGAL::squared_distance(p, closest));
  };
  double input_farthest = 0;
  for(const Point& p : stretched.points) input_farthest = std::max(input_farthest, std::sqrt(tree->squared_distance(p)));
  auto row = [&](const char* method, const Inserted& added, const Stats& time) {
    std::vector<Point> all_points = stretched.points;
    double farthest = 0, farthest_where_short = 0, mean = 0;
    for(const auto& [p, normal] : added) {
      all_points.push_back(p);
      bool short_triangle = false;
      const double d = distance_to_reference(p, short_triangle);
      farthest = std::max(farthest, d);
      if(short_triangle) farthest_where_short = std::max(farthest_where_short, d);
      mean += d / double(added.size());
    }
    const double before = covering_radius(stretched.points, reference) / h, after = covering_radius(all_points, reference) / h;
    report.addf("| %s | %s | %zu | %zu | %.3f | %.2f | %.2f | %.4f | %.4f | %.4f | %.4f |\n", name.c_str(), method, n,
                added.size(), time.median, before, after, mean / h, farthest / h, farthest_where_short / h, input_farthest / h);
    csv << name << ",\"" << method << "\"," << n << "," << added.size() << "," << time.median << "," << before << "," << after
        << "," << mean / h << "," << farthest / h << "," << farthest_where_short / h << "," << input_farthest / h << "\n";
  };
  row("ours (upsample_point_set)", ours, ours_time);
  row("CGAL edge_aware_upsample_point_set, same output size", theirs, their_time);
  // As `edit --upsample` runs it: gaps looked for from the points the edit moved only.
  std::vector<std::size_t> moved;
  for(std::size_t i = 0; i < n; ++i)
    if(stretched.points[i] != input.points[i]) moved.push_back(i);
  Inserted from_moved;
  const Stats moved_time = measure(reps, [&] {
    from_moved.clear();
    CGAL_ext::upsample_point_set<CGAL::Parallel_tag>(all, moved, settings, std::back_inserter(from_moved), np);
  });
  row("ours, gaps from the moved points only (edit --upsample)", from_moved, moved_time);
  if(!samples_are_vertices) {
    // What the sampling itself asks for, before the edit: a random sampling has gaps of its own. At the one
    // spacing h they are holes; with local spacings (the default) only gaps twice as wide as their surroundings'.
    std::vector<std::size_t> indices(input.points.size());
    std::iota(indices.begin(), indices.end(), std::size_t(0));
    for(const bool local : {false, true}) {
      CGAL_ext::Upsampling_settings unedited_settings = settings;
      if(local) unedited_settings.detection.spacing = 0;
      Inserted unedited;
      const Stats t = measure(1, [&] {
        CGAL_ext::upsample_point_set<CGAL::Parallel_tag>(indices, unedited_settings, std::back_inserter(unedited),
                                                         CGAL::parameters::point_map(CGAL::make_property_map(input.points))
                                                           .normal_map(CGAL::make_property_map(input.normals)));
      });
      const char* method = local ? "ours on the same sampling before the edit, local spacings (the default)"
                                 : "ours on the same sampling before the edit";
      report.addf("| %s | %s | %zu | %zu | %.3f | | | | | | |\n", name.c_str(), method, input.points.size(),
                  unedited.size(), t.median);
      csv << name << ",\"" << method << "\"," << input.points.size() << "," << unedited.size() << "," << t.median << ",,,,,,\n";
    }
  }
}


int run(int argc, char** argv)
{
  tune_process_environment(argv);
  const Bench_options options = parse_bench_options(argc, argv, "bench_upsampling", 3);
  if(!options.valid) return 2;
  const fs::path file = options.data / "meshes/armadillo.off";
  if(!fs::exists(file)) { std::fprintf(stderr, "bench_upsampling: no %s (run scripts/fetch_data.sh)\n", file.string().c_str()); return 1; }
  fs::create_directories(options.out);
  csv.open(options.out / "upsampling_results.csv");
  csv << "model,method,points,inserted,median_s,covering_radius_before_h,covering_radius_after_h,mean_distance_of_new_h,"
         "largest_distance_of_new_h,largest_distance_of_new_by_short_triangles_h,largest_distance_of_input_h\n";
  report.add("# Up-sampling benchmark\n\n" + machine_facts());
  report.addf("- ours: median of %d runs, CGAL's: one run\n"
              "- the arm nearest +x pulled out by 25 %% of the diagonal (detail-preserving edit, quadric, default SSPs); "
              "target spacing: the model's typical spacing h before the edit\n"
              "- covering radius: the largest distance from the edited surface (the mesh with its vertices moved by "
              "the same edit, sampled 20 times denser) to the nearest sample; distances in h\n\n"
              "| model | method | points | new points | time s | covering radius before | after | mean distance of new points to the surface | largest | largest where the surface's triangle is shorter than 4 h | largest of the edited input |\n"
              "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
                options.reps);
  Mesh mesh;
  if(!CGAL::IO::read_polygon_mesh(file.string(), mesh)) { std::fprintf(stderr, "cannot read %s\n", file.string().c_str()); return 1; }
  const Point_cloud vertices = read_point_cloud(file);
  bench("armadillo", vertices, mesh, vertices, true, options.reps);
  if(!options.quick) {
    // Three splits give edges of 0.8 of the 1M sampling's spacing, so the moved triangles follow the edit about
    // as closely as the sampling does: unsplit, the edited samples lie up to 2.4 spacings off them, split 1.1
    // (what remains is the edit's own roughness at that scale).
    const auto [refined, refined_vertices] = split_at_midpoints(mesh, vertices, 3);
    bench("armadillo_1M", sample_mesh(file, 1000000), refined, refined_vertices, false, options.reps);
  }
  write_result_file(options.out, "upsampling_results.md", report.text());
  return 0;
}

} // namespace bench_upsampling

// The project links every benchmark from one library (benchmark/CMakeLists.txt); alone, this file is a program.
#ifndef CGAL_EXT_BENCHMARK_LIBRARY
int main(int argc, char** argv) { return bench_upsampling::run(argc, argv); }
#endif
