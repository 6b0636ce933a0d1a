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
        for(std::size_t m = 0; m < k; ++m) { // at the k-th distance too, the lowest of the tied rows
          EXPECT_EQ(got[m].second, expected[m]) << "k " << k << ", query " << q;
          EXPECT_EQ(got[m].first, (points.row(expected[m]) - query).squaredNorm()) << "k " << k << ", query " << q;
        }
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

namespace {

// A sphere sampled along a Fibonacci spiral, its upper half four times as densely, with exact duplicates and a few
// points far off it, moved by `offset`, in spatial order as the library's calls have them; `pile` more copies of
// its first point.
Matrix_n3 uneven_sphere_in_spatial_order(std::size_t n, const Eigen::RowVector3d& offset = Eigen::RowVector3d::Zero(),
                                         std::size_t pile = 0)
{
  using SC_point = CGAL::Simple_cartesian<double>::Point_3;
  std::vector<SC_point> points;
  const double golden = 3.14159265358979323846 * (3 - std::sqrt(5.0));
  for(std::size_t i = 0; i < n; ++i) {
    const double z = 1 - 2 * (double(i) + 0.5) / double(n), r = std::sqrt(1 - z * z);
    if(z < 0 && i % 4 != 0) continue;
    points.emplace_back(offset(0) + r * std::cos(golden * double(i)), offset(1) + r * std::sin(golden * double(i)),
                        offset(2) + z);
  }
  for(std::size_t c = 0; c < 40; ++c) points.push_back(points[c * 131 % points.size()]);
  for(int c = 0; c < 5; ++c) points.emplace_back(offset(0) + 3.0 + c, offset(1) - 2.0 * c, offset(2) + 7.5);
  for(std::size_t c = 0; c < pile; ++c) points.push_back(points[0]);
  return sort_spatially<CGAL::Parallel_if_available_tag>(points, "test").positions;
}

// Each row's closed ball as the kd-tree alone finds it.
std::vector<std::vector<int>> tree_balls(const Matrix_n3& points, std::size_t k)
{
  const Position_tree tree(points, CGAL::Sequential_tag());
  std::vector<std::vector<int>> balls(std::size_t(points.rows()));
  std::vector<Ranked_row> ball;
  for(std::size_t i = 0; i < balls.size(); ++i) {
    tree.nearest_ball(i, k, ball);
    for(const Ranked_row& entry : ball) balls[i].push_back(entry.second);
  }
  return balls;
}

} // namespace

// The grid's blocks answer most rows of a sampled surface, and each ball a block certifies is the brute-force
// ball; the graph (grid, wider blocks and tree together) is every row's tree ball.
TEST(NeighborGraph, GridBlocksCertifyTheBallsOfASampledSurface)
{
  const Matrix_n3 points = uneven_sphere_in_spatial_order(40000);
  const std::size_t n = std::size_t(points.rows());
  Progress progress;
  for(const std::size_t k : {6u, 15u}) {
    const Cell_grid grid(points, grid_cell_size(points, k));
    Cell_grid::Block block;
    Ball_scratch scratch;
    std::vector<Ranked_row> ball;
    std::size_t certified[2] = {0, 0}; // by the block of 3 x 3 x 3 cells, then by that of 5 x 5 x 5
    // Balls checked against brute force: fewer under the sanitizers, where each costs a hundred times more.
    const int checked_every = TEST_WITH_ADDRESS_SANITIZER ? 113 : 23;
    for(std::size_t c = 0; c < grid.cell_count(); ++c)
      for(int at = grid.first(c); at < grid.first(c + 1); ++at) {
        const double p[3] = {grid.x()[at], grid.y()[at], grid.z()[at]};
        const int row = grid.rows()[std::size_t(at)];
        for(int reach = 1; reach <= 2; ++reach) {
          ASSERT_TRUE(grid.gather(c, reach, n, block));
          if(!nearest_ball_in_block(block, grid.margin(), p, row, k, scratch, ball)) continue;
          ++certified[reach - 1];
          if(row % checked_every == 0) {
            std::vector<int> rows;
            for(const Ranked_row& entry : ball) rows.push_back(entry.second);
            ASSERT_EQ(rows, brute_force_ball(points, std::size_t(row), k)) << "k " << k << ", row " << row;
          }
          break;
        }
      }
    // The cell size fits the denser half; most of the sparser half's balls reach past the smaller block.
    EXPECT_GT(certified[0], n * 3 / 4) << "k " << k;
    EXPECT_GT(certified[0] + certified[1], n * 99 / 100) << "k " << k;
    EXPECT_LT(certified[0] + certified[1], n) << "the points off the sphere lie past their blocks, k " << k;

    const Neighbor_graph graph = k_nearest_neighbor_graph<CGAL::Parallel_if_available_tag>(points, k, progress);
    const std::vector<std::vector<int>> expected = tree_balls(points, k);
    for(std::size_t i = 0; i < n; ++i)
      ASSERT_EQ(std::vector<int>(graph.begin(i), graph.end(i)), expected[i]) << "k " << k << ", row " << i;
  }
}

// Far from the origin (where the binning's rounding is largest), on one thread or several, the graph is the tree's;
// a pile of duplicates that a block of cells holds is refused as the tree refuses it.
TEST(NeighborGraph, TheGridsGraphIsTheTreesFarFromTheOriginOnAnyThreadsAndRefusesAPile)
{
  const std::size_t k = 15;
  Progress progress;
  const Matrix_n3 points = uneven_sphere_in_spatial_order(20000, Eigen::RowVector3d(1e7, -3e6, 5e5));
  const Neighbor_graph parallel = k_nearest_neighbor_graph<CGAL::Parallel_if_available_tag>(points, k, progress);
  const Neighbor_graph sequential = k_nearest_neighbor_graph<CGAL::Sequential_tag>(points, k, progress);
  EXPECT_EQ(parallel.offsets, sequential.offsets);
  EXPECT_EQ(parallel.indices, sequential.indices);
  const std::vector<std::vector<int>> expected = tree_balls(points, k);
  for(std::size_t i = 0; i < expected.size(); ++i)
    ASSERT_EQ(std::vector<int>(parallel.begin(i), parallel.end(i)), expected[i]) << "row " << i;

  // 300 coinciding points, more than k + max_tied_neighbors, in a block of fewer than 32 (k + 1) points.
  const Matrix_n3 piled = uneven_sphere_in_spatial_order(20000, Eigen::RowVector3d::Zero(), 300);
  const std::string message = thrown_message<CGAL_ext::Invalid_input>(
    [&] { k_nearest_neighbor_graph<CGAL::Parallel_if_available_tag>(piled, k, progress); });
  EXPECT_NE(message.find("duplicate"), std::string::npos) << message;
}

// A block holding more candidates than asked gathers nothing (such rows go to the tree).
TEST(NeighborGraph, AGridBlockRefusesMoreCandidatesThanAsked)
{
  const Matrix_n3 points = lattice_with_duplicates(9);
  const Cell_grid grid(points, 0.3);
  Cell_grid::Block block;
  const std::size_t cell = grid.cell_of_row(100);
  ASSERT_TRUE(grid.gather(cell, 1, std::size_t(points.rows()), block));
  const std::size_t all = block.size();
  EXPECT_GT(all, 9u);
  EXPECT_FALSE(grid.gather(cell, 1, all - 1, block));
  EXPECT_EQ(block.size(), 0u);
  EXPECT_TRUE(grid.gather(cell, 1, all, block));
  EXPECT_EQ(block.size(), all);
}

namespace {

// Every pair (squared distance, row) of the `k` rows a search reports, in its order.
template <typename Search>
std::vector<Ranked_row> reported(std::size_t k, const Search& search)
{
  std::vector<Ranked_row> got;
  search(k, [&](int j, double d2) { got.emplace_back(d2, j); });
  return got;
}

// The brute-force ranking of `k` rows by (squared distance, row), ties at the k-th distance included.
void expect_nearest(const Matrix_n3& points, const Eigen::RowVector3d& query, std::size_t k,
                    const std::vector<Ranked_row>& got)
{
  const std::vector<int> expected = brute_force_nearest(points, query, k);
  ASSERT_EQ(got.size(), k);
  for(std::size_t m = 0; m < k; ++m) {
    EXPECT_EQ(got[m].second, expected[m]) << "rank " << m;
    EXPECT_EQ(got[m].first, (points.row(got[m].second) - query).squaredNorm()) << "rank " << m;
  }
}

} // namespace

TEST(NeighborGraph, TheKdTreeRanksByDistanceThenRowAndFindsEveryRowWithinARadius)
{
  // A lattice (exact ties) with duplicates, and a random cloud; every k from 1 to past the tree's switch from a
  // sorted insertion to a heap; queries at rows, between rows and outside the cloud's box.
  for(const Matrix_n3& points : {lattice_with_duplicates(40), random_cloud(700, 5)}) {
    const Row_kd_tree tree(points, CGAL::Parallel_if_available_tag());
    ASSERT_EQ(tree.size(), std::size_t(points.rows()));
    std::vector<Ranked_row> got;
    std::vector<int> within;
    for(Eigen::Index q = 0; q < points.rows(); q += 37)
      for(const Eigen::RowVector3d& shift :
          {Eigen::RowVector3d(0, 0, 0), Eigen::RowVector3d(1.0 / 16, 1.0 / 16, 0), Eigen::RowVector3d(3, -2, 0.5)}) {
        const Eigen::RowVector3d query = points.row(q) + shift;
        std::vector<Ranked_row> expected;
        for(Eigen::Index j = 0; j < points.rows(); ++j)
          expected.emplace_back(
            squared_distance(query(0), query(1), query(2), points(j, 0), points(j, 1), points(j, 2)), int(j));
        std::sort(expected.begin(), expected.end());
        for(std::size_t k = 1; k <= expected.size(); k += k < 20 ? 1 : 37) {
          tree.nearest(query.data(), k, got);
          EXPECT_TRUE(std::equal(got.begin(), got.end(), expected.begin()) && got.size() == k)
            << "k " << k << ", query " << q;
        }
        tree.nearest(query.data(), expected.size() + 5, got);
        EXPECT_EQ(got, expected);
        // Radii at exact lattice distances: the rows at the radius are within it.
        for(const double radius : {0.0, 0.125, 0.25, 0.3}) {
          within.clear();
          tree.within(query.data(), radius, within);
          std::sort(within.begin(), within.end());
          std::vector<int> inside;
          for(const Ranked_row& e : expected)
            if(e.first <= radius * radius) inside.push_back(e.second);
          std::sort(inside.begin(), inside.end());
          EXPECT_EQ(within, inside) << "radius " << radius << ", query " << q;
        }
      }
  }
  // An empty tree and a tree of one row.
  const double origin[3] = {0, 0, 0};
  std::vector<Ranked_row> got{{1.0, 1}};
  std::vector<int> within;
  Row_kd_tree(Matrix_n3(0, 3), CGAL::Sequential_tag()).nearest(origin, 3, got);
  EXPECT_TRUE(got.empty());
  Row_kd_tree(Matrix_n3(0, 3), CGAL::Sequential_tag()).within(origin, 1.0, within);
  EXPECT_TRUE(within.empty());
  const Row_kd_tree one(Matrix_n3::Ones(1, 3), CGAL::Sequential_tag());
  one.nearest(origin, 3, got);
  EXPECT_EQ(got, std::vector<Ranked_row>({{3.0, 0}}));
  one.within(origin, std::sqrt(3.0) * 0.999, within);
  EXPECT_TRUE(within.empty());
}

TEST(NeighborGraph, ATreeOfAppendedRowsAnswersAsATreeOverAllRows)
{
  // A base cloud, then rows appended: a dense cluster, copies of base rows (ties across the two trees) and far rows.
  const Matrix_n3 base = random_cloud(1500, 7);
  Matrix_n3 appended = 0.1 * random_cloud(300, 8);
  for(Eigen::Index r = 0; r < 40; ++r) appended.row(r) = base.row(r * 13);
  for(Eigen::Index r = 40; r < 45; ++r) appended.row(r) << 5.0 + double(r), 0, 0;
  Matrix_n3 all(base.rows() + appended.rows(), 3);
  all << base, appended;
  const Position_tree base_tree(base, CGAL::Parallel_if_available_tag());
  const Position_tree extended(base_tree, appended, CGAL::Parallel_if_available_tag());
  const Position_tree whole(all, CGAL::Sequential_tag());
  ASSERT_EQ(extended.size(), whole.size());
  std::mt19937 rng(9);
  std::uniform_int_distribution<Eigen::Index> row(0, all.rows() - 1);
  for(int q = 0; q < 200; ++q) {
    const Eigen::RowVector3d query = all.row(row(rng)) + 0.01 * Eigen::RowVector3d(q % 3, q % 5, q % 7);
    const Position_tree::Point at(query(0), query(1), query(2));
    for(const std::size_t k : {1u, 12u, 126u, 2000u})
      expect_nearest(all, query, std::min<std::size_t>(k, all.rows()),
                     reported(k, [&](std::size_t count, const auto& visit) { extended.nearest(at, count, visit); }));
    std::vector<int> near, expected;
    extended.within(at, 0.3, near);
    whole.within(at, 0.3, expected);
    std::sort(near.begin(), near.end());
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(near, expected);
  }
  // Closed balls are a function of the positions: the same sets as over all rows, duplicates across the trees included.
  std::vector<Ranked_row> ball, expected_ball;
  for(std::size_t self = 0; self < std::size_t(all.rows()); self += 7) {
    extended.nearest_ball(self, 10, ball);
    whole.nearest_ball(self, 10, expected_ball);
    EXPECT_EQ(ball, expected_ball) << "row " << self;
  }
  // Nothing appended: the base's answers.
  const Position_tree nothing_appended(base_tree, Matrix_n3(0, 3), CGAL::Sequential_tag());
  const Eigen::RowVector3d query = base.row(3);
  expect_nearest(base, query, 12, reported(12, [&](std::size_t count, const auto& visit) {
                   nothing_appended.nearest(Position_tree::Point(query(0), query(1), query(2)), count, visit);
                 }));
}

TEST(NeighborGraph, MovingNeighborsAreTheTreesNearestAtEveryStep)
{
  // Points walking over a cloud in steps of a tenth to twice its spacing, and now and then a jump across it: at
  // every step the kept candidates, or a fresh lookup, give the nearest rows by brute force.
  const Matrix_n3 points = random_cloud(3000, 11);
  const Position_tree tree(points, CGAL::Sequential_tag());
  const double spacing = 2.0 / std::cbrt(3000.0);
  const std::size_t walkers = 40;
  Moving_neighbors near(tree, walkers, 48);
  std::mt19937 rng(12);
  std::normal_distribution<double> step(0, 1);
  std::vector<Eigen::Vector3d> x(walkers);
  for(std::size_t w = 0; w < walkers; ++w) x[w] = points.row(Eigen::Index(w * 71)).transpose();
  for(int s = 0; s < 30; ++s)
    for(std::size_t w = 0; w < walkers; ++w) {
      const double length = s % 10 == 9 ? 1.0 : spacing * (0.1 + 1.9 * double(w) / walkers);
      x[w] += length * Eigen::Vector3d(step(rng), step(rng), step(rng)).normalized();
      const std::size_t k = s % 2 ? 24 : 12;
      expect_nearest(points, x[w].transpose(), k,
                     reported(k, [&](std::size_t count, const auto& visit) { near.nearest(w, x[w], count, visit); }));
    }
  const std::size_t lookups = near.lookups();
  EXPECT_GT(lookups, walkers); // the jumps and the long steps asked the tree again
  // Steps of a hundredth of a spacing are answered from the kept rows: no lookup.
  for(int s = 0; s < 5; ++s)
    for(std::size_t w = 0; w < walkers; ++w) {
      x[w] += 0.01 * spacing * Eigen::Vector3d(step(rng), step(rng), step(rng)).normalized();
      expect_nearest(points, x[w].transpose(), 12,
                     reported(12, [&](std::size_t count, const auto& visit) { near.nearest(w, x[w], count, visit); }));
    }
  EXPECT_LE(near.lookups(), lookups + walkers / 10);
  // Fewer rows than the reach: every row is a candidate, and every step is certain.
  const Matrix_n3 few = random_cloud(20, 13);
  const Position_tree few_tree(few, CGAL::Sequential_tag());
  Moving_neighbors near_few(few_tree, 1, 48);
  Eigen::Vector3d at(0, 0, 0);
  for(int s = 0; s < 5; ++s, at.x() += 0.5)
    expect_nearest(few, at.transpose(), 20,
                   reported(30, [&](std::size_t count, const auto& visit) { near_few.nearest(0, at, count, visit); }));
  EXPECT_EQ(near_few.lookups(), 1u);
}
