// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DIFFUSION_VIEW_H
#define CGAL_EXT_DIFFUSION_VIEW_H

#include <CGAL_ext/Detail_preserving_deformation_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/point_diffusion.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  The sample points' side of an edit's diffusion, as of the last
  `Detail_preserving_deformation::update_sample_motions()` (from `Diffusion_view::state()`): what
  `diffuse_points()` needs to move points the deformation was not built on. Plain arrays, which a program can
  send to other processes, such as the workers of a tiled edit of a scan larger than one machine.
*/
struct Diffusion_state
{
  std::vector<double> sample_positions;          ///< three numbers per sample point
  std::vector<double> deformed_sample_positions; ///< three numbers per sample point
  /// Twelve numbers per sample point: the top three rows of `Diffusion_view::sample_motion()`, row-major.
  std::vector<double> motions;
  /// Per sample point, 1 if it is in the region of interest (only those move points), else 0.
  std::vector<std::uint8_t> region_samples;
  /// Seven numbers per handle group: its transform's rotation as a unit quaternion (w, x, y, z), then its
  /// translation.
  std::vector<double> handle_transforms;
  /// The sample points that carry each point.
  std::size_t stencil_size = 1;
  /// `Detail_preserving_deformation_settings::diffusion_origin`.
  Diffusion_origin origin = Diffusion_origin::own_sample;
  /// `Detail_preserving_deformation_settings::portable_diffusion`.
  bool portable = false;
  /// Whether handle points follow their group's transform exactly (an infinite `handle_weight`).
  bool exact_handles = true;
  /// How far the collar spreads the exact handles' steps (`Detail_preserving_deformation_settings::handle_collar`),
  /// as the deformation measured it over all its handle points; 0 without a collar.
  double collar_reach = 0;
  /// `Detail_preserving_deformation_settings::detail_anchor`, `detail_iterations` and `detail_tolerance`: how
  /// `diffuse_points()` restores the details when asked to (its `restore_details` named parameter).
  double detail_anchor = 1e-2;
  unsigned int detail_iterations = 100;
  double detail_tolerance = 1e-2;

  /// The values of `diffuse_points()`'s `selection_map` for a point outside the region of interest and for a
  /// region point that is no handle; a handle point's value is its handle group.
  static constexpr int fixed = -2, region = -1;

  std::size_t number_of_sample_points() const { return sample_positions.size() / 3; }
  std::size_t number_of_handle_groups() const { return handle_transforms.size() / 7; }

  /// \throws Invalid_input if the arrays' sizes disagree, a number is not finite, a rotation is not a unit
  /// quaternion, or `stencil_size` is 0 or more than the sample points.
  void validate() const
  {
    const std::size_t s = number_of_sample_points();
    const auto finite = [](const std::vector<double>& values) {
      return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
    };
    if(s == 0 || sample_positions.size() != 3 * s || deformed_sample_positions.size() != 3 * s ||
       motions.size() != 12 * s || region_samples.size() != s)
      throw Invalid_input("diffusion state: needs 3 sample positions, 3 deformed positions, 12 motion numbers and "
                          "a region flag per sample point, at least one sample point");
    if(handle_transforms.size() % 7 != 0)
      throw Invalid_input("diffusion state: needs 7 numbers per handle group's transform");
    if(!finite(sample_positions) || !finite(deformed_sample_positions) || !finite(motions) ||
       !finite(handle_transforms) || !(std::isfinite(collar_reach) && collar_reach >= 0))
      throw Invalid_input("diffusion state: a sample position, motion, transform or the collar's reach is not finite");
    if(!(detail_anchor > 0) || std::isinf(detail_anchor) || !(detail_tolerance >= 0) || std::isinf(detail_tolerance))
      throw Invalid_input("diffusion state: detail_anchor must be a finite number > 0 and detail_tolerance one >= 0");
    for(std::size_t g = 0; g < number_of_handle_groups(); ++g)
      if(std::abs(Eigen::Map<const Eigen::Vector4d>(&handle_transforms[7 * g]).norm() - 1) > 1e-6)
        throw Invalid_input("diffusion state: the rotation of handle group " + std::to_string(g) +
                            " is not a unit quaternion");
    if(stencil_size < 1 || stencil_size > s)
      throw Invalid_input("diffusion state: stencil_size must be between 1 and the number of sample points (" +
                          std::to_string(s) + "), not " + std::to_string(stencil_size));
  }
};

/*!
  \ingroup PkgCGALExtAlgorithms
  What `Detail_preserving_deformation::diffuse()` does to each point, for a renderer that moves the points itself
  (a GPU's vertex shader, as the studio's): from `Detail_preserving_deformation::diffusion_view()`. The renderer
  repeats `diffuse()` from data fixed at preprocessing, each point's stencil and the collar, and per drag data
  proportional to the sample points only: their motions and the collar's handle steps, as of the last
  `Detail_preserving_deformation::update_sample_motions()`.

  With `Diffusion_origin::own_sample`, point `p` (input index `i`) moves to `p + sum_e w_e M_{s_e} (p, 1)` over
  its stencil (`stencil(i, ...)`), `M_s` the top three rows of `sample_motion(s)`; an exact handle point of group
  g to its transform; a collar point further by `sum_e w_e step_e` over its entries (`for_each_collar_point()`,
  `collar_handle_step()`).

  A view: it reads the deformation object, which must outlive it, and holds until its next `preprocess()`.

  \sa The manual's page of the editing studio, whose page moves the points this way:
  <a href="../../../doc/studio.md">The editing studio</a> (`doc/studio.md`).
*/
class Diffusion_view
{
  using Matrix_n3 = internal::Matrix_n3;

public:
  /// Sample point `s`'s motion record: `[T_s, c_s; 0, 1]`, so that a point it carries alone moves by
  /// `T_s p + c_s`; `T_s` is the sample point's map less the identity rounded to floats, and `c_s` its move
  /// less `T_s` times its position.
  Eigen::Matrix4d sample_motion(std::size_t s) const { return m_diffusion.stencil.motion_record(s); }

  /// The number of sample points that carry each point (the same for every point).
  std::size_t stencil_size() const { return m_diffusion.stencil.width(); }

  /// Writes point `i`'s stencil: `stencil_size()` sample points and their weights (which sum to 1).
  void stencil(std::size_t i, int* sample_points, double* weights) const
  {
    m_diffusion.stencil.copy_row(checked_row(i), sample_points, weights);
  }

  /// Whether point `i` follows its handle group's transform exactly (exact handles, `handle_weight` infinite).
  bool is_exact_handle_point(std::size_t i) const
  {
    return std::isinf(m_settings.handle_weight) && internal::is_handle_label(m_selection.labels[checked_row(i)]);
  }

  /// The handle points whose steps the collar spreads (input indices); `collar_handle_step(c)` is the step of the
  /// c-th.
  const std::vector<int>& collar_handle_points() const { return m_diffusion.collar.stepping_handle_points; }

  /// Calls `visit(i, handles, weights, count)` for each point `i` of the collar: it moves by the weighted sum of
  /// the steps of `count` collar handle points (indices into `collar_handle_points()`).
  template <typename Visitor>
  void for_each_collar_point(const Visitor& visit) const
  {
    m_diffusion.collar.for_each_point(m_cloud.input_index, visit);
  }

  /// The step of collar handle point `c` for the sample points' motions: its transform's position less its
  /// blended one, and the same for its normal.
  void collar_handle_step(std::size_t c, Eigen::Vector3d& step, Eigen::Vector3d& normal_step) const
  {
    m_diffusion.collar.handle_step(c, m_diffusion.stencil, m_cloud.positions, m_normals, m_sample_positions,
                                   m_deformed_samples, m_settings.diffusion_origin, m_selection.transforms, step,
                                   normal_step);
  }

  /// The sample points' positions, motions and region flags, the handle groups' transforms and the collar's
  /// reach, for `diffuse_points()` in this process or another.
  /// \throws Invalid_input before the first `Detail_preserving_deformation::update_sample_motions()` (or
  /// `diffuse()`) since `preprocess()`.
  Diffusion_state state() const
  {
    Diffusion_state out;
    const std::size_t s = std::size_t(m_sample_positions.rows());
    if(m_diffusion.stencil.number_of_motion_records() != s)
      throw Invalid_input("Diffusion_view::state(): the sample points have no motions yet; call "
                          "update_sample_motions() or diffuse() first");
    out.sample_positions.assign(m_sample_positions.data(), m_sample_positions.data() + 3 * s);
    out.deformed_sample_positions.assign(m_deformed_samples.data(), m_deformed_samples.data() + 3 * s);
    out.motions.resize(12 * s);
    for(std::size_t j = 0; j < s; ++j)
      for(int r = 0; r < 3; ++r)
        for(int c = 0; c < 4; ++c) out.motions[12 * j + std::size_t(4 * r + c)] = sample_motion(j)(r, c);
    for(int label : m_sample_labels) out.region_samples.push_back(label != internal::fixed_label ? 1 : 0);
    for(const internal::Rigid_transform& T : m_selection.transforms) {
      const Eigen::Quaterniond& q = T.rotation;
      const Eigen::Vector3d& t = T.translation;
      out.handle_transforms.insert(out.handle_transforms.end(), {q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()});
    }
    out.stencil_size = stencil_size();
    out.origin = m_settings.diffusion_origin;
    out.portable = m_settings.portable_diffusion;
    out.exact_handles = std::isinf(m_settings.handle_weight);
    out.collar_reach = m_diffusion.collar.reach;
    out.detail_anchor = m_settings.detail_anchor;
    out.detail_iterations = m_settings.detail_iterations;
    out.detail_tolerance = m_settings.detail_tolerance;
    return out;
  }

  /// \cond SKIP_IN_MANUAL
  // Built by Detail_preserving_deformation::diffusion_view() over its parts.
  Diffusion_view(const internal::Point_diffusion& diffusion, const internal::Spatial_point_cloud& cloud,
                 const std::vector<int>& row_of, const Matrix_n3& normals, const Matrix_n3& sample_positions,
                 const std::vector<int>& sample_labels, const Matrix_n3& deformed_samples,
                 const internal::Edit_selection& selection, const Detail_preserving_deformation_settings& settings)
      : m_diffusion(diffusion), m_cloud(cloud), m_row_of(row_of), m_normals(normals),
        m_sample_positions(sample_positions), m_sample_labels(sample_labels), m_deformed_samples(deformed_samples),
        m_selection(selection), m_settings(settings)
  {}
  /// \endcond

private:
  std::size_t checked_row(std::size_t i) const
  {
    return internal::checked_row(m_row_of, i, "Detail_preserving_deformation::diffusion_view()");
  }

  const internal::Point_diffusion& m_diffusion;
  const internal::Spatial_point_cloud& m_cloud;
  const std::vector<int>& m_row_of;
  const Matrix_n3& m_normals;
  const Matrix_n3& m_sample_positions;
  const std::vector<int>& m_sample_labels;
  const Matrix_n3& m_deformed_samples;
  const internal::Edit_selection& m_selection;
  const Detail_preserving_deformation_settings& m_settings;
};

} // namespace CGAL_ext

#endif // CGAL_EXT_DIFFUSION_VIEW_H
