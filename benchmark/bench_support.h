// What the benchmark programs share: repeated timings, peak memory, and point samplings of mesh surfaces.
#ifndef POINT_DETAIL_BENCH_SUPPORT_H
#define POINT_DETAIL_BENCH_SUPPORT_H

#include "program_basics.h"
#include "point_io.h"

#include <CGAL_ext/internal/Point_arrays.h>

#include <Eigen/Geometry>

#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/version.h>

#include <tbb/info.h>
#include <tbb/version.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <sys/resource.h>
#include <vector>

namespace point_detail {

struct Stats { double median, min, max; };

/// Median (upper median for an even count), minimum and maximum of a non-empty list of timings.
inline Stats summarize(std::vector<double> t)
{
  std::sort(t.begin(), t.end());
  return {t[t.size() / 2], t.front(), t.back()};
}

/// Times `reps` runs of `body`.
inline Stats measure(int reps, const std::function<void()>& body)
{
  std::vector<double> t;
  for(int r = 0; r < reps; ++r) {
    const auto start = std::chrono::steady_clock::now();
    body();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return summarize(std::move(t));
}

inline double peak_rss_mib()
{
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

/// The length of the bounding box's diagonal.
inline double diagonal_of(const std::vector<Point>& points)
{
  Eigen::AlignedBox3d box;
  for(const Point& p : points) box.extend(Eigen::Vector3d(p.x(), p.y(), p.z()));
  return box.diagonal().norm();
}

/// The points as an n x 3 array, for the library's internal numerics.
inline CGAL_ext::internal::Matrix_n3 to_matrix(const std::vector<Point>& points)
{
  CGAL_ext::internal::Matrix_n3 m(Eigen::Index(points.size()), 3);
  for(std::size_t i = 0; i < points.size(); ++i) m.row(Eigen::Index(i)) << points[i].x(), points[i].y(), points[i].z();
  return m;
}

/// `n` points sampled uniformly on the surface of a triangle mesh, with the normals of their faces.
inline Point_cloud sample_mesh(const std::filesystem::path& off, std::size_t n)
{
  std::vector<Point> v;
  std::vector<std::vector<std::size_t>> faces;
  if(!CGAL::IO::read_polygon_soup(off.string(), v, faces)) throw std::runtime_error("cannot read " + off.string());
  std::vector<double> cumulative;
  double total = 0;
  for(const auto& f : faces) {
    total += std::sqrt(CGAL::squared_area(v[f[0]], v[f[1]], v[f[2]]));
    cumulative.push_back(total);
  }
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u01(0, 1);
  Point_cloud cloud;
  for(std::size_t i = 0; i < n; ++i) {
    const std::size_t f = std::size_t(std::lower_bound(cumulative.begin(), cumulative.end(), u01(rng) * total) - cumulative.begin());
    const auto& face = faces[std::min(f, faces.size() - 1)];
    double a = u01(rng), b = u01(rng);
    if(a + b > 1) { a = 1 - a; b = 1 - b; }
    const Point &p = v[face[0]], &q = v[face[1]], &r = v[face[2]];
    cloud.points.push_back(p + a * (q - p) + b * (r - p));
    Vector normal = CGAL::cross_product(q - p, r - p);
    cloud.normals.push_back(normal / std::sqrt(normal.squared_length()));
  }
  return cloud;
}

/// The mesh split `levels` times into four triangles at its edges' midpoints: the same surface with about four
/// times the vertices per level, for references and comparisons at the scale of dense samplings. Each midpoint
/// takes the mean of its ends' normals.
template <typename Mesh>
std::pair<Mesh, Point_cloud> split_at_midpoints(const Mesh& mesh, const Point_cloud& vertices, int levels)
{
  Point_cloud points = vertices;
  std::vector<std::array<std::size_t, 3>> triangles;
  for(typename Mesh::Face_index f : mesh.faces()) {
    std::array<std::size_t, 3> t;
    int m = 0;
    for(typename Mesh::Vertex_index v : vertices_around_face(mesh.halfedge(f), mesh)) t[std::size_t(m++)] = v.idx();
    triangles.push_back(t);
  }
  for(int level = 0; level < levels; ++level) {
    std::map<std::pair<std::size_t, std::size_t>, std::size_t> midpoint;
    auto middle = [&](std::size_t a, std::size_t b) {
      const auto [it, added] = midpoint.emplace(std::minmax(a, b), points.points.size());
      if(added) {
        points.points.push_back(CGAL::midpoint(points.points[a], points.points[b]));
        const Vector normal = points.normals[a] + points.normals[b];
        points.normals.push_back(normal / std::sqrt(normal.squared_length()));
      }
      return it->second;
    };
    std::vector<std::array<std::size_t, 3>> finer;
    for(const auto& [a, b, c] : triangles) {
      const std::size_t ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      finer.insert(finer.end(), {{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}});
    }
    triangles.swap(finer);
  }
  Mesh refined;
  for(const Point& p : points.points) refined.add_vertex(p);
  for(const auto& [a, b, c] : triangles)
    refined.add_face(typename Mesh::Vertex_index(typename Mesh::size_type(a)), typename Mesh::Vertex_index(typename Mesh::size_type(b)),
                     typename Mesh::Vertex_index(typename Mesh::size_type(c)));
  return {refined, points};
}

/// The command line every benchmark program takes: [--quick] [--data DIR] [--out DIR] [--reps N].
struct Bench_options
{
  bool quick = false;
  std::filesystem::path data = "data", out = "benchmark";
  int reps = 3;
  bool valid = true;
};

/// Parses the options; a quick run has one repetition. Prints the usage and sets `valid` to false on a mistake.
inline Bench_options parse_bench_options(int argc, char** argv, const char* program, int default_reps)
{
  Bench_options o;
  o.reps = default_reps;
  for(int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if(a == "--quick") o.quick = true;
    else if(a == "--data" && i + 1 < argc) o.data = argv[++i];
    else if(a == "--out" && i + 1 < argc) o.out = argv[++i];
    else if(a == "--reps" && i + 1 < argc) o.reps = std::max(1, std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "usage: %s [--quick] [--data DIR] [--out DIR] [--reps N]\n", program);
      o.valid = false;
    }
  }
  if(o.quick) o.reps = 1;
  return o;
}

inline std::string vformat(const char* fmt, va_list args)
{
  va_list again;
  va_copy(again, args);
  std::string text(std::size_t(std::max(0, std::vsnprintf(nullptr, 0, fmt, args))), '\0');
  std::vsnprintf(text.data(), text.size() + 1, fmt, again);
  va_end(again);
  return text;
}

/// `printf` into a string: a Markdown row or heading.
inline std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
inline std::string format(const char* fmt, ...)
{
  va_list args;
  va_start(args, fmt);
  std::string text = vformat(fmt, args);
  va_end(args);
  return text;
}

/// The machine and the build a benchmark ran on, as the first lines of its Markdown file.
inline std::string machine_facts()
{
  std::ifstream cpu("/proc/cpuinfo");
  std::string line, model = "unknown";
  while(std::getline(cpu, line))
    if(line.rfind("model name", 0) == 0) { model = line.substr(line.find(':') + 2); break; }
  return format("- CPU: %s; threads in parallel runs: %d\n- compiler: GCC %s, -O3 -DNDEBUG (Release); CGAL %s, "
                "Eigen %d.%d.%d, oneTBB %d.%d\n- malloc: %s (GLIBC_TUNABLES glibc.malloc.hugetlb=1, set by the harness)\n"
                "- BLAS: %s (OPENBLAS_CORETYPE=Haswell set by the harness where OpenBLAS picked older ones)\n",
                model.c_str(), tbb::info::default_concurrency(), __VERSION__, CGAL_VERSION_STR, EIGEN_WORLD_VERSION,
                EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION, TBB_VERSION_MAJOR, TBB_VERSION_MINOR, malloc_pages().c_str(),
                blas_description().c_str());
}

using Models = std::vector<std::pair<std::string, Point_cloud>>;

/// The benchmark's scans, the vertices of CGAL's meshes under DATA/meshes with normals from their faces: all of
/// `names`, or the first in a quick run. A missing file is skipped with a note.
inline Models load_scans(const std::filesystem::path& data, bool quick,
                         const std::vector<std::string>& names = {"armadillo", "bunny00", "refined_elephant", "camel"})
{
  Models models;
  for(const std::string& m : names) {
    const std::filesystem::path file = data / "meshes" / (m + ".off");
    if(!std::filesystem::exists(file)) {
      std::fprintf(stderr, "skipping %s (run scripts/fetch_data.sh)\n", file.string().c_str());
      continue;
    }
    models.emplace_back(m, read_point_cloud(file));
    if(quick) break;
  }
  return models;
}

/// `models` with the armadillo's surface sampled at 1M points (100k in a quick run) appended, when the mesh is there.
inline void add_armadillo_sampling(Models& models, const std::filesystem::path& data, bool quick)
{
  const std::filesystem::path mesh = data / "meshes/armadillo.off";
  if(std::filesystem::exists(mesh))
    models.emplace_back(quick ? "armadillo_100k" : "armadillo_1M", sample_mesh(mesh, quick ? 100000 : 1000000));
}

/// Writes `text` to DIR/NAME (creating DIR) and says so.
inline void write_result_file(const std::filesystem::path& out, const std::string& name, const std::string& text)
{
  std::filesystem::create_directories(out);
  std::ofstream(out / name) << text;
  std::printf("wrote %s\n", (out / name).string().c_str());
}

/// A Markdown report that the benchmark writes as it goes: each part is printed at once and kept for the file.
class Markdown_report
{
public:
  void add(const std::string& text)
  {
    m_text += text;
    std::printf("%s", text.c_str());
    std::fflush(stdout);
  }

  /// `add` of a `printf` format.
  void addf(const char* fmt, ...) __attribute__((format(printf, 2, 3)))
  {
    va_list args;
    va_start(args, fmt);
    add(vformat(fmt, args));
    va_end(args);
  }

  const std::string& text() const { return m_text; }

private:
  std::string m_text;
};

} // namespace point_detail

#endif
