// The neighbour graphs of internal/Neighbor_graph.h against brute force.
#include <CGAL_ext/internal/Neighbor_graph.h>

#include <CGAL/tags.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

using namespace CGAL_ext::internal;

namespace {

Matrix_n3 random_cloud(std::size_t n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Matrix_n3 m(Eigen::Index(n), 3);
  for(std::size_t i = 0; i < n; ++i) m.row(Eigen::Index(i)) << u(rng), u(rng), u(rng);
  return m;
}

} // namespace

TEST(NeighborGraph, KNearestAreTheBruteForceNearestInOrder)
{
  const Matrix_n3 points = random_cloud(400, 1);
  const std::size_t k = 8;
  Progress progress;
  const Neighbor_graph graph = k_nearest_neighbor_graph<CGAL::Parallel_if_available_tag>(points, k, progress);
  ASSERT_EQ(graph.size(), 400u);
  for(std::size_t i = 0; i < graph.size(); ++i) {
    std::vector<std::pair<double, int>> all;
    for(Eigen::Index j = 0; j < points.rows(); ++j)
      if(j != Eigen::Index(i)) all.emplace_back((points.row(j) - points.row(Eigen::Index(i))).squaredNorm(), int(j));
    std::sort(all.begin(), all.end());
    ASSERT_EQ(graph.degree(i), int(k));
    for(std::size_t m = 0; m < k; ++m) EXPECT_EQ(graph.begin(i)[m], all[m].second) << "point " << i << ", neighbour " << m;
  }
}

TEST(NeighborGraph, SymmetrizeIsTheUnionOfTheGraphAndItsTranspose)
{
  const Matrix_n3 points = random_cloud(300, 2);
  Progress progress;
  const Neighbor_graph directed = k_nearest_neighbor_graph<CGAL::Sequential_tag>(points, 6, progress);
  const Neighbor_graph graph = symmetrize<CGAL::Parallel_if_available_tag>(directed);
  std::set<std::pair<int, int>> expected;
  for(std::size_t i = 0; i < directed.size(); ++i)
    for(const int* j = directed.begin(i); j != directed.end(i); ++j) {
      expected.emplace(int(i), *j);
      expected.emplace(*j, int(i));
    }
  std::set<std::pair<int, int>> got;
  for(std::size_t i = 0; i < graph.size(); ++i) {
    EXPECT_TRUE(std::is_sorted(graph.begin(i), graph.end(i)));
    EXPECT_EQ(std::adjacent_find(graph.begin(i), graph.end(i)), graph.end(i)); // no duplicate
    for(const int* j = graph.begin(i); j != graph.end(i); ++j) {
      EXPECT_NE(*j, int(i));
      got.emplace(int(i), *j);
    }
  }
  EXPECT_EQ(got, expected);
}

TEST(NeighborGraph, ParallelAndSequentialBuildsAreIdentical)
{
  const Matrix_n3 points = random_cloud(2000, 3);
  Progress progress;
  const Neighbor_graph a = symmetrize<CGAL::Sequential_tag>(k_nearest_neighbor_graph<CGAL::Sequential_tag>(points, 10, progress));
  const Neighbor_graph b = symmetrize<CGAL::Parallel_if_available_tag>(k_nearest_neighbor_graph<CGAL::Parallel_if_available_tag>(points, 10, progress));
  EXPECT_EQ(a.offsets, b.offsets);
  EXPECT_EQ(a.indices, b.indices);
}

TEST(NeighborGraph, TheCountOfNeighboursMustBeBelowThePoints)
{
  EXPECT_THROW(check_neighbor_count(0, 10, "test"), CGAL_ext::Invalid_input);
  EXPECT_THROW(check_neighbor_count(10, 10, "test"), CGAL_ext::Invalid_input);
  EXPECT_NO_THROW(check_neighbor_count(9, 10, "test"));
}
