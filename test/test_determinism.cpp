// Every subcommand on a real scan (CGAL's armadillo): the same input gives bit-identical outputs across runs
// with the same thread count, and outputs equal within 1e-12 (relative to each column's size) with one
// thread and with two.
#include "program_run.h"
#include "test_support.h"

#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace fs = std::filesystem;

namespace {

using Point_set = CGAL::Point_set_3<Point>;

std::string contents(const fs::path& file)
{
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The largest difference of two point sets with the same properties, per column, relative to the column's
/// largest magnitude; fails if their sizes or properties differ.
double relative_difference(const fs::path& a_file, const fs::path& b_file)
{
  Point_set a, b;
  EXPECT_TRUE(CGAL::IO::read_point_set(a_file.string(), a)) << a_file;
  EXPECT_TRUE(CGAL::IO::read_point_set(b_file.string(), b)) << b_file;
  EXPECT_EQ(a.size(), b.size());
  EXPECT_EQ(a.properties(), b.properties());
  if(a.size() != b.size() || a.properties() != b.properties()) return 1;
  double worst = 0;
  auto compare = [&](auto&& value_a, auto&& value_b, const std::string& name) {
    double scale = 0, difference = 0;
    for(std::size_t i = 0; i < a.size(); ++i) {
      scale = std::max(scale, std::abs(value_a(Point_set::Index(i))));
      difference = std::max(difference, std::abs(value_a(Point_set::Index(i)) - value_b(Point_set::Index(i))));
    }
    const double relative = scale > 0 ? difference / scale : difference;
    EXPECT_LE(relative, 1e-12) << name;
    worst = std::max(worst, relative);
  };
  for(int c = 0; c < 3; ++c) {
    compare([&](Point_set::Index i) { return a.point(i)[c]; }, [&](Point_set::Index i) { return b.point(i)[c]; }, "point");
    if(a.has_normal_map())
      compare([&](Point_set::Index i) { return a.normal(i)[c]; }, [&](Point_set::Index i) { return b.normal(i)[c]; }, "normal");
  }
  for(const std::string& name : a.properties()) {
    auto pa = a.property_map<double>(name);
    auto pb = b.property_map<double>(name);
    if(pa.second && pb.second)
      compare([&](Point_set::Index i) { return pa.first[i]; }, [&](Point_set::Index i) { return pb.first[i]; }, name);
  }
  return worst;
}

class Determinism : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir = fs::temp_directory_path() / ("point_detail_determinism_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir);
    ASSERT_TRUE(fs::exists(scan)) << scan << " is missing: scripts/fetch_data.sh fetches it";
    // Regions around the scan's points: a sphere about the point farthest up in y (the raised hand's side).
    Point_set model;
    ASSERT_TRUE(CGAL::IO::read_point_set(scan, model));
    top = model.point(*model.begin());
    double lo = top.y(), hi = top.y();
    for(auto i : model) {
      if(model.point(i).y() > top.y()) top = model.point(i);
      lo = std::min(lo, model.point(i).y());
    }
    hi = top.y();
    height = hi - lo;
    std::ofstream(path("edit.json")) << R"({"roi": ["sphere:)" << top.x() << "," << top.y() << "," << top.z() << ","
                                     << 0.35 * height << R"("], "handles": [{"select": ["sphere:)" << top.x() << ","
                                     << top.y() << "," << top.z() << "," << 0.08 * height << R"("], "translation": [0, )"
                                     << 0.1 * height << ", " << 0.05 * height << "]}]}";
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
  std::string roi() const
  {
    std::ostringstream os;
    os << "sphere:" << top.x() << "," << top.y() << "," << top.z() << "," << 0.35 * height;
    return os.str();
  }

  /// Runs `arguments` (with OUT standing for the output file) twice with 2 threads and once with 1.
  void check(const std::string& name, const std::string& arguments, const std::string& extension = ".ply")
  {
    std::vector<std::string> outputs;
    for(const char* threads : {"2", "2", "1"}) {
      outputs.push_back(path(name + "_" + std::to_string(outputs.size()) + extension));
      std::string args = arguments;
      args.replace(args.find("OUT"), 3, outputs.back());
      const Program_run r = run(std::string("--threads ") + threads + " " + args);
      ASSERT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    }
    EXPECT_TRUE(contents(outputs[0]) == contents(outputs[1])) << name << ": two runs with 2 threads differ";
    if(extension == ".ply") EXPECT_LE(relative_difference(outputs[0], outputs[2]), 1e-12) << name;
    else EXPECT_TRUE(contents(outputs[0]) == contents(outputs[2])) << name << ": 1 and 2 threads differ";
  }

  const std::string scan = REAL_SCAN;
  fs::path dir;
  Point top;
  double height = 0;
};

} // namespace

TEST_F(Determinism, Details) { check("details", "details -i " + scan + " -o OUT --order cubic"); }
TEST_F(Determinism, Scale) { check("scale", "scale -i " + scan + " -o OUT -s 2.5 --order quadric --roi " + roi()); }
TEST_F(Determinism, Enhance) { check("enhance", "enhance -i " + scan + " -o OUT -s 1.5"); }
TEST_F(Determinism, EnhanceRegion)
{
  // The base surface's flow runs while the region's system is factored.
  check("enhance_region", "enhance -i " + scan + " -o OUT -s 1.5 --roi " + roi());
}
TEST_F(Determinism, Curvature) { check("curvature", "curvature -i " + scan + " -o OUT"); }
TEST_F(Determinism, Simplify) { check("simplify", "simplify -i " + scan + " -o OUT"); }
TEST_F(Determinism, Edit) { check("edit", "edit -i " + scan + " -o OUT --upsample --edit " + path("edit.json")); }
TEST_F(Determinism, EditAsRigidAsPossible)
{
  check("arap", "edit -i " + scan + " -o OUT --rotations arap --edit " + path("edit.json"));
}
TEST_F(Determinism, Upsample)
{
  // The stretched result of an edit (without its own up-sampling) is what this repairs.
  ASSERT_EQ(run("edit -i " + scan + " -o " + path("stretched.ply") + " --edit " + path("edit.json")).exit_code, 0);
  check("upsample", "upsample -i " + path("stretched.ply") + " -o OUT");
}
TEST_F(Determinism, Render) { check("render", "render -i " + scan + " -o OUT", ".png"); }

TEST_F(Determinism, Demo)
{
  // The demo has no scan input: it generates its tentacle, so this also checks the generator.
  std::vector<fs::path> runs;
  for(const char* threads : {"2", "2", "1"}) {
    runs.push_back(dir / ("demo_" + std::to_string(runs.size())));
    const Program_run r = run(std::string("--threads ") + threads + " demo --points 4000 -o " + runs.back().string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  std::size_t files = 0;
  for(const auto& entry : fs::directory_iterator(runs[0])) {
    const fs::path name = entry.path().filename();
    ASSERT_TRUE(fs::exists(runs[1] / name) && fs::exists(runs[2] / name)) << name;
    EXPECT_TRUE(contents(runs[0] / name) == contents(runs[1] / name)) << name << ": two runs with 2 threads differ";
    if(name.extension() == ".ply") EXPECT_LE(relative_difference(runs[0] / name, runs[2] / name), 1e-12) << name;
    else EXPECT_TRUE(contents(runs[0] / name) == contents(runs[2] / name)) << name << ": 1 and 2 threads differ";
    ++files;
  }
  EXPECT_GE(files, 10u) << "the demo writes its PLY and PNG files";
}

// The same points in another order give the same answer, point by point once the order is undone (doc/design.md,
// "One neighbourhood rule"): on a lattice whose distances tie exactly, on the lattice with 2 % of its points
// duplicated, and on a random sampling of the same surface.
namespace {

struct Shape
{
  std::vector<Point> points;
  std::vector<Vector> normals;
};

// Height z(x, y): flat for x < 0.55, smooth bumps beyond; the normal is exact.
void add_surface_point(Shape& shape, double x, double y)
{
  const double kx = 2 * CGAL_PI / 0.4, ky = 2 * CGAL_PI / 0.3;
  double z = 0, zx = 0, zy = 0;
  if(x > 0.55) {
    const double s = x - 0.55;
    z = 0.02 * s * s * 50 * std::sin(ky * y) * (1 - std::cos(kx * s));
    zx = 0.02 * 50 * std::sin(ky * y) * (2 * s * (1 - std::cos(kx * s)) + s * s * kx * std::sin(kx * s));
    zy = 0.02 * s * s * 50 * ky * std::cos(ky * y) * (1 - std::cos(kx * s));
  }
  shape.points.emplace_back(x, y, z);
  const double length = std::sqrt(zx * zx + zy * zy + 1);
  shape.normals.emplace_back(-zx / length, -zy / length, 1 / length);
}

// 70 x 60 points at spacing 1/64 (a range image's raster), with every 50th point again when `duplicates`.
Shape lattice(bool duplicates)
{
  Shape shape;
  for(int j = 0; j < 60; ++j)
    for(int i = 0; i < 70; ++i) add_surface_point(shape, i / 64.0, j / 64.0);
  if(duplicates)
    for(std::size_t i = 0; i < 70 * 60; i += 50) {
      shape.points.push_back(shape.points[i]);
      shape.normals.push_back(shape.normals[i]);
    }
  return shape;
}

Shape random_sampling()
{
  Shape shape;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(0, 69 / 64.0), y(0, 59 / 64.0);
  for(int i = 0; i < 4200; ++i) {
    const double u = x(rng);
    add_surface_point(shape, u, y(rng));
  }
  return shape;
}

// The shape's points in `order`, with their normals unless `bare`.
void write_shape(const Shape& shape, const std::vector<int>& order, bool bare, const fs::path& file)
{
  Point_set set;
  if(!bare) set.add_normal_map();
  for(const int i : order)
    if(bare)
      set.insert(shape.points[std::size_t(i)]);
    else
      set.insert(shape.points[std::size_t(i)], shape.normals[std::size_t(i)]);
  std::ofstream out(file, std::ios::binary);
  ASSERT_TRUE(CGAL::IO::write_PLY(out, set, CGAL::parameters::stream_precision(17)));
}

// Every column of two outputs compared to 1e-12 of its largest magnitude: row order[r] of `a` against row r of `b`
// for the first `per_point` rows (`a` ran on the points in their order, `b` on `order`); the rows after those
// (points an up-sampling added, or sample points) compared as sets, sorted by position.
void expect_same_after_undoing(const fs::path& a_file, const fs::path& b_file, const std::vector<int>& order,
                               std::size_t per_point, const std::string& what)
{
  Point_set a, b;
  ASSERT_TRUE(CGAL::IO::read_point_set(a_file.string(), a)) << a_file;
  ASSERT_TRUE(CGAL::IO::read_point_set(b_file.string(), b)) << b_file;
  ASSERT_EQ(a.size(), b.size()) << what;
  ASSERT_EQ(a.properties(), b.properties()) << what;
  std::vector<std::size_t> a_row(a.size()), b_row(b.size());
  std::iota(a_row.begin(), a_row.end(), std::size_t(0));
  std::iota(b_row.begin(), b_row.end(), std::size_t(0));
  for(std::size_t r = 0; r < per_point; ++r) a_row[r] = std::size_t(order[r]);
  auto sort_the_rest = [per_point](const Point_set& s, std::vector<std::size_t>& rows) {
    std::sort(rows.begin() + std::ptrdiff_t(per_point), rows.end(), [&](std::size_t i, std::size_t j) {
      return s.point(Point_set::Index(i)) < s.point(Point_set::Index(j));
    });
  };
  sort_the_rest(a, a_row);
  sort_the_rest(b, b_row);
  auto compare = [&](auto&& value_a, auto&& value_b, const std::string& name) {
    double scale = 0, difference = 0;
    std::size_t worst = 0;
    for(std::size_t r = 0; r < a.size(); ++r) {
      const double va = value_a(Point_set::Index(a_row[r])), vb = value_b(Point_set::Index(b_row[r]));
      scale = std::max(scale, std::abs(va));
      if(std::abs(va - vb) > difference) difference = std::abs(va - vb), worst = r;
    }
    EXPECT_LE(difference, 1e-12 * std::max(scale, 1e-300))
      << what << ", " << name << ": row " << worst << " of " << a.size();
  };
  for(int c = 0; c < 3; ++c) {
    compare([&](Point_set::Index i) { return a.point(i)[c]; }, [&](Point_set::Index i) { return b.point(i)[c]; },
            "point");
    if(a.has_normal_map())
      compare([&](Point_set::Index i) { return a.normal(i)[c]; }, [&](Point_set::Index i) { return b.normal(i)[c]; },
              "normal");
  }
  for(const std::string& name : a.properties()) {
    auto pa = a.property_map<double>(name);
    auto pb = b.property_map<double>(name);
    if(pa.second && pb.second)
      compare([&](Point_set::Index i) { return pa.first[i]; }, [&](Point_set::Index i) { return pb.first[i]; }, name);
  }
}

class OrderIndependence : public ::testing::TestWithParam<const char*>
{
protected:
  void SetUp() override
  {
    dir = fs::temp_directory_path() / ("point_detail_order_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir);
    const std::string kind = GetParam();
    shape = kind == "lattice" ? lattice(false) : kind == "duplicates" ? lattice(true) : random_sampling();
    identity.resize(shape.points.size());
    std::iota(identity.begin(), identity.end(), 0);
    order = identity;
    std::shuffle(order.begin(), order.end(), std::mt19937(11));
    for(const bool bare : {false, true}) {
      write_shape(shape, identity, bare, dir / (bare ? "in_order_bare.ply" : "in_order.ply"));
      write_shape(shape, order, bare, dir / (bare ? "shuffled_bare.ply" : "shuffled.ply"));
    }
    std::ofstream(dir / "edit.json")
      << R"({"roi": ["sphere:0.75,0.45,0,0.3"], "handles": [{"select": ["sphere:0.9,0.45,0,0.08"], )"
      << R"("translation": [0.02, 0.01, 0.08]}]})";
  }
  void TearDown() override { fs::remove_all(dir); }

  /// Runs `arguments` (IN and OUT standing for the input and output files) on both orders and compares; the
  /// inputs have no normals when `bare`.
  void check(const std::string& name, const std::string& arguments, std::size_t per_point, bool bare = false)
  {
    for(const char* input : {"in_order", "shuffled"}) {
      std::string args = arguments;
      args.replace(args.find("IN"), 2, (dir / (std::string(input) + (bare ? "_bare.ply" : ".ply"))).string());
      args.replace(args.find("OUT"), 3, (dir / (name + "_" + input + ".ply")).string());
      const Program_run r = run(args);
      ASSERT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    }
    expect_same_after_undoing(dir / (name + "_in_order.ply"), dir / (name + "_shuffled.ply"), order, per_point,
                              std::string(GetParam()) + " " + name);
  }
  std::size_t n() const { return shape.points.size(); }

  fs::path dir;
  Shape shape;
  std::vector<int> identity, order;
};

} // namespace

TEST_P(OrderIndependence, Details)
{
  for(const char* filter : {"linear", "quadric", "cubic"})
    check(std::string("details_") + filter, std::string("details -i IN -o OUT --order ") + filter, n());
}
TEST_P(OrderIndependence, DetailsOnMeanShiftNeighbourhoods)
{
  check("details_ms", "details -i IN -o OUT --order cubic --neighbors mean_shift --weights distance", n());
}
TEST_P(OrderIndependence, EstimatedNormals) { check("normals", "details -i IN -o OUT --order quadric", n(), true); }
TEST_P(OrderIndependence, Scale) { check("scale", "scale -i IN -o OUT -s 2 --roi sphere:0.7,0.45,0,0.3", n()); }
TEST_P(OrderIndependence, Enhance) { check("enhance", "enhance -i IN -o OUT -s 1.5", n()); }
TEST_P(OrderIndependence, Curvature) { check("curvature", "curvature -i IN -o OUT", n()); }
TEST_P(OrderIndependence, Simplify) { check("simplify", "simplify -i IN -o OUT", 0); }
TEST_P(OrderIndependence, Edit) { check("edit", "edit -i IN -o OUT --edit " + (dir / "edit.json").string(), n()); }
TEST_P(OrderIndependence, EditAsRigidAsPossibleAndUpsampled)
{
  check("edit_arap", "edit -i IN -o OUT --rotations arap --upsample --edit " + (dir / "edit.json").string(), n());
}
TEST_P(OrderIndependence, Upsample)
{
  // A hole of radius 0.1 cut out of both orders: the points kept keep their rows, the new ones compare as a set.
  std::vector<int> kept_row(n(), -1), kept, kept_order;
  for(std::size_t i = 0; i < n(); ++i)
    if(std::hypot(shape.points[i].x() - 0.5, shape.points[i].y() - 0.45) > 0.1) {
      kept_row[i] = int(kept.size());
      kept.push_back(int(i));
    }
  for(const int i : order)
    if(kept_row[std::size_t(i)] >= 0) kept_order.push_back(kept_row[std::size_t(i)]);
  Shape holed;
  for(const int i : kept) {
    holed.points.push_back(shape.points[std::size_t(i)]);
    holed.normals.push_back(shape.normals[std::size_t(i)]);
  }
  std::vector<int> in_order(kept.size());
  std::iota(in_order.begin(), in_order.end(), 0);
  write_shape(holed, in_order, false, dir / "holed_in_order.ply");
  write_shape(holed, kept_order, false, dir / "holed_shuffled.ply");
  for(const char* input : {"in_order", "shuffled"}) {
    const Program_run r = run("upsample -i " + (dir / (std::string("holed_") + input + ".ply")).string() + " -o " +
                              (dir / (std::string("upsampled_") + input + ".ply")).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  Point_set added;
  ASSERT_TRUE(CGAL::IO::read_point_set((dir / "upsampled_in_order.ply").string(), added));
  EXPECT_GT(added.size(), kept.size()) << "the hole is filled";
  expect_same_after_undoing(dir / "upsampled_in_order.ply", dir / "upsampled_shuffled.ply", kept_order, kept.size(),
                            std::string(GetParam()) + " upsample");
}
TEST_P(OrderIndependence, Render)
{
  for(const char* input : {"in_order", "shuffled"}) {
    const Program_run r = run("render -i " + (dir / (std::string(input) + ".ply")).string() + " -o " +
                              (dir / (std::string("render_") + input + ".png")).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  EXPECT_TRUE(contents(dir / "render_in_order.png") == contents(dir / "render_shuffled.png")) << GetParam();
}
INSTANTIATE_TEST_SUITE_P(Shapes, OrderIndependence, ::testing::Values("lattice", "duplicates", "random"));
