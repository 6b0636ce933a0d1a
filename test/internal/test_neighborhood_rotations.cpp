// The local fits of internal/neighborhood_rotations.h: the closed-form best rotation against the SVD's, and near
// its fallback.
#include <CGAL_ext/internal/neighborhood_rotations.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

TEST(NeighborhoodRotations, BestRotationIsTheSingularValueDecompositionsRotation)
{
  // The closed-form best rotation against the SVD's V U^T (reflection flipped): neighbourhoods of 10 edges,
  // spread in space, flat (one axis zero) and nearly flat, turned by a random rotation with noise, some mirrored;
  // a rigid turn without noise. (Nearly collinear ones, the SVD's path: the test below.)
  namespace in = CGAL_ext::internal;
  auto svd_rotation = [](const Eigen::Matrix3d& c) { return in::best_rotation_by_svd(c); };
  std::mt19937 rng(21);
  std::normal_distribution<double> g;
  double largest = 0, rigid = 0;
  for(int t = 0; t < 3000; ++t) {
    const Eigen::Matrix3d R = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
    const double thickness = t % 3 == 0 ? 0.0 : t % 3 == 1 ? 1e-3 : 0.5;
    const double mirror = t % 7 == 0 ? -1.0 : 1.0;
    Eigen::Matrix3d noisy = Eigen::Matrix3d::Zero(), exact = Eigen::Matrix3d::Zero();
    for(int k = 0; k < 10; ++k) {
      const Eigen::Vector3d e(g(rng), g(rng), thickness * g(rng));
      Eigen::Vector3d moved = R * e + 0.05 * Eigen::Vector3d(g(rng), g(rng), g(rng));
      moved.x() *= mirror;
      noisy += e * moved.transpose();
      exact += e * (R * e).transpose();
    }
    const Eigen::Matrix3d fitted = in::best_rotation(noisy);
    largest = std::max(largest, (fitted - svd_rotation(noisy)).cwiseAbs().maxCoeff());
    ASSERT_LT((fitted * fitted.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-13);
    ASSERT_NEAR(fitted.determinant(), 1.0, 1e-13);
    rigid = std::max(rigid, (in::best_rotation(exact) - R).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(largest, 1e-10);
  EXPECT_LT(rigid, 1e-10);
}

TEST(NeighborhoodRotations, BestRotationReachesTheOptimumNearItsFallback)
{
  // The rotation R maximising tr(R C) (C = sum e_j e'_j^T) minimises sum |R e_j - e'_j|^2, and the maximum is
  // s1 + s2 + sign(det C) s3 over C's singular values (from Eigen's SVD, not from the rotation's closed form
  // or its fallback). Nearly collinear neighbourhoods, whose middle singular value lies about the closed form's fallback
  // threshold (a hundredth of the largest), and nearly flat ones, some mirrored, with and without noise: the
  // rotation must reach the optimum on both sides of the threshold and be one.
  namespace in = CGAL_ext::internal;
  std::mt19937 rng(33);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> exponent(-4.5, -0.3);
  std::size_t below = 0, above = 0, flat = 0;
  double worst_gap = 0, worst_orthonormality = 0;
  for(int t = 0; t < 6000; ++t) {
    const Eigen::Matrix3d R = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
    const Eigen::Matrix3d frame = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
    const bool collinear = t % 2 == 0;
    // Collinear: a width about the line of 10^-4.5 to 10^-0.3, so the middle singular value's ratio to the largest
    // (about the width squared) spans the threshold; flat: a thickness of 1e-9 to 0.25 off a plane.
    const double width = collinear ? std::pow(10.0, exponent(rng)) : 1.0;
    const double thickness = collinear ? width : std::pow(10.0, 2 * exponent(rng));
    const double noise = t % 3 == 0 ? 0.0 : 0.01 * width;
    const double mirror = t % 5 == 0 ? -1.0 : 1.0;
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    for(int k = 0; k < 10; ++k) {
      const Eigen::Vector3d e = frame * Eigen::Vector3d(g(rng), width * g(rng), thickness * g(rng));
      Eigen::Vector3d moved = R * e + noise * Eigen::Vector3d(g(rng), g(rng), g(rng));
      moved.x() *= mirror;
      C += e * moved.transpose();
    }
    // The sign of det C from the singular vectors' handedness: det C itself is lost to rounding where s3 is.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector3d sigma = svd.singularValues(); // descending
    const double handedness = svd.matrixU().determinant() * svd.matrixV().determinant();
    const double optimum = sigma(0) + sigma(1) + (handedness < 0 ? -1 : 1) * sigma(2);
    const Eigen::Matrix3d fitted = in::best_rotation(C);
    worst_orthonormality = std::max(worst_orthonormality, (fitted * fitted.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
    ASSERT_GT(fitted.determinant(), 0);
    worst_gap = std::max(worst_gap, (optimum - (fitted * C).trace()) / sigma(0));
    if(collinear) (sigma(1) > 1e-2 * sigma(0) ? above : below) += 1;
    else ++flat;
  }
  std::printf("best rotation: largest shortfall from the optimum %.2e of the largest singular value, orthonormal to "
              "%.2e (%zu nearly collinear below the fallback threshold, %zu above, %zu nearly flat)\n", worst_gap,
              worst_orthonormality, below, above, flat);
  EXPECT_LT(worst_gap, 1e-12);
  EXPECT_LT(worst_orthonormality, 1e-11);
  EXPECT_GT(below, 300u);
  EXPECT_GT(above, 300u);
}
