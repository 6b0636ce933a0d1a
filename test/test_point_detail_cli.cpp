// The point-detail program, run as a user would: outputs, errors, and files it must not touch.
#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/scale_geometric_details.h>
#include <CGAL_ext/generated_shapes.h>

#include "program_basics.h"
#include "program_run.h"
#include "test_support.h"

#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb/stb_image.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>

namespace fs = std::filesystem;

namespace {

class Cli : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir = fs::temp_directory_path() / ("point_detail_cli_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }

  /// A bumpy sphere as an ASCII PLY with normals.
  std::string write_sphere_ply(const std::string& name, std::size_t n = 3000)
  {
    return write_ply(name, CGAL_ext::shapes::bumpy_sphere<Kernel>(n, 1.0, 0.02));
  }

  std::string write_ply(const std::string& name, const CGAL_ext::shapes::Oriented_sample<Kernel>& s)
  {
    const std::size_t n = s.points.size();
    std::ofstream out(path(name));
    out << "ply\nformat ascii 1.0\nelement vertex " << n
        << "\nproperty double x\nproperty double y\nproperty double z\nproperty double nx\nproperty double ny\nproperty double nz\nend_header\n";
    out.precision(17);
    for(std::size_t i = 0; i < n; ++i) out << s.points[i] << " " << s.normals[i] << "\n";
    return path(name);
  }

  static std::string contents(const std::string& file)
  {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }

  /// No output or temporary file was left in the directory besides `keep`.
  void expect_only(std::initializer_list<std::string> keep) const
  {
    for(const auto& entry : fs::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      EXPECT_NE(std::find(keep.begin(), keep.end(), name), keep.end()) << "unexpected file " << name;
    }
  }

  fs::path dir;
};

} // namespace

TEST_F(Cli, DetailsWiringEveryPropertyInInputOrderAsTheLibraryComputesItAndTheRelief)
{
  const std::string in = write_sphere_ply("in.ply");
  const Program_run r = run("details -i " + in + " -o " + path("out.ply") + " --order cubic --lambda 0.3 --mu 1.8 -k 12 --png " +
                    path("out.png") + " --report " + path("report.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;

  CGAL::Point_set_3<Point> input, output;
  ASSERT_TRUE(CGAL::IO::read_point_set(in, input));
  ASSERT_TRUE(CGAL::IO::read_point_set(path("out.ply"), output));
  ASSERT_EQ(output.size(), input.size());
  ASSERT_TRUE(output.has_normal_map());
  auto dx = output.property_map<double>("detail_x").first, dy = output.property_map<double>("detail_y").first,
       dz = output.property_map<double>("detail_z").first, mag = output.property_map<double>("detail_magnitude").first,
       along_normal = output.property_map<double>("detail_normal").first;
  ASSERT_TRUE(output.property_map<double>("detail_magnitude").second);
  ASSERT_TRUE(output.property_map<double>("detail_normal").second);
  ASSERT_TRUE(output.property_map<unsigned char>("red").second);

  std::vector<Vector> details(input.size());
  std::vector<double> magnitude(input.size());
  ASSERT_TRUE(CGAL_ext::compute_geometric_details(input, 12, CGAL_ext::Detail_filter{CGAL_ext::Detail_order::cubic, 0.3, 1.8},
                                                  CGAL::make_property_map(details), CGAL::make_property_map(magnitude),
                                                  input.parameters()));
  std::size_t i = 0;
  for(auto it = output.begin(); it != output.end(); ++it, ++i) {
    ASSERT_EQ(output.point(*it), input.point(*(input.begin() + std::ptrdiff_t(i)))) << "order changed at " << i;
    EXPECT_DOUBLE_EQ(mag[*it], magnitude[i]);
    EXPECT_NEAR(std::sqrt(dx[*it] * dx[*it] + dy[*it] * dy[*it] + dz[*it] * dz[*it]), std::abs(magnitude[i]), 1e-12);
    EXPECT_NEAR(along_normal[*it], details[i] * input.normal(*(input.begin() + std::ptrdiff_t(i))), 1e-12);
  }
  // Beyond the wiring, an independent oracle: the written delta . n follows the sphere's known bump height.
  const auto shape = CGAL_ext::shapes::bumpy_sphere<Kernel>(3000, 1.0, 0.02);
  std::vector<double> written;
  for(auto it = output.begin(); it != output.end(); ++it) written.push_back(along_normal[*it]);
  EXPECT_GT(pearson(written, shape.bump_height), 0.8);
  // On a random sampling most of delta is tangential (doc/geometric_details.md, "Colour maps"): there the relief
  // is delta . n, not the paper's signed |delta|. 4,000 points drawn from a fine Fibonacci sampling, bumps of a
  // wavelength of 8 average spacings.
  {
    const auto fine = CGAL_ext::shapes::bumpy_sphere<Kernel>(40000, 1.0, 0.01, 8.0 * std::sqrt(10.0));
    CGAL_ext::shapes::Oriented_sample<Kernel> drawn;
    std::vector<std::size_t> order(fine.points.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::shuffle(order.begin(), order.end(), std::mt19937(3));
    for(std::size_t m = 0; m < 4000; ++m) {
      const std::size_t j = order[m];
      drawn.points.push_back(fine.points[j]);
      drawn.normals.push_back(fine.normals[j]);
      drawn.bump_height.push_back(fine.bump_height[j]);
    }
    ASSERT_EQ(run("details -i " + write_ply("random.ply", drawn) + " -o " + path("random_out.ply")).exit_code, 0);
    CGAL::Point_set_3<Point> random_out;
    ASSERT_TRUE(CGAL::IO::read_point_set(path("random_out.ply"), random_out));
    std::vector<double> relief, signed_magnitude;
    auto normal_map = random_out.property_map<double>("detail_normal").first;
    auto magnitude_map = random_out.property_map<double>("detail_magnitude").first;
    for(auto it = random_out.begin(); it != random_out.end(); ++it) {
      relief.push_back(normal_map[*it]);
      signed_magnitude.push_back(magnitude_map[*it]);
    }
    const double r_relief = pearson(relief, drawn.bump_height), r_magnitude = pearson(signed_magnitude, drawn.bump_height);
    std::printf("random sampling: Pearson(detail_normal, height) %.3f, Pearson(detail_magnitude, height) %.3f\n", r_relief, r_magnitude);
    EXPECT_GT(r_relief, 0.6);
    EXPECT_GT(r_relief, r_magnitude + 0.1);
  }
  EXPECT_EQ(contents(path("out.png")).substr(1, 3), "PNG");
  const auto report = nlohmann::json::parse(contents(path("report.json")));
  EXPECT_EQ(report["points"], 3000);
  EXPECT_EQ(report["order"], "cubic");
  EXPECT_EQ(report["normal_source"], "file");
  for(const char* stage : {"read", "details", "write", "base_surface", "render"})
    EXPECT_GE(report["timings_s"][stage].get<double>(), 0.0) << stage;
  expect_only({"in.ply", "out.ply", "out.png", "report.json", "random.ply", "random_out.ply"});
}

TEST_F(Cli, GlobalOptionsMayFollowTheSubcommand)
{
  // `point-detail details -i a.ply -o b.ply -q --threads 1`: the same file as with the options first, quietly.
  const std::string in = write_sphere_ply("in.ply", 600);
  const std::string program = POINT_DETAIL_EXE;
  const Program_run after = run_command(program + " details -i " + in + " -o " + path("after.ply") + " -q --threads 1");
  ASSERT_EQ(after.exit_code, 0) << after.output;
  EXPECT_EQ(after.output, "");
  const Program_run before = run_command(program + " --threads 1 details -i " + in + " -o " + path("before.ply"));
  ASSERT_EQ(before.exit_code, 0) << before.output;
  EXPECT_NE(before.output, ""); // its progress, without -q
  EXPECT_EQ(contents(path("after.ply")), contents(path("before.ply")));
  const Program_run unknown = run_command(program + " details -i " + in + " -o " + path("x.ply") + " --treads 1");
  EXPECT_EQ(unknown.exit_code, 109) << unknown.output; // a misspelt option is still refused
  EXPECT_NE(unknown.output.find("--treads"), std::string::npos) << unknown.output;
}

TEST_F(Cli, NormalsComeFromMeshFacesOrAreEstimated)
{
  // A bumpy grid as an OFF mesh with upward faces: its vertex normals are the faces' (about +z).
  const auto g = CGAL_ext::shapes::bumpy_grid<Kernel>(30, 30, 0.1, 0.01, 1.0);
  {
    std::ofstream off(path("grid.off"));
    off << "OFF\n" << g.points.size() << " " << 2 * 29 * 29 << " 0\n";
    off.precision(17);
    for(const Point& p : g.points) off << p << "\n";
    for(int j = 0; j < 29; ++j)
      for(int i = 0; i < 29; ++i) {
        const int a = j * 30 + i;
        off << "3 " << a << " " << a + 1 << " " << a + 31 << "\n3 " << a << " " << a + 31 << " " << a + 30 << "\n";
      }
    std::ofstream xyz(path("grid.xyz"));
    xyz.precision(17);
    for(const Point& p : g.points) xyz << p << "\n";
    // The same mesh as PLY, ASCII and big-endian binary, faces as the usual 'list uchar int vertex_indices':
    // the walk over its lists (which refuses counts the file cannot hold) lets a valid file through.
    std::ofstream ascii(path("grid_ascii.ply")), binary(path("grid_binary.ply"), std::ios::binary);
    for(auto [out, format] : {std::pair{&ascii, "ascii"}, std::pair{&binary, "binary_big_endian"}})
      *out << "ply\nformat " << format << " 1.0\nelement vertex " << g.points.size()
           << "\nproperty double x\nproperty double y\nproperty double z\nelement face " << 2 * 29 * 29
           << "\nproperty list uchar int vertex_indices\nend_header\n";
    auto big_endian = [&](auto value) {
      char bytes[sizeof value];
      std::memcpy(bytes, &value, sizeof value);
      std::reverse(bytes, bytes + sizeof value);
      binary.write(bytes, sizeof value);
    };
    ascii.precision(17);
    for(const Point& p : g.points) {
      ascii << p << "\n";
      for(double c : {p.x(), p.y(), p.z()}) big_endian(c);
    }
    for(int j = 0; j < 29; ++j)
      for(int i = 0; i < 29; ++i)
        for(const std::array<int, 3>& t : {std::array<int, 3>{j * 30 + i, j * 30 + i + 1, j * 30 + i + 31},
                                           std::array<int, 3>{j * 30 + i, j * 30 + i + 31, j * 30 + i + 30}}) {
          ascii << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
          binary.put(3);
          for(int v : t) big_endian(std::int32_t(v));
        }
  }
  for(const auto& [file, source] : {std::pair{"grid.off", "mesh"}, std::pair{"grid.xyz", "estimated"},
                                    std::pair{"grid_ascii.ply", "mesh"}, std::pair{"grid_binary.ply", "mesh"}}) {
    const Program_run r = run(std::string("details -i ") + path(file) + " -o " + path("out.ply") + " --report " + path("r.json"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(contents(path("r.json")))["normal_source"], source);
    CGAL::Point_set_3<Point> out;
    ASSERT_TRUE(CGAL::IO::read_point_set(path("out.ply"), out));
    ASSERT_TRUE(out.has_normal_map());
    std::size_t up = 0;
    for(auto it = out.begin(); it != out.end(); ++it) up += out.normal(*it).z() > 0.9;
    if(std::string(source) == "mesh") EXPECT_EQ(up, out.size());
    else EXPECT_TRUE(up == out.size() || up == 0) << up; // one consistent orientation
  }

  // Vertices on no face (three extra vertices on the surface, in no face) get estimated normals, turned to the
  // mesh's side; the others keep the faces' normals.
  {
    std::ofstream off(path("unused.off"));
    off.precision(17);
    off << "OFF\n" << g.points.size() + 3 << " " << 2 * 29 * 29 << " 0\n";
    for(const Point& p : g.points) off << p << "\n";
    for(int m = 0; m < 3; ++m) off << g.points[std::size_t(100 + 200 * m)] + Vector(0.05, 0.05, 0) << "\n";
    for(int j = 0; j < 29; ++j)
      for(int i = 0; i < 29; ++i) {
        const int a = j * 30 + i;
        off << "3 " << a << " " << a + 1 << " " << a + 31 << "\n3 " << a << " " << a + 31 << " " << a + 30 << "\n";
      }
  }
  const Program_run unused = run("details -i " + path("unused.off") + " -o " + path("out.ply") + " --report " + path("r.json"));
  ASSERT_EQ(unused.exit_code, 0) << unused.output;
  const auto report = nlohmann::json::parse(contents(path("r.json")));
  EXPECT_EQ(report["normal_source"], "mesh");
  EXPECT_EQ(report["estimated_normals"], 3);
  CGAL::Point_set_3<Point> out;
  ASSERT_TRUE(CGAL::IO::read_point_set(path("out.ply"), out));
  ASSERT_EQ(out.size(), g.points.size() + 3);
  for(auto it = out.begin(); it != out.end(); ++it) EXPECT_GT(out.normal(*it).z(), 0.9);

  // A PLY mesh of triangle strips: its faces are not read; the program says so and estimates the normals.
  {
    std::ofstream ply(path("strips.ply"));
    ply.precision(17);
    ply << "ply\nformat ascii 1.0\nelement vertex " << g.points.size()
        << "\nproperty double x\nproperty double y\nproperty double z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n";
    for(const Point& p : g.points) ply << p << "\n";
    ply << "4 0 30 1 31\n";
  }
  const Program_run strips = run("details -i " + path("strips.ply") + " -o " + path("out.ply") + " --report " + path("r.json"));
  ASSERT_EQ(strips.exit_code, 0) << strips.output;
  EXPECT_NE(strips.output.find("triangle strips"), std::string::npos) << strips.output;
  EXPECT_EQ(nlohmann::json::parse(contents(path("r.json")))["normal_source"], "estimated");
}

TEST_F(Cli, PlainBinaryPlyFilesReadAsCgalsReaderReadsTheSameValues)
{
  // Binary x y z (nx ny nz) files of one float type are read directly; CGAL's reader reads the same values from
  // an ASCII file (its path) and from a binary one with an extra property (also its path). The outputs, which
  // hold every input value, agree byte for byte, and the plain file without normals gets estimated ones.
  const auto s = CGAL_ext::shapes::bumpy_sphere<Kernel>(1500, 1.0, 0.02);
  const std::size_t n = s.points.size();
  auto write_binary = [&](const std::string& name, bool as_float, bool with_normals, bool with_extra) {
    std::ofstream out(path(name), std::ios::binary);
    const char* type = as_float ? "float" : "double";
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << n << "\n";
    for(const char* p : {"x", "y", "z"}) out << "property " << type << " " << p << "\n";
    if(with_normals)
      for(const char* p : {"nx", "ny", "nz"}) out << "property " << type << " " << p << "\n";
    if(with_extra) out << "property uchar quality\n";
    out << "end_header\n";
    for(std::size_t i = 0; i < n; ++i) {
      std::vector<double> v{s.points[i].x(), s.points[i].y(), s.points[i].z()};
      if(with_normals) v.insert(v.end(), {s.normals[i].x(), s.normals[i].y(), s.normals[i].z()});
      for(double x : v) {
        if(as_float) { const float f = float(x); out.write(reinterpret_cast<const char*>(&f), sizeof f); }
        else out.write(reinterpret_cast<const char*>(&x), sizeof x);
      }
      if(with_extra) out.put(char(7));
    }
  };
  auto details = [&](const std::string& in, const std::string& out) {
    const Program_run r = run("details -i " + path(in) + " -o " + path(out) + " --report " + path("r.json"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(contents(path("r.json")))["normal_source"].get<std::string>();
  };
  write_binary("plain.ply", false, true, false);
  write_binary("extra.ply", false, true, true);
  write_sphere_ply("ascii.ply", 1500);
  EXPECT_EQ(details("plain.ply", "plain_out.ply"), "file");
  EXPECT_EQ(details("extra.ply", "extra_out.ply"), "file");
  EXPECT_EQ(details("ascii.ply", "ascii_out.ply"), "file");
  const std::string plain_out = contents(path("plain_out.ply"));
  EXPECT_EQ(plain_out, contents(path("ascii_out.ply")));
  // An extra file's output carries its 'quality' property besides: compare what the plain one's holds.
  auto same_points_and_normals = [&](const std::string& plain, const std::string& extra) {
    CGAL::Point_set_3<Point> a, b;
    EXPECT_TRUE(CGAL::IO::read_point_set(path(plain), a));
    EXPECT_TRUE(CGAL::IO::read_point_set(path(extra), b));
    EXPECT_EQ(a.size(), n);
    EXPECT_EQ(b.size(), n);
    for(std::size_t i = 0; i < std::min({n, a.size(), b.size()}); ++i) {
      EXPECT_EQ(a.point(i), b.point(i));
      EXPECT_EQ(a.normal(i), b.normal(i));
    }
    return a;
  };
  same_points_and_normals("plain_out.ply", "extra_out.ply");
  // Floats without normals, beside the same floats with an extra property (CGAL's path).
  write_binary("plain_float.ply", true, false, false);
  write_binary("extra_float.ply", true, false, true);
  EXPECT_EQ(details("plain_float.ply", "plain_float_out.ply"), "estimated");
  EXPECT_EQ(details("extra_float.ply", "extra_float_out.ply"), "estimated");
  const CGAL::Point_set_3<Point> floats = same_points_and_normals("plain_float_out.ply", "extra_float_out.ply");
  for(std::size_t i = 0; i < std::min(n, floats.size()); ++i)
    EXPECT_EQ(floats.point(i), Point(float(s.points[i].x()), float(s.points[i].y()), float(s.points[i].z())));
}

TEST_F(Cli, BadFilesAndOptionsGiveOneClearLineAndNoOutput)
{
  const std::string in = write_sphere_ply("in.ply", 200);
  const std::string before = contents(in);
  { std::ofstream(path("garbage.ply")) << "ply\nformat ascii 1.0\nelement vertex 10\nproperty double x\nend_header\n1\n2\n"; }
  { std::ofstream(path("empty.xyz")); }
  struct Case { std::string args, needle; };
  const Case cases[] = {
    {"details -i " + path("missing.ply") + " -o " + path("o.ply"), "no such file"},
    {"details -i " + path("garbage.ply") + " -o " + path("o.ply"), "garbage.ply"},
    {"details -i " + path("empty.xyz") + " -o " + path("o.ply"), "no points"},
    {"details -i " + in + " -o " + in, "is the input file"},
    {"details -i " + in + " -o " + path("no/such/dir/o.ply"), "does not exist"},
    {"details -i " + in + " -o " + path("o.ply") + " --lambda 0", "lambda"},
    {"details -i " + in + " -o " + path("o.ply") + " --order cubic --lambda 0.8 --mu 0.5", "mu"},
    {"details -i " + in + " -o " + path("o.ply") + " -k 200", "-k 200"},
    {"simplify -i " + in + " -o " + path("o.ply") + " -k 200", "-k 200"}, // -k: the same rule in every subcommand
    {"details -i " + in + " -o " + path("o.ply") + " --png " + path("o.png") + " --view sideways", "bad view"},
    {"render -i " + in + " -o " + path("o.png") + " --color-by curvature", "no property 'curvature'"},
  };
  for(const Case& c : cases) {
    const Program_run r = run(c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.needle), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 2) << r.output;
  }
  EXPECT_EQ(contents(in), before); // the input is never touched
  expect_only({"in.ply", "garbage.ply", "empty.xyz"});
}

TEST_F(Cli, RenderAndDemoWritePictures)
{
  const std::string in = write_sphere_ply("in.ply", 2000);
  ASSERT_EQ(run("details -i " + in + " -o " + path("d.ply")).exit_code, 0);
  for(const char* by : {"", "--color-by detail_magnitude", "--color-by rgb", "--color-by none"}) {
    const Program_run r = run("render -i " + path("d.ply") + " -o " + path("d.png") + " --view 30,20 --width 200 --height 150 " + by);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(contents(path("d.png")).substr(1, 3), "PNG");
  }
  ASSERT_EQ(run("render -i " + path("d.ply") + " -o " + path("d.png") + " --report " + path("r.json")).exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(contents(path("r.json")))["points"], 2000);
  const Program_run demo = run("demo --points 3000 -o " + path("demo") + " --report " + path("demo.json"));
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  const auto runs = nlohmann::json::parse(contents(path("demo.json")))["runs"];
  ASSERT_EQ(runs.size(), 11u); // 3 detail maps, 2 scalings, 2 enhancements, 3 edits, a stretch up-sampled
  EXPECT_GT(runs[9]["roi_ssps"].get<std::size_t>(), 0u);
  EXPECT_GT(runs[10]["upsampling"]["inserted"].get<std::size_t>(), 0u);
  for(const char* f : {"tentacle.ply", "tentacle.png", "details_linear.png", "details_quadric.ply", "details_cubic.png",
                       "scale_0.6.png", "scale_1.2.ply", "enhance_2.0.png", "enhance_3.0.ply", "edit_linear.png",
                       "edit_quadric.ply", "edit_cubic.png", "edit_stretch.png", "edit_stretch_upsampled.ply"})
    EXPECT_TRUE(fs::is_regular_file(dir / "demo" / f)) << f;
}

/// Pixels of the picture's model part (above the legend strip) near the flag colour (255, 0, 200) under any
/// shading, and pixels there in the green-to-yellow half of the sequential map (values above its lowest).
std::pair<std::size_t, std::size_t> flagged_and_coloured_pixels(const std::string& png)
{
  int width = 0, height = 0, channels = 0;
  unsigned char* rgb = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()), int(png.size()), &width,
                                             &height, &channels, 3);
  if(!rgb) return {0, 0};
  std::size_t flagged = 0, coloured = 0;
  const int legend = std::max(20, height / 25);
  for(int p = 0; p < width * (height - legend); ++p) {
    const int r = rgb[3 * p], g = rgb[3 * p + 1], b = rgb[3 * p + 2];
    flagged += r > 60 && g < 20 && b > 0.6 * r && b < 0.95 * r;
    coloured += std::max({r, g, b}) - std::min({r, g, b}) > 40 && g > 50;
  }
  stbi_image_free(rgb);
  return {flagged, coloured};
}

// Colour maps that never collapse: 0.1 % new points of an up-sampling stay visible, and a property that is zero
// on 98.5 % of the points still colours the others (the 2nd-98th percentile range once made both blank). The
// sphere is dense for its picture (splats of about one pixel), so flags show only because they are emphasized.
TEST_F(Cli, PicturesShowAFewNewPointsAndAChangeOfAFewPoints)
{
  const std::size_t n = 40000;
  const auto s = CGAL_ext::shapes::bumpy_sphere<Kernel>(n, 1.0, 0.02);
  {
    std::ofstream out(path("flags.ply"));
    out << "ply\nformat ascii 1.0\nelement vertex " << n << "\nproperty double x\nproperty double y\nproperty double z\n"
        << "property double nx\nproperty double ny\nproperty double nz\nproperty double inserted\nproperty double displacement\nend_header\n";
    out.precision(17);
    for(std::size_t i = 0; i < n; ++i)
      out << s.points[i] << " " << s.normals[i] << " " << (i % 1000 == 0 ? 1 : 0) << " " << (i % 67 == 0 ? 0.01 * double(i % 5) : 0.0) << "\n";
  }
  ASSERT_EQ(run("render -i " + path("flags.ply") + " -o " + path("new.png") + " --color-by inserted --width 200 --height 200").exit_code, 0);
  ASSERT_EQ(run("render -i " + path("flags.ply") + " -o " + path("moved.png") + " --color-by displacement --width 200 --height 200").exit_code, 0);
  ASSERT_EQ(run("render -i " + path("flags.ply") + " -o " + path("plain.png") + " --color-by none --width 200 --height 200").exit_code, 0);
  const auto [flagged, mapped] = flagged_and_coloured_pixels(contents(path("new.png")));
  const auto [unflagged, coloured] = flagged_and_coloured_pixels(contents(path("moved.png")));
  const auto [none, grey] = flagged_and_coloured_pixels(contents(path("plain.png")));
  std::printf("0.1 %% flagged: %zu flag pixels; 1.5 %% changed: %zu coloured pixels; plain: %zu\n", flagged, coloured, grey);
  // About 20 of the 40 flagged points face the camera, each drawn over its neighbours as a disc at least 2
  // pixels in radius (measured 152 pixels; drawn like the other points they gave 6).
  EXPECT_GT(flagged, 20u * 5);
  EXPECT_EQ(none + grey, 0u);
  // 478 of the 597 changed points have a non-zero value (the others are 0.01 * 0), about half of them face the
  // camera; each covers a pixel or so (measured 161).
  EXPECT_GT(coloured, 240u / 3);
  EXPECT_EQ(unflagged, 0u);
  (void)mapped; // the flag picture's splat edges blend pink into grey
}

// A colour bar says what it shows: the quantity's name over it, in the legend's capitals.
TEST_F(Cli, TheLegendNamesWhatTheColoursShow)
{
  const std::string in = write_sphere_ply("in.ply", 2000);
  ASSERT_EQ(run("details -i " + in + " -o " + path("d.ply")).exit_code, 0);
  auto dark_legend_pixels = [&](const std::string& legend) {
    const Program_run r = run("render -i " + path("d.ply") + " -o " + path("d.png") +
                              " --color-by detail_normal --width 400 --height 400 --legend '" + legend + "'");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const std::string png = contents(path("d.png"));
    int width = 0, height = 0, channels = 0;
    unsigned char* rgb = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()), int(png.size()), &width,
                                               &height, &channels, 3);
    std::size_t dark = 0;
    for(int p = width * (height - 40); rgb && p < width * height; ++p) dark += rgb[3 * p] < 80 && rgb[3 * p + 2] < 80;
    stbi_image_free(rgb);
    return dark;
  };
  const std::size_t short_name = dark_legend_pixels("x"), long_name = dark_legend_pixels("detail along the normal, model units");
  std::printf("dark legend pixels: named x %zu, named in full %zu\n", short_name, long_name);
  EXPECT_GT(long_name, short_name + 100); // about 30 more glyphs of 5 to 11 pixels each
  const Program_run bad = run("render -i " + path("d.ply") + " -o " + path("e.png") + " --legend 'δ, model units'");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("font writes letters"), std::string::npos) << bad.output;
}

TEST_F(Cli, ScaleWiringMovesTheRegionOnlyAsTheLibraryDoes)
{
  const std::string in = write_sphere_ply("in.ply", 3000);
  { std::ofstream(path("anchors.txt")) << "# anchors\n0\n\n1 # the first two points\n"; }
  const Program_run r = run("scale -i " + in + " -o " + path("out.ply") + " --factor 2.5 --roi sphere:0,0,1,0.6 --roi box:-2,-2,0.9,2,2,2 --order linear --png " +
                            path("out.png") + " --report " + path("report.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CGAL::Point_set_3<Point> input, output;
  ASSERT_TRUE(CGAL::IO::read_point_set(in, input));
  ASSERT_TRUE(CGAL::IO::read_point_set(path("out.ply"), output));
  ASSERT_EQ(output.size(), input.size());
  auto in_roi = output.property_map<double>("in_roi");
  ASSERT_TRUE(in_roi.second);
  ASSERT_TRUE(output.property_map<double>("displacement").second);

  std::vector<Point> expected;
  std::vector<std::size_t> roi;
  for(auto it = input.begin(); it != input.end(); ++it) {
    const Point& p = input.point(*it);
    if(CGAL::squared_distance(p, Point(0, 0, 1)) <= 0.36 || p.z() >= 0.9) roi.push_back(expected.size());
    expected.push_back(p);
  }
  CGAL_ext::scale_geometric_details(expected, 10, roi, 2.5, CGAL_ext::Detail_filter{CGAL_ext::Detail_order::linear});
  std::size_t i = 0, moved = 0;
  for(auto it = output.begin(); it != output.end(); ++it, ++i) {
    EXPECT_LT(std::sqrt(CGAL::squared_distance(output.point(*it), expected[i])), 1e-12) << i;
    EXPECT_EQ(in_roi.first[*it] == 1.0, std::binary_search(roi.begin(), roi.end(), i)) << i;
    if(in_roi.first[*it] == 0.0) {
      EXPECT_EQ(output.point(*it), input.point(*(input.begin() + std::ptrdiff_t(i))));
    }
    moved += output.point(*it) != input.point(*(input.begin() + std::ptrdiff_t(i)));
  }
  EXPECT_GT(moved, roi.size() / 2);
  const auto report = nlohmann::json::parse(contents(path("report.json")));
  EXPECT_EQ(report["roi_points"], roi.size());
  EXPECT_EQ(report["default_anchors"], true);
  EXPECT_LT(report["solver"]["relative_residual"].get<double>(), 1e-10);
  EXPECT_EQ(contents(path("out.png")).substr(1, 3), "PNG");

  // Given anchors and conjugate gradients; enhancement of the whole model with s = 1 changes nothing.
  ASSERT_EQ(run("scale -i " + in + " -o " + path("a.ply") + " -s 0.5 --roi sphere:0,0,1,0.6 --anchors indices:" + path("anchors.txt") +
                " --solver cg --report " + path("a.json")).exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(contents(path("a.json")))["default_anchors"], false);
  ASSERT_EQ(run("enhance -i " + in + " -o " + path("e.ply") + " -s 1 --report " + path("e.json")).exit_code, 0);
  CGAL::Point_set_3<Point> same;
  ASSERT_TRUE(CGAL::IO::read_point_set(path("e.ply"), same));
  i = 0;
  for(auto it = same.begin(); it != same.end(); ++it, ++i)
    EXPECT_LT(std::sqrt(CGAL::squared_distance(same.point(*it), input.point(*(input.begin() + std::ptrdiff_t(i))))), 1e-9);
  EXPECT_EQ(nlohmann::json::parse(contents(path("e.json")))["roi_points"], 3000);

  // An independent oracle for enhance: the sphere's bumps (known height field) come out twice as high at s = 2.
  ASSERT_EQ(run("enhance -i " + in + " -o " + path("e2.ply") + " -s 2").exit_code, 0);
  CGAL::Point_set_3<Point> enhanced;
  ASSERT_TRUE(CGAL::IO::read_point_set(path("e2.ply"), enhanced));
  const auto shape = CGAL_ext::shapes::bumpy_sphere<Kernel>(3000, 1.0, 0.02);
  auto amplitude = [&](const CGAL::Point_set_3<Point>& set) {
    std::vector<double> radius;
    for(auto it = set.begin(); it != set.end(); ++it) radius.push_back(std::sqrt((set.point(*it) - CGAL::ORIGIN).squared_length()));
    const double mean = std::accumulate(radius.begin(), radius.end(), 0.0) / double(radius.size());
    double rh = 0, hh = 0;
    for(std::size_t m = 0; m < radius.size(); ++m) {
      rh += (radius[m] - mean) * shape.bump_height[m];
      hh += shape.bump_height[m] * shape.bump_height[m];
    }
    return rh / hh;
  };
  EXPECT_NEAR(amplitude(enhanced) / amplitude(input), 2.0, 0.3);
}

// An independent oracle for scale: the sphere's bumps (known height field h) in the middle of a cap scaled by
// s = 2 grow by about 2. The cap's own bulge changes too, so the amplitude is the coefficient of h in a
// least-squares fit of the radial deviation by 1, z and h over the cap's middle. These bumps are fine (4
// spacings): the smooth surface the border spans (s = 0) keeps about a quarter of them, so they grow by
// 0.26 + 2 x 0.74 = 1.74.
TEST_F(Cli, ScaleDoublesBumpsOfKnownHeight)
{
  const std::string in = write_sphere_ply("in.ply", 6000);
  ASSERT_EQ(run("scale -i " + in + " -o " + path("s2.ply") + " -s 2 --roi sphere:0,0,1,1.0").exit_code, 0);
  CGAL::Point_set_3<Point> input, output;
  ASSERT_TRUE(CGAL::IO::read_point_set(in, input));
  ASSERT_TRUE(CGAL::IO::read_point_set(path("s2.ply"), output));
  const auto shape = CGAL_ext::shapes::bumpy_sphere<Kernel>(6000, 1.0, 0.02);
  auto amplitude = [&](const CGAL::Point_set_3<Point>& set) {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    std::size_t m = 0;
    for(auto it = set.begin(); it != set.end(); ++it, ++m) {
      const Point& p = set.point(*it);
      if(shape.points[m].z() < 0.85) continue;
      const Eigen::Vector3d row(1, shape.points[m].z(), shape.bump_height[m]);
      normal += row * row.transpose();
      rhs += row * (std::sqrt((p - CGAL::ORIGIN).squared_length()) - 1);
    }
    return Eigen::Vector3d(normal.ldlt().solve(rhs))(2);
  };
  const double before = amplitude(input), after = amplitude(output);
  std::printf("scale -s 2: bump amplitude %.4f -> %.4f (x %.3f)\n", before, after, after / before);
  EXPECT_NEAR(before, 1.0, 0.02);
  EXPECT_GT(after / before, 1.6);
  EXPECT_LT(after / before, 2.2);
}

TEST_F(Cli, RegionSpecsWithMistakesAreRejectedNamingTheBadToken)
{
  const std::string in = write_sphere_ply("in.ply", 500);
  { std::ofstream(path("bad_index.txt")) << "3\nseven\n"; }
  { std::ofstream(path("far_index.txt")) << "3\n500\n"; }
  struct Case { std::string args, needle; };
  const std::string scale = "scale -i " + in + " -o " + path("o.ply") + " -s 2 ";
  const Case cases[] = {
    {scale + "--roi sphere:0,0,x,1", "'x' is not a finite number"},
    {scale + "--roi sphere:0,0,1", "sphere takes 4 numbers, got 3"},
    {scale + "--roi sphere:0,0,1,-1", "radius '-1' must be > 0"},
    {scale + "--roi cube:0,0,0,1", "unknown kind 'cube'"},
    {scale + "--roi box:0,0,0,1,1", "box takes 6 numbers, got 5"},
    {scale + "--roi box:1,0,0,0,1,1", "minimum '1' exceeds the maximum '0'"},
    {scale + "--roi 0,0,0,1", "expected sphere:"},
    {scale + "--roi indices:" + path("bad_index.txt"), "bad_index.txt:2: 'seven' is not a point index"},
    {scale + "--roi indices:" + path("far_index.txt"), "index 500 is out of range"},
    {scale + "--roi indices:" + path("none.txt"), "cannot read"},
    {scale + "--roi sphere:9,9,9,0.1", "contains none"},
    {scale + "--roi sphere:0,0,0,5", "whole model and no anchors"},
    {scale + "--roi sphere:0,0,1,0.5 --anchors sphere:0,0,-1,0.5", "is not in the region of interest"},
    {"scale -i " + in + " -o " + path("o.ply") + " -s inf --roi sphere:0,0,1,0.5", "factor"},
    {"scale -i " + in + " -o " + path("o.ply") + " -s 2", "--roi"},
  };
  for(const Case& c : cases) {
    const Program_run r = run(c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.needle), std::string::npos) << c.args << "\n" << r.output;
  }
  expect_only({"in.ply", "bad_index.txt", "far_index.txt"});
}

TEST_F(Cli, CurvatureOfASphereIsOneOverItsRadius)
{
  const std::string in = write_sphere_ply("in.ply", 4000);
  for(const char* fitting : {"monge", "closed_form", "closed-form"}) { // and the older spelling
    const Program_run r = run("curvature -i " + in + " -o " + path("h.ply") + " --fitting " + fitting + " --png " + path("h.png") +
                              " --report " + path("h.json"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    CGAL::Point_set_3<Point> out;
    ASSERT_TRUE(CGAL::IO::read_point_set(path("h.ply"), out));
    auto H = out.property_map<double>("mean_curvature");
    ASSERT_TRUE(H.second);
    std::vector<double> values(H.first.begin(), H.first.end());
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(values.size() / 2), values.end());
    // The file's sphere has bumps of 2 % of the radius: the median stays within 5 % of 1.
    EXPECT_NEAR(values[values.size() / 2], 1.0, 0.05) << fitting;
    EXPECT_NEAR(nlohmann::json::parse(contents(path("h.json")))["curvature_percentiles"]["p50"].get<double>(), 1.0, 0.05);
    EXPECT_EQ(contents(path("h.png")).substr(1, 3), "PNG");
  }
  const Program_run bad = run("curvature -i " + in + " -o " + path("x.ply") + " -k 3");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("at least 5"), std::string::npos) << bad.output;
}

TEST_F(Cli, SimplifyWiringSurfelsCoverEveryPointOnceAsTheLibraryMakesThem)
{
  const std::string in = write_sphere_ply("in.ply", 3000);
  const Program_run r = run("simplify -i " + in + " -o " + path("ssp.ply") + " --max-cluster-size 20 --clusters " +
                            path("clusters.ply") + " --png " + path("ssp.png") + " --report " + path("ssp.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CGAL::Point_set_3<Point> input, surfels, clusters;
  ASSERT_TRUE(CGAL::IO::read_point_set(in, input));
  ASSERT_TRUE(CGAL::IO::read_point_set(path("ssp.ply"), surfels));
  ASSERT_TRUE(CGAL::IO::read_point_set(path("clusters.ply"), clusters));
  ASSERT_TRUE(surfels.has_normal_map());
  auto radius = surfels.property_map<double>("radius");
  auto members = surfels.property_map<double>("member_count");
  auto ssp_index = clusters.property_map<double>("ssp_index");
  ASSERT_TRUE(radius.second && members.second && ssp_index.second);

  CGAL_ext::Simplification_settings settings;
  settings.max_cluster_size = 20;
  std::vector<std::size_t> sample_of(input.size());
  const auto library = CGAL_ext::compute_simplification_sample_points(input, settings, CGAL::make_property_map(sample_of),
                                                                      input.parameters());
  ASSERT_EQ(surfels.size(), library.size());
  std::vector<double> counted(surfels.size(), 0.0);
  std::size_t i = 0;
  for(auto it = clusters.begin(); it != clusters.end(); ++it, ++i) {
    ASSERT_EQ(std::size_t(ssp_index.first[*it]), sample_of[i]);
    counted[sample_of[i]] += 1;
  }
  double total = 0;
  std::size_t s = 0;
  for(auto it = surfels.begin(); it != surfels.end(); ++it, ++s) {
    EXPECT_EQ(members.first[*it], counted[s]);
    EXPECT_LE(members.first[*it], 20.0);
    EXPECT_GE(radius.first[*it], 0.0);
    EXPECT_NEAR(CGAL::squared_distance(surfels.point(*it), library.samples[s].centroid), 0.0, 1e-24);
    total += members.first[*it];
  }
  EXPECT_EQ(total, double(input.size()));
  // An oracle independent of the library: each surfel is the centroid of the input points labelled with it, and
  // its radius is the largest distance of one of them.
  std::vector<Vector> sum(surfels.size(), CGAL::NULL_VECTOR);
  std::vector<double> farthest(surfels.size(), 0.0);
  i = 0;
  for(auto it = input.begin(); it != input.end(); ++it, ++i) sum[std::size_t(ssp_index.first[*(clusters.begin() + i)])] += input.point(*it) - CGAL::ORIGIN;
  s = 0;
  for(auto it = surfels.begin(); it != surfels.end(); ++it, ++s)
    EXPECT_LT(CGAL::squared_distance(surfels.point(*it), CGAL::ORIGIN + sum[s] / counted[s]), 1e-24) << "surfel " << s;
  i = 0;
  for(auto it = input.begin(); it != input.end(); ++it, ++i) {
    const std::size_t own = std::size_t(ssp_index.first[*(clusters.begin() + i)]);
    farthest[own] = std::max(farthest[own], std::sqrt(CGAL::squared_distance(input.point(*it), surfels.point(*(surfels.begin() + own)))));
  }
  s = 0;
  for(auto it = surfels.begin(); it != surfels.end(); ++it, ++s) EXPECT_NEAR(radius.first[*it], farthest[s], 1e-12) << "surfel " << s;
  const auto report = nlohmann::json::parse(contents(path("ssp.json")));
  EXPECT_EQ(report["ssps"], library.size());
  EXPECT_LE(report["max_cluster_size"].get<int>(), 20);
  EXPECT_EQ(report["requested_ssps"], library.requested_count);
  EXPECT_GT(report["mean_shift"]["mean_iterations"].get<double>(), 1.0);
  EXPECT_EQ(contents(path("ssp.png")).substr(1, 3), "PNG");

  for(const auto& [args, needle] : {std::pair<std::string, std::string>{"--max-cluster-size 0", "max_cluster_size"},
                                    {"--mode-threshold 0", "mode_spread_threshold"},
                                    {"--target 0", "target_count"},
                                    {"-k 4", "mean_shift_neighbors"},
                                    {"--range-bandwidth -1", "range_bandwidth"}}) {
    const Program_run bad = run("simplify -i " + in + " -o " + path("x.ply") + " " + args);
    EXPECT_EQ(bad.exit_code, 1) << args;
    EXPECT_NE(bad.output.find(needle), std::string::npos) << args << "\n" << bad.output;
  }
  expect_only({"in.ply", "ssp.ply", "clusters.ply", "ssp.png", "ssp.json"});
}

TEST_F(Cli, DetailsWiringMeanShiftNeighbourhoodsAsTheLibrary)
{
  const std::string in = write_sphere_ply("in.ply", 3000);
  const Program_run r = run("details -i " + in + " -o " + path("out.ply") + " --neighbors mean-shift --report " + path("r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CGAL::Point_set_3<Point> input, output;
  ASSERT_TRUE(CGAL::IO::read_point_set(in, input));
  ASSERT_TRUE(CGAL::IO::read_point_set(path("out.ply"), output));
  CGAL_ext::Detail_settings settings;
  settings.neighborhood = CGAL_ext::Laplacian_neighborhood::mean_shift;
  std::vector<Vector> details(input.size());
  std::vector<double> magnitude(input.size());
  ASSERT_TRUE(CGAL_ext::compute_geometric_details(input, CGAL_ext::default_laplacian_neighbors, settings,
                                                  CGAL::make_property_map(details), CGAL::make_property_map(magnitude),
                                                  input.parameters()));
  auto mag = output.property_map<double>("detail_magnitude").first;
  std::size_t i = 0;
  for(auto it = output.begin(); it != output.end(); ++it, ++i) ASSERT_DOUBLE_EQ(mag[*it], magnitude[i]);
  EXPECT_EQ(nlohmann::json::parse(contents(path("r.json")))["neighbors"], "mean_shift"); // the name, not the older spelling
  const Program_run bad = run("details -i " + in + " -o " + path("x.ply") + " --neighbors delaunay");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("delaunay"), std::string::npos) << bad.output;
}

// An edit file spells each setting as the library, the options and Python do (flat "diffusion_origin"); older
// files' "diffusion" object is still read, to the same edit; both at once are refused.
TEST_F(Cli, EditFilesSpellSettingsAsEverywhereAndOlderFilesStillRead)
{
  const std::string in = write_sphere_ply("in.ply", 2000);
  const std::string edit = R"({"roi": ["box:-2,-2,0,2,2,2"], "handles": [{"select": ["sphere:0,0,1,0.25"],
                               "translation": [0.1, 0, 0.2]}], )";
  const std::map<std::string, std::string> files = {
    {"flat", edit + R"("diffusion_origin": "nearest", "diffusion_turn": "frames", "diffusion_samples": 5})"},
    {"nested", edit + R"("diffusion": {"origin": "nearest", "turn": "frames", "samples": 5}})"},
    {"both", edit + R"("diffusion_turn": "frames", "diffusion": {"origin": "nearest"}})"}};
  for(const auto& [name, text] : files) {
    std::ofstream(path(name + ".json")) << text;
    const Program_run r = run("edit -i " + in + " -o " + path(name + ".ply") + " --edit " + path(name + ".json"));
    if(name == "both") {
      EXPECT_NE(r.exit_code, 0);
      EXPECT_NE(r.output.find("diffusion_turn and the older \"diffusion\" object are both given"), std::string::npos)
        << r.output;
    } else
      ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  EXPECT_EQ(contents(path("flat.ply")), contents(path("nested.ply")));
  const Program_run other = run("edit -i " + in + " -o " + path("other.ply") + " --edit " + path("flat.json") +
                                " --diffusion-turn fitted --diffusion-samples 6");
  ASSERT_EQ(other.exit_code, 0) << other.output;
  EXPECT_NE(contents(path("flat.ply")), contents(path("other.ply"))) << "the options override the file";
}

TEST_F(Cli, EditWiringJsonAsTheLibraryDoesAndHandlesOnTheirTransform)
{
  const std::string in = write_sphere_ply("in.ply", 3000);
  {
    std::ofstream edit(path("edit.json"));
    edit << R"({"roi": ["box:-2,-2,0,2,2,2"],
               "handles": [{"select": ["sphere:0,0,1,0.25"], "translation": [0.1, 0, 0.2],
                            "rotation": {"axis": [0, 1, 0], "degrees": 25}, "pivot": [0, 0, 1]}],
               "filter": {"order": "cubic", "lambda": 0.8, "mu": 1.6}, "diffusion": {"origin": "nearest", "turn": "frames"}})";
  }
  const Program_run r = run("edit -i " + in + " -o " + path("out.ply") + " --edit " + path("edit.json") + " --png " +
                            path("out.png") + " --report " + path("out.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CGAL::Point_set_3<Point> input, output;
  ASSERT_TRUE(CGAL::IO::read_point_set(in, input));
  ASSERT_TRUE(CGAL::IO::read_point_set(path("out.ply"), output));
  ASSERT_EQ(output.size(), input.size());
  auto status = output.property_map<double>("status");
  ASSERT_TRUE(status.second);

  // The same edit through the library.
  CGAL_ext::Detail_preserving_deformation_settings settings(CGAL_ext::Detail_filter{CGAL_ext::Detail_order::cubic, 0.8, 1.6});
  settings.diffusion_origin = CGAL_ext::Diffusion_origin::nearest_sample;
  settings.diffusion_turn = CGAL_ext::Sample_turn::frames;
  std::size_t roi = 0, handles = 0, ssps = 0, roi_ssps = 0;
  auto library_edit = [&](const CGAL_ext::Detail_preserving_deformation_settings& s) {
    CGAL::Point_set_3<Point> points = input;
    CGAL_ext::Detail_preserving_deformation<> deformation(points, s, points.parameters());
    const std::size_t g = deformation.create_handle_group();
    roi = handles = 0;
    for(auto i : points) {
      const Point& p = points.point(i);
      if(p.z() >= 0) { deformation.insert_roi_point(i); ++roi; }
      if(CGAL::squared_distance(p, Point(0, 0, 1)) <= 0.0625) { deformation.insert_handle_point(g, i); ++handles; }
    }
    const Eigen::Matrix3d R = Eigen::AngleAxisd(25 * CGAL_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
    deformation.set_handle_transform(g, R, Eigen::Vector3d(0, 0, 1) - R * Eigen::Vector3d(0, 0, 1) + Eigen::Vector3d(0.1, 0, 0.2));
    EXPECT_TRUE(deformation.deform());
    deformation.diffuse(points, points.parameters());
    deformation.restore_details(points, points.parameters());
    ssps = deformation.number_of_sample_points();
    roi_ssps = deformation.number_of_roi_sample_points();
    return std::vector<Point>(points.points().begin(), points.points().end());
  };
  EXPECT_LT(max_distance(std::vector<Point>(output.points().begin(), output.points().end()), library_edit(settings)), 1e-12);
  // Beyond the wiring: handle points end on their transform, the fixed part does not move.
  {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(25 * CGAL_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Vector3d t = Eigen::Vector3d(0, 0, 1) - R * Eigen::Vector3d(0, 0, 1) + Eigen::Vector3d(0.1, 0, 0.2);
    double handle_error = 0, fixed_motion = 0;
    auto in_it = input.begin();
    for(auto it = output.begin(); it != output.end(); ++it, ++in_it) {
      const Point& p = input.point(*in_it);
      const Eigen::Vector3d target = R * Eigen::Vector3d(p.x(), p.y(), p.z()) + t;
      const Point& q = output.point(*it);
      if(status.first[*it] == 2) handle_error = std::max(handle_error, (Eigen::Vector3d(q.x(), q.y(), q.z()) - target).norm());
      if(status.first[*it] == 0) fixed_motion = std::max(fixed_motion, std::sqrt(CGAL::squared_distance(p, q)));
    }
    EXPECT_LT(handle_error, 1e-12);
    EXPECT_EQ(fixed_motion, 0.0);
  }
  std::size_t marked_roi = 0, marked_handles = 0;
  for(auto i : output) {
    marked_roi += status.first[i] >= 1;
    marked_handles += status.first[i] == 2;
  }
  EXPECT_EQ(marked_roi, roi);
  EXPECT_EQ(marked_handles, handles);
  const auto report = nlohmann::json::parse(contents(path("out.json")));
  EXPECT_EQ(report["points"], 3000);
  EXPECT_EQ(report["ssps"], ssps);
  EXPECT_EQ(report["roi_ssps"], roi_ssps);
  EXPECT_EQ(report["order"], "cubic");
  EXPECT_EQ(report["handle_constraints"], "exact");
  EXPECT_LT(report["max_handle_point_error"].get<double>(), 1e-12);
  EXPECT_GE(report["requested_ssps"].get<std::size_t>(), ssps);
  EXPECT_GE(report["displacement_ratio"].get<double>(), 1.0);
  EXPECT_GT(report["table1"]["editing_ssps_s"].get<double>(), 0.0);
  EXPECT_GE(report["table1"]["diffusion_s"].get<double>(), 0.0);
  EXPECT_GT(report["restore_details"]["iterations"].get<unsigned>(), 0u);
  EXPECT_LE(report["restore_details"]["residual"].get<double>(), settings.detail_tolerance);
  EXPECT_EQ(contents(path("out.png")).substr(1, 3), "PNG");

  // The program's edit with `options` over the file, read back: it must be the library's with `s`.
  auto program_edit = [&](const std::string& name, const std::string& options,
                          const CGAL_ext::Detail_preserving_deformation_settings& s) {
    const Program_run r = run("edit -i " + in + " -o " + path(name + ".ply") + " --edit " + path("edit.json") + " " + options);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    CGAL::Point_set_3<Point> edited;
    EXPECT_TRUE(CGAL::IO::read_point_set(path(name + ".ply"), edited));
    const std::vector<Point> points(edited.points().begin(), edited.points().end());
    EXPECT_LT(max_distance(points, library_edit(s)), 1e-12) << options;
    return std::make_pair(points, r.output);
  };
  // As rigid as possible, chosen on the command line over the file.
  settings.rotations = CGAL_ext::Detail_rotation::as_rigid_as_possible;
  settings.rigid_iterations = 2;
  const std::vector<Point> rigid_points = program_edit("arap", "--rotations arap --rigid-iterations 2", settings).first;
  EXPECT_GT(max_distance(rigid_points, std::vector<Point>(output.points().begin(), output.points().end())), 1e-3);
  // Two steps of the restore, and a warning that it stopped early.
  settings.detail_iterations = 2;
  const std::string capped =
    program_edit("capped", "--rotations arap --rigid-iterations 2 --detail-iterations 2", settings).second;
  EXPECT_NE(capped.find("stopped after 2 steps"), std::string::npos) << capped;
  // SRE-ARAP's smooth-rotation term.
  settings.detail_iterations = CGAL_ext::Detail_preserving_deformation_settings().detail_iterations;
  settings.rigid_rotation_smoothing = 1;
  const std::vector<Point> smooth_points =
    program_edit("smooth", "--rotations arap --rigid-iterations 2 --rigid-rotation-smoothing 1", settings).first;
  EXPECT_GT(max_distance(smooth_points, rigid_points), 1e-6);
  // Cotangent edge weights (by their older option's spelling); the report names them.
  settings.rigid_rotation_smoothing = 0;
  settings.rigid_edge_weights = CGAL_ext::Rigid_edge_weights::cotangent;
  const std::vector<Point> cotangent_points =
    program_edit("cotangent", "--rotations arap --rigid-iterations 2 --rigid-weights cotangent --report " +
                                path("cotangent.json"), settings).first;
  EXPECT_GT(max_distance(cotangent_points, rigid_points), 1e-6);
  EXPECT_EQ(nlohmann::json::parse(contents(path("cotangent.json")))["rigid_edge_weights"], "cotangent");
  // SRE_ARAP's own energy (the term relative to the surface's area); the report names it.
  settings.rigid_rotation_smoothing = 0.02;
  settings.rigid_rotation_smoothing_scale = CGAL_ext::Rotation_smoothing_scale::surface_area;
  const std::vector<Point> sre_points =
    program_edit("sre", "--rotations arap --rigid-iterations 2 --rigid-edge-weights cotangent --rigid-rotation-smoothing "
                        "0.02 --rigid-rotation-smoothing-scale surface_area --report " + path("sre.json"), settings).first;
  EXPECT_GT(max_distance(sre_points, cotangent_points), 1e-6);
  EXPECT_EQ(nlohmann::json::parse(contents(path("sre.json")))["rigid_rotation_smoothing_scale"], "surface_area");
  // A misspelt mode is named.
  {
    std::ofstream edit(path("bad.json"));
    edit << R"({"handles": [{"select": ["sphere:0,0,1,0.25"], "translation": [0.1, 0, 0.2]}], "rotations": "rigid"})";
  }
  const Program_run bad = run("edit -i " + in + " -o " + path("bad.ply") + " --edit " + path("bad.json"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("rotations must be \"none\", \"propagate\" or \"arap\""), std::string::npos) << bad.output;
  {
    std::ofstream edit(path("bad_weights.json"));
    edit << R"({"handles": [{"select": ["sphere:0,0,1,0.25"], "translation": [0.1, 0, 0.2]}], "rigid_edge_weights": "cot"})";
  }
  const Program_run bad_weights = run("edit -i " + in + " -o " + path("bad.ply") + " --edit " + path("bad_weights.json"));
  EXPECT_NE(bad_weights.exit_code, 0);
  EXPECT_NE(bad_weights.output.find("rigid_edge_weights must be \"uniform\" or \"cotangent\", not \"cot\""), std::string::npos)
    << bad_weights.output;
  {
    std::ofstream edit(path("bad_scale.json"));
    edit << R"({"handles": [{"select": ["sphere:0,0,1,0.25"], "translation": [0.1, 0, 0.2]}], "rigid_rotation_smoothing_scale": "area"})";
  }
  const Program_run bad_scale = run("edit -i " + in + " -o " + path("bad.ply") + " --edit " + path("bad_scale.json"));
  EXPECT_NE(bad_scale.exit_code, 0);
  EXPECT_NE(bad_scale.output.find("rigid_rotation_smoothing_scale must be \"edge_lengths\" or \"surface_area\", not \"area\""),
            std::string::npos) << bad_scale.output;
  expect_only({"in.ply", "edit.json", "out.ply", "out.png", "out.json", "arap.ply", "capped.ply", "smooth.ply", "cotangent.ply",
               "cotangent.json", "sre.ply", "sre.json", "bad.json", "bad_weights.json", "bad_scale.json"});
}

TEST_F(Cli, EditBySelAndDefAndItsMistakes)
{
  const std::string in = write_sphere_ply("in.ply", 2000);
  CGAL::Point_set_3<Point> input;
  ASSERT_TRUE(CGAL::IO::read_point_set(in, input));
  {
    std::ofstream sel(path("in.sel"));
    sel << "# per vertex status: 0=fixed, 1=deformable-region, 2=handle\n";
    for(auto i : input) sel << (input.point(i).z() > 0.8 ? 2 : input.point(i).z() > 0 ? 1 : 0) << "\n";
  }
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(path(name)) << text;
    return path(name);
  };
  // An identity transform: every point stays where it is.
  write("identity.def", "# 4x4 handle transformation matrix\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  Program_run r = run("edit -i " + in + " -o " + path("same.ply") + " --sel " + path("in.sel") + " --def " + path("identity.def"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CGAL::Point_set_3<Point> same;
  ASSERT_TRUE(CGAL::IO::read_point_set(path("same.ply"), same));
  EXPECT_EQ(max_distance(std::vector<Point>(same.points().begin(), same.points().end()),
                         std::vector<Point>(input.points().begin(), input.points().end())), 0.0);
  // A rotation printed with six digits, as Botsch and Sorkine's files are, is snapped to a rotation.
  write("turn.def", "0.999641 0.021031 0.016579 -0.019322\n-0.022776 0.342021 0.939416 -0.134331\n"
                    "0.014087 -0.939457 0.342378 0.821073\n0 0 0 1\n");
  r = run("edit -i " + in + " -o " + path("turned.ply") + " --sel " + path("in.sel") + " --def " + path("turn.def"));
  EXPECT_EQ(r.exit_code, 0) << r.output;

  // No fixed point (no 0 status) and a rigid .def: the whole model moves rigidly with its handle.
  {
    std::ofstream sel(path("all.sel"));
    for(auto i : input) sel << (input.point(i).z() > 0.8 ? 2 : 1) << "\n";
  }
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 2).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.3, -0.2, 0.5);
  std::ostringstream rigid;
  rigid.precision(17);
  for(int row = 0; row < 3; ++row) rigid << R(row, 0) << " " << R(row, 1) << " " << R(row, 2) << " " << t(row) << "\n";
  rigid << "0 0 0 1\n";
  write("rigid.def", rigid.str());
  r = run("edit -i " + in + " -o " + path("rigid.ply") + " --sel " + path("all.sel") + " --def " + path("rigid.def"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CGAL::Point_set_3<Point> moved;
  ASSERT_TRUE(CGAL::IO::read_point_set(path("rigid.ply"), moved));
  double error = 0;
  auto m = moved.begin();
  for(auto i = input.begin(); i != input.end(); ++i, ++m) {
    const Point& p = input.point(*i);
    const Eigen::Vector3d want = R * Eigen::Vector3d(p.x(), p.y(), p.z()) + t;
    error = std::max(error, (want - Eigen::Vector3d(moved.point(*m).x(), moved.point(*m).y(), moved.point(*m).z())).norm());
  }
  EXPECT_LT(error, 1e-6 * 2 * std::sqrt(3.0)); // 1e-6 of the bounding diagonal

  write("short.sel", "1\n2\n");
  std::string bad_sel = "x\n"; // the right number of lines, the first one not a status
  for(std::size_t i = 1; i < input.size(); ++i) bad_sel += "1\n";
  write("bad.sel", bad_sel);
  write("scaled.def", "2 0 0 0\n0 2 0 0\n0 0 2 0\n0 0 0 1\n");
  write("few.def", "1 0 0\n");
  write("broken.json", "{\"handles\": [");
  write("typo.json", R"({"handles": [{"select": ["sphere:0,0,1,0.2"]}], "handle_wieght": 2})");
  write("empty_handle.json", R"({"handles": [{"select": ["sphere:5,5,5,0.1"]}]})");
  write("outside.json", R"({"roi": ["box:-2,-2,0.5,2,2,2"], "handles": [{"select": ["sphere:0,0,-1,0.2"]}]})");
  write("quaternion.json", R"({"handles": [{"select": ["sphere:0,0,1,0.2"], "quaternion": [2, 0, 0, 0]}]})");
  for(const auto& [args, needle] : std::vector<std::pair<std::string, std::string>>{
        {"--sel " + path("short.sel") + " --def " + path("identity.def"), "has 2 status lines but the model has 2000 points"},
        {"--sel " + path("bad.sel") + " --def " + path("identity.def"), "is not a status"},
        {"--sel " + path("in.sel") + " --def " + path("scaled.def"), "not a rotation"},
        {"--sel " + path("in.sel") + " --def " + path("few.def"), "holds 3 numbers"},
        {"--edit " + path("broken.json"), "not valid JSON"},
        {"--edit " + path("typo.json"), "unknown key 'handle_wieght'"},
        {"--edit " + path("empty_handle.json"), "selects no point"},
        {"--edit " + path("outside.json"), "is not in the region of interest"},
        {"--edit " + path("quaternion.json"), "unit quaternion"},
        {"", "edit needs --edit"}}) {
    const Program_run bad = run("edit -i " + in + " -o " + path("x.ply") + " " + args);
    EXPECT_EQ(bad.exit_code, 1) << args << "\n" << bad.output;
    EXPECT_NE(bad.output.find(needle), std::string::npos) << args << "\n" << bad.output;
  }
  // The program never writes over an input.
  const Program_run over = run("edit -i " + in + " -o " + path("in.sel") + " --sel " + path("in.sel") + " --def " + path("identity.def"));
  EXPECT_EQ(over.exit_code, 1);
  EXPECT_FALSE(fs::exists(path("x.ply")));
}

TEST_F(Cli, UpsampleFillsAHoleAndEditUpsampleFillsAStretch)
{
  // A unit grid with a hole of radius 2.6 in its middle.
  {
    std::ofstream out(path("holed.xyz"));
    for(int i = 0; i < 30; ++i)
      for(int j = 0; j < 30; ++j)
        if(std::hypot(i - 14.5, j - 14.5) >= 2.6) out << i << " " << j << " 0 0 0 1\n";
  }
  Program_run r = run("upsample -i " + path("holed.xyz") + " -o " + path("filled.ply") + " --spacing 1 --report " + path("u.json") +
                      " --png " + path("u.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CGAL::Point_set_3<Point> filled;
  ASSERT_TRUE(CGAL::IO::read_point_set(path("filled.ply"), filled));
  auto inserted = filled.property_map<double>("inserted");
  ASSERT_TRUE(inserted.second);
  const auto report = nlohmann::json::parse(contents(path("u.json")));
  std::size_t count = 0;
  for(auto i : filled)
    if(inserted.first[i] == 1) {
      ++count;
      EXPECT_LT(std::hypot(filled.point(i).x() - 14.5, filled.point(i).y() - 14.5), 3.1);
      EXPECT_LT(std::abs(filled.point(i).z()), 0.01);
    }
  EXPECT_EQ(count, report["upsampling"]["inserted"].get<std::size_t>());
  // The hole is filled at the requested spacing (1, the grid's): about as many points as it lacks.
  std::size_t removed = 0;
  for(int i = 0; i < 30; ++i)
    for(int j = 0; j < 30; ++j) removed += std::hypot(i - 14.5, j - 14.5) < 2.6;
  EXPECT_GT(double(count), 0.75 * double(removed));
  EXPECT_LT(double(count), 1.25 * double(removed));
  // The hole is covered: no place in it is much farther than one grid spacing from a point (2.6 before; the
  // fill leaves 1.09).
  double farthest = 0;
  for(double x = 11.5; x <= 17.5; x += 0.1)
    for(double y = 11.5; y <= 17.5; y += 0.1) {
      if(std::hypot(x - 14.5, y - 14.5) >= 2.6) continue;
      double nearest = 1e9;
      for(auto p : filled) nearest = std::min(nearest, std::hypot(filled.point(p).x() - x, filled.point(p).y() - y));
      farthest = std::max(farthest, nearest);
    }
  std::printf("hole of %zu grid points: %zu points inserted, farthest place from a point %.3f\n", removed, count, farthest);
  EXPECT_LT(farthest, 1.2);
  EXPECT_EQ(filled.size(), report["points"].get<std::size_t>() + count);
  EXPECT_EQ(contents(path("u.png")).substr(1, 3), "PNG");
  const Program_run bad = run("upsample -i " + path("holed.xyz") + " -o " + path("x.ply") + " --spacing -1");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("spacing"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(path("x.ply")));

  // An edit that pulls one end of a strip far away: the stretched part is filled at the pre-edit spacing.
  {
    std::ofstream out(path("strip.xyz"));
    for(int i = 0; i < 40; ++i)
      for(int j = 0; j < 8; ++j) out << i << " " << j << " 0 0 0 1\n";
    std::ofstream(path("pull.json")) << R"({"roi": ["box:10,-1,-1,50,10,1"], "handles": [{"select": ["box:35,-1,-1,50,10,1"], "translation": [30, 0, 0]}]})";
  }
  r = run("edit -i " + path("strip.xyz") + " -o " + path("pulled.ply") + " --edit " + path("pull.json") + " --upsample --report " + path("e.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto edit_report = nlohmann::json::parse(contents(path("e.json")));
  EXPECT_GT(edit_report["upsampling"]["inserted"].get<std::size_t>(), 50u);
  EXPECT_NEAR(edit_report["upsampling"]["spacing"].get<double>(), 1.2, 0.25); // the grid's, before the edit
}

TEST_F(Cli, CtrlCEndsARunWithinAboutASecondEvenInsideAFactorisationAndWritesNothing)
{
  // The cubic order on most of a 40k-point sphere, no anchors: the factorisation, which reports no progress,
  // takes seconds. The interrupt comes 2.5 s in (in the factorisation in a Release build, earlier stages in a
  // sanitized one); the run must end within the grace period of the watchdog plus a margin.
  const std::string in = write_sphere_ply("in.ply", 40000);
  const std::string command = "enhance -i " + in + " -o " + path("out.ply") + " --order cubic -s 2 --roi box:-2,-2,-0.9,2,2,2";
  const Program_run r = run(command + " 2>&1 & pid=$!; sleep 2.5; kill -INT $pid; start=$(date +%s%N); wait $pid; "
                                      "echo \"status=$? ms=$(( ($(date +%s%N) - start) / 1000000 ))\"; : ");
  EXPECT_NE(r.output.find("cancelled; nothing written"), std::string::npos) << r.output;
  const std::size_t at = r.output.find("status=");
  ASSERT_NE(at, std::string::npos) << r.output;
  int status = -1, ms = -1;
  ASSERT_EQ(std::sscanf(r.output.c_str() + at, "status=%d ms=%d", &status, &ms), 2) << r.output;
  EXPECT_EQ(status, 130);
  EXPECT_LT(ms, 2500) << "the run went on for " << ms << " ms after Ctrl-C";
  expect_only({"in.ply"});
}

TEST(ProgramEnvironment, OpenBlasCoresOlderThanAvx2AreTold)
{
  for(const char* older : {"Prescott", "Core2", "Nehalem", "Sandybridge", "Bulldozer", "Piledriver"})
    EXPECT_TRUE(point_detail::openblas_core_predates_avx2(older)) << older;
  for(const char* avx2 : {"Haswell", "Zen", "SkylakeX", "Cooperlake", "SapphireRapids", "Excavator", "Unknown", ""})
    EXPECT_FALSE(point_detail::openblas_core_predates_avx2(avx2)) << avx2;
}

namespace {
/// The OpenBLAS kernels `point-detail --version` reports ("not OpenBLAS" when BLAS is another library).
std::string reported_blas_kernels(const std::string& environment)
{
  const Program_run r = run("--version", environment);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  if(r.output.find("BLAS: not OpenBLAS") != std::string::npos) return "not OpenBLAS";
  const std::string marker = "BLAS: OpenBLAS, ";
  const std::size_t at = r.output.find(marker);
  if(at == std::string::npos) return "";
  const std::string rest = r.output.substr(at + marker.size());
  return rest.substr(0, rest.find(" kernels"));
}
} // namespace

TEST_F(Cli, OpenBlasRunsItsAvx2KernelsWhereTheCpuHasThemUnlessTheUserChoseOthers)
{
  const std::string core = reported_blas_kernels("");
  ASSERT_FALSE(core.empty());
  if(core == "not OpenBLAS") GTEST_SKIP() << "CHOLMOD does not run on OpenBLAS here";
  const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"); // x86: Debian 12's amd64
  if(avx2) {
    EXPECT_FALSE(point_detail::openblas_core_predates_avx2(core)) << core;
  }
  // The user's own choice stands, and the program's can be turned off.
  EXPECT_EQ(reported_blas_kernels("OPENBLAS_CORETYPE=Prescott "), "Prescott");
  if(avx2) {
    const std::string untouched = reported_blas_kernels("POINT_DETAIL_OPENBLAS_CORE=0 ");
    EXPECT_FALSE(untouched.empty());
    EXPECT_TRUE(untouched == core || point_detail::openblas_core_predates_avx2(untouched)) << untouched;
  }
}
