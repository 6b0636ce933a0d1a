#include <CGAL_ext/compute_mean_shift_modes.h>
#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/generated_shapes.h>

#include "test_support.h"

#include <CGAL/Point_set_3.h>
#include <CGAL/property_map.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>

using namespace CGAL_ext;

namespace {
using Mode = Mean_shift_mode<Kernel>;

struct Outcome
{
  std::vector<Mode> modes;
  Mean_shift_result result;
};

template <typename Tag = CGAL::Parallel_if_available_tag>
Outcome modes_of(const shapes::Oriented_sample<Kernel>& s, const Mean_shift_settings& settings = {},
             unsigned k = default_mean_shift_neighbors)
{
  std::vector<std::size_t> idx(s.points.size());
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  Outcome run;
  run.modes.resize(s.points.size());
  run.result = compute_mean_shift_modes<Tag>(idx, k, settings, CGAL::make_property_map(run.modes),
                                             CGAL::parameters::point_map(CGAL::make_property_map(s.points))
                                               .normal_map(CGAL::make_property_map(s.normals)));
  return run;
}

} // namespace

TEST(MeanShift, CubeModesStayOnTheirFace)
{
  for(Mean_shift_kernel kernel : {Mean_shift_kernel::gaussian, Mean_shift_kernel::epanechnikov}) {
    const auto cube = shapes::cube<Kernel>(30);
    Mean_shift_settings settings;
    settings.kernel = kernel;
    const Outcome run = modes_of(cube, settings);
    ASSERT_TRUE(run.result.completed);
    std::size_t wrong_face = 0, off_plane = 0;
    for(std::size_t i = 0; i < cube.points.size(); ++i) {
      const int face = face_of(cube.normals[i]);
      if(face_of(run.modes[i].normal) != face) ++wrong_face;
      // The mode's position stays in its face's plane (within a tenth of the spacing) ...
      const int axis = face / 2;
      if(std::abs(std::abs(run.modes[i].position[axis]) - 0.5) > 0.1 * cube.average_spacing) ++off_plane;
      // ... and its normal part stays close to the face normal: the range kernel keeps other faces out.
      EXPECT_GT(run.modes[i].normal * cube.normals[i], 0.9) << i;
    }
    EXPECT_EQ(wrong_face, 0u);
    EXPECT_LE(double(off_plane), 0.01 * double(cube.points.size()));
    EXPECT_GT(run.result.mean_iterations, 1.0);
    EXPECT_LE(run.result.max_iterations, settings.max_iterations);
  }
}

// Against a brute-force mean shift: with k = n - 1 every sample is a candidate of every mode, so the modes
// are those of the textbook joint spatial-range mean shift over all samples, with the features
// (x / h_s, n / h_r, c H / h_r), H the closed-form curvature on the same neighbours and the scales the run
// reports. Each mode is also a fixed point: one more step over all samples moves it by less than 1e-9.
// (Break tried: a range kernel of exp(-dr2) instead of exp(-dr2 / 2) misses by 3.4 bandwidths.)
TEST(MeanShift, ModesAreFixedPointsOfABruteForceMeanShift)
{
  const auto s = shapes::bumpy_sphere<Kernel>(150, 1.0, 0.08, 2.0);
  const std::size_t n = s.points.size();
  const unsigned k = unsigned(n - 1);
  Mean_shift_settings settings;
  settings.tolerance = 1e-12;
  settings.max_iterations = 2000;
  const Outcome run = modes_of(s, settings, k);
  ASSERT_TRUE(run.result);
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  std::vector<double> H(n);
  ASSERT_TRUE(estimate_mean_curvature(idx, k, Curvature_fitting::closed_form, CGAL::make_property_map(H),
                                      CGAL::parameters::point_map(CGAL::make_property_map(s.points))
                                        .normal_map(CGAL::make_property_map(s.normals))));
  const double hs = run.result.spatial_bandwidth, hr = run.result.range_bandwidth, c = run.result.curvature_scale;
  using Row = Eigen::Matrix<double, 1, 7>;
  std::vector<Row> features(n);
  for(std::size_t i = 0; i < n; ++i)
    features[i] << s.points[i].x() / hs, s.points[i].y() / hs, s.points[i].z() / hs, s.normals[i].x() / hr,
      s.normals[i].y() / hr, s.normals[i].z() / hr, c * H[i] / hr;
  // Plain loops over the coefficients: the sanitized pass compiles the tests without optimisation, where
  // Eigen's expressions would take most of this test's time.
  auto step = [&](const Row& mode) {
    double sum[7] = {0, 0, 0, 0, 0, 0, 0}, weights = 0;
    const double* m = mode.data();
    for(const Row& feature : features) {
      const double* q = feature.data();
      double d2 = 0;
      for(int j = 0; j < 7; ++j) d2 += (m[j] - q[j]) * (m[j] - q[j]);
      const double w = std::exp(-0.5 * d2);
      for(int j = 0; j < 7; ++j) sum[j] += w * q[j];
      weights += w;
    }
    Row next;
    for(int j = 0; j < 7; ++j) next(j) = sum[j] / weights;
    return next;
  };
  double worst_match = 0, worst_shift = 0;
  for(std::size_t i = 0; i < n; ++i) {
    Row reference = features[i];
    for(int it = 0; it < 2000; ++it) {
      const Row next = step(reference);
      const double moved = (next - reference).norm();
      reference = next;
      if(moved < 1e-13) break;
    }
    const Mode& m = run.modes[i];
    Row mode;
    mode << m.position.x() / hs, m.position.y() / hs, m.position.z() / hs, m.normal.x() / hr, m.normal.y() / hr,
      m.normal.z() / hr, c * m.mean_curvature / hr;
    worst_match = std::max(worst_match, (mode - reference).norm());
    worst_shift = std::max(worst_shift, (step(mode) - mode).norm());
  }
  std::printf("mean shift on %zu points: modes within %.2g bandwidths of the brute-force ones, one more step moves "
              "them by at most %.2g\n", n, worst_match, worst_shift);
  EXPECT_LT(worst_match, 1e-6);
  EXPECT_LT(worst_shift, 1e-9);
}

TEST(MeanShift, AutomaticScalesFollowTheSpacingAndCurvature)
{
  // A sphere of radius 2 has H = 1/2 everywhere: the curvature scale is 0.5 / H90 = 1, and the spatial
  // bandwidth is the mean distance to the 15 nearest neighbours, between one and three spacings.
  const auto sphere = shapes::bumpy_sphere<Kernel>(5000, 2.0, 0.0);
  const Outcome run = modes_of(sphere);
  EXPECT_NEAR(run.result.curvature_scale, 1.0, 0.05);
  EXPECT_GT(run.result.spatial_bandwidth, sphere.average_spacing);
  EXPECT_LT(run.result.spatial_bandwidth, 3 * sphere.average_spacing);
  EXPECT_EQ(run.result.range_bandwidth, 0.5);
  // The modes of a uniform sphere stay near it and keep H = 1/2.
  for(std::size_t i = 0; i < sphere.points.size(); i += 37) {
    EXPECT_NEAR(std::sqrt((run.modes[i].position - CGAL::ORIGIN).squared_length()), 2.0, 0.05);
    EXPECT_NEAR(run.modes[i].mean_curvature, 0.5, 0.03);
  }
}

TEST(MeanShift, GivenBandwidthsAreUsedAndAStepCapIsHonoured)
{
  const auto grid = shapes::bumpy_grid<Kernel>(40, 40, 1.0, 0.5, 8.0);
  Mean_shift_settings settings;
  settings.spatial_bandwidth = 1.7;
  settings.curvature_scale = 3.0;
  settings.max_iterations = 1;
  const Outcome run = modes_of(grid, settings);
  EXPECT_EQ(run.result.spatial_bandwidth, 1.7);
  EXPECT_EQ(run.result.curvature_scale, 3.0);
  EXPECT_EQ(run.result.max_iterations, 1u);
  for(const Mode& m : run.modes) EXPECT_EQ(m.iterations, 1u);
}

// The range-part stop follows the same steps and ends at or before the whole mode's: a point that stops at
// the same step has the same mode, bit for bit. On a cube's flat faces the range part settles at once while
// the position drifts on, so it takes far fewer steps there; its modes stay on their faces. On a bumpy
// sphere its range parts lie about as near those of a converged run as the whole mode's do.
TEST(MeanShift, TheRangePartStopTakesFewerStepsToTheSameRangePart)
{
  const auto cube = shapes::cube<Kernel>(30);
  const auto sphere = shapes::bumpy_sphere<Kernel>(4000, 1.0, 0.08, 4.0);
  Mean_shift_settings converged;
  converged.tolerance = 1e-9;
  converged.max_iterations = 2000;
  const Outcome truth = modes_of(sphere, converged);
  for(const auto* shape : {&cube, &sphere}) {
    const Outcome a = modes_of(*shape), b = modes_of(*shape, range_part_mean_shift_settings());
    double error_a = 0, error_b = 0; // mean distance of the normal parts to the converged ones (sphere)
    for(std::size_t i = 0; i < shape->points.size(); ++i) {
      ASSERT_LE(b.modes[i].iterations, a.modes[i].iterations) << i;
      if(b.modes[i].iterations == a.modes[i].iterations) {
        EXPECT_EQ(b.modes[i].position, a.modes[i].position) << i;
        EXPECT_EQ(b.modes[i].normal, a.modes[i].normal) << i;
      }
      if(shape == &cube) EXPECT_EQ(face_of(b.modes[i].normal), face_of(cube.normals[i])) << i;
      else {
        error_a += std::sqrt((a.modes[i].normal - truth.modes[i].normal).squared_length()) / double(sphere.points.size());
        error_b += std::sqrt((b.modes[i].normal - truth.modes[i].normal).squared_length()) / double(sphere.points.size());
      }
    }
    if(shape == &cube) EXPECT_LT(b.result.mean_iterations, 0.5 * a.result.mean_iterations);
    else {
      EXPECT_LT(b.result.mean_iterations, a.result.mean_iterations);
      EXPECT_LT(error_b, 1.5 * error_a + 1e-4); // measured: 0.0115 -> 0.0116 (cube: 7.5 -> 3.6 steps)
    }
  }
}

TEST(MeanShift, SequentialAndParallelGiveTheSameModes)
{
  const auto tube = shapes::bumpy_tube<Kernel>(8000);
  const Outcome seq = modes_of<CGAL::Sequential_tag>(tube);
  const Outcome par = modes_of<CGAL::Parallel_if_available_tag>(tube);
  ASSERT_EQ(seq.modes.size(), par.modes.size());
  for(std::size_t i = 0; i < seq.modes.size(); ++i) {
    EXPECT_EQ(seq.modes[i].position, par.modes[i].position);
    EXPECT_EQ(seq.modes[i].normal, par.modes[i].normal);
    EXPECT_EQ(seq.modes[i].mean_curvature, par.modes[i].mean_curvature);
  }
}

TEST(MeanShift, PointSet3WithoutNormalsEstimatesThem)
{
  const auto sphere = shapes::bumpy_sphere<Kernel>(3000, 1.0, 0.0);
  CGAL::Point_set_3<Point> set;
  for(const Point& p : sphere.points) set.insert(p);
  auto [mode_map, created] = set.add_property_map<Mode>("mode", Mode());
  ASSERT_TRUE(created);
  ASSERT_TRUE(compute_mean_shift_modes(set, default_mean_shift_neighbors, Mean_shift_settings(), mode_map,
                                       set.parameters()));
  // Estimated normals are oriented consistently (all outward or all inward): |H| = 1 either way.
  for(std::size_t i = 0; i < set.size(); i += 29) EXPECT_NEAR(std::abs(mode_map[i].mean_curvature), 1.0, 0.06);
}

TEST(MeanShift, CancelledRunLeavesTheMapUntouched)
{
  const auto sphere = shapes::bumpy_sphere<Kernel>(2000);
  std::vector<std::size_t> idx(sphere.points.size());
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  Mode marker;
  marker.iterations = 12345;
  std::vector<Mode> modes(sphere.points.size(), marker);
  const Mean_shift_result result = compute_mean_shift_modes(
    idx, 15, Mean_shift_settings(), CGAL::make_property_map(modes),
    CGAL::parameters::point_map(CGAL::make_property_map(sphere.points))
      .normal_map(CGAL::make_property_map(sphere.normals))
      .callback(std::function<bool(double)>([](double f) { return f < 0.6; })));
  EXPECT_FALSE(result.completed);
  for(const Mode& m : modes) EXPECT_EQ(m.iterations, 12345u);
}

TEST(MeanShift, BadInputIsRefusedWithAClearError)
{
  const auto sphere = shapes::bumpy_sphere<Kernel>(500);
  auto expect_error = [&](const shapes::Oriented_sample<Kernel>& s, const Mean_shift_settings& settings, unsigned k,
                          const char* needle) {
    try {
      modes_of(s, settings, k);
      ADD_FAILURE() << "no error for " << needle;
    } catch(const Invalid_input& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  Mean_shift_settings zero_range;
  zero_range.range_bandwidth = 0;
  expect_error(sphere, zero_range, 15, "range_bandwidth");
  Mean_shift_settings negative_spatial;
  negative_spatial.spatial_bandwidth = -1;
  expect_error(sphere, negative_spatial, 15, "spatial_bandwidth");
  Mean_shift_settings nan_scale;
  nan_scale.curvature_scale = std::numeric_limits<double>::quiet_NaN();
  expect_error(sphere, nan_scale, 15, "curvature_scale");
  Mean_shift_settings no_steps;
  no_steps.max_iterations = 0;
  expect_error(sphere, no_steps, 15, "max_iterations");
  expect_error(sphere, {}, 4, "at least 5");
  expect_error(sphere, {}, 500, "smaller than the number of points");

  auto zero_normal = sphere;
  zero_normal.normals[7] = Vector(0, 0, 0);
  expect_error(zero_normal, {}, 15, "normal of point #7");
  auto nan_normal = sphere;
  nan_normal.normals[3] = Vector(std::numeric_limits<double>::quiet_NaN(), 0, 1);
  expect_error(nan_normal, {}, 15, "normal of point #3");
  auto nan_point = sphere;
  nan_point.points[11] = Point(0, std::numeric_limits<double>::infinity(), 0);
  expect_error(nan_point, {}, 15, "point #11");

  shapes::Oriented_sample<Kernel> duplicates;
  for(int i = 0; i < 20; ++i) duplicates.push_back(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(0, 0, 1), 0);
  expect_error(duplicates, {}, 15, "coincide");
}
