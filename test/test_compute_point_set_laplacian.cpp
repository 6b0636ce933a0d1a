#include <CGAL_ext/compute_point_set_laplacian.h>
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/internal/Neighbor_graph.h>

#include "test_support.h"

#include <CGAL/Point_set_3.h>
#include <CGAL/Random.h>

#include <gtest/gtest.h>

#include <set>

using namespace CGAL_ext;
using Sparse = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

namespace {
std::vector<Point> random_points(std::size_t n, unsigned seed)
{
  CGAL::Random rng(seed);
  std::vector<Point> pts;
  for(std::size_t i = 0; i < n; ++i) pts.emplace_back(rng.get_double(-1, 1), rng.get_double(-1, 1), rng.get_double(-1, 1));
  return pts;
}

Sparse laplacian(const std::vector<Point>& pts, unsigned k, const Laplacian_weights& w = {})
{
  Sparse K;
  EXPECT_TRUE(compute_point_set_laplacian(pts, k, w, K));
  return K;
}
} // namespace

TEST(Laplacian, RowsOfWSumToOneAndConstantsAreInTheKernel)
{
  const auto pts = random_points(2000, 1);
  for(Laplacian_weights w : {Laplacian_weights{}, Laplacian_weights{Laplacian_weighting::distance_power, -1.0}}) {
    const Sparse K = laplacian(pts, 10, w);
    ASSERT_EQ(K.rows(), 2000);
    const Eigen::VectorXd ones = Eigen::VectorXd::Ones(K.cols());
    EXPECT_LT((K * ones).cwiseAbs().maxCoeff(), 1e-14);
    for(int i = 0; i < K.outerSize(); ++i) {
      double off = 0;
      for(Sparse::InnerIterator it(K, i); it; ++it) {
        if(it.col() == i) EXPECT_EQ(it.value(), 1.0);
        else { EXPECT_LT(it.value(), 0.0); off -= it.value(); }
      }
      EXPECT_NEAR(off, 1.0, 1e-14);
    }
  }
}

TEST(Laplacian, GraphIsSymmetrisedAndContainsEveryKNearestNeighbour)
{
  const auto pts = random_points(500, 2);
  const unsigned k = 6;
  const Sparse K = laplacian(pts, k);
  // Brute force: each point's k nearest must be in its row, and the pattern must be symmetric.
  for(std::size_t i = 0; i < pts.size(); ++i) {
    std::vector<std::pair<double, int>> d;
    for(std::size_t j = 0; j < pts.size(); ++j)
      if(j != i) d.emplace_back(CGAL::squared_distance(pts[i], pts[j]), int(j));
    std::partial_sort(d.begin(), d.begin() + k, d.end());
    std::set<int> row;
    for(Sparse::InnerIterator it(K, Eigen::Index(i)); it; ++it) if(it.col() != Eigen::Index(i)) row.insert(int(it.col()));
    for(unsigned m = 0; m < k; ++m) EXPECT_TRUE(row.count(d[m].second)) << "point " << i;
    EXPECT_GE(row.size(), std::size_t(k));
    for(int j : row) EXPECT_NE(K.coeff(j, Eigen::Index(i)), 0.0) << i << " -> " << j << " not symmetric";
  }
}

TEST(Laplacian, UniformWeightsAreInverseValenceAndDistanceWeightsFollowThePower)
{
  const auto pts = random_points(300, 3);
  const Sparse U = laplacian(pts, 8);
  const Sparse D = laplacian(pts, 8, {Laplacian_weighting::distance_power, -1.0});
  for(int i = 0; i < U.outerSize(); ++i) {
    const double degree = double(U.row(i).nonZeros() - 1);
    double normaliser = 0;
    for(Sparse::InnerIterator it(D, i); it; ++it)
      if(it.col() != i) normaliser += 1.0 / std::sqrt(CGAL::squared_distance(pts[std::size_t(i)], pts[std::size_t(it.col())]));
    for(Sparse::InnerIterator it(U, i); it; ++it) {
      if(it.col() == i) continue;
      EXPECT_NEAR(it.value(), -1.0 / degree, 1e-15);
      const double dist = std::sqrt(CGAL::squared_distance(pts[std::size_t(i)], pts[std::size_t(it.col())]));
      EXPECT_NEAR(D.coeff(i, it.col()), -(1.0 / dist) / normaliser, 1e-12);
    }
  }
}

TEST(Laplacian, ExactDuplicatesKeepTheWeightsFinite)
{
  auto pts = random_points(200, 4);
  pts.push_back(pts[7]);
  pts.push_back(pts[7]);
  const Sparse D = laplacian(pts, 5, {Laplacian_weighting::distance_power, -1.0});
  for(int e = 0; e < D.nonZeros(); ++e) ASSERT_TRUE(std::isfinite(D.valuePtr()[e]));
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(D.cols());
  EXPECT_LT((D * ones).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Laplacian, SameMatrixThroughPointSet3AndSequentialOrParallel)
{
  const auto pts = random_points(3000, 5);
  CGAL::Point_set_3<Point> ps;
  for(const Point& p : pts) ps.insert(p);
  Sparse A, B, C;
  ASSERT_TRUE(compute_point_set_laplacian<CGAL::Sequential_tag>(pts, 10, {}, A));
  ASSERT_TRUE(compute_point_set_laplacian<CGAL::Parallel_if_available_tag>(pts, 10, {}, B));
  ASSERT_TRUE(compute_point_set_laplacian(ps, 10, {}, C, ps.parameters()));
  EXPECT_EQ((A - B).norm(), 0.0);
  EXPECT_EQ((A - C).norm(), 0.0);
}

TEST(Laplacian, CancelledRunLeavesTheOutputUntouched)
{
  const auto pts = random_points(200000, 6);
  Sparse K(3, 3);
  K.insert(1, 1) = 5.0;
  int calls = 0;
  const bool done = compute_point_set_laplacian(pts, 10, {}, K, CGAL::parameters::callback([&](double) { return ++calls < 2; }));
  EXPECT_FALSE(done);
  EXPECT_EQ(K.rows(), 3);
  EXPECT_EQ(K.coeff(1, 1), 5.0);
}

TEST(Laplacian, BadInputThrowsAClearError)
{
  Sparse K;
  const std::vector<Point> empty;
  EXPECT_THROW(compute_point_set_laplacian(empty, 3, {}, K), Invalid_input);
  auto pts = random_points(10, 7);
  EXPECT_THROW(compute_point_set_laplacian(pts, 10, {}, K), Invalid_input); // k must be < n
  EXPECT_THROW(compute_point_set_laplacian(pts, 0, {}, K), Invalid_input);
  pts[4] = Point(0, std::numeric_limits<double>::quiet_NaN(), 0);
  try {
    compute_point_set_laplacian(pts, 3, {}, K);
    FAIL() << "NaN accepted";
  } catch(const Invalid_input& e) {
    EXPECT_NE(std::string(e.what()).find("#4"), std::string::npos) << e.what();
  }
}
