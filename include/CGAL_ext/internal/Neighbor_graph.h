// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_NEIGHBOR_GRAPH_H
#define CGAL_EXT_INTERNAL_NEIGHBOR_GRAPH_H

#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Cell_grid.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/Row_kd_tree.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <sstream>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// A neighbour graph in compressed sparse row form: the neighbours of vertex i are
/// `indices[offsets[i] .. offsets[i+1])`. Indices are `int`, Eigen's sparse storage index, so the arrays
/// feed a sparse matrix without conversion.
struct Neighbor_graph
{
  std::vector<int> offsets{0};
  std::vector<int> indices;

  std::size_t size() const { return offsets.size() - 1; }
  int degree(std::size_t i) const { return offsets[i + 1] - offsets[i]; }
  const int* begin(std::size_t i) const { return indices.data() + offsets[i]; }
  const int* end(std::size_t i) const { return indices.data() + offsets[i + 1]; }
};

/// Throws unless 0 < k < n (k counts neighbours, the point itself not included).
inline void check_neighbor_count(std::size_t k, std::size_t n, const char* who)
{
  if(k == 0 || k >= n) {
    std::ostringstream os;
    os << who << ": the number of neighbours k = " << k << " must be at least 1 and smaller than the number of points ("
       << n << ")";
    throw Invalid_input(os.str());
  }
}

/// A kd-tree over the rows of a position array (Row_kd_tree), or over those of another tree followed by rows
/// of its own: nearest-neighbour queries that report row indices, ranked by (squared distance, row); a closed
/// ball of the k-th nearest depends on the positions alone (doc/design.md, "One neighbourhood rule").
class Position_tree
{
  using SC = CGAL::Simple_cartesian<double>;

  // The radius of a range search that must take in the rows at a squared distance: larger by this relative
  // margin, for the rounding of the square root.
  static constexpr double tie_margin = 1e-12;

public:
  using Point = SC::Point_3;

  static Point point(const Matrix_n3& positions, Eigen::Index i)
  {
    return Point(positions(i, 0), positions(i, 1), positions(i, 2));
  }

  static double squared_distance(const Point& a, const Point& b)
  {
    return internal::squared_distance(a.x(), a.y(), a.z(), b.x(), b.y(), b.z());
  }

  template <typename ConcurrencyTag>
  explicit Position_tree(const Matrix_n3& positions, ConcurrencyTag tag)
      : m_points(std::size_t(positions.rows())), m_tree(positions, tag)
  {
    for(std::size_t i = 0; i < m_points.size(); ++i) m_points[i] = point(positions, Eigen::Index(i));
  }

  /// A tree over the rows of `base` followed by those of `appended` (rows `base.size()` on), built over the
  /// appended rows only: `base` must outlive it.
  template <typename ConcurrencyTag>
  Position_tree(const Position_tree& base, const Matrix_n3& appended, ConcurrencyTag tag) : Position_tree(appended, tag)
  {
    m_base = &base;
    m_first_own_row = base.size();
  }

  std::size_t size() const { return m_first_own_row + m_points.size(); }
  const Point& operator[](std::size_t i) const
  {
    return i < m_first_own_row ? (*m_base)[i] : m_points[i - m_first_own_row];
  }

  /// Calls `visit(row, squared_distance)` for the `min(k, size())` rows nearest to `query` in the order
  /// (squared distance, row), nearest first: of rows tied at the k-th distance, those of the lowest rows. With
  /// `bound`, only rows at most at that squared distance.
  template <typename Visit>
  void nearest(const Point& query, std::size_t k, const Visit& visit,
               double bound = std::numeric_limits<double>::infinity()) const
  {
    thread_local std::vector<Ranked_row> found;
    search(query, std::min(k, size()), found, bound);
    for(const Ranked_row& entry : found) visit(entry.second, entry.first);
  }

  /// `out` = the closed ball of row `self`'s k-th nearest other row: every other row whose squared distance is at
  /// most the k-th smallest (all rows tied there included, so exact duplicates are taken or left together), in the
  /// order (squared distance, row). `k < size()`.
  void nearest_ball(std::size_t self, std::size_t k, std::vector<Ranked_row>& out) const
  {
    const Point& query = (*this)[self];
    const auto drop_self = [&] {
      out.erase(std::remove(out.begin(), out.end(), Ranked_row(0.0, int(self))), out.end());
    };
    search(query, std::min(k + 2, size()), out); // the point itself, k others and one to see a tie
    drop_self();
    if(out.size() > k && out[k].first <= out[k - 1].first) {
      gather_ties(query, out[k - 1].first, out);
      drop_self();
    }
    const double kth = out[k - 1].first;
    std::size_t end = k;
    while(end < out.size() && out[end].first <= kth) ++end;
    out.resize(end);
  }

  /// Appends to `out` the rows within `radius` of `centre`.
  void within(const Point& centre, double radius, std::vector<int>& out) const
  {
    if(m_base) m_base->within(centre, radius, out);
    const std::size_t first = out.size();
    m_tree.within(coordinates(centre).data(), radius, out);
    for(std::size_t i = first; i < out.size(); ++i) out[i] += int(m_first_own_row);
  }

private:
  static std::array<double, 3> coordinates(const Point& p) { return {p.x(), p.y(), p.z()}; }

  // The tree's `count` nearest to `query`, ranked; with `bound`, only those at most at that squared distance.
  void search(const Point& query, std::size_t count, std::vector<Ranked_row>& out,
              double bound = std::numeric_limits<double>::infinity()) const
  {
    if(!m_base) {
      m_tree.nearest(coordinates(query).data(), count, out, bound);
      return;
    }
    // The base's nearest first, then the appended rows': only those within the base's count-th distance can be
    // among the nearest.
    m_base->search(query, std::min(count, m_base->size()), out, bound);
    thread_local std::vector<Ranked_row> own;
    m_tree.nearest(coordinates(query).data(), count, own, count > 0 && out.size() == count ? out.back().first : bound);
    const std::size_t first = out.size();
    for(const Ranked_row& entry : own) out.emplace_back(entry.first, entry.second + int(m_first_own_row));
    if(first > 0 && first < out.size()) { // the base's nearest and the appended rows' nearest: merged, cut to count
      thread_local std::vector<Ranked_row> merged;
      merged.clear();
      for(std::size_t a = 0, b = first; merged.size() < count && (a < first || b < out.size());)
        merged.push_back(b == out.size() || (a < first && out[a] < out[b]) ? out[a++] : out[b++]);
      out.swap(merged);
    }
  }

  // Replaces `out` by every row at most at `kth` (a squared distance), ranked: the rows tied with the k-th that a
  // search for k + 1 leaves out.
  void gather_ties(const Point& query, double kth, std::vector<Ranked_row>& out) const
  {
    thread_local std::vector<int> rows;
    rows.clear();
    within(query, std::sqrt(kth) * (1 + tie_margin), rows);
    out.clear();
    for(const int row : rows) {
      const double d2 = squared_distance(query, (*this)[std::size_t(row)]);
      if(d2 <= kth) out.emplace_back(d2, row);
    }
    std::sort(out.begin(), out.end());
  }

  std::vector<Point> m_points;
  Row_kd_tree m_tree;
  const Position_tree* m_base = nullptr; // the rows before m_first_own_row
  std::size_t m_first_own_row = 0;
};

/// The nearest rows of a tree to points that move a little at a time (the new samples during relaxation): each
/// point keeps the `reach` rows nearest to where it was last looked up, and its `k` <= `reach` nearest are taken
/// from them while that is certain, that is, while the k-th of them is nearer to it than the reach-th was to the
/// old place less the distance moved (then no other row can be nearer); otherwise the tree is asked again. The
/// answer is the tree's, ranked by (squared distance, row), for `reach` distances and a partial sort where a step
/// is certain. It keeps `reach` rows and an anchor per point (about 4 reach + 32 bytes).
class Moving_neighbors
{
public:
  /// For `points` moving points, each to keep its `reach` nearest rows of `tree` (which must outlive this).
  Moving_neighbors(const Position_tree& tree, std::size_t points, std::size_t reach)
      : m_tree(tree), m_reach(std::min(reach, tree.size())), m_anchor(points), m_radius(points, -1.0),
        m_candidates(points * m_reach)
  {}

  /// Calls `visit(row, squared_distance)` for the `k` rows nearest to `x`, the position of point `point` now.
  template <typename Visit>
  void nearest(std::size_t point, const Eigen::Vector3d& x, std::size_t k, const Visit& visit)
  {
    thread_local std::vector<Ranked_row> ranked;
    assert(k <= m_reach || m_reach == m_tree.size());
    k = std::min(k, m_reach);
    if(k == 0) return;
    const Position_tree::Point at(x.x(), x.y(), x.z());
    int* candidates = m_candidates.data() + point * m_reach;
    if(m_radius[point] >= 0) {
      // The rows are kept in the order of the last ranking and the point moved little since: an insertion sort
      // ranks them again in about one pass.
      ranked.resize(m_reach);
      for(std::size_t c = 0; c < m_reach; ++c) {
        const Ranked_row row(Position_tree::squared_distance(at, m_tree[std::size_t(candidates[c])]), candidates[c]);
        std::size_t e = c;
        for(; e > 0 && row < ranked[e - 1]; --e) ranked[e] = ranked[e - 1];
        ranked[e] = row;
      }
      for(std::size_t c = 0; c < m_reach; ++c) candidates[c] = ranked[c].second;
      const double moved = (x - m_anchor[point]).norm();
      // A relative margin for the rounding of the distances.
      if(std::sqrt(ranked[k - 1].first) + moved < m_radius[point] * (1 - 1e-9)) {
        for(std::size_t c = 0; c < k; ++c) visit(ranked[c].second, ranked[c].first);
        return;
      }
    }
    ranked.clear();
    m_tree.nearest(at, m_reach, [&](int j, double d2) { ranked.emplace_back(d2, j); });
    assert(ranked.size() == m_reach);
    ++m_lookups;
    for(std::size_t c = 0; c < m_reach; ++c) candidates[c] = ranked[c].second;
    m_anchor[point] = x;
    // All the rows taken: every later step is certain.
    m_radius[point] =
      m_reach < m_tree.size() ? std::sqrt(ranked.back().first) : std::numeric_limits<double>::infinity();
    for(std::size_t c = 0; c < k; ++c) visit(ranked[c].second, ranked[c].first);
  }

  /// How many rows each point keeps.
  std::size_t reach() const { return m_reach; }

  /// How often the tree was asked (for the tests).
  std::size_t lookups() const { return m_lookups.load(); }

private:
  const Position_tree& m_tree;
  std::size_t m_reach;
  std::atomic<std::size_t> m_lookups{0};
  std::vector<Eigen::Vector3d> m_anchor;
  std::vector<double> m_radius; // < 0: not looked up yet
  std::vector<int> m_candidates;
};

/// A graph of `n` rows of `k` neighbours each, to be filled.
inline Neighbor_graph fixed_degree_graph(std::size_t n, std::size_t k)
{
  Neighbor_graph graph;
  graph.offsets.resize(n + 1);
  for(std::size_t i = 0; i <= n; ++i) graph.offsets[i] = int(i * k);
  graph.indices.resize(n * k);
  return graph;
}

/// How many rows past k a neighbourhood may take in for ties at the k-th distance before the points are refused
/// as a pile of duplicates (whose neighbourhoods would grow with the square of the pile).
constexpr std::size_t max_tied_neighbors = 256;

/// The cell size of the grid that answers a k-nearest graph: on a sampled surface a little more than the distance
/// of a point's k-th nearest other point, from the median distance between consecutive distinct rows (in spatial
/// order mostly near neighbours) and the area a ball of k + 1 points covers (doc/editing_at_scale.md, "The
/// k-nearest graph on a grid"). Only the time depends on it; 0 when it cannot tell (then the tree answers every row).
inline double grid_cell_size(const Matrix_n3& positions, std::size_t k)
{
  std::vector<double> steps;
  for(Eigen::Index i = 0; i + 1 < positions.rows(); i += 4) {
    const double step = std::sqrt(squared_distance(positions(i, 0), positions(i, 1), positions(i, 2),
                                                   positions(i + 1, 0), positions(i + 1, 1), positions(i + 1, 2)));
    if(step > 0) steps.push_back(step); // coinciding points stand one after another
  }
  if(steps.empty()) return 0;
  const auto middle = steps.begin() + std::ptrdiff_t(steps.size() / 2);
  std::nth_element(steps.begin(), middle, steps.end());
  const double size = 0.71 * std::sqrt(double(k + 1)) * *middle;
  const double extent = (positions.colwise().maxCoeff() - positions.colwise().minCoeff()).maxCoeff();
  return std::isfinite(size) && std::isfinite(1 / size) && std::isfinite(extent) ? size : 0;
}

/// What ranking a query's candidates needs besides its result, kept from one query to the next.
struct Ball_scratch
{
  std::vector<double> squared_distances;
  std::vector<int> kept, kept_rows;
  std::vector<double> kept_distances;
  double estimate = 0;  ///< where the ranking starts looking: the last query's k-th squared distance, widened a little
  double cell_size = 0; ///< of the grid the estimate was made on
};

/*
  `ball` = the closed ball of the k-th nearest candidate of `block` other than row `self` at `p`, ranked by (squared
  distance, row), as `Position_tree::nearest_ball` ranks all rows. Returns whether the block certifies it: the
  ball stays inside the block's box by `margin`, so that no point outside the block can belong to it. Only the
  candidates within the scratch's estimate are sorted (widened until k others are in).
*/
inline bool nearest_ball_in_block(const Cell_grid::Block& block, double margin, const double* p, int self,
                                  std::size_t k, Ball_scratch& scratch, std::vector<Ranked_row>& ball)
{
  const std::size_t m = block.size();
  if(m < k + 1) return false;
  scratch.squared_distances.resize(m);
  scratch.kept.resize(m);
  double* d2 = scratch.squared_distances.data();
  int* kept = scratch.kept.data();
  for(std::size_t j = 0; j < m; ++j) d2[j] = squared_distance(p[0], p[1], p[2], block.x[j], block.y[j], block.z[j]);
  double limit = scratch.estimate > 0 ? scratch.estimate : std::numeric_limits<double>::infinity();
  std::size_t count = 0;
  for(;;) {
    count = 0;
    for(std::size_t j = 0; j < m; ++j) kept[count] = int(j), count += d2[j] <= limit; // the query itself among them
    if(count > k) break;
    limit = limit > 1e-100 ? 2 * limit : std::numeric_limits<double>::infinity();
  }
  // The kept others ranked by counting, without branches: in no order as they come, they would make a sort's
  // comparisons mispredict half the time.
  scratch.kept_distances.clear();
  scratch.kept_rows.clear();
  for(std::size_t q = 0; q < count; ++q)
    if(block.rows[std::size_t(kept[q])] != self) {
      scratch.kept_distances.push_back(d2[kept[q]]);
      scratch.kept_rows.push_back(block.rows[std::size_t(kept[q])]);
    }
  const std::size_t others = scratch.kept_rows.size();
  const double* kd = scratch.kept_distances.data();
  const int* kr = scratch.kept_rows.data();
  ball.resize(others);
  for(std::size_t q = 0; q < others; ++q) {
    std::size_t rank = 0;
    for(std::size_t o = 0; o < others; ++o) rank += (kd[o] < kd[q]) | ((kd[o] == kd[q]) & (kr[o] < kr[q]));
    ball[rank] = Ranked_row(kd[q], kr[q]);
  }
  const double kth = ball[k - 1].first;
  if(kth > 0) scratch.estimate = 1.1 * kth;
  std::size_t end = k;
  while(end < ball.size() && ball[end].first <= kth) ++end;
  ball.resize(end);
  double reach = std::numeric_limits<double>::infinity();
  for(int a = 0; a < 3; ++a) reach = std::min({reach, p[a] - block.low[a], block.high[a] - p[a]});
  reach -= margin;
  return reach > 0 && kth < reach * reach;
}

/// Directed k-nearest-neighbour graph under the package's one rule: each row holds the closed ball of its k-th
/// nearest other point (exactly k, more where points tie at that distance), ranked by (distance, row). Each row
/// ranks the points of the block of grid cells around its own, then of a wider block where its ball reaches past
/// it; the kd-tree (Position_tree) answers the rows no block can (doc/editing_at_scale.md, "The k-nearest graph on
/// a grid"). Returns an empty graph when cancelled.
template <typename ConcurrencyTag>
Neighbor_graph k_nearest_neighbor_graph(const Matrix_n3& positions, std::size_t k, Progress& progress)
{
  const std::size_t n = std::size_t(positions.rows());
  Neighbor_graph graph = fixed_degree_graph(n, k);
  // Rows with ties past the k-th: rare but for lattices and duplicates, kept aside and merged after the loop.
  std::mutex tied_mutex;
  std::vector<std::pair<int, std::vector<int>>> tied;
  std::atomic<std::size_t> pile{n};
  const auto keep = [&](std::size_t i, const std::vector<Ranked_row>& ball) {
    int* out = graph.indices.data() + i * k;
    for(std::size_t m = 0; m < k; ++m) out[m] = ball[m].second;
    if(ball.size() == k) return;
    if(ball.size() > k + max_tied_neighbors) {
      for(std::size_t seen = pile.load(); i < seen && !pile.compare_exchange_weak(seen, i);) {}
      return;
    }
    std::vector<int> rest;
    for(std::size_t m = k; m < ball.size(); ++m) rest.push_back(ball[m].second);
    const std::lock_guard<std::mutex> lock(tied_mutex);
    tied.emplace_back(int(i), std::move(rest));
  };
  std::vector<int> unanswered; // rows left to the tree
  const Progress::Range whole = progress.range();
  progress.stage(whole.begin, whole.at(0.9));
  const double cell_size = grid_cell_size(positions, k);
  if(cell_size > 0) {
    const Cell_grid grid(positions, cell_size);
    const std::size_t most_candidates = 32 * (k + 1); // past this a block is a cluster the tree ranks faster
    std::vector<int> wider; // places in the grid whose ball reached past their block of 3 x 3 x 3 cells
    std::mutex left_mutex;
    // Ranks the places of `cells[t]` (or the one place `(*only)[t]` there) in the block of `reach`; the places
    // whose ball leaves the block go to `past`, those in too full a block to the tree.
    const auto rank_in_blocks = [&](const std::vector<std::size_t>& cells, int reach, const std::vector<int>* only,
                                    std::vector<int>& past) {
      return for_each_index<ConcurrencyTag>(cells.size(), progress, [&](std::size_t t) {
        thread_local Cell_grid::Block block;
        thread_local Ball_scratch scratch;
        thread_local std::vector<Ranked_row> ball;
        thread_local std::vector<int> left, full;
        const std::size_t cell = cells[t];
        if(scratch.cell_size != cell_size) // a new grid: about the k-th squared distance its cell size assumes
          scratch.cell_size = cell_size, scratch.estimate = 0.6 * cell_size * cell_size;
        left.clear(), full.clear();
        const bool gathered = grid.gather(cell, reach, most_candidates, block);
        const auto answer = [&](int at) {
          const double p[3] = {grid.x()[at], grid.y()[at], grid.z()[at]};
          const int row = grid.rows()[std::size_t(at)];
          if(!gathered)
            full.push_back(row);
          else if(nearest_ball_in_block(block, grid.margin(), p, row, k, scratch, ball))
            keep(std::size_t(row), ball);
          else
            left.push_back(at);
        };
        if(only)
          answer((*only)[t]);
        else
          for(int at = grid.first(cell); at < grid.first(cell + 1); ++at) answer(at);
        if(left.empty() && full.empty()) return;
        const std::lock_guard<std::mutex> lock(left_mutex);
        past.insert(past.end(), left.begin(), left.end());
        unanswered.insert(unanswered.end(), full.begin(), full.end());
      });
    };
    std::vector<std::size_t> cells(grid.cell_count());
    std::iota(cells.begin(), cells.end(), std::size_t(0));
    if(!rank_in_blocks(cells, 1, nullptr, wider)) return {};
    progress.stage(whole.at(0.9), whole.at(0.95));
    std::sort(wider.begin(), wider.end());
    cells.resize(wider.size());
    for(std::size_t t = 0; t < wider.size(); ++t)
      cells[t] = grid.cell_of_row(std::size_t(grid.rows()[std::size_t(wider[t])]));
    std::vector<int> beyond;
    if(!rank_in_blocks(cells, 2, &wider, beyond)) return {};
    for(const int at : beyond) unanswered.push_back(grid.rows()[std::size_t(at)]);
    std::sort(unanswered.begin(), unanswered.end());
  } else {
    unanswered.resize(n);
    std::iota(unanswered.begin(), unanswered.end(), 0);
  }
  progress.stage(whole.at(0.95), whole.end);
  std::unique_ptr<Position_tree> built; // only where some row needs it
  const auto tree = [&]() -> const Position_tree& {
    if(!built) built = std::make_unique<Position_tree>(positions, ConcurrencyTag());
    return *built;
  };
  if(!unanswered.empty()) {
    const Position_tree& search = tree();
    if(!for_each_index<ConcurrencyTag>(unanswered.size(), progress, [&](std::size_t t) {
         thread_local std::vector<Ranked_row> ball;
         search.nearest_ball(std::size_t(unanswered[t]), k, ball);
         keep(std::size_t(unanswered[t]), ball);
       }))
      return {};
  }
  progress.stage(whole.begin, whole.end);
  if(pile.load() < n) {
    const std::size_t i = pile.load();
    const Position_tree& search = tree();
    std::vector<Ranked_row> ball;
    search.nearest_ball(i, k, ball);
    const Position_tree::Point& p = search[i];
    const Position_tree::Point& tied_with = search[std::size_t(ball[k - 1].second)];
    std::ostringstream os;
    os << ball.size() << " points lie within the distance of the " << k << "-th nearest neighbour of the point ("
       << p.x() << ", " << p.y() << ", " << p.z() << "), (" << tied_with.x() << ", " << tied_with.y() << ", "
       << tied_with.z() << "), all tied at that distance (at most " << k + max_tied_neighbors
       << " are taken): duplicate points pile up there; remove duplicates first";
    throw Invalid_input(os.str());
  }
  if(tied.empty()) return graph;
  std::sort(tied.begin(), tied.end());
  Neighbor_graph wide;
  wide.offsets.resize(n + 1);
  wide.indices.reserve(graph.indices.size() + tied.size());
  auto next = tied.begin();
  for(std::size_t i = 0; i < n; ++i) {
    wide.indices.insert(wide.indices.end(), graph.begin(i), graph.end(i));
    if(next != tied.end() && std::size_t(next->first) == i)
      wide.indices.insert(wide.indices.end(), next->second.begin(), next->second.end()), ++next;
    wide.offsets[i + 1] = int(wide.indices.size());
  }
  return wide;
}

/// The rows of a graph of closed balls (`k_nearest_neighbor_graph` for some k' >= k) cut to the closed balls of
/// their k-th nearest: the first k entries and those tied with the k-th.
inline Neighbor_graph nearest_prefix(const Neighbor_graph& graph, const Matrix_n3& positions, std::size_t k)
{
  const std::size_t n = graph.size();
  const auto d2 = [&](std::size_t i, int j) {
    return squared_distance(positions(Eigen::Index(i), 0), positions(Eigen::Index(i), 1), positions(Eigen::Index(i), 2),
                            positions(j, 0), positions(j, 1), positions(j, 2));
  };
  Neighbor_graph prefix;
  prefix.offsets.resize(n + 1);
  prefix.indices.reserve(n * k);
  prefix.offsets[0] = 0;
  for(std::size_t i = 0; i < n; ++i) {
    int count = std::min(graph.degree(i), int(k));
    if(count > 0) {
      const double kth = d2(i, graph.begin(i)[count - 1]);
      while(count < graph.degree(i) && d2(i, graph.begin(i)[count]) <= kth) ++count;
    }
    prefix.indices.insert(prefix.indices.end(), graph.begin(i), graph.begin(i) + count);
    prefix.offsets[i + 1] = int(prefix.indices.size());
  }
  return prefix;
}

/// Each query row's distance to its last neighbour among the rows of `samples`: in a graph of nearest-first rows,
/// to its k-th nearest.
inline std::vector<double> last_neighbor_distances(const Matrix_n3& queries, const Matrix_n3& samples,
                                                   const Neighbor_graph& nearest_first)
{
  std::vector<double> distances(nearest_first.size(), 0.0);
  for(std::size_t i = 0; i < distances.size(); ++i)
    if(nearest_first.degree(i) > 0)
      distances[i] = (queries.row(Eigen::Index(i)) - samples.row(*(nearest_first.end(i) - 1))).norm();
  return distances;
}

/// For every row of `queries`, its `k` nearest rows of `samples` (`k <= samples.rows()`), nearest first.
template <typename ConcurrencyTag>
Neighbor_graph k_nearest_samples(const Matrix_n3& samples, const Matrix_n3& queries, std::size_t k)
{
  const std::size_t n = std::size_t(queries.rows());
  const Position_tree tree(samples, ConcurrencyTag());
  Neighbor_graph graph = fixed_degree_graph(n, k);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    int* out = graph.indices.data() + i * k;
    tree.nearest(Position_tree::point(queries, Eigen::Index(i)), k, [&](int j, double) { *out++ = j; });
  });
  return graph;
}

/*
  `k_nearest_samples` for queries that each belong to a sample (`owner[q]`, a row of `samples`, such as the
  sample point of the cluster that q belongs to), ties broken by row. The queries of sample s lie within r_s of it, so
  the k nearest of each lie within D_k(s) + r_s of it and within D_k(s) + 2 r_s of s, D_k(s) the distance of
  s to its own k-th nearest sample (itself included): one range query per sample replaces one tree query per
  point, then each query ranks its owner's few candidates. Any `owner` gives the exact answer; one that
  keeps queries near their owners gives few candidates.
*/
template <typename ConcurrencyTag>
Neighbor_graph k_nearest_samples_by_owner(const Matrix_n3& samples, const Matrix_n3& queries,
                                          const std::vector<int>& owner, std::size_t k)
{
  const std::size_t n = std::size_t(queries.rows()), count = std::size_t(samples.rows());
  // The queries of each sample, by counting sort.
  std::vector<int> first(count + 1, 0), members(n);
  for(const int s : owner) ++first[std::size_t(s) + 1];
  for(std::size_t s = 0; s < count; ++s) first[s + 1] += first[s];
  {
    std::vector<int> fill(first.begin(), first.end() - 1);
    for(std::size_t q = 0; q < n; ++q) members[std::size_t(fill[std::size_t(owner[q])]++)] = int(q);
  }
  const Position_tree tree(samples, ConcurrencyTag());
  Neighbor_graph graph = fixed_degree_graph(n, k);
  for_range<ConcurrencyTag>(0, count, [&](std::size_t s) {
    if(first[s] == first[s + 1]) return;
    const Eigen::RowVector3d centre = samples.row(Eigen::Index(s));
    double reach2 = 0; // D_k(s)^2
    tree.nearest(tree[s], k, [&](int, double d2) { reach2 = std::max(reach2, d2); });
    const double reach = std::sqrt(reach2);
    double radius = 0; // r_s
    for(int m = first[s]; m < first[s + 1]; ++m)
      radius = std::max(radius, (queries.row(members[std::size_t(m)]) - centre).norm());
    thread_local std::vector<int> candidates;
    thread_local std::vector<Ranked_row> ranked; // nearest first
    candidates.clear();
    ranked.resize(k);
    // A relative margin for the rounding of the distances compared.
    tree.within(tree[s], (reach + 2 * radius) * (1 + 1e-12), candidates);
    for(int m = first[s]; m < first[s + 1]; ++m) {
      const int q = members[std::size_t(m)];
      const Eigen::RowVector3d p = queries.row(q);
      const double bound = reach + (p - centre).norm();
      const double bound2 = bound * bound * (1 + 1e-12);
      std::size_t found = 0;
      for(const int c : candidates) {
        const double d2 = squared_distance(p(0), p(1), p(2), samples(c, 0), samples(c, 1), samples(c, 2));
        if(d2 > bound2) continue;
        const Ranked_row entry(d2, c);
        if(found == k && !(entry < ranked[k - 1])) continue;
        std::size_t e = found < k ? found++ : k - 1;
        for(; e > 0 && entry < ranked[e - 1]; --e) ranked[e] = ranked[e - 1];
        ranked[e] = entry;
      }
      int* out = graph.indices.data() + std::size_t(q) * k;
      if(found == k)
        for(std::size_t e = 0; e < k; ++e) out[e] = ranked[e].second;
      else // only if the bound failed (non-finite coordinates): the tree's answer
        tree.nearest(Position_tree::point(queries, q), k, [&](int j, double) { *out++ = j; });
    }
  });
  return graph;
}

/// Union of a directed graph and its transpose: j is a neighbour of i if either lists the other.
/// Rows come out sorted by index, free of duplicates and of self-loops.
template <typename ConcurrencyTag>
Neighbor_graph symmetrize(const Neighbor_graph& directed)
{
  const std::size_t n = directed.size();
  // Transpose by counting sort; filling in increasing i keeps each reversed row sorted.
  std::vector<int> reverse_offsets(n + 1, 0);
  for(int j : directed.indices) ++reverse_offsets[std::size_t(j) + 1];
  for(std::size_t i = 0; i < n; ++i) reverse_offsets[i + 1] += reverse_offsets[i];
  std::vector<int> reverse(directed.indices.size());
  {
    std::vector<int> fill(reverse_offsets.begin(), reverse_offsets.end() - 1);
    for(std::size_t i = 0; i < n; ++i)
      for(const int* j = directed.begin(i); j != directed.end(i); ++j) reverse[std::size_t(fill[std::size_t(*j)]++)] = int(i);
  }

  // Merge each sorted forward row with its reversed row: count first, then fill in place.
  std::vector<int> forward(directed.indices);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    std::sort(forward.begin() + directed.offsets[i], forward.begin() + directed.offsets[i + 1]);
  });
  auto merge_row = [&](std::size_t i, int* out) {
    const int *a = forward.data() + directed.offsets[i], *a_end = forward.data() + directed.offsets[i + 1];
    const int *b = reverse.data() + reverse_offsets[i], *b_end = reverse.data() + reverse_offsets[i + 1];
    int count = 0, last = -1;
    while(a != a_end || b != b_end) {
      const int v = (b == b_end || (a != a_end && *a < *b)) ? *a++ : *b++;
      if(v != last && v != int(i)) {
        if(out) out[count] = v;
        ++count;
        last = v;
      }
    }
    return count;
  };
  Neighbor_graph graph;
  graph.offsets.assign(n + 1, 0);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) { graph.offsets[i + 1] = merge_row(i, nullptr); });
  for(std::size_t i = 0; i < n; ++i) graph.offsets[i + 1] += graph.offsets[i];
  graph.indices.resize(std::size_t(graph.offsets[n]));
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) { merge_row(i, graph.indices.data() + graph.offsets[i]); });
  return graph;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_NEIGHBOR_GRAPH_INSTANCES(EXTERN, Tag) \
  EXTERN template Neighbor_graph k_nearest_neighbor_graph<Tag>(const Matrix_n3&, std::size_t, Progress&); \
  EXTERN template Neighbor_graph k_nearest_samples<Tag>(const Matrix_n3&, const Matrix_n3&, std::size_t); \
  EXTERN template Neighbor_graph k_nearest_samples_by_owner<Tag>(const Matrix_n3&, const Matrix_n3&, \
                                                                 const std::vector<int>&, std::size_t); \
  EXTERN template Neighbor_graph symmetrize<Tag>(const Neighbor_graph&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_NEIGHBOR_GRAPH_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_NEIGHBOR_GRAPH_H
