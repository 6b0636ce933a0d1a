#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/generated_shapes.h>

#include "bumpy_sphere_fixture.h"

#include <gtest/gtest.h>

using namespace CGAL_ext;

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

