// The catalogue of bad inputs (doc/bad_input.md): one case per row, across the public functions and the
// program. Each row gets a clear error naming the problem, or the documented result; nothing crashes, hangs
// or writes a half file, and input files are never touched.
#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_mean_shift_modes.h>
#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/scale_geometric_details.h>
#include <CGAL_ext/upsample_point_set.h>

#include "las_test_file.h"
#include "program_run.h"
#include "test_support.h"

#include <CGAL/Point_set_3.h>

#include <boost/property_map/function_property_map.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <sstream>

namespace fs = std::filesystem;
using namespace CGAL_ext;
using Point_set = CGAL::Point_set_3<Point>;

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr double inf = std::numeric_limits<double>::infinity();

Point_set with_normals(const std::vector<Point>& points, const std::vector<Vector>& normals)
{
  Point_set set;
  set.add_normal_map();
  for(std::size_t i = 0; i < points.size(); ++i) set.insert(points[i], normals[i]);
  return set;
}

Point_set sphere(std::size_t n = 1500)
{
  const auto s = shapes::bumpy_sphere<Kernel>(n, 1.0, 0.02);
  return with_normals(s.points, s.normals);
}

/// A 30 x 30 grid of unit spacing in the plane z = 0, normals +z.
Point_set plane_grid()
{
  std::vector<Point> points;
  for(int i = 0; i < 30; ++i)
    for(int j = 0; j < 30; ++j) points.emplace_back(i, j, 0);
  return with_normals(points, std::vector<Vector>(points.size(), Vector(0, 0, 1)));
}

std::vector<std::size_t> indices_where(const Point_set& set, const std::function<bool(const Point&)>& keep)
{
  std::vector<std::size_t> out;
  for(std::size_t i = 0; i < set.size(); ++i)
    if(keep(set.point(Point_set::Index(i)))) out.push_back(i);
  return out;
}

#define EXPECT_INVALID_INPUT(call, needle)                                                                       \
  do {                                                                                                           \
    const std::string message_ = thrown_message<Invalid_input>([&] { call; });                                      \
    EXPECT_NE(message_.find(needle), std::string::npos) << "message: " << message_;                              \
  } while(false)

/// Details of a point set with the default filter (throws what the function throws).
void details_of(const Point_set& set, unsigned int k = 10)
{
  Point_set copy = set;
  auto detail = copy.add_property_map<Vector>("detail").first;
  compute_geometric_details(copy, k, Detail_filter{}, detail, copy.parameters());
}

/// Selects the bumpy sphere's top cap as region of interest and its tip as handle group 0.
void select_cap(Detail_preserving_deformation<>& d, const Point_set& set)
{
  d.insert_roi_points(indices_where(set, [](const Point& p) { return p.z() > 0.3; }));
  d.insert_handle_points(d.create_handle_group(), indices_where(set, [](const Point& p) { return p.z() > 0.9; }));
}

/// A folder for the program's rows; checks that a failing run leaves it as it found it.
class Workspace
{
public:
  Workspace() : m_dir(fs::temp_directory_path() / ("bad_input_" + std::to_string(std::random_device{}())))
  {
    fs::create_directories(m_dir);
  }
  ~Workspace() { fs::remove_all(m_dir); }

  std::string path(const std::string& name) const { return (m_dir / name).string(); }

  std::string write(const std::string& name, const std::string& bytes) const
  {
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
  }

  std::string sphere_ply(const std::string& name = "in.ply", std::size_t n = 400) const
  {
    const auto s = shapes::bumpy_sphere<Kernel>(n, 1.0, 0.02);
    std::ostringstream out;
    out << "ply\nformat ascii 1.0\nelement vertex " << n << "\nproperty double x\nproperty double y\nproperty double z\n"
        << "property double nx\nproperty double ny\nproperty double nz\nend_header\n";
    out.precision(17);
    for(std::size_t i = 0; i < n; ++i) out << s.points[i] << " " << s.normals[i] << "\n";
    return write(name, out.str());
  }

  /// Runs the program; it must fail with one line or two that contain `needle`, touch no file of the folder
  /// and leave no new one.
  void expect_failure(const std::string& arguments, const std::string& needle, const std::string& shell_prefix = "") const
  {
    const std::map<std::string, std::string> before = snapshot();
    const Program_run r = run(arguments, shell_prefix);
    EXPECT_EQ(r.exit_code, 1) << arguments << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << arguments << "\n" << r.output;
    EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 2) << r.output;
    EXPECT_EQ(snapshot(), before) << "a file of the folder was written, changed or left behind";
  }

private:
  std::map<std::string, std::string> snapshot() const
  {
    std::map<std::string, std::string> files;
    for(const auto& entry : fs::recursive_directory_iterator(m_dir)) {
      std::ifstream in(entry.path(), std::ios::binary);
      std::ostringstream bytes;
      bytes << in.rdbuf();
      files[entry.path().string()] = bytes.str();
    }
    return files;
  }

  fs::path m_dir;
};

[[maybe_unused]] std::string file_bytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

std::string binary_ply_header(std::size_t vertices)
{
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
}

std::string ascii_ply_header(std::size_t vertices)
{
  return "ply\nformat ascii 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
}

/// "x y z" lines; the x of row `bad` (if any) is replaced by `bad_token`.
std::string ascii_xyz(const std::vector<std::array<double, 3>>& points, std::size_t bad = std::size_t(-1),
                      const std::string& bad_token = "")
{
  std::string text;
  for(std::size_t i = 0; i < points.size(); ++i)
    text += (i == bad ? bad_token : std::to_string(points[i][0])) + " " + std::to_string(points[i][1]) + " " +
            std::to_string(points[i][2]) + "\n";
  return text;
}

std::string binary_xyz(const std::vector<std::array<double, 3>>& points)
{
  std::string bytes;
  for(const auto& p : points) bytes.append(reinterpret_cast<const char*>(p.data()), sizeof p);
  return bytes;
}

/// Points on a sphere as three doubles each.
std::vector<std::array<double, 3>> sphere_coordinates(std::size_t n)
{
  const auto s = shapes::bumpy_sphere<Kernel>(n, 1.0, 0.0);
  std::vector<std::array<double, 3>> out;
  for(const Point& p : s.points) out.push_back({p.x(), p.y(), p.z()});
  return out;
}

/// A PCD file of x y z floats: its header (POINTS, WIDTH 1 unless `header_lines` replaces the lines after TYPE)
/// and `data`.
std::string pcd_file(const std::string& kind, std::size_t points, const std::string& data,
                     const std::string& header_lines = "")
{
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n" +
         (header_lines.empty()
            ? "WIDTH " + std::to_string(points) + "\nHEIGHT 1\nPOINTS " + std::to_string(points) + "\n"
            : header_lines) +
         "DATA " + kind + "\n" + data;
}

std::string binary_xyz_floats(const std::vector<std::array<double, 3>>& points)
{
  std::string bytes;
  for(const auto& p : points)
    for(double c : p) {
      const float f = float(c);
      bytes.append(reinterpret_cast<const char*>(&f), sizeof f);
    }
  return bytes;
}

/// A LAS 1.`minor` file of point format `format` (records of `record_bytes`, 0 for the format's own size) holding
/// `points` at a scale of 0.001; only the coordinates are set.
std::string las_file(unsigned minor, unsigned format, const std::vector<std::array<double, 3>>& points,
                     std::uint16_t record_bytes = 0)
{
  std::string las = las_test_file::header(minor, format, points.size(), record_bytes);
  const std::size_t bytes = record_bytes == 0 ? std::size_t(point_detail::las_format_bytes(format)) : record_bytes;
  for(const auto& p : points) {
    std::string record(bytes, '\0');
    for(std::size_t axis = 0; axis < 3; ++axis) {
      const std::int32_t v = std::int32_t(std::lround(p[axis] / 0.001));
      std::memcpy(&record[4 * axis], &v, sizeof v);
    }
    las += record;
  }
  return las;
}

/// A PTX scan of the points, seen from the origin without transform.
std::string ptx_scan(const std::vector<std::array<double, 3>>& points,
                     const std::string& last_transform_row = "0 0 0 1")
{
  std::string text = "1\n" + std::to_string(points.size()) +
                     "\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n" + last_transform_row + "\n";
  for(const auto& p : points)
    text += std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + " 0.5\n";
  return text;
}

const char* const edit_json_sphere = R"({"handles": [{"select": ["sphere:0,0,1,0.3"], "translation": [0, 0, 0.2]}]})";

struct Row
{
  const char* id;
  std::function<void()> check;
};

const std::vector<Row>& catalogue()
{
  // Each row keeps its name and its lambda on one line, as the manual lists them.
  // clang-format off
  static const std::vector<Row> rows = {
    // ---- The public functions ----
    {"empty_input", [] { EXPECT_INVALID_INPUT(details_of(Point_set()), "empty"); }},
    {"one_point", [] {
       Point_set one = with_normals({Point(0, 0, 0)}, {Vector(0, 0, 1)});
       EXPECT_INVALID_INPUT(details_of(one), "k = 10");
       EXPECT_INVALID_INPUT(Detail_preserving_deformation<>(one, {}, one.parameters()), "at least two points");
     }},
    {"fewer_points_than_k", [] {
       Point_set few = sphere(8);
       EXPECT_INVALID_INPUT(details_of(few, 10), "k = 10");
       std::vector<double> H(few.size());
       EXPECT_INVALID_INPUT(estimate_mean_curvature(few, 12, CGAL::make_property_map(H), few.parameters()), "k = 12");
       // Editing: every point is its own sample point, fewer than the 10 neighbours of their Laplacian.
       Detail_preserving_deformation<> d(few, {}, few.parameters());
       d.insert_roi_points(indices_where(few, [](const Point&) { return true; }));
       d.insert_handle_point(d.create_handle_group(), 0);
       EXPECT_INVALID_INPUT(d.preprocess(), "sample_neighbors (10) must be less than the number of sample points (8)");
     }},
    {"nan_coordinate", [] {
       Point_set set = sphere();
       set.point(Point_set::Index(5)) = Point(nan, 0, 0);
       EXPECT_INVALID_INPUT(details_of(set), "point #5");
     }},
    {"inf_coordinate", [] {
       Point_set set = sphere();
       set.point(Point_set::Index(7)) = Point(0, inf, 0);
       std::vector<double> H(set.size());
       EXPECT_INVALID_INPUT(estimate_mean_curvature(set, 12, CGAL::make_property_map(H), set.parameters()), "point #7");
     }},
    {"exact_duplicates", [] {
       // Documented result: accepted. A copy is a separate point of the neighbour graph, so the copies' details
       // need not agree, but all are finite and of the same size as without the copies.
       const auto s = shapes::bumpy_sphere<Kernel>(1500, 1.0, 0.02);
       auto mean_magnitude = [](const std::vector<Point>& points, const std::vector<Vector>& normals) {
         Point_set set = with_normals(points, normals);
         auto detail = set.add_property_map<Vector>("detail").first;
         EXPECT_TRUE(compute_geometric_details(set, 10, Detail_filter{}, detail, set.parameters()));
         double sum = 0;
         for(auto i : set) {
           EXPECT_TRUE(std::isfinite(detail[i].squared_length()));
           sum += std::sqrt(detail[i].squared_length());
         }
         return sum / double(set.size());
       };
       std::vector<Point> points = s.points;
       std::vector<Vector> normals = s.normals;
       points.insert(points.end(), s.points.begin(), s.points.end());
       normals.insert(normals.end(), s.normals.begin(), s.normals.end());
       const double once = mean_magnitude(s.points, s.normals), twice = mean_magnitude(points, normals);
       EXPECT_GT(twice, 0.5 * once);
       EXPECT_LT(twice, 2.0 * once);
     }},
    {"collinear_points", [] {
       // No surface to fit: every function names the problem.
       std::vector<Point> line;
       for(int i = 0; i < 100; ++i) line.emplace_back(0.01 * i, 0, 0);
       Point_set set = with_normals(line, std::vector<Vector>(line.size(), Vector(0, 0, 1)));
       std::vector<double> H(set.size(), nan);
       EXPECT_INVALID_INPUT(estimate_mean_curvature(set, 12, CGAL::make_property_map(H), set.parameters()),
                            "100 points are collinear");
       EXPECT_INVALID_INPUT(details_of(set), "collinear");
     }},
    {"coplanar_curvature", [] {
       Point_set grid = plane_grid();
       for(Curvature_fitting fitting : {Curvature_fitting::monge_jet_fitting, Curvature_fitting::closed_form}) {
         std::vector<double> H(grid.size(), nan);
         ASSERT_TRUE(estimate_mean_curvature(grid, 12, fitting, CGAL::make_property_map(H), grid.parameters()));
         for(double h : H) ASSERT_LT(std::abs(h), 1e-9);
       }
     }},
    {"coplanar_mean_shift", [] {
       Point_set grid = plane_grid();
       auto modes = grid.add_property_map<Mean_shift_mode<Kernel>>("mode").first;
       ASSERT_TRUE(compute_mean_shift_modes(grid, default_mean_shift_neighbors, Mean_shift_settings(), modes,
                                            grid.parameters()).completed);
       for(auto i : grid) {
         ASSERT_LT(std::abs(modes[i].position.z()), 1e-9);
         ASSERT_LT(std::abs(modes[i].mean_curvature), 1e-9);
       }
     }},
    {"coplanar_simplification", [] {
       Point_set grid = plane_grid();
       std::vector<std::size_t> sample_of(grid.size());
       Simplification_settings settings;
       settings.max_cluster_size = 20;
       const auto samples = compute_simplification_sample_points(grid, settings, CGAL::make_property_map(sample_of),
                                                                 grid.parameters());
       ASSERT_TRUE(samples.completed);
       EXPECT_GE(samples.size(), grid.size() / 20);
       for(std::size_t s : sample_of) ASSERT_LT(s, samples.size());
     }},
    {"zero_normal", [] {
       Point_set set = sphere();
       set.normal(Point_set::Index(3)) = CGAL::NULL_VECTOR;
       EXPECT_INVALID_INPUT(details_of(set), "normal of point #3");
     }},
    {"missing_normals", [] {
       // Documented result: the functions that can estimate normals do; up-sampling needs them.
       const auto s = shapes::bumpy_sphere<Kernel>(1500, 1.0, 0.02);
       std::vector<std::pair<Point, Vector>> inserted;
       EXPECT_INVALID_INPUT(upsample_point_set(s.points, Upsampling_settings(), std::back_inserter(inserted)),
                            "need normals");
     }},
    {"lambda_not_positive", [] {
       EXPECT_INVALID_INPUT((Detail_filter{Detail_order::linear, 0.0, 1.6}.validate()), "lambda");
       EXPECT_INVALID_INPUT((Detail_filter{Detail_order::quadric, -1.0, 1.6}.validate()), "lambda");
     }},
    {"mu_not_above_lambda", [] {
       EXPECT_INVALID_INPUT((Detail_filter{Detail_order::cubic, 0.8, 0.8}.validate()), "mu");
     }},
    {"scale_factor_not_finite", [] {
       Point_set set = sphere();
       const auto roi = indices_where(set, [](const Point& p) { return p.z() > 0; });
       EXPECT_INVALID_INPUT(scale_geometric_details(set, 10, roi, nan, Detail_scaling_settings(), set.parameters()),
                            "s must be finite");
       EXPECT_INVALID_INPUT(scale_geometric_details(set, 10, roi, inf, Detail_scaling_settings(), set.parameters()),
                            "s must be finite");
     }},
    {"empty_roi", [] {
       Point_set set = sphere();
       EXPECT_INVALID_INPUT(scale_geometric_details(set, 10, std::vector<std::size_t>(), 2.0, Detail_scaling_settings(),
                                                    set.parameters()),
                            "region of interest is empty");
       Detail_preserving_deformation<> d(set, {}, set.parameters());
       d.create_handle_group();
       EXPECT_INVALID_INPUT(d.preprocess(), "region of interest is empty");
     }},
    {"whole_model_scaling_without_anchors", [] {
       Point_set set = sphere();
       std::vector<std::size_t> all(set.size());
       std::iota(all.begin(), all.end(), 0);
       EXPECT_INVALID_INPUT(scale_geometric_details(set, 10, all, 2.0, Detail_scaling_settings(), set.parameters()),
                            "whole model and no anchors");
     }},
    {"anchor_outside_roi", [] {
       Point_set set = sphere();
       const auto roi = indices_where(set, [](const Point& p) { return p.z() > 0; });
       const auto anchors = indices_where(set, [](const Point& p) { return p.z() < -0.9; });
       EXPECT_INVALID_INPUT(scale_geometric_details(set, 10, roi, anchors, 2.0, Detail_scaling_settings(),
                                                    set.parameters()),
                            "is not in the region");
     }},
    {"index_out_of_range", [] {
       Point_set set = sphere();
       EXPECT_INVALID_INPUT(scale_geometric_details(set, 10, std::vector<std::size_t>{0, set.size()}, 2.0,
                                                    Detail_scaling_settings(), set.parameters()),
                            "index 1500 is not a point index");
       Detail_preserving_deformation<> d(set, {}, set.parameters());
       EXPECT_INVALID_INPUT(d.insert_roi_point(set.size() + 3), "out of range");
     }},
    {"handle_outside_roi", [] {
       Point_set set = sphere();
       Detail_preserving_deformation<> d(set, {}, set.parameters());
       select_cap(d, set);
       d.insert_handle_points(0, indices_where(set, [](const Point& p) { return p.z() < -0.95; }));
       EXPECT_INVALID_INPUT(d.preprocess(), "handle point #");
     }},
    {"overlapping_handle_groups", [] {
       Point_set set = sphere();
       Detail_preserving_deformation<> d(set, {}, set.parameters());
       select_cap(d, set);
       const std::size_t second = d.create_handle_group();
       EXPECT_INVALID_INPUT(d.insert_handle_points(second, indices_where(set, [](const Point& p) { return p.z() > 0.95; })),
                            "handle groups must not overlap");
       d.insert_handle_points(0, indices_where(set, [](const Point& p) { return p.z() > 0.95; })); // same group: fine
     }},
    {"non_rigid_handle_matrix", [] {
       Point_set set = sphere();
       Detail_preserving_deformation<> d(set, {}, set.parameters());
       select_cap(d, set);
       EXPECT_INVALID_INPUT(d.set_handle_transform(0, Eigen::Matrix3d(2 * Eigen::Matrix3d::Identity()), Eigen::Vector3d::Zero()),
                            "is not a rotation");
       EXPECT_INVALID_INPUT(d.set_handle_transform(0, Eigen::Matrix3d(Eigen::Vector3d(1, 1, -1).asDiagonal()),
                                                   Eigen::Vector3d::Zero()),
                            "is not a rotation"); // a mirror
       EXPECT_INVALID_INPUT(d.set_handle_transform(0, Eigen::Quaterniond(2, 0, 0, 0), Eigen::Vector3d::Zero()),
                            "unit quaternion");
       EXPECT_INVALID_INPUT(d.set_handle_transform(0, Eigen::Matrix3d::Identity(), Eigen::Vector3d(nan, 0, 0)),
                            "not finite");
     }},
    {"cancelled_callback", [] {
       // Documented result: false, nothing changed, and the object can run again.
       Point_set set = sphere();
       Detail_preserving_deformation<> d(set, {}, set.parameters().callback(std::function<bool(double)>([](double) { return false; })));
       select_cap(d, set);
       EXPECT_FALSE(d.preprocess());
       EXPECT_FALSE(d.deform());
       EXPECT_INVALID_INPUT(d.diffuse(), "needs preprocess() or deform() first");

       Point_set smoothed = set;
       EXPECT_FALSE(balanced_flow_smooth_point_set(
         smoothed, 10, Balanced_flow_settings(),
         smoothed.parameters().callback(std::function<bool(double)>([](double f) { return f < 0.3; }))));
       for(std::size_t i = 0; i < set.size(); ++i)
         ASSERT_EQ(smoothed.point(Point_set::Index(i)), set.point(Point_set::Index(i))) << i;
     }},
    {"spacing_not_positive", [] {
       Point_set set = sphere();
       Upsampling_settings settings;
       settings.detection.spacing = -1;
       std::vector<std::pair<Point, Vector>> inserted;
       EXPECT_INVALID_INPUT(upsample_point_set(set, settings, std::back_inserter(inserted), set.parameters()), "spacing");
       // A spacing map (the spacings before an edit) with a value that is not a positive number.
       std::vector<double> before(set.size(), 0.01);
       before[3] = 0;
       std::vector<std::size_t> all(set.size());
       std::iota(all.begin(), all.end(), std::size_t(0));
       EXPECT_INVALID_INPUT(upsample_point_set(set, all, boost::make_function_property_map<Point_set::Index, double>(
                                                            [&](Point_set::Index i) { return before[std::size_t(i)]; }),
                                               Upsampling_settings(), std::back_inserter(inserted), set.parameters()),
                            "the spacing of point 3 is not a positive number");
     }},
    {"diffuse_into_another_point_set", [] {
       Point_set set = sphere();
       Detail_preserving_deformation<> d(set, {}, set.parameters());
       select_cap(d, set);
       ASSERT_TRUE(d.deform());
       Point_set other = sphere(1000);
       EXPECT_INVALID_INPUT(d.diffuse(other, other.parameters()), "was given 1000 points");
     }},
    {"restore_details_before_diffuse", [] {
       Point_set set = sphere();
       Detail_preserving_deformation<> d(set, {}, set.parameters());
       select_cap(d, set);
       ASSERT_TRUE(d.deform());
       EXPECT_INVALID_INPUT(d.restore_details(), "call diffuse() first");
       d.diffuse();
       Point_set other = sphere(1000);
       EXPECT_INVALID_INPUT(d.restore_details(other, other.parameters()), "was given 1000 points");
     }},

    // ---- The program ----
    {"cli_empty_file", [] {
       Workspace w;
       w.expect_failure("details -i " + w.write("empty.xyz", "") + " -o " + w.path("o.ply"), "no points");
     }},
    {"cli_fewer_points_than_k", [] {
       Workspace w;
       w.expect_failure("details -i " + w.write("one.xyz", "0 0 0 0 0 1\n") + " -o " + w.path("o.ply"), "needs more than k points");
     }},
    {"cli_nan_in_file", [] {
       Workspace w;
       w.expect_failure("details -i " + w.write("nan.xyz", "0 0 0\n1 0 0\nnan 1 0\n0 1 1\n") + " -o " + w.path("o.ply"), "nan.xyz");
     }},
    {"cli_ply_truncated_binary", [] {
       Workspace w;
       const std::string in = w.write("cut.ply", binary_ply_header(1000) + binary_xyz(sphere_coordinates(1000)).substr(0, 5000));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "truncated");
     }},
    {"cli_ply_truncated_ascii", [] {
       Workspace w;
       const std::string in = w.write("cut.ply", ascii_ply_header(400) + ascii_xyz(sphere_coordinates(300)));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "truncated");
     }},
    {"cli_ply_corrupted_binary", [] {
       // A whole file whose coordinates decode to NaN at point 17.
       Workspace w;
       auto points = sphere_coordinates(400);
       points[17][1] = nan;
       w.expect_failure("details -i " + w.write("nan.ply", binary_ply_header(400) + binary_xyz(points)) + " -o " + w.path("o.ply"),
                        "point #17");
     }},
    {"cli_ply_corrupted_ascii", [] {
       Workspace w;
       const std::string in = w.write("bad.ply", ascii_ply_header(300) + ascii_xyz(sphere_coordinates(300), 42, "1.0e+x"));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "bad.ply");
     }},
    {"cli_ply_corrupted_header", [] {
       Workspace w;
       const std::string in = w.write("bad.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty quadruple x\n"
                                                 "end_header\n" + std::string(100, '\x7f'));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "line 4: unknown property type 'quadruple'");
     }},
    {"cli_ply_property_twice_as_list", [] {
       Workspace w;
       const std::string in = w.write("twin.ply", ascii_ply_header(3).substr(0, ascii_ply_header(3).size() - 11) +
                                                  "property uchar blue\nproperty list uchar int blue\nend_header\n" +
                                                  "0 0 0 1 0\n1 0 0 1 0\n0 1 0 1 0\n");
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "property 'blue' appears twice");
     }},
    {"cli_ply_normals_as_lists", [] {
       Workspace w;
       const std::string in = w.write("lists.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                                                   "property double y\nproperty double z\nproperty list uchar double nx\n"
                                                   "property list uchar double ny\nproperty list uchar double nz\nend_header\n"
                                                   "0 0 0 1 0 1 0 1 1\n1 0 0 1 0 1 0 1 1\n0 1 0 1 0 1 0 1 1\n");
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"),
                        "the normals need nx, ny and nz properties, all float or all double");
     }},
    {"cli_ply_list_longer_than_the_file", [] {
       Workspace w;
       std::string face(1, char(200)); // a triangle announced with 200 indices, followed by 3
       for(std::int32_t v : {0, 1, 2}) face.append(reinterpret_cast<const char*>(&v), sizeof v);
       const std::string in = w.write("long.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 400\nproperty double x\n"
                                                  "property double y\nproperty double z\nelement face 1\n"
                                                  "property list uchar int vertex_indices\nend_header\n" +
                                                  binary_xyz(sphere_coordinates(400)) + face);
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"),
                        "element 'face' item 0: a list of 200 values, more than the file holds");
     }},
    {"cli_ply_ascii_value_that_does_not_read", [] {
       Workspace w;
       const std::string in = w.write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                                                 "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                                 "end_header\n0 0 0\n1 0 0\n0 1 0.5.1\n3 0 1 2\n");
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "element 'vertex' item 2: '0.5.1' is not a double");
     }},
    {"cli_off_bad_counts", [] {
       Workspace w;
       const std::string in = w.write("bad.off", "OFF\n500 0 0\n" + ascii_xyz(sphere_coordinates(300)));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "announces 500 points");
     }},
    {"cli_file_too_large", [] {
       // The header asks for more memory than any machine here has: refused before reading.
       Workspace w;
       const std::string in = w.write("huge.ply", binary_ply_header(100000000000ull) + binary_xyz(sphere_coordinates(10)));
       w.expect_failure("edit -i " + in + " -o " + w.path("o.ply") + " --edit " + w.write("e.json", edit_json_sphere), "of memory");
     }},
    {"cli_off_too_large", [] {
       Workspace w;
       const std::string in = w.write("huge.off", "OFF\n100000000000 0 0\n" + ascii_xyz(sphere_coordinates(10)));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "of memory");
     }},
    {"cli_out_of_memory", [] {
       // Under an address-space limit (ulimit -v, as batch systems impose) a run of each solver-backed subcommand
       // either writes what it writes without one, byte for byte, or fails with one line naming the shortage,
       // exit status 3 and no output, within seconds: never stuck (OpenBLAS retries a failed allocation of its
       // buffers forever, so a factorisation must not start where they would not fit).
#if TEST_WITH_ADDRESS_SANITIZER
       GTEST_SKIP() << "AddressSanitizer reserves more address space than these limits allow";
#else
       // Three quarters of a 30,000-point sphere, cubic order: its factorisation peaks near 540 MB.
       Workspace w;
       const std::string in = w.sphere_ply("in.ply", 30000);
       const std::string edit = w.write("e.json", R"({"roi": ["box:-2,-2,-0.5,2,2,2"],
                                                      "handles": [{"select": ["sphere:0,0,1,0.3"], "translation": [0, 0, 0.2]}]})");
       const std::string region = " --order cubic --roi box:-2,-2,-2,2,2,0.5 -i " + in;
       for(const std::string& command : {"enhance -s 2" + region, "scale -s 0" + region, "edit --edit " + edit + " -i " + in}) {
         const std::string unlimited = w.path("unlimited.ply");
         const Program_run free_run = run(command + " -o " + unlimited);
         ASSERT_EQ(free_run.exit_code, 0) << command << "\n" << free_run.output;
         int failures = 0, successes = 0;
         // Steps of 150 MB through the range where the factorisation stops fitting, then room to spare (how much
         // address space the process holds when it checks varies with its threads' malloc arenas).
         for(int megabytes = 250; megabytes <= 2000; megabytes += megabytes < 1000 ? 150 : 1000) {
           const std::string out = w.path("limited.ply");
           const Program_run r = run(command + " -o " + out, "ulimit -v " + std::to_string(megabytes * 1024) + "; timeout 60 ");
           const std::string at = command.substr(0, command.find(' ')) + " at " + std::to_string(megabytes) + " MB";
           if(r.exit_code == 0) {
             EXPECT_EQ(file_bytes(out), file_bytes(unlimited)) << at << ": a different result";
             fs::remove(out);
             ++successes;
             continue;
           }
           ++failures;
           EXPECT_EQ(r.exit_code, 3) << at << (r.exit_code == 124 ? ": stuck for a minute" : "") << "\n" << r.output;
           EXPECT_EQ(r.output.find("point-detail: error: "), 0u) << at << "\n" << r.output;
           EXPECT_NE(r.output.find("out of memory"), std::string::npos) << at << "\n" << r.output;
           EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
           EXPECT_FALSE(fs::exists(out)) << at;
         }
         EXPECT_GT(failures, 0) << command << ": no limit was low enough to make the run fail";
         EXPECT_GT(successes, 0) << command << ": no limit was high enough for the run to succeed";
         fs::remove(unlimited);
       }
#endif
     }},
    {"cli_json_wrong_type", [] {
       Workspace w;
       const std::string in = w.sphere_ply();
       const std::string json = w.write("e.json", R"({"handles": [{"select": ["sphere:0,0,1,0.3"], "translation": "up"}]})");
       w.expect_failure("edit -i " + in + " -o " + w.path("o.ply") + " --edit " + json, "translation");
     }},
    {"cli_json_missing_field", [] {
       Workspace w;
       const std::string in = w.sphere_ply();
       const std::string json = w.write("e.json", R"({"handles": [{"translation": [0, 0, 1]}]})");
       w.expect_failure("edit -i " + in + " -o " + w.path("o.ply") + " --edit " + json, "select");
     }},
    {"cli_json_overlapping_handles", [] {
       Workspace w;
       const std::string in = w.sphere_ply();
       const std::string json = w.write("e.json", R"({"handles": [{"select": ["sphere:0,0,1,0.4"], "translation": [0, 0, 1]},
                                                                  {"select": ["sphere:0,0,1,0.2"], "translation": [0, 1, 0]}]})");
       w.expect_failure("edit -i " + in + " -o " + w.path("o.ply") + " --edit " + json, "must not overlap");
     }},
    {"cli_json_chain_bad_step", [] {
       Workspace w;
       const std::string in = w.sphere_ply();
       const std::string edit = R"({"type": "edit", "handles": [{"select": ["sphere:0,0,1,0.3"], "translation": [0, 0, 0.2]}]})";
       const std::string run = "edit -i " + in + " -o " + w.path("o.ply") + " --edit ";
       w.expect_failure(run + w.write("a.json", R"({"steps": [{"type": "fill"}, )" + edit + "]}"),
                        "a.json: steps[0]: a fill step fills what the edit step just before it stretched");
       w.expect_failure(run + w.write("b.json", R"({"steps": [)" + edit + R"(, {"type": "twist"}]})"),
                        "b.json: steps[1]: unknown type 'twist'");
       w.expect_failure(run + w.write("c.json", R"({"steps": [)" + edit + R"(, {"type": "scale", "roi": ["box:0,0,0,1,1,1"]}]})"),
                        "c.json: steps[1] needs s");
       w.expect_failure(run + w.write("d.json", R"({"steps": [)" + edit + R"(, {"type": "scale", "s": 2, "rio": []}]})"),
                        "d.json: steps[1]: unknown key 'rio'");
       w.expect_failure(run + w.write("e.json", R"({"steps": []})"), "e.json: steps must be a non-empty array");
       // A selection is checked on the points its step starts from: here the second edit's handle selects nothing.
       w.expect_failure(run + w.write("f.json", R"({"steps": [)" + edit +
                                                  R"(, {"type": "edit", "handles": [{"select": ["sphere:9,9,9,0.1"]}]}]})"),
                        "f.json: steps[1]: handles[0].select selects no point");
     }},
    {"cli_sel_too_few_lines", [] {
       Workspace w;
       const std::string in = w.sphere_ply();
       w.expect_failure("edit -i " + in + " -o " + w.path("o.ply") + " --sel " + w.write("s.sel", "0\n1\n2\n") + " --def " +
                          w.write("d.def", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"),
                        "has 3 status lines but the model has 400 points");
     }},
    {"cli_def_not_4x4", [] {
       Workspace w;
       const std::string in = w.sphere_ply();
       std::string sel;
       for(int i = 0; i < 400; ++i) sel += i < 10 ? "2\n" : "1\n";
       w.expect_failure("edit -i " + in + " -o " + w.path("o.ply") + " --sel " + w.write("s.sel", sel) + " --def " +
                          w.write("d.def", "1 0 0\n0 1 0\n0 0 1\n"),
                        "holds 9 numbers");
     }},
    {"cli_pcd_truncated_binary", [] {
       Workspace w;
       const std::string in = w.write("cut.pcd", pcd_file("binary", 400, binary_xyz_floats(sphere_coordinates(100))));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "truncated pcd file (the header announces 400 points");
     }},
    {"cli_pcd_corrupted_compressed", [] {
       // Sizes that fit the file, LZF data that do not decompress to them.
       Workspace w;
       std::string data;
       for(std::uint32_t v : {64u, 400u * 12u}) data.append(reinterpret_cast<const char*>(&v), sizeof v);
       data += std::string(64, '\xe0');
       const std::string in = w.write("bad.pcd", pcd_file("binary_compressed", 400, data));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "corrupted pcd file");
     }},
    {"cli_pcd_malformed_header", [] {
       Workspace w;
       const std::string run = "details -o " + w.path("o.ply") + " -i ", points = ascii_xyz(sphere_coordinates(400));
       w.expect_failure(run + w.write("a.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nPOINTS 400\nDATA ascii\n" + points),
                        "FIELDS, SIZE, TYPE and COUNT name 3, 2, 3 and 0 fields");
       w.expect_failure(run + w.write("b.pcd", "FIELDS x y intensity\nSIZE 4 4 4\nTYPE F F F\nPOINTS 400\nDATA ascii\n" + points),
                        "the fields need x, y and z");
       w.expect_failure(run + w.write("c.pcd", pcd_file("ascii", 400, points, "WIDTH 20\nHEIGHT 10\nPOINTS 400\n")),
                        "POINTS 400 is not WIDTH x HEIGHT (20 x 10)");
       w.expect_failure(run + w.write("d.pcd", pcd_file("lzma", 400, points)), "DATA is ascii, binary or binary_compressed");
     }},
    {"cli_pcd_ascii_wrong_value_count", [] {
       Workspace w;
       std::string points = ascii_xyz(sphere_coordinates(400));
       points.insert(points.find('\n', 100) + 1, "0.5 0.5\n");
       const std::string in = w.write("bad.pcd", pcd_file("ascii", 401, points));
       w.expect_failure("details -i " + in + " -o " + w.path("o.ply"), "has 2 values, the fields need 3");
     }},
    {"cli_pcd_points_without_position", [] {
       // An organised cloud's missing measurements (x y z all NaN) are left out, with a note; a point with one NaN
       // coordinate is an error of the library, naming it.
       Workspace w;
       auto points = sphere_coordinates(400);
       for(std::size_t i = 0; i < 400; i += 40) points[i] = {nan, nan, nan};
       const std::string header = "WIDTH 20\nHEIGHT 20\nPOINTS 400\n";
       const Program_run r = run("details -i " + w.write("holes.pcd", pcd_file("binary", 400, binary_xyz_floats(points), header)) +
                                 " -o " + w.path("o.ply"));
       EXPECT_EQ(r.exit_code, 0) << r.output;
       EXPECT_NE(r.output.find("10 points of"), std::string::npos) << r.output;
       EXPECT_NE(file_bytes(w.path("o.ply")).find("element vertex 390\n"), std::string::npos);
       points[0] = {0.0, nan, 1.0};
       w.expect_failure("details -i " + w.write("nan.pcd", pcd_file("binary", 400, binary_xyz_floats(points), header)) + " -o " +
                          w.path("p.ply"),
                        "non-finite coordinate");
     }},
    {"cli_pts_malformed", [] {
       Workspace w;
       const std::string run = "details -o " + w.path("o.ply") + " -i ", points = ascii_xyz(sphere_coordinates(300));
       w.expect_failure(run + w.write("cut.pts", "400\n" + points), "truncated pts file (a block announces 400 points, 300 follow)");
       w.expect_failure(run + w.write("mixed.pts", "301\n" + points + "1 2 3 4\n"), "cannot read " + w.path("mixed.pts") + ":302: this line has 4 values, the file's first point 3");
       w.expect_failure(run + w.write("huge.pts", "1000000000\n" + points), "announces 1000000000 points, more than its");
       w.expect_failure(run + w.write("word.pts", "300\n" + points.substr(0, 40) + "x" + points.substr(40)), "is not a number");
     }},
    {"cli_ptx_malformed", [] {
       Workspace w;
       const std::string run = "details -o " + w.path("o.ply") + " -i ";
       const std::string scan = ptx_scan(sphere_coordinates(300));
       w.expect_failure(run + w.write("cut.ptx", scan.substr(0, scan.rfind('\n', scan.size() / 2) + 1)), "truncated ptx file (scan 1 announces 300 points");
       w.expect_failure(run + w.write("bent.ptx", ptx_scan(sphere_coordinates(300), "0 0 0 2")), "the transform is not an affine map");
       w.expect_failure(run + w.write("short.ptx", "1\n2\n0 0 0\n1 0 0\n"), "the scan's header ends before a scanner axis");
     }},
    {"cli_las_compressed", [] {
       // LAZ, by its extension or by the bit LASzip sets in the point format, gets the way to decompress it.
       Workspace w;
       const std::string run = "details -o " + w.path("o.ply") + " -i ";
       std::string las = las_file(2, 0, sphere_coordinates(400));
       w.expect_failure(run + w.write("scan.laz", las), "decompress it first, e.g. `laszip -i scan.laz -o scan.las`");
       las[104] = char(0x80 | 3);
       w.expect_failure(run + w.write("scan.las", las), "LAZ (compressed LAS) is not read");
     }},
    {"cli_las_truncated", [] {
       Workspace w;
       const std::string las = las_file(4, 7, sphere_coordinates(400));
       w.expect_failure("details -i " + w.write("cut.las", las.substr(0, las.size() - 100)) + " -o " + w.path("o.ply"),
                        "truncated las file (the header announces 400 points of 36 bytes");
       w.expect_failure("details -i " + w.write("head.las", las.substr(0, 200)) + " -o " + w.path("o.ply"),
                        "the header alone needs 227");
     }},
    {"cli_las_inconsistent_header", [] {
       Workspace w;
       const std::string run = "details -o " + w.path("o.ply") + " -i ";
       const auto points = sphere_coordinates(400);
       w.expect_failure(run + w.write("a.las", las_file(2, 6, points)), "point format 6 needs LAS 1.4, the file says 1.2");
       w.expect_failure(run + w.write("b.las", las_file(2, 3, points, 30)), "records of 30 bytes; point format 3 needs at least 34");
       std::string zero_scale = las_file(3, 1, points);
       std::memset(&zero_scale[139], 0, 8);
       w.expect_failure(run + w.write("c.las", zero_scale), "the scale not zero");
       w.expect_failure(run + w.write("d.las", "LASX" + las_file(2, 0, points).substr(4)), "not a LAS file");
       std::string version = las_file(2, 0, points);
       version[25] = 5;
       w.expect_failure(run + w.write("e.las", version), "LAS version 1.5 (1.0 to 1.4 are read)");
     }},
    {"cli_output_is_input", [] {
       Workspace w;
       const std::string in = w.sphere_ply();
       w.expect_failure("details -i " + in + " -o " + in, "is the input file");
     }},
    {"cli_output_directory_missing", [] {
       Workspace w;
       w.expect_failure("details -i " + w.sphere_ply() + " -o " + w.path("no/such/o.ply"), "does not exist");
     }},
    {"cli_output_over_the_file_size_limit", [] {
       // Under ulimit -f (1 KiB blocks), the nearest thing to a full disk: each subcommand's output is larger than
       // 4 KiB, and every one fails with one line naming the file, exit status 1 and no file, not even a temporary.
       Workspace w;
       const std::string in = w.sphere_ply(), out = " -o " + w.path("o.ply");
       for(const std::string& command : {"details -i " + in + out, "curvature -i " + in + out, "scale -s 2 --roi box:-2,-2,0,2,2,2 -i " + in + out,
                                         "enhance -s 2 -i " + in + out, "simplify --target 40 -i " + in + out,
                                         "edit --edit " + w.write("e.json", edit_json_sphere) + " -i " + in + out,
                                         "render -i " + in + " -o " + w.path("o.png")})
         w.expect_failure(command, "File too large", "ulimit -f 4; ");
     }},
    {"cli_output_directory_unwritable", [] {
       // /proc takes no new files, not even from root (CI runs as root, for whom permission bits do not count).
       Workspace w;
       w.expect_failure("details -i " + w.sphere_ply() + " -o /proc/point-detail-out.ply", "is not writable");
       w.expect_failure("details -i " + w.sphere_ply() + " -o " + w.sphere_ply() + "/o.ply", "is not a directory");
     }},
  };
  // clang-format on
  return rows;
}

class BadInput : public ::testing::TestWithParam<std::size_t>
{};

} // namespace

TEST_P(BadInput, GetsAClearErrorOrTheDocumentedResult) { catalogue()[GetParam()].check(); }

INSTANTIATE_TEST_SUITE_P(Catalogue, BadInput, ::testing::Range<std::size_t>(0, catalogue().size()),
                         [](const ::testing::TestParamInfo<std::size_t>& info) { return std::string(catalogue()[info.param].id); });

TEST(BadInputCatalogue, HasAtLeast30RowsAndEveryRowIsListedInTheManual)
{
  EXPECT_GE(catalogue().size(), 30u);
  std::ifstream in(BAD_INPUT_DOC);
  ASSERT_TRUE(in) << BAD_INPUT_DOC;
  std::ostringstream doc;
  doc << in.rdbuf();
  for(const Row& row : catalogue())
    EXPECT_NE(doc.str().find("`" + std::string(row.id) + "`"), std::string::npos) << row.id << " is not in " << BAD_INPUT_DOC;
}
