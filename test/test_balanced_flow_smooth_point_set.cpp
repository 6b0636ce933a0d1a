#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/internal/balanced_flow.h>

#include <Eigen/IterativeLinearSolvers>

#include "bumpy_sphere_fixture.h"

#include <gtest/gtest.h>

#include <random>

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


// The balance equation's BiCGSTAB runs its products and updates in parallel and still takes Eigen's steps:
// the same iterate, bit for bit, on a non-symmetric diagonally dominant system like the flow's, with either
// concurrency tag; a singular system that cannot reach the tolerance is an error, not a result.
TEST(BalancedFlow, ParallelBiCGSTABTakesEigensStepsAndReportsFailure)
{
  const int n = 3000;
  std::vector<Eigen::Triplet<double>> entries;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> weight(-1.0, 1.0);
  std::uniform_int_distribution<int> column(0, n - 1);
  for(int i = 0; i < n; ++i) {
    entries.emplace_back(i, i, 1.005);
    for(int e = 0; e < 10; ++e) entries.emplace_back(i, column(random), 0.099 * weight(random));
  }
  internal::Sparse_row_matrix M(n, n);
  M.setFromTriplets(entries.begin(), entries.end());
  Eigen::VectorXd rhs(n);
  for(int i = 0; i < n; ++i) rhs[i] = weight(random);
  Eigen::BiCGSTAB<internal::Sparse_row_matrix, Eigen::DiagonalPreconditioner<double>> eigen(M);
  eigen.setTolerance(1e-8);
  const Eigen::VectorXd expected = eigen.solve(rhs);
  ASSERT_EQ(eigen.info(), Eigen::Success);
  const Eigen::VectorXd parallel = internal::bicgstab_jacobi<CGAL::Parallel_if_available_tag>(M, rhs, 1e-8);
  const Eigen::VectorXd sequential = internal::bicgstab_jacobi<CGAL::Sequential_tag>(M, rhs, 1e-8);
  EXPECT_TRUE((parallel.array() == expected.array()).all());
  EXPECT_TRUE((sequential.array() == expected.array()).all());
  EXPECT_LE((M * parallel - rhs).norm(), 1e-8 * rhs.norm());

  // Two equal rows and a right-hand side that asks them for different values.
  internal::Sparse_row_matrix singular(2, 2);
  std::vector<Eigen::Triplet<double>> ones{{0, 0, 1.0}, {0, 1, 1.0}, {1, 0, 1.0}, {1, 1, 1.0}};
  singular.setFromTriplets(ones.begin(), ones.end());
  EXPECT_THROW(internal::bicgstab_jacobi<CGAL::Sequential_tag>(singular, Eigen::Vector2d(1.0, -1.0), 1e-8),
               Numerical_failure);
}
