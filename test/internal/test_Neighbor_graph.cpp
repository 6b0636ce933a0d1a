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

namespace {

// The k nearest samples of a query by brute force, ties broken by row.
std::vector<int> brute_force_nearest(const Matrix_n3& samples, const Eigen::RowVector3d& query, std::size_t k)
{
  std::vector<std::pair<double, int>> all;
  for(Eigen::Index j = 0; j < samples.rows(); ++j) all.emplace_back((samples.row(j) - query).squaredNorm(), int(j));
  std::sort(all.begin(), all.end());
  std::vector<int> nearest;
  for(std::size_t m = 0; m < k; ++m) nearest.push_back(all[m].second);
  return nearest;
}

} // namespace

TEST(NeighborGraph, NearestSamplesByOwnerAreTheBruteForceNearestForAnyOwner)
{
  Matrix_n3 samples = random_cloud(300, 3), queries = random_cloud(3000, 4);
  samples.row(7) = samples.row(3); // coincident samples: a tie the rows break
  queries.row(0) = samples.row(5);
  const std::size_t k = 7;
  // Owners as a clustering gives them (the nearest sample), and arbitrary ones (far from their queries).
  std::vector<int> nearest_owner(3000), any_owner(3000);
  std::mt19937 rng(5);
  for(std::size_t q = 0; q < 3000; ++q) {
    nearest_owner[q] = brute_force_nearest(samples, queries.row(Eigen::Index(q)), 1)[0];
    any_owner[q] = int(rng() % 300);
  }
  for(const auto* owner : {&nearest_owner, &any_owner}) {
    const Neighbor_graph graph =
      k_nearest_samples_by_owner<CGAL::Parallel_if_available_tag>(samples, queries, *owner, k);
    ASSERT_EQ(graph.size(), 3000u);
    for(std::size_t q = 0; q < graph.size(); ++q) {
      ASSERT_EQ(graph.degree(q), int(k));
      const std::vector<int> expected = brute_force_nearest(samples, queries.row(Eigen::Index(q)), k);
      EXPECT_EQ(std::vector<int>(graph.begin(q), graph.end(q)), expected) << "query " << q;
    }
  }
  // And the tree's queries find the same rows but at ties.
  const Neighbor_graph by_tree = k_nearest_samples<CGAL::Sequential_tag>(samples, queries, k);
  const Neighbor_graph by_owner = k_nearest_samples_by_owner<CGAL::Sequential_tag>(samples, queries, nearest_owner, k);
  for(std::size_t e = 0; e < by_tree.indices.size(); ++e) {
    const Eigen::RowVector3d query = queries.row(Eigen::Index(e / k));
    EXPECT_EQ((samples.row(by_tree.indices[e]) - query).squaredNorm(),
              (samples.row(by_owner.indices[e]) - query).squaredNorm());
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
