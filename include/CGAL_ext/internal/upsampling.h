// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_UPSAMPLING_H
#define CGAL_EXT_INTERNAL_UPSAMPLING_H

// The steps of up-sampling: new samples across each hole gap, kept apart on a grid of cells, projected onto
// local surface fits and relaxed by repulsion.

#include <CGAL_ext/Upsampling_settings.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/local_fit.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/sparse_directions.h>

#include <CGAL/number_type_config.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <numeric>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// A hash of grid cells of side `cell`: the points already accepted, to keep new samples apart.
class Cell_set
{
public:
  explicit Cell_set(double cell) : m_cell(cell) {}
  using Key = std::tuple<long long, long long, long long>;

  Key key(const Eigen::Vector3d& p) const
  {
    return Key((long long)std::floor(p.x() / m_cell), (long long)std::floor(p.y() / m_cell), (long long)std::floor(p.z() / m_cell));
  }
  /// Whether a point of the set lies within `radius` of `p`.
  bool near(const Eigen::Vector3d& p, double radius, const std::vector<Eigen::Vector3d>& points) const
  {
    // The cells the ball meets (widened a little for the rounding of the division).
    const double reach = radius * (1 + 1e-9);
    long long low[3], high[3];
    for(int d = 0; d < 3; ++d) {
      low[d] = (long long)std::floor((p[d] - reach) / m_cell);
      high[d] = (long long)std::floor((p[d] + reach) / m_cell);
    }
    for(long long x = low[0]; x <= high[0]; ++x)
      for(long long y = low[1]; y <= high[1]; ++y)
        for(long long z = low[2]; z <= high[2]; ++z) {
          const auto it = m_members.find(Key(x, y, z));
          if(it == m_members.end()) continue;
          for(int m : it->second)
            if((points[std::size_t(m)] - p).norm() < radius) return true;
        }
    return false;
  }
  void insert(const Eigen::Vector3d& p, int index) { m_members[key(p)].push_back(index); }

private:
  struct Hash
  {
    std::size_t operator()(const Key& k) const
    {
      return std::size_t(std::get<0>(k) * 73856093LL ^ std::get<1>(k) * 19349663LL ^ std::get<2>(k) * 83492791LL);
    }
  };
  double m_cell;
  std::unordered_map<Key, std::vector<int>, Hash> m_members;
};

/// The indices of the points of `copy` within `reach` of one of the points `region` (indices into `copy`, at least
/// one), with some farther ones (whole cells of a grid are taken, so up to about 2.6 reach), increasing: a function
/// of the positions alone. Cells of reach / 2 (larger when the box would need more than 2^21 of them) are marked
/// where a region point lies, then grown by the cells a reach spans along each axis.
inline std::vector<int> points_near(const std::vector<CGAL::Simple_cartesian<double>::Point_3>& copy,
                                    const std::vector<int>& region, double reach)
{
  const auto at = [&](int i) {
    return Eigen::Array3d(copy[std::size_t(i)].x(), copy[std::size_t(i)].y(), copy[std::size_t(i)].z());
  };
  Eigen::Array3d low = at(region.front()), high = low;
  for(const int i : region) {
    low = low.min(at(i));
    high = high.max(at(i));
  }
  low -= reach;
  high += reach;
  const Eigen::Array3d extent = high - low;
  const double cell = std::max(0.5 * reach, std::cbrt(extent.prod() / double(1 << 21)));
  if(!std::isfinite(cell) || !(cell > 0)) { // a reach or a box too large for a grid: every point
    std::vector<int> all(copy.size());
    std::iota(all.begin(), all.end(), 0);
    return all;
  }
  const long margin = long(std::ceil(reach / cell));
  std::array<long, 3> dims;
  for(int d = 0; d < 3; ++d) dims[std::size_t(d)] = long(extent[d] / cell) + 1;
  std::vector<char> marked(std::size_t(dims[0] * dims[1] * dims[2]), 0);
  const auto cell_of = [&](const Eigen::Array3d& p) {
    long c[3];
    for(int d = 0; d < 3; ++d) c[d] = std::min(dims[std::size_t(d)] - 1, long((p[d] - low[d]) / cell));
    return std::size_t((c[0] * dims[1] + c[1]) * dims[2] + c[2]);
  };
  for(const int i : region) marked[cell_of(at(i))] = 1;
  // Grown along each axis in turn: a cell is marked when one within `margin` cells along the axis was.
  const std::array<long, 3> stride{dims[1] * dims[2], dims[2], 1};
  std::vector<char> line;
  for(int d = 0; d < 3; ++d) {
    const int a = (d + 1) % 3, b = (d + 2) % 3;
    const long length = dims[std::size_t(d)], step = stride[std::size_t(d)];
    for(long ia = 0; ia < dims[std::size_t(a)]; ++ia)
      for(long ib = 0; ib < dims[std::size_t(b)]; ++ib) {
        char* cells = marked.data() + ia * stride[std::size_t(a)] + ib * stride[std::size_t(b)];
        line.assign(std::size_t(length), 0);
        for(long c = 0, last = -margin - 1; c < length; ++c) {
          if(cells[c * step]) last = c;
          line[std::size_t(c)] = c - last <= margin;
        }
        for(long c = length - 1, last = length + margin; c >= 0; --c) {
          if(cells[c * step]) last = c;
          cells[c * step] = line[std::size_t(c)] || last - c <= margin;
        }
      }
  }
  std::vector<int> near;
  for(std::size_t i = 0; i < copy.size(); ++i) {
    const Eigen::Array3d p = at(int(i));
    if((p >= low).all() && (p <= high).all() && marked[cell_of(p)]) near.push_back(int(i));
  }
  return near;
}

/// The order in which new samples are kept, from their coordinates alone (a splitmix64 hash of their bits): which
/// of two close candidates is kept then depends on those two, not on how the points are numbered or which points
/// a tile of a larger scan holds. Unlike an order along an axis, it starts no chain of decisions running across
/// the surface: a decision depends on candidates within a few spacings.
inline std::uint64_t keep_priority(const Eigen::Vector3d& x)
{
  std::uint64_t h = 0;
  for(int d = 0; d < 3; ++d) {
    const double c = x[d] + 0.0; // -0 as +0
    std::uint64_t bits;
    std::memcpy(&bits, &c, sizeof bits);
    h += bits + 0x9E3779B97F4A7C15ULL;
    h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ULL;
    h = (h ^ (h >> 27)) * 0x94D049BB133111EBULL;
    h ^= h >> 31;
  }
  return h;
}

/// Whether `a` comes before `b` in the order of their coordinates, x first.
inline bool lexicographically_before(const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

/// Rows of `samples` with their squared distances to a point, nearest first, as a tree search visits them.
using Ranked_rows = std::vector<std::pair<double, int>>;

/// Orders the rows of `near` that lie at one distance by their coordinates: sums over them then come in an order
/// of the points alone. Tree searches break such ties by row, and a new point halfway across a gap is often exactly
/// as far from both ends, whose rows depend on which points a tile of a larger scan holds.
template <typename Rows>
void break_ties_by_coordinates(const Rows& samples, Ranked_rows& near)
{
  for(std::size_t a = 0; a < near.size();) {
    std::size_t b = a + 1;
    while(b < near.size() && near[b].first == near[a].first) ++b;
    if(b - a > 1)
      std::sort(near.begin() + std::ptrdiff_t(a), near.begin() + std::ptrdiff_t(b), [&](const auto& p, const auto& q) {
        return lexicographically_before(samples.row(p.second).transpose(), samples.row(q.second).transpose());
      });
    a = b;
  }
}

/// Projects `x` onto the surface fitted to the input samples around it, with a normal oriented like `normal`;
/// updates both. Near the samples, a degree-2 fit to the `k` nearest. Inside a hole, where the nearest sample
/// is `d` > 1.5 h away, the k nearest would lie on the hole's near side and the fit would extrapolate from there;
/// so the fit takes the nearest k / 8 samples in each of 8 directions around `x` (among the about
/// 3 pi (d / h)^2 samples of a disc of radius 2 d), which surround the hole, and a degree-3 surface through
/// them interpolates the rim: a wave's inflection across a hole is then followed, not flattened.
/// Either fit leaves out the samples whose normals (`normals`) face away from `normal`: across a thin part (a
/// plate, a finger) they lie on its other side, and a fit through both sides would land between them.
/// `tree` holds the samples; `nearest` keeps its nearest samples to the new point `point`, which `x` is, and
/// `nearest_in_hole` more of them for the fits inside a hole.
inline void project_onto_surface(const Matrix_n3& samples, const Matrix_n3& normals, const Position_tree& tree,
                                 Moving_neighbors& nearest, Moving_neighbors& nearest_in_hole, std::size_t point,
                                 std::size_t k, double h, Eigen::Vector3d& x, Eigen::Vector3d& normal)
{
  thread_local Ranked_rows near;
  near.clear();
  const Position_tree::Point query(x.x(), x.y(), x.z());
  double nearest2 = 0;
  nearest.nearest(point, x, k, [&](int j, double d2) {
    if(faces_away(normals, j, normal)) return;
    if(near.empty()) nearest2 = d2;
    near.emplace_back(d2, j);
  });
  const bool inside_hole = nearest2 > 2.25 * h * h;
  Height_fit fit(x, normal, inside_hole ? 3 : 2);
  if(inside_hole) {
    near.clear();
    const Eigen::Vector3d& u = fit.tangent_u();
    const Eigen::Vector3d& v = fit.tangent_v();
    constexpr double pi = CGAL_PI;
    const std::size_t per_direction = (k + 7) / 8, candidates = k + std::size_t(std::ceil(3 * pi * nearest2 / (h * h)));
    std::size_t taken[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    const auto take = [&](int j, double d2) {
      if(faces_away(normals, j, normal)) return;
      const Eigen::Vector3d d = samples.row(j).transpose() - x;
      const double turn = std::atan2(d.dot(v), d.dot(u)) / (2 * pi) + 0.5; // in [0, 1]
      std::size_t& in_direction = taken[std::min(7, int(turn * 8))];
      if(in_direction < per_direction) {
        ++in_direction;
        near.emplace_back(d2, j);
      }
    };
    const std::size_t wanted = std::min<std::size_t>(candidates, std::size_t(samples.rows()));
    if(wanted <= nearest_in_hole.reach())
      nearest_in_hole.nearest(point, x, wanted, take);
    else
      tree.nearest(query, wanted, take);
  }
  break_ties_by_coordinates(samples, near);
  fit.fit(int(near.size()),
          [&](int m) { return Eigen::Vector3d(samples.row(near[std::size_t(m)].second).transpose()); });
  x = fit.project(x);
  const Eigen::Vector3d n = fit.normal(x);
  normal = n.dot(normal) < 0 ? Eigen::Vector3d(-n) : n;
}

/// Whether `x` continues the surface of its 3 nearest input samples: its offset from each leans at most 30
/// degrees out of that sample's tangent plane. A projection that lands off the surface (a fit misled where the
/// surface folds, or across a thin part) fails this, and the new point is dropped rather than written there.
inline bool continues_surface(const Matrix_n3& samples, const Matrix_n3& normals, const Position_tree& tree, const Eigen::Vector3d& x)
{
  bool along = true;
  tree.nearest(Position_tree::Point(x.x(), x.y(), x.z()), 3, [&](int j, double) {
    const Eigen::Vector3d offset = x - samples.row(j).transpose();
    const double height = std::abs(offset.dot(normals.row(j).transpose()));
    along = along && 3 * height * height <= offset.squaredNorm() - height * height;
  });
  return along;
}

/// Up-sampling's rounds on the input's arrays: detect the gaps across holes from the points `examine` (all
/// of them in the first round unless `region_given`), insert samples along them at the spacing interpolated
/// between the gap's ends, relax them on the surface of the input, drop those that do not settle on it, and
/// examine the sparse points and the new ones again, for at most `settings.max_rounds` rounds. `spacing` holds
/// each input point's target spacing; `local_empty_radii` says whether its empty radius is measured against the
/// points' own quarter gaps (`empty_radii`). Returns false when cancelled.
template <typename ConcurrencyTag>
bool fill_holes(const Matrix_n3& positions, const Matrix_n3& input_normals, const Position_tree& input_tree,
                const Upsampling_settings& settings, bool region_given, std::vector<int> examine,
                std::vector<double> all_spacing, bool local_empty_radii, Progress& progress, Upsampling_result& result,
                std::vector<Eigen::Vector3d>& new_points, std::vector<Eigen::Vector3d>& new_normals)
{
  const std::size_t k = settings.neighbors;
  // All samples so far: the input first, then the new ones (rows n.., `added`), read as one without copying the
  // input.
  const std::size_t n = std::size_t(positions.rows());
  Matrix_n3 added(0, 3), added_normals(0, 3);
  const Stacked_rows all(positions, added), all_normals(input_normals, added_normals);
  // New samples fill quarters; they empty one only by turning a point's principal axes, which is rare: after
  // the first round, only the points that were sparse and the new points are examined again.
  std::vector<int> sparse;
  // Each sample's empty radius in its spacings (see `empty_radii`): new samples take the one interpolated along
  // their gap, so a hole in a random sampling is filled to its surroundings' own standard.
  std::vector<double> all_empty_factor;
  {
    const std::vector<double> radius =
      empty_radii<ConcurrencyTag>(positions, input_normals, input_tree, k, all_spacing, local_empty_radii);
    all_empty_factor.resize(n);
    for(std::size_t i = 0; i < n; ++i) all_empty_factor[i] = radius[i] / all_spacing[i];
  }
  for(std::size_t round = 0; round < settings.max_rounds; ++round) {
    std::vector<double> empty_radius(all.rows());
    for(std::size_t i = 0; i < empty_radius.size(); ++i) empty_radius[i] = all_empty_factor[i] * all_spacing[i];
    progress.stage(double(round) / settings.max_rounds, double(round + 1) / settings.max_rounds);
    if(!progress.report(0.0)) return false;
    // The first round's samples are the input: its tree serves; later rounds add a tree of the new samples to it.
    std::unique_ptr<Position_tree> round_tree;
    if(round > 0) round_tree = std::make_unique<Position_tree>(input_tree, added, ConcurrencyTag());
    const Position_tree& tree = round > 0 ? *round_tree : input_tree;
    const std::vector<Hole_gap> gaps = hole_gaps<ConcurrencyTag>(all, all_normals, tree, k, all_spacing, empty_radius,
                                                                 settings.detection.max_hole_size,
                                                                 round == 0 && !region_given ? nullptr : &examine, sparse);
    if(round == 0) {
      std::vector<char> boundary(n, 0);
      for(const Hole_gap& g : gaps) boundary[std::size_t(g.from)] = 1;
      result.hole_boundary_points = std::size_t(std::count(boundary.begin(), boundary.end(), 1));
    }
    // Candidates along every gap at the target spacing (interpolated between the gap's ends); a candidate is
    // kept only at least half a spacing from every sample and from the candidates kept before it, in the order
    // of `keep_priority`.
    double widest = 0;
    for(const Hole_gap& g : gaps) widest = std::max({widest, all_spacing[std::size_t(g.from)], all_spacing[std::size_t(g.across)]});
    Cell_set kept(0.5 * widest);
    // Whether a sample lies that near is asked of the tree for every candidate at once, in parallel; those kept are
    // chosen in order after.
    struct Candidate
    {
      const Hole_gap* gap;
      double t, h; // along the gap, and the spacing there
      Eigen::Vector3d x;
    };
    std::vector<Candidate> candidates;
    for(const Hole_gap& g : gaps) {
      const Eigen::Vector3d a = all.row(g.from).transpose(), b = all.row(g.across).transpose();
      const double ha = all_spacing[std::size_t(g.from)], hb = all_spacing[std::size_t(g.across)];
      const int steps = int(std::lround((b - a).norm() / (0.5 * (ha + hb))));
      for(int s = 1; s < steps; ++s) {
        const double t = double(s) / steps;
        candidates.push_back({&g, t, (1 - t) * ha + t * hb, a + t * (b - a)});
      }
    }
    std::vector<char> near_sample(candidates.size(), 0);
    for_range<ConcurrencyTag>(0, candidates.size(), [&](std::size_t c) {
      const Candidate& candidate = candidates[c];
      const Eigen::Vector3d& x = candidate.x;
      tree.nearest(Position_tree::Point(x.x(), x.y(), x.z()), 1,
                   [&](int, double d2) { near_sample[c] = d2 < 0.25 * candidate.h * candidate.h; });
    });
    std::vector<std::uint64_t> priority(candidates.size());
    for(std::size_t c = 0; c < candidates.size(); ++c) priority[c] = keep_priority(candidates[c].x);
    std::vector<std::size_t> keep_order(candidates.size());
    std::iota(keep_order.begin(), keep_order.end(), std::size_t(0));
    std::sort(keep_order.begin(), keep_order.end(), [&](std::size_t a, std::size_t b) {
      if(priority[a] != priority[b]) return priority[a] < priority[b];
      const Candidate &p = candidates[a], &q = candidates[b];
      if(p.x != q.x) return lexicographically_before(p.x, q.x);
      // The same position from two gaps: the gap with the first ends takes it.
      const Eigen::Vector3d p_from = all.row(p.gap->from).transpose(), q_from = all.row(q.gap->from).transpose();
      if(p_from != q_from) return lexicographically_before(p_from, q_from);
      return lexicographically_before(all.row(p.gap->across).transpose(), all.row(q.gap->across).transpose());
    });
    std::vector<Eigen::Vector3d> round_points, round_normals;
    std::vector<double> round_spacing, round_empty_factor;
    std::vector<char> chosen(candidates.size(), 0);
    std::vector<Eigen::Vector3d> chosen_points;
    for(const std::size_t c : keep_order) {
      const Candidate& candidate = candidates[c];
      if(near_sample[c] || kept.near(candidate.x, 0.5 * candidate.h, chosen_points)) continue;
      kept.insert(candidate.x, int(chosen_points.size()));
      chosen_points.push_back(candidate.x);
      chosen[c] = 1;
    }
    // Stored in the gaps' order, which follows the points along the surface: the relaxation's searches then walk
    // the trees in that order, not in the hash's.
    for(std::size_t c = 0; c < candidates.size(); ++c) {
      if(!chosen[c]) continue;
      const auto& [gap, t, h, x] = candidates[c];
      const Hole_gap& g = *gap;
      const Eigen::Vector3d na = all_normals.row(g.from).transpose(), nb = all_normals.row(g.across).transpose();
      round_points.push_back(x);
      Eigen::Vector3d normal = (1 - t) * na + t * nb;
      round_normals.push_back(normal.norm() > 0 ? Eigen::Vector3d(normal.normalized()) : na);
      round_spacing.push_back(h);
      round_empty_factor.push_back((1 - t) * all_empty_factor[std::size_t(g.from)] +
                                   t * all_empty_factor[std::size_t(g.across)]);
    }
    if(round_points.empty()) break;
    ++result.rounds;

    // Relaxation (Jacobi steps, so the result does not depend on the thread count): repulsion in the tangent
    // plane from every sample closer than 1.5 spacings (the moving point's), then back onto the surface of the
    // input samples.
    // The samples of earlier rounds stay put: the round's tree serves them; only the new ones get a tree per step.
    Matrix_n3 moving(Eigen::Index(round_points.size()), 3);
    std::vector<char> settled(round_points.size(), 1);
    // A step moves most new points little (the push is capped at 0.3 spacings; the projection moves them back onto
    // the surface): their nearest input samples (for the projections, twice the fit's) and their nearest samples
    // (input and earlier rounds, for the repulsion) are kept between steps.
    Moving_neighbors near_input(input_tree, round_points.size(), 4 * k);
    // Inside a hole a fit takes the nearest 2 k + 3 pi (d / h)^2 rows (`project_onto_surface`): 8 k of them cover
    // a distance d to the nearest sample of up to about 2.8 spacings, most of a stretch's holes; wider ones ask the
    // tree.
    Moving_neighbors near_input_in_hole(input_tree, round_points.size(), 8 * k);
    std::unique_ptr<Moving_neighbors> near_earlier;
    if(round > 0) near_earlier = std::make_unique<Moving_neighbors>(tree, round_points.size(), 24);
    Moving_neighbors& near_samples = round > 0 ? *near_earlier : near_input;
    for(unsigned int iteration = 0; iteration <= settings.relaxation_iterations; ++iteration) {
      for(std::size_t m = 0; m < round_points.size(); ++m) moving.row(Eigen::Index(m)) = round_points[m].transpose();
      const Position_tree moving_tree(moving, ConcurrencyTag());
      std::vector<Eigen::Vector3d> moved(round_points.size()), turned(round_points.size());
      for_range<ConcurrencyTag>(0, round_points.size(), [&](std::size_t m) {
        Eigen::Vector3d x = round_points[m], normal = round_normals[m];
        const double h = round_spacing[m], radius = 1.5 * h;
        if(iteration < settings.relaxation_iterations) {
          Eigen::Vector3d push = Eigen::Vector3d::Zero();
          thread_local Ranked_rows pushing;
          auto repel = [&push, &x, radius](const auto& from) {
            break_ties_by_coordinates(from, pushing);
            for(const auto& [d2, j] : pushing) {
              const double d = std::sqrt(d2);
              if(d >= radius || !(d > 0)) continue;
              const double w = 1 - d / radius;
              push += w * w * (x - from.row(j).transpose()) / d;
            }
          };
          const auto gather = [](int j, double d2) { pushing.emplace_back(d2, j); };
          pushing.clear();
          near_samples.nearest(m, x, 12, gather);
          repel(all);
          // Of the 12 nearest new points (this one among them), those within its reach: a search bounded there
          // costs less than the 12 nearest.
          pushing.clear();
          moving_tree.nearest(Position_tree::Point(x.x(), x.y(), x.z()), 12, gather,
                              std::nextafter(radius * radius, 0.0));
          repel(moving);
          push = 0.5 * h * (push - push.dot(normal) * normal);
          if(push.norm() > 0.3 * h) push *= 0.3 * h / push.norm();
          x += push;
        }
        project_onto_surface(positions, input_normals, input_tree, near_input, near_input_in_hole, m, 2 * k, h, x,
                             normal);
        if(iteration == settings.relaxation_iterations) {
          // A projection onto the surface should be a fixed point: projecting the result again must not move
          // it. Where the fit is unstable (a cubic across a tear, in a frame that tilts with the normal) it
          // does, and the point is dropped rather than written off the surface.
          Eigen::Vector3d again = x, again_normal = normal;
          project_onto_surface(positions, input_normals, input_tree, near_input, near_input_in_hole, m, 2 * k, h, again,
                               again_normal);
          settled[m] = (again - x).squaredNorm() <= 0.0625 * h * h; // a quarter spacing
        }
        moved[m] = x;
        turned[m] = normal;
      });
      round_points.swap(moved);
      round_normals.swap(turned);
    }
    std::vector<char> keep(round_points.size());
    for_range<ConcurrencyTag>(0, round_points.size(), [&](std::size_t m) {
      keep[m] = settled[m] && continues_surface(positions, input_normals, input_tree, round_points[m]);
    });
    std::size_t kept_count = 0;
    for(std::size_t m = 0; m < round_points.size(); ++m)
      if(keep[m]) {
        round_points[kept_count] = round_points[m];
        round_normals[kept_count] = round_normals[m];
        round_empty_factor[kept_count] = round_empty_factor[m];
        round_spacing[kept_count++] = round_spacing[m];
      }
    round_points.resize(kept_count);
    round_normals.resize(kept_count);
    round_spacing.resize(kept_count);
    round_empty_factor.resize(kept_count);
    examine = sparse;
    for(std::size_t m = 0; m < round_points.size(); ++m) examine.push_back(int(n + new_points.size() + m));
    new_points.insert(new_points.end(), round_points.begin(), round_points.end());
    new_normals.insert(new_normals.end(), round_normals.begin(), round_normals.end());
    all_spacing.insert(all_spacing.end(), round_spacing.begin(), round_spacing.end());
    all_empty_factor.insert(all_empty_factor.end(), round_empty_factor.begin(), round_empty_factor.end());
    added.conservativeResize(Eigen::Index(new_points.size()), 3);
    added_normals.conservativeResize(added.rows(), 3);
    for(std::size_t m = 0; m < new_points.size(); ++m) {
      added.row(Eigen::Index(m)) = new_points[m].transpose();
      added_normals.row(Eigen::Index(m)) = new_normals[m].transpose();
    }
  }
  return true;
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_UPSAMPLING_H
