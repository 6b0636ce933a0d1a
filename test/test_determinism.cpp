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
