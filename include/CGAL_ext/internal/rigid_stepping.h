// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_RIGID_STEPPING_H
#define CGAL_EXT_INTERNAL_RIGID_STEPPING_H

// The drag of the sample points: as rigid as possible (Sorkine and Alexa 2007), a drag cut into steps and the
// alternation of solve and rotation fits within a step; or with the strength field's propagated rotations, one solve.

#include <CGAL_ext/Detail_preserving_deformation_settings.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/neighborhood_rotations.h>
#include <CGAL_ext/internal/sample_system.h>
#include <CGAL_ext/internal/strength_field.h>

#include <CGAL/number_type_config.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

namespace CGAL_ext {
namespace internal {

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
/// `rotations`, the handles pulled by `system.pull_anchors`) and the local fit of `rotations` to its result
/// (the region's and the fixed ring's around it, `Sample_system::rigid_rotation_rows`);
/// with `tolerance` > 0, it stops once no region sample point moved more than `tolerance` in an iteration;
/// `smoothing` is the rotation fit's (`fit_neighborhood_rotations`, scaled by `system.smoothing_area` when it is
/// > 0). `edge_change`, `previous` and
/// `previous_rotations` are buffers. Returns the iterations taken.
template <typename ConcurrencyTag>
unsigned int rigid_iterations(Sample_system& system, const Matrix_n3& samples, unsigned int iterations, double tolerance, double smoothing,
                              std::vector<Eigen::Matrix3d>& rotations, Matrix_n3& deformed, Matrix_n3& edge_change,
                              Matrix_n3& previous, std::vector<Eigen::Matrix3d>& previous_rotations)
{
  unsigned int used = 0;
  for(unsigned int iteration = 0; iteration < iterations; ++iteration) {
    edge_change = rigid_edge_change<ConcurrencyTag>(system.rigid_edges, system.rigid_edge_scales, samples, rotations);
    if(tolerance > 0) previous = deformed;
    system.solve<ConcurrencyTag>(samples, edge_change, deformed);
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

/// An as-rigid-as-possible drag and the state it keeps between drags. The energy is not convex: a large change of
/// the handles since the last solve is taken in steps (`rigid_step_count`; each group's rotation slerped about the
/// handles' common centre, which moves on a line), along which the solution follows the deformation the user would
/// drag through. Each step starts from the rotations of the one before (the first drag from the propagated
/// ones): on the cactus that lands far closer to CGAL's mesh ARAP than one step of more iterations, or each step
/// first turning the rotations by the strength field's blend (doc/editing_arap.md, "As rigid as possible").
class Rigid_drag
{
public:
  /// A new selection: the handles' centre and the region's size; no drag yet.
  void setup(const Sample_system& system, const Matrix_n3& samples, std::size_t groups)
  {
    m_centre.setZero();
    for(int a : system.anchors)
      m_centre += samples.row(system.roi[std::size_t(a)]).transpose() / double(system.anchors.size());
    Eigen::AlignedBox3d region_box;
    for(int s : system.roi) region_box.extend(samples.row(s).transpose());
    m_region_size = region_box.diagonal().norm();
    reset(groups);
  }

  /// Back to the rest shape: the next drag starts from the identity transforms and the propagated rotations.
  void reset(std::size_t groups)
  {
    m_solved.assign(groups, Rigid_transform());
    m_has_rotations = false;
  }

  /// Whether `rotations` hold the last drag's fitted rotations.
  bool has_rotations() const { return m_has_rotations; }

  /// Drags the handles from the last drag's transforms to `transforms`: writes the region's rows of `deformed` and
  /// the fitted `rotations` (per sample point). Returns the iterations taken.
  template <typename ConcurrencyTag>
  unsigned int drag(Sample_system& system, const Strength_field& field, const Matrix_n3& samples,
                    const std::vector<Rigid_transform>& transforms, const Detail_preserving_deformation_settings& settings,
                    std::vector<Eigen::Matrix3d>& rotations, Matrix_n3& deformed)
  {
    const std::size_t groups = transforms.size();
    const std::size_t steps = rigid_step_count(
      m_solved, transforms, m_centre, m_region_size,
      Rigid_step_limits{settings.rigid_step_degrees, settings.rigid_step_fraction, settings.max_rigid_steps});
    std::vector<Rigid_transform> along(groups);
    std::vector<Eigen::Quaterniond> previous(groups), turns(groups);
    unsigned int used = 0;
    for(std::size_t step = 1; step <= steps; ++step) {
      for(std::size_t g = 0; g < groups; ++g)
        along[g] = step == steps ? transforms[g] : rigid_step(m_solved[g], transforms[g], m_centre, double(step) / double(steps));
      if(!m_has_rotations) {
        for(std::size_t g = 0; g < groups; ++g) turns[g] = along[g].rotation;
        field.propagate<ConcurrencyTag>(turns, system.roi, rotations);
        m_has_rotations = true;
      } else if(system.roi.size() == std::size_t(samples.rows())) {
        // Nothing is fixed: the strength field is 1 everywhere and its blend of the handles' turns is exact for
        // a rigid motion, so each step starts from it (with a fixed part it misleads, as on the cactus).
        for(std::size_t g = 0; g < groups; ++g)
          turns[g] = along[g].rotation * (step == 1 ? m_solved[g].rotation : previous[g]).conjugate();
        field.propagate<ConcurrencyTag>(turns, system.roi, rotations, true);
      }
      for(std::size_t g = 0; g < groups; ++g) previous[g] = along[g].rotation;
      system.pull_anchors(samples, along);
      used += rigid_iterations<ConcurrencyTag>(system, samples, settings.rigid_iterations,
                                               settings.rigid_tolerance * m_region_size, settings.rigid_rotation_smoothing,
                                               rotations, deformed, m_edge_change, m_previous, m_previous_rotations);
    }
    m_solved = transforms;
    return used;
  }

private:
  std::vector<Rigid_transform> m_solved; // the handles' transforms of the last drag
  bool m_has_rotations = false;
  Eigen::Vector3d m_centre = Eigen::Vector3d::Zero(); // centroid of the handles' sample points
  double m_region_size = 0;                           // bounding-box diagonal of the region's sample points
  Matrix_n3 m_edge_change, m_previous;                // per-iteration buffers
  std::vector<Eigen::Matrix3d> m_previous_rotations;
};

/// The drag without fitted rotations: the details turned by the rotations the strength `field` propagates from the
/// handle groups' `transforms` (`Detail_rotation::propagated`) or not turned (`none`), in one solve; writes the
/// region's rows of `deformed` and the `rotations` (per sample point).
template <typename ConcurrencyTag>
void propagated_drag(Sample_system& system, const Strength_field& field, const Matrix_n3& samples,
                     const std::vector<Rigid_transform>& transforms, Detail_rotation kind,
                     std::vector<Eigen::Matrix3d>& rotations, Matrix_n3& deformed)
{
  if(kind == Detail_rotation::none)
    std::fill(rotations.begin(), rotations.end(), Eigen::Matrix3d::Identity());
  else {
    std::vector<Eigen::Quaterniond> turns(transforms.size());
    for(std::size_t g = 0; g < transforms.size(); ++g) turns[g] = transforms[g].rotation;
    field.propagate<ConcurrencyTag>(turns, system.roi, rotations);
  }
  system.pull_anchors(samples, transforms);
  system.template solve_turned_details<ConcurrencyTag>(samples, rotations, deformed);
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_RIGID_STEPPING_H
