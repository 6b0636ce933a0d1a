// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_STRENGTH_FIELD_H
#define CGAL_EXT_INTERNAL_STRENGTH_FIELD_H

#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Euclidean distance from every row of `positions` to the nearest of the rows `sources`; infinity when
/// there is none.
template <typename ConcurrencyTag>
Eigen::VectorXd euclidean_distance_to(const Matrix_n3& positions, const std::vector<int>& sources)
{
  const Eigen::Index n = positions.rows();
  Eigen::VectorXd distance = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity());
  if(sources.empty()) return distance;
  Matrix_n3 source_positions(Eigen::Index(sources.size()), 3);
  for(std::size_t s = 0; s < sources.size(); ++s) source_positions.row(Eigen::Index(s)) = positions.row(sources[s]);
  const Neighbor_graph nearest = k_nearest_samples<ConcurrencyTag>(source_positions, positions, 1);
  for_range<ConcurrencyTag>(0, std::size_t(n), [&](std::size_t i) {
    distance(Eigen::Index(i)) = (positions.row(Eigen::Index(i)) - source_positions.row(nearest.indices[i])).norm();
  });
  return distance;
}

/// Shortest-path distance along the edges of `graph` (lengths: Euclidean) from every vertex to the nearest
/// of `sources` (multi-source Dijkstra); infinity where no source is reachable.
inline Eigen::VectorXd graph_distance_to(const Matrix_n3& positions, const Neighbor_graph& graph,
                                         const std::vector<int>& sources)
{
  const std::size_t n = graph.size();
  Eigen::VectorXd distance = Eigen::VectorXd::Constant(Eigen::Index(n), std::numeric_limits<double>::infinity());
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for(int s : sources) {
    distance(s) = 0;
    queue.emplace(0.0, s);
  }
  while(!queue.empty()) {
    const auto [d, i] = queue.top();
    queue.pop();
    if(d > distance(i)) continue;
    for(const int* j = graph.begin(std::size_t(i)); j != graph.end(std::size_t(i)); ++j) {
      const double through = d + (positions.row(i) - positions.row(*j)).norm();
      if(through < distance(*j)) {
        distance(*j) = through;
        queue.emplace(through, *j);
      }
    }
  }
  return distance;
}

/// The smooth step `beta(t) = 3 t^2 - 2 t^3` on [0, 1]: beta(0) = 0, beta(1) = 1, flat at both ends, so the
/// strength field has no kink where it meets the fixed part or the handle.
inline double smooth_step(double t)
{
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

/// Strength `beta(d0 / (d0 + d1))` of one handle group: 1 on the handle (d1 = 0) and where no fixed point is
/// reachable (d0 infinite), 0 on the fixed part.
inline double strength(double d0, double d1)
{
  if(d1 == 0 || std::isinf(d0)) return 1.0;
  if(std::isinf(d1)) return 0.0;
  return smooth_step(d0 / (d0 + d1));
}

/// Propagated rotation of one point from the handle groups' rotations (unit quaternions): each group pulls by
/// its strength `f_g`, shared among groups in proportion to `1 / d1_g` (a point on a handle takes that
/// handle's rotation only), and the rest of the weight stays with the identity; the blend is normalised
/// (nlerp). Quaternions are taken on the identity's side (w >= 0), so the blend follows the shorter arc.
inline Eigen::Quaterniond propagated_rotation(const std::vector<Eigen::Quaterniond>& rotations,
                                              const double* d1, const double* strengths)
{
  const std::size_t groups = rotations.size();
  double total = 0;
  std::size_t on_handle = groups;
  for(std::size_t g = 0; g < groups; ++g) {
    if(d1[g] == 0) on_handle = g;
    if(std::isfinite(d1[g])) total += 1.0 / std::max(d1[g], std::numeric_limits<double>::min());
  }
  Eigen::Vector4d blend = Eigen::Vector4d::Zero(); // (x, y, z, w)
  double pulled = 0;
  for(std::size_t g = 0; g < groups; ++g) {
    double share = 0;
    if(on_handle < groups) share = g == on_handle ? 1.0 : 0.0;
    else if(std::isfinite(d1[g]) && total > 0) share = (1.0 / std::max(d1[g], std::numeric_limits<double>::min())) / total;
    const double w = share * strengths[g];
    const Eigen::Vector4d q = rotations[g].w() < 0 ? Eigen::Vector4d(-rotations[g].coeffs()) : Eigen::Vector4d(rotations[g].coeffs());
    blend += w * q;
    pulled += w;
  }
  blend(3) += 1.0 - pulled;
  return Eigen::Quaterniond(blend(3), blend(0), blend(1), blend(2)).normalized();
}

/// The strength field of an edit's handle groups on its sample points (Miao et al. 2007, Sect. 6.2): per sample
/// point and group the distance `d1` to the group's handle and the strength `beta(d0 / (d0 + d1))`, `d0` the
/// distance to the fixed part, along the sample points' graph (geodesic) or straight. Set up once per selection;
/// each drag blends the groups' rotations by it.
class Strength_field
{
public:
  /// `labels`: per sample point (`Edit_label`); `groups`: the number of handle groups.
  template <typename ConcurrencyTag>
  void setup(const Matrix_n3& samples, const Neighbor_graph& graph, const std::vector<int>& labels, std::size_t groups,
             bool geodesic)
  {
    const std::size_t count = std::size_t(samples.rows());
    m_groups = groups;
    std::vector<int> fixed;
    std::vector<std::vector<int>> handles(groups);
    for(std::size_t s = 0; s < count; ++s) {
      if(labels[s] == fixed_label) fixed.push_back(int(s));
      else if(is_handle_label(labels[s])) handles[handle_group_of_label(labels[s])].push_back(int(s));
    }
    auto distance_to = [&](const std::vector<int>& sources) {
      return geodesic ? graph_distance_to(samples, graph, sources) : euclidean_distance_to<ConcurrencyTag>(samples, sources);
    };
    const Eigen::VectorXd d0 = distance_to(fixed);
    m_d1.assign(count * groups, 0.0);
    m_strength.assign(count * groups, 0.0);
    for(std::size_t g = 0; g < groups; ++g) {
      const Eigen::VectorXd d1 = distance_to(handles[g]);
      for(std::size_t s = 0; s < count; ++s) {
        m_d1[s * groups + g] = d1(Eigen::Index(s));
        // Only the region's sample points turn; the fixed part has strength 0 by definition (d0 = 0).
        m_strength[s * groups + g] = labels[s] == fixed_label ? 0.0 : strength(d0(Eigen::Index(s)), d1(Eigen::Index(s)));
      }
    }
  }

  /// The strength of group `g` at sample point `s`.
  double at(std::size_t s, std::size_t g) const { return m_strength.at(s * m_groups + g); }

  /// At each sample point `s` of `rows`, `rotations[s]` becomes the blend of the groups' `turns`
  /// (`propagated_rotation`), or with `compose` that blend times `rotations[s]`.
  template <typename ConcurrencyTag>
  void propagate(const std::vector<Eigen::Quaterniond>& turns, const std::vector<int>& rows,
                 std::vector<Eigen::Matrix3d>& rotations, bool compose = false) const
  {
    for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t r) {
      const std::size_t s = std::size_t(rows[r]);
      const Eigen::Matrix3d blend =
        propagated_rotation(turns, &m_d1[s * m_groups], &m_strength[s * m_groups]).toRotationMatrix();
      rotations[s] = compose ? Eigen::Matrix3d(blend * rotations[s]) : blend;
    });
  }

private:
  std::size_t m_groups = 0;
  std::vector<double> m_d1, m_strength; // per sample point and group
};

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_STRENGTH_FIELD_INSTANCES(EXTERN, Tag) \
  EXTERN template Eigen::VectorXd euclidean_distance_to<Tag>(const Matrix_n3&, const std::vector<int>&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_STRENGTH_FIELD_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_STRENGTH_FIELD_H
