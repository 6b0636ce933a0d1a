#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/generated_shapes.h>

#include "test_support.h"

#include <CGAL/property_map.h>

#include <boost/property_map/function_property_map.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>

using namespace CGAL_ext;

namespace {
struct Radial_statistics
{
  double mean_radius = 0, bump_rms = 0, centroid_offset = 0;
};

/// Mean distance from the origin, RMS of its deviation (the bumps), and the centroid's distance from the origin.
Radial_statistics radial(const std::vector<Point>& points)
{
  Radial_statistics s;
  double cx = 0, cy = 0, cz = 0;
  for(const Point& p : points) {
    s.mean_radius += std::sqrt((p - CGAL::ORIGIN).squared_length());
    cx += p.x(); cy += p.y(); cz += p.z();
  }
  const double n = double(points.size());
  s.mean_radius /= n;
  for(const Point& p : points) {
    const double d = std::sqrt((p - CGAL::ORIGIN).squared_length()) - s.mean_radius;
    s.bump_rms += d * d;
  }
  s.bump_rms = std::sqrt(s.bump_rms / n);
  s.centroid_offset = std::sqrt(cx * cx + cy * cy + cz * cz) / n;
  return s;
}

double max_distance(const std::vector<Point>& a, const std::vector<Point>& b)
{
  double d = 0;
  for(std::size_t i = 0; i < a.size(); ++i) d = std::max(d, std::sqrt(CGAL::squared_distance(a[i], b[i])));
  return d;
}

const auto sphere = shapes::bumpy_sphere<Kernel>(20000, 1.0, 0.02, 4.0);
const std::vector<std::size_t> indices = [] {
  std::vector<std::size_t> v(sphere.points.size());
  std::iota(v.begin(), v.end(), std::size_t(0));
  return v;
}();

/// Named parameters for an index range over `points` with the sphere's exact normals.
auto on(std::vector<Point>& points)
{
  return CGAL::parameters::point_map(CGAL::make_property_map(points)).normal_map(CGAL::make_property_map(sphere.normals));
}
} // namespace

TEST(BalancedFlow, BumpySphereLosesItsBumpsButNotItsSizeOrPlace)
{
  std::vector<Point> base = sphere.points;
  ASSERT_TRUE(balanced_flow_smooth_point_set(indices, 10, Balanced_flow_settings(), on(base)));
  const Radial_statistics before = radial(sphere.points), after = radial(base);
  EXPECT_LT(after.bump_rms, 0.1 * before.bump_rms);
  EXPECT_LT(std::abs(after.mean_radius - before.mean_radius), 0.01);
  EXPECT_LT(after.centroid_offset, 0.01);
  // Normals estimated instead of given: the same properties.
  std::vector<Point> estimated = sphere.points;
  ASSERT_TRUE(balanced_flow_smooth_point_set(estimated, 10));
  EXPECT_LT(radial(estimated).bump_rms, 0.1 * before.bump_rms);
  EXPECT_LT(std::abs(radial(estimated).mean_radius - before.mean_radius), 0.01);
}

TEST(BalancedFlow, ThinTubeKeepsItsThickness)
{
  // The tentacle tapers from radius 0.25 to 0.083: a plain curvature flow would thin its tip first.
  const auto tube = shapes::bumpy_tube<Kernel>(30000);
  std::vector<Point> base = tube.points;
  std::vector<std::size_t> tube_indices(base.size());
  std::iota(tube_indices.begin(), tube_indices.end(), std::size_t(0));
  balanced_flow_smooth_point_set(tube_indices, 10, Balanced_flow_settings(),
                                 CGAL::parameters::point_map(CGAL::make_property_map(base))
                                   .normal_map(CGAL::make_property_map(tube.normals)));
  // Signed change along the normal, averaged: the base neither shrinks nor swells by more than 2 % of the
  // tip radius, while the bumps (height along the normal) lose most of their energy.
  double mean_offset = 0, bump_energy = 0, left_energy = 0;
  for(std::size_t i = 0; i < base.size(); ++i) {
    const double offset = (base[i] - tube.points[i]) * tube.normals[i];
    mean_offset += offset;
    bump_energy += tube.bump_height[i] * tube.bump_height[i];
    const double left = tube.bump_height[i] + offset;
    left_energy += left * left;
  }
  mean_offset /= double(base.size());
  EXPECT_LT(std::abs(mean_offset), 0.02 * 0.083);
  EXPECT_LT(left_energy, 0.2 * bump_energy);
}

TEST(EnhanceGeometricDetails, WholeModelEnhancementIsTheExactSolutionAndDoublesTheBumps)
{
  std::vector<Point> base = sphere.points;
  balanced_flow_smooth_point_set(indices, 10, Balanced_flow_settings(), on(base));
  for(Detail_order order : {Detail_order::linear, Detail_order::quadric}) {
    std::vector<Point> enhanced = sphere.points;
    const auto result = enhance_geometric_details(indices, 10, 2.0, Detail_filter{order, 0.8, 1.6}, on(enhanced));
    ASSERT_TRUE(result);
    EXPECT_TRUE(result.default_anchors);
    EXPECT_EQ(result.region_size, sphere.points.size());
    EXPECT_NEAR(double(result.anchor_count), 0.01 * double(sphere.points.size()), 0.005 * double(sphere.points.size()));
    double worst = 0;
    for(std::size_t i = 0; i < enhanced.size(); ++i) {
      const Point exact = base[i] + 2.0 * (sphere.points[i] - base[i]);
      worst = std::max(worst, std::sqrt(CGAL::squared_distance(enhanced[i], exact)));
    }
    EXPECT_LT(worst, 1e-9) << Detail_filter::order_name(order);
    const Radial_statistics before = radial(sphere.points), after = radial(enhanced);
    EXPECT_NEAR(after.bump_rms / before.bump_rms, 2.0, 0.3) << Detail_filter::order_name(order);
    EXPECT_LT(std::abs(after.mean_radius - before.mean_radius), 0.01);
  }
}

TEST(EnhanceGeometricDetails, FactorOneReturnsTheInputAndTheOutsideNeverMoves)
{
  std::vector<std::size_t> cap;
  for(std::size_t i = 0; i < sphere.points.size(); ++i)
    if(sphere.points[i].z() > 0.5) cap.push_back(i);
  std::vector<Point> whole = sphere.points, partial = sphere.points, enhanced = sphere.points;
  enhance_geometric_details(indices, 10, 1.0, Detail_filter{}, on(whole));
  enhance_geometric_details(indices, 10, cap, 1.0, Detail_filter{}, on(partial));
  EXPECT_LT(max_distance(whole, sphere.points), 2e-9);
  EXPECT_LT(max_distance(partial, sphere.points), 2e-9);
  const auto result = enhance_geometric_details(indices, 10, cap, 3.0, Detail_filter{}, on(enhanced));
  EXPECT_EQ(result.region_size, cap.size());
  EXPECT_GT(max_distance(enhanced, sphere.points), 1e-3);
  for(std::size_t i = 0; i < enhanced.size(); ++i) {
    if(sphere.points[i].z() <= 0.5) {
      ASSERT_EQ(enhanced[i], sphere.points[i]);
    }
  }
}

TEST(EnhanceGeometricDetails, BadInputIsAClearError)
{
  std::vector<Point> points = sphere.points;
  auto message = [&](auto&& call) {
    try { call(); } catch(const Invalid_input& e) { return std::string(e.what()); }
    return std::string("no exception");
  };
  EXPECT_NE(message([&] { enhance_geometric_details(points, 10, std::numeric_limits<double>::infinity(), Detail_filter{}); }).find("finite"), std::string::npos);
  EXPECT_NE(message([&] { enhance_geometric_details(points, 10, std::vector<int>{}, 2.0, Detail_filter{}); }).find("empty"), std::string::npos);
  Detail_enhancement_settings bad_flow;
  bad_flow.flow.fidelity = 0;
  EXPECT_NE(message([&] { enhance_geometric_details(points, 10, 2.0, bad_flow); }).find("fidelity"), std::string::npos);
  EXPECT_NE(message([&] { enhance_geometric_details(points, 10, 2.0, Detail_filter{},
                                                    CGAL::parameters::normal_map(boost::make_function_property_map<Point>([&](const Point&) { return Vector(0, 0, 0); }))); }).find("normal"), std::string::npos);
  EXPECT_EQ(points, sphere.points);
}
