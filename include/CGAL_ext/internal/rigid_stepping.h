// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_RIGID_STEPPING_H
#define CGAL_EXT_INTERNAL_RIGID_STEPPING_H

// As-rigid-as-possible editing on the sample points (Sorkine and Alexa 2007): a drag cut into steps, and the
// alternation of solve and rotation fits within a step.

#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/neighborhood_rotations.h>
#include <CGAL_ext/internal/sample_system.h>

#include <CGAL/number_type_config.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// A rigid transform `p -> rotation p + translation`.
struct Rigid_transform
{
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d operator()(const Eigen::Vector3d& p) const { return rotation * p + translation; }
};

/// How finely a drag is cut: each step turns a handle group by at most `max_degrees` and moves the handles'
/// centre by at most `max_fraction` of the region's size, in at most `max_steps` steps.
struct Rigid_step_limits
{
  double max_degrees;
  double max_fraction;
  unsigned int max_steps;
};

/// The steps from the transforms `from` to `to` (per handle group) under `limits`; `centre` is the handles'
/// centre, `region_size` the region's bounding diagonal (0: the shift sets no limit).
inline std::size_t rigid_step_count(const std::vector<Rigid_transform>& from, const std::vector<Rigid_transform>& to,
                                    const Eigen::Vector3d& centre, double region_size, const Rigid_step_limits& limits)
{
  std::size_t steps = 1;
  const double cap = double(limits.max_steps);
  for(std::size_t g = 0; g < to.size(); ++g) {
    const double angle = from[g].rotation.angularDistance(to[g].rotation);
    const double shift = (to[g](centre) - from[g](centre)).norm();
    steps = std::max(steps, std::size_t(std::ceil(std::min(angle / (limits.max_degrees * CGAL_PI / 180), cap) - 1e-9)));
    if(region_size > 0)
      steps = std::max(steps, std::size_t(std::ceil(std::min(shift / (limits.max_fraction * region_size), cap) - 1e-9)));
  }
  return steps;
}

/// The transform a fraction `f` of the way from `from` to `to`: the rotation slerped about `centre`, which
/// moves on a line.
inline Rigid_transform rigid_step(const Rigid_transform& from, const Rigid_transform& to, const Eigen::Vector3d& centre,
                                  double f)
{
  Rigid_transform along;
  along.rotation = from.rotation.slerp(f, to.rotation);
  along.translation = ((1 - f) * from(centre) + f * to(centre)) - along.rotation * centre;
  return along;
}

/// One step: at most `iterations` alternations of the global solve (the edges' right-hand side turned by
/// `rotations`, the handles pulled by `anchor_displacement`) and the local fit of `rotations` to its result
/// (the region's and the fixed ring's around it, `Sample_system::rigid_rotation_rows`);
/// with `tolerance` > 0, it stops once no region sample point moved more than `tolerance` in an iteration;
/// `smoothing` is the rotation fit's (`fit_neighborhood_rotations`, scaled by `system.smoothing_area` when it is
/// > 0). `edge_change`, `previous` and
/// `previous_rotations` are buffers. Returns the iterations taken.
template <typename ConcurrencyTag>
unsigned int rigid_iterations(Sample_system& system, const Matrix_n3& samples, const Matrix_n3& anchor_displacement,
                              unsigned int iterations, double tolerance, double smoothing,
                              std::vector<Eigen::Matrix3d>& rotations, Matrix_n3& deformed, Matrix_n3& edge_change,
                              Matrix_n3& previous, std::vector<Eigen::Matrix3d>& previous_rotations)
{
  unsigned int used = 0;
  for(unsigned int iteration = 0; iteration < iterations; ++iteration) {
    edge_change = rigid_edge_change<ConcurrencyTag>(system.rigid_edges, system.rigid_edge_scales, samples, rotations);
    if(tolerance > 0) previous = deformed;
    system.solve<ConcurrencyTag>(samples, edge_change, anchor_displacement, deformed);
    fit_neighborhood_rotations<ConcurrencyTag>(samples, deformed, system.graph, system.edge_weights,
                                               system.rigid_rotation_rows, smoothing, system.smoothing_area, rotations,
                                               previous_rotations);
    ++used;
    if(!(tolerance > 0)) continue;
    double moved = 0;
    for(int s : system.roi) moved = std::max(moved, (deformed.row(s) - previous.row(s)).norm());
    if(moved <= tolerance) break;
  }
  return used;
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_RIGID_STEPPING_H
