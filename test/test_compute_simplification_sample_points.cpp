#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/generated_shapes.h>

#include "test_support.h"

#include <CGAL/Point_set_3.h>
#include <CGAL/property_map.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <random>
#include <set>

using namespace CGAL_ext;

namespace {
using Samples = Simplification_sample_points<Kernel>;

struct Simplification_outcome
{
  Samples samples;
  std::vector<std::size_t> sample_of;
};

template <typename Tag = CGAL::Parallel_if_available_tag>
Simplification_outcome cluster(const shapes::Oriented_sample<Kernel>& s, const Simplification_settings& settings,
            const std::vector<int>* labels = nullptr)
{
  std::vector<std::size_t> idx(s.points.size());
  std::iota(idx.begin(), idx.end(), std::size_t(0));
  Simplification_outcome run;
  run.sample_of.assign(s.points.size(), std::numeric_limits<std::size_t>::max());
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(s.points)).normal_map(CGAL::make_property_map(s.normals));
  if(labels)
    run.samples = compute_simplification_sample_points<Tag>(idx, CGAL::make_property_map(*labels), settings,
                                                            CGAL::make_property_map(run.sample_of), np);
  else
    run.samples = compute_simplification_sample_points<Tag>(idx, settings, CGAL::make_property_map(run.sample_of), np);
  return run;
}

Simplification_settings with_cluster_size(std::size_t size)
{
  Simplification_settings settings;
  settings.max_cluster_size = size;
  return settings;
}

/// Every point is a member of exactly one sample point, the one the per-point map names.
void expect_partition(const Simplification_outcome& run, std::size_t n, std::size_t max_size)
{
  ASSERT_TRUE(run.samples.completed);
  std::vector<int> seen(n, 0);
  for(std::size_t s = 0; s < run.samples.size(); ++s) {
    const auto& sample = run.samples.samples[s];
    EXPECT_GE(sample.member_count, 1u);
    EXPECT_LE(sample.member_count, max_size);
    for(std::size_t m = 0; m < sample.member_count; ++m) {
      const std::size_t i = run.samples.members[sample.first_member + m];
      ++seen[i];
      EXPECT_EQ(run.sample_of[i], s);
    }
  }
  for(std::size_t i = 0; i < n; ++i) EXPECT_EQ(seen[i], 1) << "point " << i;
}

/// A 120 x 60 grid of spacing 1 in z = 0, jittered, with bumps of wavelength 10 and height 2 on its x > 0 half only
/// (slopes up to 57 degrees: beyond one range bandwidth, so the modes of the bumps stay apart).
shapes::Oriented_sample<Kernel> half_bumpy_plane()
{
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double w = 2 * CGAL_PI / 10, a = 2.0;
  shapes::Oriented_sample<Kernel> s;
  s.average_spacing = 1;
  for(int j = 0; j < 60; ++j)
    for(int i = -60; i < 60; ++i) {
      const double x = i + 0.5 + jitter(rng), y = j + jitter(rng);
      const double z = x > 0 ? a * std::sin(w * x) * std::sin(w * y) : 0;
      const Eigen::Vector3d n = x > 0 ? Eigen::Vector3d(-a * w * std::cos(w * x) * std::sin(w * y),
                                                         -a * w * std::sin(w * x) * std::cos(w * y), 1).normalized()
                                      : Eigen::Vector3d::UnitZ();
      s.push_back(Eigen::Vector3d(x, y, z), n, z);
    }
  return s;
}
} // namespace

TEST(SimplificationSamplePoints, EveryPointBelongsToOneSamplePointOfBoundedSize)
{
  const auto tube = shapes::bumpy_tube<Kernel>(20000);
  for(std::size_t size : {1u, 7u, 50u, 400u}) {
    const Simplification_outcome run = cluster(tube, with_cluster_size(size));
    expect_partition(run, tube.points.size(), size);
    EXPECT_LE(run.samples.max_cluster_size, size);
    // Cuts at the centroid leave clusters of at least a few points when only the size drives them.
    if(size == 1) EXPECT_EQ(run.samples.size(), tube.points.size());
    else EXPECT_GE(run.samples.size(), tube.points.size() / size);
  }
}

TEST(SimplificationSamplePoints, CubeSamplePointsDoNotStraddleEdges)
{
  const auto cube = shapes::cube<Kernel>(40); // 9600 points with exact face normals
  const Simplification_outcome run = cluster(cube, with_cluster_size(50));
  expect_partition(run, cube.points.size(), 50);
  std::size_t single_face = 0;
  for(const auto& sample : run.samples.samples) {
    std::set<int> faces;
    for(std::size_t m = 0; m < sample.member_count; ++m)
      faces.insert(face_of(cube.normals[run.samples.members[sample.first_member + m]]));
    if(faces.size() == 1) ++single_face;
  }
  const double fraction = double(single_face) / double(run.samples.size());
  std::printf("cube: %zu sample points, %.2f %% on one face\n", run.samples.size(), 100 * fraction);
  EXPECT_GE(fraction, 0.99);

  // Size alone cuts across edges: the mode criterion is what keeps faces apart.
  Simplification_settings size_only = with_cluster_size(50);
  size_only.mode_spread_threshold = std::numeric_limits<double>::infinity();
  const Simplification_outcome plain = cluster(cube, size_only);
  EXPECT_FALSE(plain.samples.mean_shift.completed);
  std::size_t mixed = 0;
  for(const auto& sample : plain.samples.samples) {
    std::set<int> faces;
    for(std::size_t m = 0; m < sample.member_count; ++m)
      faces.insert(face_of(cube.normals[plain.samples.members[sample.first_member + m]]));
    mixed += faces.size() > 1;
  }
  EXPECT_GT(mixed, std::size_t(0.05 * double(plain.samples.size())));
}

TEST(SimplificationSamplePoints, DenserWhereTheSurfaceBends)
{
  const auto plane = half_bumpy_plane();
  const Simplification_outcome run = cluster(plane, with_cluster_size(50));
  expect_partition(run, plane.points.size(), 50);
  double samples[2] = {0, 0}, points[2] = {0, 0};
  for(const Point& p : plane.points) points[p.x() > 0] += 1;
  for(const auto& sample : run.samples.samples) {
    // A sample point belongs to the half that holds most of its members.
    std::size_t bumpy = 0;
    for(std::size_t m = 0; m < sample.member_count; ++m) bumpy += plane.points[run.samples.members[sample.first_member + m]].x() > 0;
    samples[2 * bumpy > sample.member_count] += 1;
  }
  const double ratio = (samples[1] / points[1]) / (samples[0] / points[0]);
  std::printf("sample points per point: bumpy half %.4f, flat half %.4f, ratio %.2f\n", samples[1] / points[1],
              samples[0] / points[0], ratio);
  EXPECT_GT(ratio, 1.5);
}

TEST(SimplificationSamplePoints, SurfelsFitTheirMembers)
{
  const auto sphere = shapes::bumpy_sphere<Kernel>(8000, 1.0, 0.0);
  const Simplification_outcome run = cluster(sphere, with_cluster_size(30));
  expect_partition(run, sphere.points.size(), 30);
  for(const auto& sample : run.samples.samples) {
    Vector mean_normal(0, 0, 0);
    double radius = 0;
    for(std::size_t m = 0; m < sample.member_count; ++m) {
      const std::size_t i = run.samples.members[sample.first_member + m];
      mean_normal = mean_normal + sphere.normals[i];
      radius = std::max(radius, std::sqrt(CGAL::squared_distance(sphere.points[i], sample.centroid)));
    }
    EXPECT_NEAR(sample.radius, radius, 1e-12);
    EXPECT_NEAR(sample.normal.squared_length(), 1.0, 1e-12);
    // On a unit sphere the surfel normal is close to the radial direction of its centroid and oriented outward.
    const Vector radial = (sample.centroid - CGAL::ORIGIN) / std::sqrt((sample.centroid - CGAL::ORIGIN).squared_length());
    EXPECT_GT(sample.normal * radial, 0.98);
    EXPECT_GT(sample.normal * mean_normal, 0);
  }
}

TEST(SimplificationSamplePoints, TargetCountBoundsTheCount)
{
  const auto sphere = shapes::bumpy_sphere<Kernel>(20000);
  Simplification_settings settings;
  settings.target_count = 1000;
  const Simplification_outcome run = cluster(sphere, settings);
  std::size_t largest = 0;
  for(const auto& sample : run.samples.samples) largest = std::max(largest, sample.member_count);
  EXPECT_EQ(run.samples.max_cluster_size, largest);
  expect_partition(run, sphere.points.size(), largest);
  EXPECT_LE(largest, 3 * 20u) << "the largest clusters are split first";
  EXPECT_EQ(run.samples.size_split_count, 1000u);
  EXPECT_GE(run.samples.size(), 1000u);
  EXPECT_LE(run.samples.size(), 1500u);
  EXPECT_GE(run.samples.requested_count, run.samples.size());
  // At most the target count of points: every point is its own sample point, with its own normal.
  const auto small = shapes::bumpy_sphere<Kernel>(800);
  const Simplification_outcome own = cluster(small, Simplification_settings());
  EXPECT_EQ(own.samples.size(), 800u);
  for(std::size_t i = 0; i < 800; ++i) {
    const auto& sample = own.samples.samples[own.sample_of[i]];
    EXPECT_EQ(sample.centroid, small.points[i]);
    EXPECT_NEAR(sample.normal * small.normals[i], 1.0, 1e-12);
    EXPECT_EQ(sample.radius, 0);
  }
}

TEST(SimplificationSamplePoints, SelectionsAreNeverMixed)
{
  const auto tube = shapes::bumpy_tube<Kernel>(10000);
  std::vector<int> labels(tube.points.size());
  for(std::size_t i = 0; i < labels.size(); ++i) {
    const Point& p = tube.points[i];
    labels[i] = p.z() > 0.7 ? 2 : (p.z() > 0.3 ? 1 : 0); // handle, deformable, fixed: by height along the bend
  }
  const Simplification_outcome run = cluster(tube, with_cluster_size(50), &labels);
  expect_partition(run, tube.points.size(), 50);
  for(const auto& sample : run.samples.samples)
    for(std::size_t m = 1; m < sample.member_count; ++m)
      EXPECT_EQ(labels[run.samples.members[sample.first_member + m]], labels[run.samples.members[sample.first_member]]);
}

TEST(SimplificationSamplePoints, SequentialAndParallelGiveTheSameSamplePoints)
{
  const auto cube = shapes::cube<Kernel>(100); // 60,000 points: the parallel split hands out tasks
  const Simplification_outcome seq = cluster<CGAL::Sequential_tag>(cube, with_cluster_size(50));
  const Simplification_outcome par = cluster<CGAL::Parallel_if_available_tag>(cube, with_cluster_size(50));
  ASSERT_EQ(seq.samples.size(), par.samples.size());
  EXPECT_EQ(seq.samples.members, par.samples.members);
  EXPECT_EQ(seq.sample_of, par.sample_of);
  for(std::size_t s = 0; s < seq.samples.size(); ++s) {
    EXPECT_EQ(seq.samples.samples[s].centroid, par.samples.samples[s].centroid);
    EXPECT_EQ(seq.samples.samples[s].normal, par.samples.samples[s].normal);
  }
}

TEST(SimplificationSamplePoints, PointSet3AndCancellation)
{
  const auto sphere = shapes::bumpy_sphere<Kernel>(5000);
  CGAL::Point_set_3<Point> set;
  set.add_normal_map();
  for(std::size_t i = 0; i < sphere.points.size(); ++i) set.insert(sphere.points[i], sphere.normals[i]);
  auto [index_map, created] = set.add_property_map<std::size_t>("ssp", std::size_t(777777));
  ASSERT_TRUE(created);
  const auto cancelled = compute_simplification_sample_points(
    set, with_cluster_size(40), index_map,
    set.parameters().callback(std::function<bool(double)>([](double f) { return f < 0.5; })));
  EXPECT_FALSE(cancelled.completed);
  for(std::size_t i = 0; i < set.size(); ++i) EXPECT_EQ(index_map[i], 777777u);
  const auto done = compute_simplification_sample_points(set, with_cluster_size(40), index_map, set.parameters());
  ASSERT_TRUE(done.completed);
  for(std::size_t i = 0; i < set.size(); ++i) EXPECT_LT(index_map[i], done.size());
}

TEST(SimplificationSamplePoints, BadSettingsAreRefusedWithAClearError)
{
  const auto sphere = shapes::bumpy_sphere<Kernel>(500);
  auto expect_error = [&](const Simplification_settings& settings, const char* needle) {
    try {
      cluster(sphere, settings);
      ADD_FAILURE() << "no error for " << needle;
    } catch(const Invalid_input& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expect_error(with_cluster_size(0), "max_cluster_size");
  Simplification_settings no_target;
  no_target.target_count = 0;
  expect_error(no_target, "target_count");
  for(double threshold : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
    Simplification_settings bad = with_cluster_size(10);
    bad.mode_spread_threshold = threshold;
    expect_error(bad, "mode_spread_threshold");
  }
  Simplification_settings few_neighbors = with_cluster_size(10);
  few_neighbors.mean_shift_neighbors = 3;
  expect_error(few_neighbors, "mean_shift_neighbors");
  Simplification_settings zero_bandwidth = with_cluster_size(10);
  zero_bandwidth.mean_shift.range_bandwidth = 0;
  expect_error(zero_bandwidth, "range_bandwidth");
}

namespace {

/// `shape` with every point moved by Gaussian noise of `sigma` along its normal (fixed seed).
shapes::Oriented_sample<Kernel> with_noise(shapes::Oriented_sample<Kernel> shape, double sigma)
{
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0, sigma);
  for(std::size_t i = 0; i < shape.points.size(); ++i) shape.points[i] = shape.points[i] + noise(rng) * shape.normals[i];
  return shape;
}

/// The points of `b` moved by `offset`, appended to `a`.
shapes::Oriented_sample<Kernel> combined(shapes::Oriented_sample<Kernel> a, const shapes::Oriented_sample<Kernel>& b, const Vector& offset)
{
  for(std::size_t i = 0; i < b.points.size(); ++i) {
    a.points.push_back(b.points[i] + offset);
    a.normals.push_back(b.normals[i]);
    a.bump_height.push_back(0);
  }
  return a;
}

} // namespace

// The paper's unbounded rule gives many times the target where the modes spread everywhere (sharp edges, noise);
// the budget keeps the count within 1.5 times the target and spends the extra sample points on the spread.
TEST(SimplificationSamplePoints, CountStaysWithinTheBudgetOnCreasesNoiseAndSeveralComponents)
{
  const auto cube = shapes::cube<Kernel>(40);
  const auto noisy = with_noise(shapes::bumpy_sphere<Kernel>(20000, 1.0, 0.05), 0.02);
  const auto parts = combined(combined(shapes::cube<Kernel>(30), shapes::bumpy_sphere<Kernel>(6000), Vector(3, 0, 0)),
                              shapes::bumpy_tube<Kernel>(6000), Vector(0, 3, 0));
  struct Case { const char* name; const shapes::Oriented_sample<Kernel>* shape; };
  for(const Case& c : {Case{"cube", &cube}, Case{"noisy sphere", &noisy}, Case{"three components", &parts}}) {
    Simplification_settings settings;
    settings.target_count = 400;
    const Simplification_outcome run = cluster(*c.shape, settings);
    settings.max_cluster_size = settings.cluster_size_for(c.shape->points.size());
    const Simplification_outcome paper = cluster(*c.shape, settings);
    std::printf("%s: %zu points, %zu sample points (size splits %zu, the spread asked for %zu), paper's rule %zu\n", c.name,
                c.shape->points.size(), run.samples.size(), run.samples.size_split_count, run.samples.requested_count,
                paper.samples.size());
    expect_partition(run, c.shape->points.size(), run.samples.max_cluster_size);
    EXPECT_GE(run.samples.size(), 400u) << c.name;
    EXPECT_LE(run.samples.size(), 600u) << c.name;
    EXPECT_GE(run.samples.requested_count, run.samples.size()) << c.name;
    EXPECT_GT(paper.samples.size(), 600u) << c.name << ": the unbounded rule must exceed the budget for this test to mean anything";
  }
  // The budget goes to the creases: fewer of the cube's points lie in sample points that straddle an edge than
  // with size splits only.
  Simplification_settings size_only;
  size_only.target_count = 400;
  size_only.mode_spread_threshold = std::numeric_limits<double>::infinity();
  Simplification_settings budgeted = size_only;
  budgeted.mode_spread_threshold = 1.0;
  auto straddling = [&](const Simplification_outcome& run) {
    std::size_t points = 0;
    for(const auto& sample : run.samples.samples) {
      std::set<int> faces;
      for(std::size_t m = 0; m < sample.member_count; ++m)
        faces.insert(face_of(cube.normals[run.samples.members[sample.first_member + m]]));
      if(faces.size() > 1) points += sample.member_count;
    }
    return double(points) / double(cube.points.size());
  };
  const double plain = straddling(cluster(cube, size_only)), spread = straddling(cluster(cube, budgeted));
  std::printf("cube, target 400: %.1f %% of the points in sample points across an edge by size only, %.1f %% with the "
              "spread's budget\n", 100 * plain, 100 * spread);
  EXPECT_LT(spread, 0.7 * plain);
}
