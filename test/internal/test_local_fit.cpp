// The height fit of internal/local_fit.h: exact on what it can represent, biased only by its light ridge.
#include <CGAL_ext/internal/local_fit.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <vector>

using CGAL_ext::internal::Height_fit;

namespace {

/// Samples of the graph `z = height(x, y)` over the tangent plane of `fit` (its axes u, v, n at `origin`), on a
/// jittered grid of (2r+1)^2 points of spacing `h`.
std::vector<Eigen::Vector3d> graph_samples(const Height_fit& fit, const Eigen::Vector3d& origin, const Eigen::Vector3d& n,
                                           const std::function<double(double, double)>& height, int r, double h)
{
  std::vector<Eigen::Vector3d> samples;
  for(int i = -r; i <= r; ++i)
    for(int j = -r; j <= r; ++j) {
      const double x = h * (i + 0.3 * std::sin(7.0 * i + j)), y = h * (j + 0.3 * std::cos(5.0 * j - i));
      samples.push_back(origin + x * fit.tangent_u() + y * fit.tangent_v() + height(x, y) * n);
    }
  return samples;
}

void fit_to(Height_fit& fit, const std::vector<Eigen::Vector3d>& samples)
{
  fit.fit(int(samples.size()), [&](int m) { return samples[std::size_t(m)]; });
}

const Eigen::Vector3d fit_origin(1.5, -2.0, 0.25);
const Eigen::Vector3d fit_normal = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();

} // namespace

TEST(HeightFit, ATiltedPlaneIsFittedExactly)
{
  // Plane terms: the ridge leaves the constant alone and pulls the slopes by 1e-3 of their size, so the plane
  // through the samples is recovered with its tilt to about 1e-3.
  Height_fit fit(fit_origin, fit_normal);
  const auto plane = [](double x, double y) { return 0.05 + 0.2 * x - 0.1 * y; };
  fit_to(fit, graph_samples(fit, fit_origin, fit_normal, plane, 3, 0.1));
  const Eigen::Vector3d analytic = (fit_normal - 0.2 * fit.tangent_u() + 0.1 * fit.tangent_v()).normalized();
  for(const Eigen::Vector3d& q : {fit_origin, Eigen::Vector3d(fit_origin + 0.1 * fit.tangent_u()), Eigen::Vector3d(fit_origin - 0.2 * fit.tangent_v())}) {
    EXPECT_LT(std::acos(std::min(1.0, fit.normal(q).dot(analytic))), 2e-3);
    const Eigen::Vector3d d = q - fit_origin;
    const double x = d.dot(fit.tangent_u()), y = d.dot(fit.tangent_v());
    EXPECT_NEAR((fit.project(q) - fit_origin).dot(fit_normal), plane(x, y), 1e-3 * 0.3);
  }
}

TEST(HeightFit, AQuadricIsRecoveredToTheRidgesBias)
{
  Height_fit fit(fit_origin, fit_normal);
  const auto quadric = [](double x, double y) { return 0.4 * x * x - 0.3 * x * y + 0.6 * y * y; };
  fit_to(fit, graph_samples(fit, fit_origin, fit_normal, quadric, 4, 0.05));
  // At the fit_origin the analytic fit_normal is n itself; away from it the slope is (0.8 x - 0.3 y, -0.3 x + 1.2 y).
  EXPECT_LT(std::acos(std::min(1.0, fit.normal(fit_origin).dot(fit_normal))), 1e-3);
  const double x = 0.1, y = -0.05;
  const Eigen::Vector3d q = fit_origin + x * fit.tangent_u() + y * fit.tangent_v();
  const Eigen::Vector3d analytic =
    (fit_normal - (0.8 * x - 0.3 * y) * fit.tangent_u() - (-0.3 * x + 1.2 * y) * fit.tangent_v()).normalized();
  EXPECT_LT(std::acos(std::min(1.0, fit.normal(q).dot(analytic))), 5e-3);
  EXPECT_NEAR((fit.project(q) - fit_origin).dot(fit_normal), quadric(x, y), 2e-4);
}

TEST(HeightFit, DegreeThreeFollowsACubicThatDegreeTwoCannot)
{
  const auto cubic = [](double x, double y) { return 0.5 * x * x * x - 0.8 * x * y * y; };
  Height_fit quadratic(fit_origin, fit_normal, 2), cubic_fit(fit_origin, fit_normal, 3);
  const auto samples = graph_samples(quadratic, fit_origin, fit_normal, cubic, 4, 0.1);
  fit_to(quadratic, samples);
  fit_to(cubic_fit, samples);
  double error2 = 0, error3 = 0;
  for(const Eigen::Vector3d& p : samples) {
    error2 = std::max(error2, (quadratic.project(p) - p).norm());
    error3 = std::max(error3, (cubic_fit.project(p) - p).norm());
  }
  EXPECT_LT(error3, 1e-3);
  EXPECT_GT(error2, 10 * error3);
}

TEST(HeightFit, FewSamplesFallBackToLowerDegreesAndThenToTheMeanHeight)
{
  // Five samples: below the six coefficients of degree 2, the fit is the tangent plane at their mean height.
  Height_fit fit(fit_origin, fit_normal);
  std::vector<Eigen::Vector3d> samples;
  const double heights[] = {0.1, 0.2, -0.05, 0.3, 0.0};
  for(int m = 0; m < 5; ++m)
    samples.push_back(fit_origin + 0.1 * m * fit.tangent_u() - 0.05 * m * fit.tangent_v() + heights[m] * fit_normal);
  fit_to(fit, samples);
  EXPECT_NEAR((fit.project(fit_origin + 0.3 * fit.tangent_u()) - fit_origin).dot(fit_normal), 0.11, 1e-12);
  EXPECT_LT((fit.normal(fit_origin) - fit_normal).norm(), 1e-12);
  // Eight samples for degree 3 (ten coefficients): it fits degree 2, which is exact on a quadric up to the ridge.
  Height_fit reduced(fit_origin, fit_normal, 3);
  const auto quadric = [](double x, double y) { return 0.3 * x * x + 0.2 * y * y; };
  auto eight = graph_samples(reduced, fit_origin, fit_normal, quadric, 1, 0.1);
  eight.pop_back();
  fit_to(reduced, eight);
  for(const Eigen::Vector3d& p : eight) EXPECT_LT((reduced.project(p) - p).norm(), 1e-3);
}
