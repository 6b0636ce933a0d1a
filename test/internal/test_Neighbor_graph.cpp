// The neighbour graphs of internal/Neighbor_graph.h against brute force.
#include <CGAL_ext/internal/Neighbor_graph.h>

#include "neighborhood_reference.h"
#include "test_support.h"

#include <CGAL/tags.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <string>
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

namespace {

// A 16 x 12 lattice of spacing 1/8 in the plane z = 0 (its distances tie exactly), with `copies` of its first points
// appended again (exact duplicates).
Matrix_n3 lattice_with_duplicates(std::size_t copies)
{
  Matrix_n3 m(Eigen::Index(16 * 12 + copies), 3);
  for(int i = 0; i < 16 * 12; ++i) m.row(i) << (i % 16) / 8.0, (i / 16) / 8.0, 0.0;
  for(std::size_t c = 0; c < copies; ++c) m.row(Eigen::Index(16 * 12 + c)) = m.row(Eigen::Index(c * 7 % (16 * 12)));
  return m;
}

std::vector<int> random_permutation(std::size_t n, unsigned seed)
{
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  return order;
}

} // namespace

TEST(NeighborGraph, RowsHoldTheClosedBallOfTheKthNearestWhateverTheOrder)
{
  const Matrix_n3 points = lattice_with_duplicates(9);
  const std::vector<int> order =
    random_permutation(std::size_t(points.rows()), 7); // permuted row r = points row order[r]
  Matrix_n3 permuted(points.rows(), 3);
  for(Eigen::Index r = 0; r < points.rows(); ++r) permuted.row(r) = points.row(order[std::size_t(r)]);
  Progress progress;
  for(const std::size_t k : {4u, 6u, 10u, 17u}) {
    const Neighbor_graph graph = k_nearest_neighbor_graph<CGAL::Parallel_if_available_tag>(points, k, progress);
    const Neighbor_graph other = k_nearest_neighbor_graph<CGAL::Sequential_tag>(permuted, k, progress);
    std::size_t wider = 0;
    for(std::size_t i = 0; i < graph.size(); ++i) {
      ASSERT_EQ(std::vector<int>(graph.begin(i), graph.end(i)), brute_force_ball(points, i, k))
        << "k " << k << ", row " << i;
      wider += graph.degree(i) > int(k);
    }
    if(k != 4) { // the lattice's four nearest are never tied with a fifth but at its border
      EXPECT_GT(wider, graph.size() / 2) << "the lattice ties at the k-th distance for most points, k " << k;
    }
    for(std::size_t r = 0; r < other.size(); ++r) {
      std::vector<int> mapped;
      for(const int* j = other.begin(r); j != other.end(r); ++j) mapped.push_back(order[std::size_t(*j)]);
      std::sort(mapped.begin(), mapped.end());
      const std::size_t i = std::size_t(order[r]);
      std::vector<int> expected(graph.begin(i), graph.end(i));
      std::sort(expected.begin(), expected.end());
      ASSERT_EQ(mapped, expected) << "k " << k << ", row " << i;
    }
    // A smaller k's balls cut from these rows are that k's graph.
    const Neighbor_graph cut = nearest_prefix(graph, points, k / 2);
    const Neighbor_graph direct = k_nearest_neighbor_graph<CGAL::Sequential_tag>(points, k / 2, progress);
    EXPECT_EQ(cut.offsets, direct.offsets);
    EXPECT_EQ(cut.indices, direct.indices);
  }
}

TEST(NeighborGraph, NearestAreTheNearestRankedByDistanceAndRow)
{
  const Matrix_n3 points = lattice_with_duplicates(9);
  const Position_tree tree(points, CGAL::Sequential_tag());
  for(const std::size_t k : {1u, 3u, 5u, 9u, 13u})
    for(Eigen::Index q = 0; q < points.rows(); q += 5) {
      // Queries at lattice points and halfway between four of them (four ties for the nearest).
      for(const double shift : {0.0, 1.0 / 16}) {
        const Eigen::RowVector3d query = points.row(q) + Eigen::RowVector3d(shift, shift, 0);
        std::vector<Ranked_row> got;
        tree.nearest(Position_tree::Point(query(0), query(1), query(2)), k,
                     [&](int j, double d2) { got.emplace_back(d2, j); });
        const std::vector<int> expected = brute_force_nearest(points, query, k);
        ASSERT_EQ(got.size(), k);
        EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
        for(std::size_t m = 0; m < k; ++m) // the same distances; at the k-th, any of the tied rows
          EXPECT_EQ(got[m].first, (points.row(expected[m]) - query).squaredNorm()) << "k " << k << ", query " << q;
      }
    }
}

TEST(NeighborGraph, APileOfDuplicatesIsRefusedByName)
{
  Matrix_n3 points = random_cloud(100, 9);
  points.conservativeResize(100 + 300, 3);
  for(Eigen::Index i = 100; i < 400; ++i) points.row(i) << 0.25, 0.5, 0.125;
  Progress progress;
  const std::string message = thrown_message<CGAL_ext::Invalid_input>(
    [&] { k_nearest_neighbor_graph<CGAL::Parallel_if_available_tag>(points, 10, progress); });
  EXPECT_NE(message.find("(0.25, 0.5, 0.125)"), std::string::npos) << message;
  EXPECT_NE(message.find("duplicate"), std::string::npos) << message;
  // A pile as large as the rule allows is taken whole.
  points.conservativeResize(100 + 200, 3);
  const Neighbor_graph graph = k_nearest_neighbor_graph<CGAL::Parallel_if_available_tag>(points, 10, progress);
  EXPECT_EQ(graph.degree(150), 199);
}

TEST(NeighborGraph, TheSpatialOrderIsTheSameWhateverTheCallersOrder)
{
  using SC_point = CGAL::Simple_cartesian<double>::Point_3;
  const Matrix_n3 points = lattice_with_duplicates(30);
  const std::vector<int> order = random_permutation(std::size_t(points.rows()), 11);
  std::vector<SC_point> original, permuted;
  for(Eigen::Index r = 0; r < points.rows(); ++r) {
    original.emplace_back(points(r, 0), points(r, 1), 0.25 * points(r, 0) * points(r, 1));
    const int i = order[std::size_t(r)];
    permuted.emplace_back(points(i, 0), points(i, 1), 0.25 * points(i, 0) * points(i, 1));
  }
  const Spatial_point_cloud a = sort_spatially<CGAL::Parallel_if_available_tag>(original, "test");
  const Spatial_point_cloud b = sort_spatially<CGAL::Sequential_tag>(permuted, "test");
  EXPECT_EQ(a.positions, b.positions);
  // Coinciding points stand one after another (then which of them is which changes no sum over rows).
  std::map<std::array<double, 3>, std::vector<Eigen::Index>> rows_of;
  for(Eigen::Index r = 0; r < a.positions.rows(); ++r)
    rows_of[{a.positions(r, 0), a.positions(r, 1), a.positions(r, 2)}].push_back(r);
  std::size_t groups = 0;
  for(const auto& entry : rows_of) {
    EXPECT_EQ(entry.second.back() - entry.second.front() + 1, Eigen::Index(entry.second.size()));
    groups += entry.second.size() > 1;
  }
  EXPECT_EQ(groups, 30u);
}
