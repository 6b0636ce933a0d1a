#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/generated_shapes.h>

#include "bumpy_sphere_fixture.h"

#include <CGAL/property_map.h>

#include <boost/property_map/function_property_map.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>

using namespace CGAL_ext;

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
    // Written directly, without a solve (that a solve gives the same: DetailLeastSquares.ConsistentSystemsAreSolvedExactly).
    EXPECT_EQ(result.anchor_count, 0u);
    EXPECT_EQ(result.least_squares.method.find("exact"), 0u) << result.least_squares.method;
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
