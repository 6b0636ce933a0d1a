// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_SPARSE_DIRECTIONS_H
#define CGAL_EXT_INTERNAL_SPARSE_DIRECTIONS_H

// What hole detection and up-sampling share: local spacings, the quarter gaps around a point's normal and
// the gaps across holes.

#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/number_type_config.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// A gap across a hole: from row `from`, toward row `across` (the first sample beyond the gap).
struct Hole_gap
{
  int from, across;
};

/// Whether the normal of row `j` of `normals` faces away from `normal`: across a thin part, the row is a sample of
/// its other side, which no neighbourhood on this side takes (doc/upsampling.md, "Thin parts").
template <typename Normals>
bool faces_away(const Normals& normals, Eigen::Index j, const Eigen::Vector3d& normal)
{
  return normals.row(j).dot(normal.transpose()) <= 0;
}

/// The rows of two arrays read as one, `first`'s then `second`'s (rows `first.rows()` on): up-sampling's input
/// samples and the samples it added, without copying the input each round.
class Stacked_rows
{
public:
  Stacked_rows(const Matrix_n3& first) : m_first(first), m_second(nullptr) {}
  Stacked_rows(const Matrix_n3& first, const Matrix_n3& second) : m_first(first), m_second(&second) {}

  Eigen::Index rows() const { return m_first.rows() + (m_second ? m_second->rows() : 0); }
  Eigen::RowVector3d row(Eigen::Index i) const
  {
    return i < m_first.rows() ? Eigen::RowVector3d(m_first.row(i))
                              : Eigen::RowVector3d(m_second->row(i - m_first.rows()));
  }

private:
  const Matrix_n3& m_first;
  const Matrix_n3* m_second;
};

/// The typical spacing of a sampling: the median over points of their mean distance to their 6 nearest
/// neighbours (`CGAL::compute_average_spacing`'s measure, with a median against outliers). The nearest
/// neighbour alone underestimates a jittered sampling, whose natural gaps would then look like holes.
template <typename ConcurrencyTag>
double typical_spacing(const Matrix_n3& positions, const Position_tree& tree)
{
  const std::size_t k = std::min<std::size_t>(6, std::size_t(positions.rows()) - 1);
  std::vector<double> mean(std::size_t(positions.rows()), 0.0);
  for_range<ConcurrencyTag>(0, mean.size(), [&](std::size_t i) {
    tree.nearest(Position_tree::point(positions, Eigen::Index(i)), k + 1, [&](int j, double d2) {
      if(std::size_t(j) != i) mean[i] += std::sqrt(d2) / double(k);
    });
  });
  std::nth_element(mean.begin(), mean.begin() + std::ptrdiff_t(mean.size() / 2), mean.end());
  return mean[mean.size() / 2];
}

/// Every point's local spacing: the median, over the point and its 15 nearest neighbours, of their mean
/// distance to their 6 nearest neighbours. The median over a neighbourhood follows a change of density (an
/// adaptive mesh, a random sampling) but not one point's luck; at a hole's rim it is that of the rim's side.
/// With `rows` (distinct), only theirs are computed (from their neighbourhoods only) and the others are 0.
template <typename ConcurrencyTag>
std::vector<double> local_spacings(const Matrix_n3& positions, const Position_tree& tree,
                                   const std::vector<int>* rows = nullptr)
{
  const std::size_t n = std::size_t(positions.rows()), k = std::min<std::size_t>(6, n - 1),
                    around = std::min<std::size_t>(16, n);
  std::vector<double> mean(n, 0.0), spacing(n, 0.0);
  const auto mean_distance = [&](std::size_t i) {
    tree.nearest(Position_tree::point(positions, Eigen::Index(i)), k + 1, [&](int j, double d2) {
      if(std::size_t(j) != i) mean[i] += std::sqrt(d2) / double(k);
    });
  };
  const auto median_of = [](std::vector<double>& near) {
    std::nth_element(near.begin(), near.begin() + std::ptrdiff_t(near.size() / 2), near.end());
    return near[near.size() / 2];
  };
  if(!rows) {
    for_range<ConcurrencyTag>(0, n, mean_distance);
    for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
      thread_local std::vector<double> near;
      near.clear();
      tree.nearest(Position_tree::point(positions, Eigen::Index(i)), around,
                   [&](int j, double) { near.push_back(mean[std::size_t(j)]); });
      spacing[i] = median_of(near);
    });
    return spacing;
  }
  // Only the spacings of `rows` (the others stay 0): the mean distances of their neighbourhoods only. A row's
  // own mean distance comes from the first k + 1 of its neighbourhood (rows are distinct).
  const std::size_t count = rows->size();
  std::vector<int> near_rows(count * around);
  std::vector<char> needed(n, 0);
  for_range<ConcurrencyTag>(0, count, [&](std::size_t m) {
    const std::size_t i = std::size_t((*rows)[m]);
    int* out = near_rows.data() + m * around;
    std::size_t rank = 0;
    tree.nearest(Position_tree::point(positions, Eigen::Index(i)), around, [&](int j, double d2) {
      *out++ = j;
      if(rank++ <= k && std::size_t(j) != i) mean[i] += std::sqrt(d2) / double(k);
    });
  });
  for(int j : near_rows) needed[std::size_t(j)] = 1;
  for(int i : *rows) needed[std::size_t(i)] = 0;
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    if(needed[i]) mean_distance(i);
  });
  for_range<ConcurrencyTag>(0, count, [&](std::size_t m) {
    thread_local std::vector<double> near;
    near.clear();
    for(std::size_t e = 0; e < around; ++e) near.push_back(mean[std::size_t(near_rows[m * around + e])]);
    spacing[std::size_t((*rows)[m])] = median_of(near);
  });
  return spacing;
}

/// The principal axis, in the tangent plane of `normal`, of the tangent offsets `offset(0)`, ..., `offset(count - 1)`
/// to a point's nearest neighbours (from their covariance); not finite when they span no direction.
template <typename OffsetOf>
Eigen::Vector3d principal_tangent_axis(std::size_t count, const OffsetOf& offset, const Eigen::Vector3d& normal)
{
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for(std::size_t m = 0; m < count; ++m) covariance += offset(m) * offset(m).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(covariance);
  const Eigen::Vector3d axis = eigen.eigenvectors().col(2);
  return (axis - axis.dot(normal) * normal).normalized();
}

/// Each point's largest quarter gap: over the four quarters of its tangent plane around the principal axes of its
/// k nearest projected neighbours, the largest distance to the nearest neighbour within the quarter (the
/// smallest empty radius under which the point has no sparse quarter); a quarter with none among the 24
/// nearest counts the farthest of them. Neighbours whose normals face away (the other side of a thin part) are
/// left out, as in `hole_gaps`.
template <typename ConcurrencyTag>
std::vector<double> largest_quarter_gaps(const Matrix_n3& positions, const Matrix_n3& normals, const Position_tree& tree, std::size_t k)
{
  const std::size_t n = std::size_t(positions.rows()), count = std::min<std::size_t>(std::max<std::size_t>(k, 24) + 1, n);
  std::vector<double> gap(n, 0.0);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    thread_local std::vector<Eigen::Vector3d> offsets;
    offsets.clear();
    const Eigen::Vector3d p = positions.row(Eigen::Index(i)).transpose(), normal = normals.row(Eigen::Index(i)).transpose();
    tree.nearest(Position_tree::point(positions, Eigen::Index(i)), count, [&](int j, double) {
      if(std::size_t(j) == i || faces_away(normals, j, normal)) return;
      Eigen::Vector3d d = positions.row(j).transpose() - p;
      offsets.push_back(d - d.dot(normal) * normal);
    });
    const Eigen::Vector3d a = principal_tangent_axis(std::min(k, offsets.size()), [&](std::size_t m) { return offsets[m]; }, normal);
    if(!a.allFinite()) return;
    const Eigen::Vector3d b = normal.cross(a);
    double farthest = 0;
    for(const Eigen::Vector3d& d : offsets) farthest = std::max(farthest, d.norm());
    double largest = 0;
    for(const Eigen::Vector3d& d : {a, Eigen::Vector3d(-a), b, Eigen::Vector3d(-b)}) {
      double nearest = farthest;
      for(const Eigen::Vector3d& o : offsets) {
        const double length = o.norm();
        if(length > 0 && o.dot(d) > std::sqrt(0.5) * length) nearest = std::min(nearest, length);
      }
      largest = std::max(largest, nearest);
    }
    gap[i] = largest;
  });
  return gap;
}

/// The radius within which an empty quarter makes each point sparse: twice its spacing; when the spacings are
/// local (`against_surroundings`), also at least twice the largest quarter gap typical around the point (the
/// median over it and its 15 nearest neighbours). A random or anisotropic sampling has wide gaps everywhere
/// (a fifth of a random sampling's points have a quarter empty within two local spacings): only a gap twice as
/// wide as its surroundings' is taken for a hole (doc/upsampling.md, "Random samplings").
template <typename ConcurrencyTag>
std::vector<double> empty_radii(const Matrix_n3& positions, const Matrix_n3& normals, const Position_tree& tree, std::size_t k,
                                const std::vector<double>& spacing, bool against_surroundings)
{
  const std::size_t n = std::size_t(positions.rows());
  std::vector<double> radius(n);
  for(std::size_t i = 0; i < n; ++i) radius[i] = 2 * spacing[i];
  if(!against_surroundings) return radius;
  const std::vector<double> gap = largest_quarter_gaps<ConcurrencyTag>(positions, normals, tree, k);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    thread_local std::vector<double> around;
    around.clear();
    tree.nearest(Position_tree::point(positions, Eigen::Index(i)), std::min<std::size_t>(16, n),
                 [&](int j, double) { around.push_back(gap[std::size_t(j)]); });
    std::nth_element(around.begin(), around.begin() + std::ptrdiff_t(around.size() / 2), around.end());
    radius[i] = std::max(radius[i], 2 * around[around.size() / 2]);
  });
  return radius;
}

/// The hole gaps of the points `rows` (all when null; doc/upsampling.md, "Finding holes"): for each sparse
/// quarter of a point's tangent plane (empty within the point's `empty_radius`), the first sample that
/// reappears along it within `max_hole_size` spacings, if any. Samples whose normals face away from the point's
/// (the other side of a thin part) fill no quarter. `spacing` and `empty_radius` have one entry per
/// row of `positions`; `tree` holds those rows.
/// `sparse` receives the examined points with a sparse quarter, increasing. Gaps come out ordered by point,
/// then quarter, so any thread count gives the same list.
template <typename ConcurrencyTag>
std::vector<Hole_gap> hole_gaps(const Stacked_rows& positions, const Stacked_rows& normals, const Position_tree& tree,
                                std::size_t k, const std::vector<double>& spacing,
                                const std::vector<double>& empty_radius, double max_hole_size,
                                const std::vector<int>* rows, std::vector<int>& sparse)
{
  const std::size_t n = rows ? rows->size() : std::size_t(positions.rows());
  // Enough candidates to see across a gap of max_hole_size spacings: about the samples of that disc.
  const std::size_t reach = std::min<std::size_t>(std::size_t(positions.rows()),
                                                  std::max<std::size_t>(k + 1, std::size_t(std::ceil(3.5 * max_hole_size * max_hole_size))));
  const double cos_cone = std::cos(30 * CGAL_PI / 180), tan_sheet = std::tan(30 * CGAL_PI / 180);
  std::vector<std::array<int, 4>> across(n);
  std::vector<char> is_sparse(n, 0);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
    across[r].fill(-1);
    const std::size_t i = rows ? std::size_t((*rows)[r]) : r;
    const double empty_within = empty_radius[i], max_gap = max_hole_size * spacing[i];
    const Eigen::Vector3d p = positions.row(Eigen::Index(i)).transpose(), normal = normals.row(Eigen::Index(i)).transpose();
    struct Candidate
    {
      int row;
      Eigen::Vector3d offset; // tangent
      double length;          // of the offset
      bool facing;            // its normal on the side of this point's
    };
    thread_local std::vector<Candidate> candidates;
    thread_local std::vector<char> same_sheet; // whether a sample across a gap may continue this point's surface
    auto gather = [&](std::size_t count) {
      candidates.clear();
      same_sheet.clear();
      tree.nearest(tree[i], count, [&](int j, double) {
        if(std::size_t(j) == i) return;
        Eigen::Vector3d d = positions.row(j).transpose() - p;
        const double height = d.dot(normal);
        d -= height * normal;
        candidates.push_back({j, d, d.norm(), !faces_away(normals, j, normal)});
        // Within 30 degrees of the tangent plane, facing the same way: not a sample of another sheet (the body
        // under an arm), whose bridge would cross empty space.
        same_sheet.push_back(std::abs(height) <= tan_sheet * candidates.back().length &&
                             normals.row(j).dot(normal.transpose()) > 0.5);
      });
    };
    // A few neighbours decide most points: the search across a gap needs the wide query only where a quarter
    // looks empty among them.
    gather(std::min(reach, std::max<std::size_t>(k, 16) + 1));
    // Principal axes of the k nearest projected neighbours (the wide query's first k are the same rows: both
    // rank by distance, then row).
    const Eigen::Vector3d e1 = principal_tangent_axis(
      std::min(k, candidates.size()), [&](std::size_t m) { return candidates[m].offset; }, normal);
    if(!e1.allFinite()) return;
    const Eigen::Vector3d e2 = normal.cross(e1);
    const std::array<Eigen::Vector3d, 4> directions{e1, Eigen::Vector3d(-e1), e2, Eigen::Vector3d(-e2)};
    int seen = 0;
    for(const Eigen::Vector3d& d : directions)
      for(const Candidate& candidate : candidates)
        if(candidate.facing && candidate.length > 0 && candidate.length < empty_within &&
           candidate.offset.dot(d) > std::sqrt(0.5) * candidate.length) {
          ++seen;
          break;
        }
    if(seen == 4) return;
    gather(reach);
    for(int q = 0; q < 4; ++q) {
      const Eigen::Vector3d& d = directions[std::size_t(q)];
      bool empty = true;
      double best = max_gap;
      for(std::size_t c = 0; c < candidates.size(); ++c) {
        const auto& [j, offset, length, facing] = candidates[c];
        if(!(length > 0)) continue;
        const double along = offset.dot(d) / length;
        if(facing && length < empty_within && along > std::sqrt(0.5)) { // a sample inside the quarter
          empty = false;
          break;
        }
        if(length >= empty_within && length < best && along > cos_cone && same_sheet[c]) {
          best = length;
          across[r][std::size_t(q)] = j;
        }
      }
      if(!empty) across[r][std::size_t(q)] = -1;
      else is_sparse[r] = 1;
    }
  });
  sparse.clear();
  std::vector<Hole_gap> gaps;
  for(std::size_t r = 0; r < n; ++r) {
    const int i = rows ? (*rows)[r] : int(r);
    if(is_sparse[r]) sparse.push_back(i);
    for(int j : across[r])
      if(j >= 0) gaps.push_back({i, j});
  }
  return gaps;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_SPARSE_DIRECTIONS_INSTANCES(EXTERN, Tag)                                                              \
  EXTERN template double typical_spacing<Tag>(const Matrix_n3&, const Position_tree&);                                 \
  EXTERN template std::vector<double> local_spacings<Tag>(const Matrix_n3&, const Position_tree&,                      \
                                                          const std::vector<int>*);                                    \
  EXTERN template std::vector<double> empty_radii<Tag>(const Matrix_n3&, const Matrix_n3&, const Position_tree&,       \
                                                       std::size_t, const std::vector<double>&, bool);                 \
  EXTERN template std::vector<Hole_gap> hole_gaps<Tag>(                                                                \
    const Stacked_rows&, const Stacked_rows&, const Position_tree&, std::size_t, const std::vector<double>&,           \
    const std::vector<double>&, double, const std::vector<int>*, std::vector<int>&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_SPARSE_DIRECTIONS_INSTANCES)

inline double median(std::vector<double> values)
{
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(values.size() / 2), values.end());
  return values[values.size() / 2];
}

/// `given` at every point when it is > 0, otherwise the local spacings, where a point among coincident copies
/// (zero spacing) takes the median. Throws when most points coincide: then no spacing can be measured.
template <typename ConcurrencyTag>
std::vector<double> spacings(const Matrix_n3& positions, const Position_tree& tree, double given, const char* who)
{
  if(given > 0) return std::vector<double>(std::size_t(positions.rows()), given);
  std::vector<double> spacing = local_spacings<ConcurrencyTag>(positions, tree);
  const double typical = median(spacing);
  if(!(typical > 0)) throw Invalid_input(std::string(who) + ": the points coincide (zero spacing); give a spacing");
  for(double& h : spacing)
    if(!(h > 0)) h = typical;
  return spacing;
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_SPARSE_DIRECTIONS_H
