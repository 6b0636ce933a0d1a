// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_H
#define CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_H

#include <CGAL_ext/Detail_preserving_deformation_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/detail_relaxation.h>
#include <CGAL_ext/internal/estimate_oriented_normals.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/rigid_stepping.h>
#include <CGAL_ext/internal/sample_points.h>
#include <CGAL_ext/internal/sample_system.h>
#include <CGAL_ext/internal/ssp_diffusion.h>
#include <CGAL_ext/internal/strength_field.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Detail-preserving editing of a point-sampled surface (Miao et al. 2007, Sect. 6), shaped like
  `CGAL::Surface_mesh_deformation`: select a region of interest (ROI) and handle groups, `preprocess()`,
  then move the handles with `set_handle_transform()` and call `deform()` and `diffuse()` as often as wanted.

  - The points are clustered into simplification sample points (SSPs) that never mix fixed, ROI and handle
    points (`compute_simplification_sample_points`).
  - The SSPs' geometric details `delta = f(K) s` are kept in the least-squares sense with the handle SSPs on
    their targets: `min alpha sum_{i in ROI} ||(f(K) s')_i - R(Q_i) delta_i||^2` subject to
    `s'_h = R_g s_h + t_g` (or, with a finite `handle_weight` w, the paper's soft constraint
    `+ w sum_{h in handles} ||s'_h - (R_g s_h + t_g)||^2`), with SSPs outside the ROI fixed. The unknowns are
    displacements and the normal matrix is factored once in `preprocess()`; a handle move only changes the
    right-hand side.
  - Rotations propagate from the handles by the strength field `f = beta(d0 / (d0 + d1))`, `beta(t) =
    3t^2 - 2t^3`: `Q_i = nlerp(identity, Q_handle, f)`. Several groups share the pull in proportion to
    `1 / d1_g` (a handle SSP follows its own group only).
  - Or, `Detail_rotation::as_rigid_as_possible`, each `R_i` is the best rotation of the SSP's neighbourhood
    edges from rest to the solved shape, alternated with the solve (same factorisation) a few times per drag;
    the edges weigh the same, or (`Rigid_edge_weights::cotangent`) by the cotangent weights of each SSP's
    Voronoi cell in its tangent plane.
  - Every point follows its `m` nearest SSPs through their local frames (normal refitted after the edit,
    first axis toward a fixed reference neighbour), blended by weights `(1 - d_j / d_max)^2` that vanish at
    the (m+1)-th nearest SSP, so the motion is continuous in space; normals turn with the blended rotation.
    With exact handles, handle points follow their transform exactly.

  Identities (tested): handle points end on their targets to rounding; unmoved handles return every point
  exactly; with the whole model as ROI, moving every handle group by one rigid motion moves every point and
  normal rigidly; points whose SSPs are all fixed never move.

  The object copies the points and normals at construction; the caller's range is only written by
  `diffuse(points, np)`. It is not copyable (it owns its factorisation).

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/editing.md">Detail-preserving editing</a> (`doc/editing.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
class Detail_preserving_deformation
{
  using Matrix_n3 = internal::Matrix_n3;
  using Transform = internal::Rigid_transform;
  static constexpr const char* who = "Detail_preserving_deformation";
  static constexpr int fixed_label = internal::fixed_label, roi_label = internal::roi_label,
                       first_handle_label = internal::first_handle_label;

public:
  using Settings = Detail_preserving_deformation_settings;
  using Statistics = Detail_preserving_deformation_statistics;

  /*!
    Copies the points and their normals.

    \param points the points (any range; its order defines the point indices used below)
    \param settings details, clustering, solver, strength field and diffusion settings
    \param np `point_map`, `normal_map` (estimated by `estimate_oriented_normals`
           when absent) and `callback` (progress of `preprocess()`; false cancels it)
    \throws Invalid_input for an empty range, non-finite coordinates, zero or non-finite normals, fewer than
            two points, or invalid settings.
  */
  template <typename PointRange, typename NamedParameters = CGAL::parameters::Default_named_parameters>
  explicit Detail_preserving_deformation(const PointRange& points, const Settings& settings = Settings(),
                                         const NamedParameters& np = CGAL::parameters::default_values())
    : m_settings(settings)
  {
    using CGAL::parameters::choose_parameter;
    using CGAL::parameters::get_parameter;
    using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
    m_settings.validate();
    m_callback = choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
    m_cloud = internal::make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
    if(m_cloud.size() < 2) throw Invalid_input(std::string(who) + ": editing needs at least two points");
    m_row_of = m_cloud.spatial_index();
    internal::Progress progress;
    internal::given_or_estimated_normals<ConcurrencyTag>(points, np, m_cloud, default_normal_neighbors, progress,
                                                         m_normals, who);
    m_label.assign(m_cloud.size(), fixed_label);
    m_in_roi.assign(m_cloud.size(), 0);
    m_deformed_points = m_cloud.positions;
    m_deformed_normals = m_normals;
  }

  Detail_preserving_deformation(const Detail_preserving_deformation&) = delete;
  Detail_preserving_deformation& operator=(const Detail_preserving_deformation&) = delete;

  /// \name Selection
  /// Point indices are positions in the range given at construction. Changing the selection makes the
  /// next `deform()` preprocess again.
  /// @{

  /// Adds a point to the region of interest (the deformable part; every other point stays fixed).
  void insert_roi_point(std::size_t i)
  {
    const std::size_t row = checked_row(i);
    m_in_roi[row] = 1;
    if(m_label[row] == fixed_label) m_label[row] = roi_label;
    m_preprocessed = false;
  }

  template <typename IndexRange>
  void insert_roi_points(const IndexRange& indices)
  {
    for(const auto& i : indices) insert_roi_point(std::size_t(i));
  }

  /// Adds a handle group, initially with the identity transform, and returns its index.
  std::size_t create_handle_group()
  {
    m_transforms.push_back(Transform());
    m_preprocessed = false;
    return m_transforms.size() - 1;
  }

  /// Makes point `i`, which must be (or later be put) in the region of interest, a handle of `group`.
  /// \throws Invalid_input if the point is already a handle of another group (it cannot follow two transforms).
  void insert_handle_point(std::size_t group, std::size_t i)
  {
    check_group(group);
    const std::size_t row = checked_row(i);
    const int label = first_handle_label + int(group);
    if(m_label[row] >= first_handle_label && m_label[row] != label)
      throw Invalid_input(std::string(who) + ": point #" + std::to_string(i) + " is a handle of group " +
                          std::to_string(m_label[row] - first_handle_label) + " and cannot also be one of group " +
                          std::to_string(group) + " (handle groups must not overlap)");
    m_label[row] = label;
    m_preprocessed = false;
  }

  template <typename IndexRange>
  void insert_handle_points(std::size_t group, const IndexRange& indices)
  {
    for(const auto& i : indices) insert_handle_point(group, std::size_t(i));
  }

  /// Puts every point back to fixed and removes the handle groups.
  void clear_selection()
  {
    std::fill(m_label.begin(), m_label.end(), fixed_label);
    std::fill(m_in_roi.begin(), m_in_roi.end(), 0);
    m_transforms.clear();
    m_preprocessed = false;
  }

  std::size_t number_of_handle_groups() const { return m_transforms.size(); }
  /// @}

  /// \name Editing
  /// @{

  /*!
    Clusters the points into sample points, builds their Laplacian and details, the strength field and the
    diffusion stencils, and factors the normal matrix. Called by `deform()` when the selection changed.
    \return false if the callback cancelled (the object then stays unpreprocessed).
    \throws Invalid_input for an empty region of interest, a handle group without points, a handle point
            outside the region, or a part of the region that neither a handle nor the fixed part pins.
    \throws Numerical_failure when the factorisation fails.
  */
  bool preprocess();

  /*!
    Computes now the part of `preprocess()` that does not depend on the selection, the points' mean-shift modes
    (the clustering's most costly part; nothing when the clustering does not use them), so that a program can
    compute it while its user selects. `preprocess()` computes it when it has not been.
    \return false if the callback cancelled.
  */
  bool analyse_points();

  /// The rigid transform `p -> R p + t` (world frame, the convention of the Botsch-Sorkine `.def` files) of a
  /// handle group. `R` must be a rotation (orthonormal within 1e-6, determinant +1).
  void set_handle_transform(std::size_t group, const Eigen::Matrix3d& R, const Eigen::Vector3d& t)
  {
    check_group(group);
    if(!R.allFinite() || !t.allFinite())
      throw Invalid_input(std::string(who) + ": the transform of handle group " + std::to_string(group) + " is not finite");
    const double error = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
    if(!(error < 1e-6) || !(R.determinant() > 0)) {
      std::ostringstream os;
      os << who << ": the matrix of handle group " << group << " is not a rotation (|R^T R - I| = " << error
         << ", det R = " << R.determinant() << "); give a rigid transform without scaling, shear or mirroring";
      throw Invalid_input(os.str());
    }
    m_transforms[group] = Transform{Eigen::Quaterniond(R).normalized(), t};
  }

  /// As above with the rotation as a unit quaternion (norm within 1e-6 of 1).
  void set_handle_transform(std::size_t group, const Eigen::Quaterniond& q, const Eigen::Vector3d& t)
  {
    check_group(group);
    if(!q.coeffs().allFinite() || !t.allFinite())
      throw Invalid_input(std::string(who) + ": the transform of handle group " + std::to_string(group) + " is not finite");
    if(!(std::abs(q.norm() - 1) < 1e-6)) {
      std::ostringstream os;
      os << who << ": the quaternion of handle group " << group << " has norm " << q.norm()
         << "; a rotation needs a unit quaternion (normalise it)";
      throw Invalid_input(os.str());
    }
    m_transforms[group] = Transform{q.normalized(), t};
  }

  /*!
    Solves the sample points' new positions for the current handle transforms (preprocessing first if the
    selection changed). Only the right-hand side changes between calls: one back-substitution.
    \return false if a needed preprocessing was cancelled.
  */
  bool deform();

  /// Carries the sample points' deformation to every point and normal (internal arrays; read them with
  /// `deformed_point()` or write them with `diffuse(points, np)`). Parallel and allocation-free.
  void diffuse();

  /*!
    `diffuse()`, then writes every point's deformed position through `point_map` and, when given, its
    normal through `normal_map` (`np`), in the order of `points`, which must have as many elements as the
    range given at construction.
  */
  template <typename PointRange, typename NamedParameters = CGAL::parameters::Default_named_parameters>
  void diffuse(PointRange& points, const NamedParameters& np = CGAL::parameters::default_values());

  /*!
    Puts back the fine details that `diffuse()` smooths out where neighbouring sample points move differently.
    Over every point the last `diffuse()` moved it solves `(1 + a) x_i - mean_j x_j = R_i (p_i - mean_j p_j) +
    a y_i`, `j` over the point's neighbours in the point-set Laplacian's graph (10 nearest, symmetrised), `y_i`
    where `diffuse()` put it, `R_i` the rotation of its neighbourhood there and `a` = `settings().detail_anchor`:
    the details finer than about `1 / sqrt(a)` point spacings come back, the coarser shape stays the
    diffusion's. Jacobi-preconditioned conjugate gradients, up to `settings().detail_iterations` of them or
    to `settings().detail_tolerance` (`statistics()` reports both). Handle points (exact handles), points that
    did not move and the fixed part pin the solve and keep their positions bit for bit; a rigid motion stays
    exact to rounding. Normals keep the diffusion's. It costs many diffusions (the first call after
    preprocessing also finds the points' neighbours), so call it once a drag ends, not per drag; the next
    `diffuse()` starts from the blend again (doc/editing.md, "Restoring the details", gives its times).
    \throws Invalid_input unless `diffuse()` ran since the last `preprocess()` or `reset()`.
  */
  void restore_details();

  /// `restore_details()`, then writes every point and normal as `diffuse(points, np)` does.
  template <typename PointRange, typename NamedParameters = CGAL::parameters::Default_named_parameters>
  void restore_details(PointRange& points, const NamedParameters& np = CGAL::parameters::default_values());

  /// Handle transforms back to the identity and every point back to its input position and normal; the
  /// preprocessing is kept.
  void reset()
  {
    for(Transform& t : m_transforms) t = Transform();
    m_deformed_points = m_cloud.positions;
    m_deformed_normals = m_normals;
    m_deformed_samples = m_samples;
    std::fill(m_sample_map.begin(), m_sample_map.end(), Eigen::Matrix3d::Identity());
    std::fill(m_propagated.begin(), m_propagated.end(), Eigen::Matrix3d::Identity());
    m_has_rigid_rotations = m_diffused = false;
    m_solved_transforms.assign(m_transforms.size(), Transform());
  }
  /// @}

  /// \name Results and sizes
  /// @{
  std::size_t number_of_points() const { return m_cloud.size(); }
  std::size_t number_of_sample_points() const { return std::size_t(m_samples.rows()); }
  std::size_t number_of_roi_sample_points() const { return m_system.roi.size(); }
  bool is_preprocessed() const { return m_preprocessed; }
  const Statistics& statistics() const { return m_statistics; }

  Eigen::Vector3d point(std::size_t i) const { return m_cloud.positions.row(m_row_of.at(i)).transpose(); }
  Eigen::Vector3d normal(std::size_t i) const { return m_normals.row(m_row_of.at(i)).transpose(); }
  Eigen::Vector3d deformed_point(std::size_t i) const { return m_deformed_points.row(m_row_of.at(i)).transpose(); }
  Eigen::Vector3d deformed_normal(std::size_t i) const { return m_deformed_normals.row(m_row_of.at(i)).transpose(); }

  /*!
    Calls `write(i, point, normal)` for every input index `i` with its deformed position and normal (three
    doubles each), in parallel and in increasing `i`: the cheap way to copy the result out of the object's
    spatial order into a caller's arrays after a drag (their writes go forward; the reads, scattered, are
    fetched ahead). With `movable_only`, only for the points the edit can move (those a region sample point
    carries, the handles among them): since `preprocess()` the others keep their input position and normal,
    so a caller that wrote every point once since then need only rewrite these after each drag.
  */
  template <typename Writer>
  void for_each_deformed_point(const Writer& write, bool movable_only = false) const
  {
    const std::size_t count = movable_only ? m_movable_points.size() : m_row_of.size();
    const auto input = [&](std::size_t a) { return movable_only ? std::size_t(m_movable_points[a]) : a; };
    internal::for_range<ConcurrencyTag>(0, count, [&](std::size_t a) {
      constexpr std::size_t ahead = 16; // rows in flight: enough to hide a memory access behind the writes
#if defined(__GNUC__)
      if(a + ahead < count) {
        const Eigen::Index later = m_row_of[input(a + ahead)];
        __builtin_prefetch(m_deformed_points.row(later).data());
        __builtin_prefetch(m_deformed_normals.row(later).data());
      }
#endif
      const std::size_t i = input(a);
      const Eigen::Index row = m_row_of[i];
      write(i, m_deformed_points.row(row).data(), m_deformed_normals.row(row).data());
    });
  }

  /// \name Moving the points elsewhere
  /// A renderer that moves the points itself (a GPU's vertex shader, as the studio's) repeats `diffuse()` from
  /// data fixed at preprocessing, each point's stencil and the collar, and per drag data proportional to the
  /// sample points only: their motions and the collar's handle steps. With `Diffusion_origin::own_sample`, point
  /// `p` (input index `i`) moves to `p + sum_e w_e M_{s_e} (p, 1)` over its stencil (`stencil(i, ...)`), `M_s` the
  /// top three rows of `sample_motion(s)`; an exact handle point of group g to its transform; a collar point further
  /// by `sum_e w_e step_e` over its entries (`for_each_collar_point()`, `collar_handle_step()`).
  /// @{

  /// The first half of `diffuse()`: each sample point's motion for the last `deform()`; moves no point.
  /// O(sample points).
  void update_sample_motions();

  /// Sample point `s`'s motion record from `update_sample_motions()` (or `diffuse()`): `[A_s - I, c_s; 0, 1]`,
  /// so that a point it carries alone moves by `(A_s - I) p + c_s`.
  const Eigen::Matrix4d& sample_motion(std::size_t s) const { return m_stencil.motion_record(s); }

  /// The number of sample points that carry each point (the same for every point, after `preprocess()`).
  std::size_t stencil_size() const { return m_stencil.samples.size() ? std::size_t(m_stencil.samples.degree(0)) : 0; }

  /// Writes point `i`'s stencil: `stencil_size()` sample points and their weights (which sum to 1).
  void stencil(std::size_t i, int* sample_points, double* weights) const
  {
    const std::size_t row = checked_row(i);
    for(int e = m_stencil.samples.offsets[row], k = 0; e < m_stencil.samples.offsets[row + 1]; ++e, ++k) {
      sample_points[k] = m_stencil.samples.indices[std::size_t(e)];
      weights[k] = m_stencil.weights[std::size_t(e)];
    }
  }

  /// Whether point `i` follows its handle group's transform exactly (exact handles, `handle_weight` infinite).
  bool is_exact_handle_point(std::size_t i) const
  {
    return std::isinf(m_settings.handle_weight) && m_label[checked_row(i)] >= first_handle_label;
  }

  /// The handle points whose steps the collar spreads (input indices); `collar_handle_step(c)` is the step of the
  /// c-th.
  const std::vector<int>& collar_handle_points() const { return m_collar_handle_points; }

  /// Calls `visit(i, handles, weights, count)` for each point `i` of the collar: it moves by the weighted sum of
  /// the steps of `count` collar handle points (indices into `collar_handle_points()`).
  template <typename Visitor>
  void for_each_collar_point(const Visitor& visit) const
  {
    for(std::size_t c = 0; c < m_collar_rows.size(); ++c) {
      const int first = m_collar.offsets[c];
      visit(std::size_t(m_cloud.input_index[std::size_t(m_collar_rows[c])]), m_collar_slots.data() + first,
            m_collar_weights.data() + first, std::size_t(m_collar.offsets[c + 1] - first));
    }
  }

  /// The step of collar handle point `c` for the motions of `update_sample_motions()`: its transform's position
  /// less its blended one, and the same for its normal.
  void collar_handle_step(std::size_t c, Eigen::Vector3d& step, Eigen::Vector3d& normal_step) const;
  /// @}

  /// The sample point of input point `i` (after `preprocess()`).
  std::size_t sample_point_of(std::size_t i) const { return std::size_t(m_sample_of.at(std::size_t(m_row_of.at(i)))); }
  Eigen::Vector3d sample_position(std::size_t s) const { return m_samples.row(Eigen::Index(s)).transpose(); }
  Eigen::Vector3d sample_normal(std::size_t s) const { return m_sample_normals.row(Eigen::Index(s)).transpose(); }
  Eigen::Vector3d deformed_sample_position(std::size_t s) const { return m_deformed_samples.row(Eigen::Index(s)).transpose(); }
  /// The detail vector `f(K) s` of sample point `s` (zero outside the region of interest).
  Eigen::Vector3d sample_detail(std::size_t s) const
  {
    const int r = m_system.roi_local.at(s);
    return r < 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(m_system.details.row(r).transpose());
  }
  /// The rotation of sample point `s`'s detail in the last `deform()`: propagated, or fitted to the result in
  /// as-rigid-as-possible mode (the identity outside the region, but for the fixed sample points next to it in
  /// as-rigid-as-possible mode, whose rotations the energy fits too; they still carry their points unturned).
  Eigen::Matrix3d propagated_rotation(std::size_t s) const { return m_propagated.at(s); }
  /// The strength `f = beta(d0 / (d0 + d1))` of handle group `g` at sample point `s`.
  double strength(std::size_t s, std::size_t g) const { return m_strength.at(s * m_transforms.size() + g); }
  /// The sample points' Laplacian `K` (rows in sample-point order).
  const Eigen::SparseMatrix<double, Eigen::RowMajor, int>& sample_laplacian() const { return m_system.K; }
  /// Whether sample point `s` is in the region of interest / a handle.
  bool is_roi_sample_point(std::size_t s) const { return m_sample_label.at(s) != fixed_label; }
  bool is_handle_sample_point(std::size_t s) const { return m_sample_label.at(s) >= first_handle_label; }
  /// The handle group of sample point `s`; only for handle sample points.
  std::size_t handle_group_of(std::size_t s) const { return std::size_t(m_sample_label.at(s) - first_handle_label); }
  /// The target of a handle point under its group's current transform.
  Eigen::Vector3d handle_target(std::size_t group, const Eigen::Vector3d& p) const
  {
    check_group(group);
    return m_transforms[group].rotation * p + m_transforms[group].translation;
  }
  const Settings& settings() const { return m_settings; }
  /// @}

private:
  void check_group(std::size_t group) const
  {
    if(group >= m_transforms.size())
      throw Invalid_input(std::string(who) + ": there is no handle group " + std::to_string(group) + " (" +
                          std::to_string(m_transforms.size()) + " groups; create_handle_group() adds one)");
  }

  std::size_t checked_row(std::size_t i) const
  {
    if(i >= m_cloud.size())
      throw Invalid_input(std::string(who) + ": point index " + std::to_string(i) + " is out of range (" +
                          std::to_string(m_cloud.size()) + " points)");
    return std::size_t(m_row_of[i]);
  }

  void check_selection() const;
  // Writes every deformed point, and normal when `np` names a normal map, through `np`'s maps.
  template <typename PointRange, typename NamedParameters>
  void write_deformed(PointRange& points, const NamedParameters& np) const;
  void cluster(internal::Progress& progress);
  void build_strength_field();
  void build_handle_collar();
  internal::Offset_origin offset_origin() const
  {
    return m_settings.diffusion_origin == Diffusion_origin::nearest_sample ? internal::Offset_origin::nearest_sample
                                                                           : internal::Offset_origin::own_sample;
  }

  Settings m_settings;
  std::function<bool(double)> m_callback;
  internal::Spatial_point_cloud m_cloud;
  std::vector<int> m_row_of;
  Matrix_n3 m_normals;
  std::vector<int> m_label;         // per row: fixed, ROI, or handle of group (label - 2)
  std::vector<char> m_in_roi;       // per row: inserted into the ROI (handles must be too)
  std::vector<Transform> m_transforms;
  bool m_preprocessed = false;
  internal::Mean_shift_analysis m_mean_shift; // selection-independent: computed once
  bool m_has_mean_shift = false;

  // Sample points (after preprocess).
  Matrix_n3 m_samples, m_sample_normals, m_deformed_samples;
  std::vector<int> m_sample_of;    // per row
  std::vector<int> m_sample_label; // per sample point
  std::vector<int> m_sample_first_row; // a member row of each sample point (for messages)
  std::size_t m_requested_samples = 0;  // what the mode-spread rule asked for
  internal::Sample_system m_system; // graph, Laplacian, region indexing and factored system of the sample points
  std::vector<double> m_d1, m_strength; // per sample point and group
  std::vector<Eigen::Matrix3d> m_propagated, m_frames; // m_propagated: the details' R_i
  std::vector<Eigen::Matrix3d> m_sample_map; // per sample point, the linear part of its motion (a rotation unless affine)
  std::vector<internal::Linear_map_prior> m_linear_map_priors; // affine turns: per region sample point
  bool m_has_rigid_rotations = false; // as-rigid-as-possible: m_propagated holds the last drag's rotations
  std::vector<Transform> m_solved_transforms;   // as-rigid-as-possible: the handles' transforms of the last drag
  Eigen::Vector3d m_handles_centre;             // centroid of the handles' sample points
  double m_region_size = 0;                     // bounding-box diagonal of the region's sample points
  internal::Ssp_frames m_frame_builder;
  internal::Diffusion_stencil m_stencil;
  std::vector<int> m_active_points; // rows carried by at least one region sample point
  std::vector<int> m_movable_points; // their input indices, increasing (for_each_deformed_point())
  std::vector<int> m_handle_rows;   // with exact handles: the rows that follow their group's transform exactly
  // With exact handles, the collar: the region's rows within reach of a handle and, per row, the nearest handle
  // point of each group that reaches it (an index into m_handle_rows) with the weight of that point's step.
  std::vector<int> m_collar_rows;
  internal::Neighbor_graph m_collar;
  std::vector<double> m_collar_weights;
  std::vector<int> m_collar_handles;       // the distinct handles of m_collar (indices into m_handle_rows)
  std::vector<int> m_collar_handle_points; // their input indices
  std::vector<int> m_collar_slots;         // per entry of m_collar, its handle's place in m_collar_handles
  Matrix_n3 m_handle_steps, m_handle_normal_steps; // per handle row, its transform's position less the blend's
  internal::Detail_relaxation m_relaxation; // restore_details(): set up by its first call after preprocess()
  bool m_has_relaxation = false;
  bool m_diffused = false; // diffuse() ran since preprocess() or reset(): the stencil holds its motions
  std::vector<Eigen::Matrix3d> m_group_rotations; // per handle group, filled by each diffuse()
  Matrix_n3 m_anchor_displacement, m_detail_change, m_previous_samples; // per-edit buffers
  std::vector<Eigen::Matrix3d> m_previous_rotations;                    // per-edit buffer
  Matrix_n3 m_deformed_points, m_deformed_normals;
  Statistics m_statistics;
};

template <typename ConcurrencyTag>
void Detail_preserving_deformation<ConcurrencyTag>::check_selection() const
{
  if(std::find(m_in_roi.begin(), m_in_roi.end(), 1) == m_in_roi.end())
    throw Invalid_input(std::string(who) + ": the region of interest is empty; insert_roi_points() selects the "
                        "deformable part");
  if(m_transforms.empty())
    throw Invalid_input(std::string(who) + ": there is no handle group; create_handle_group() and "
                        "insert_handle_points() select what the user moves");
  std::vector<std::size_t> count(m_transforms.size(), 0);
  for(std::size_t row = 0; row < m_label.size(); ++row) {
    if(m_label[row] < first_handle_label) continue;
    ++count[std::size_t(m_label[row] - first_handle_label)];
    if(!m_in_roi[row])
      throw Invalid_input(std::string(who) + ": handle point #" + std::to_string(m_cloud.input_index[row]) +
                          " is not in the region of interest; handles are deformable points (insert it into the "
                          "region too)");
  }
  for(std::size_t g = 0; g < count.size(); ++g)
    if(count[g] == 0)
      throw Invalid_input(std::string(who) + ": handle group " + std::to_string(g) + " has no point");
}

template <typename ConcurrencyTag>
void Detail_preserving_deformation<ConcurrencyTag>::cluster(internal::Progress& progress)
{
  using namespace internal;
  const std::size_t n = m_cloud.size();
  std::vector<int> order;
  Simplification_sample_points<CGAL::Simple_cartesian<double>> ssps;
  if(!cluster_into_sample_points<CGAL::Simple_cartesian<double>, ConcurrencyTag>(
       m_cloud, m_normals, m_settings.simplification, &m_label, progress, m_mean_shift, m_has_mean_shift, order, ssps))
    return;
  m_requested_samples = ssps.requested_count;

  const std::size_t count = ssps.size();
  m_samples.resize(Eigen::Index(count), 3);
  m_sample_normals.resize(Eigen::Index(count), 3);
  m_sample_label.resize(count);
  m_sample_first_row.resize(count);
  m_sample_of.assign(n, -1);
  for(std::size_t s = 0; s < count; ++s) {
    const auto& ssp = ssps.samples[s];
    m_samples.row(Eigen::Index(s)) << ssp.centroid.x(), ssp.centroid.y(), ssp.centroid.z();
    m_sample_normals.row(Eigen::Index(s)) << ssp.normal.x(), ssp.normal.y(), ssp.normal.z();
    const int first = order[ssp.first_member];
    m_sample_first_row[s] = first;
    m_sample_label[s] = m_label[std::size_t(first)];
    for(std::size_t m = 0; m < ssp.member_count; ++m) m_sample_of[std::size_t(order[ssp.first_member + m])] = int(s);
  }
}

template <typename ConcurrencyTag>
bool Detail_preserving_deformation<ConcurrencyTag>::analyse_points()
{
  using namespace internal;
  bool needs_modes = false;
  split_rule_for(m_settings.simplification, m_cloud.size(), needs_modes);
  if(!needs_modes || m_has_mean_shift) return true;
  Progress progress(m_callback);
  const std::size_t k = std::min<std::size_t>(m_settings.simplification.mean_shift_neighbors, m_cloud.size() - 1);
  m_has_mean_shift = analyse_mean_shift<ConcurrencyTag>(m_cloud, m_normals, k, m_settings.simplification.mean_shift,
                                                        progress, m_mean_shift);
  return m_has_mean_shift;
}

template <typename ConcurrencyTag>
void Detail_preserving_deformation<ConcurrencyTag>::build_strength_field()
{
  using namespace internal;
  const std::size_t count = std::size_t(m_samples.rows()), groups = m_transforms.size();
  std::vector<int> fixed;
  std::vector<std::vector<int>> handles(groups);
  for(std::size_t s = 0; s < count; ++s) {
    if(m_sample_label[s] == fixed_label) fixed.push_back(int(s));
    else if(m_sample_label[s] >= first_handle_label) handles[std::size_t(m_sample_label[s] - first_handle_label)].push_back(int(s));
  }
  auto distance_to = [&](const std::vector<int>& sources) {
    return m_settings.strength_distance == Strength_distance::geodesic
             ? graph_distance_to(m_samples, m_system.graph, sources)
             : euclidean_distance_to<ConcurrencyTag>(m_samples, sources);
  };
  const Eigen::VectorXd d0 = distance_to(fixed);
  m_d1.assign(count * groups, 0.0);
  m_strength.assign(count * groups, 0.0);
  for(std::size_t g = 0; g < groups; ++g) {
    const Eigen::VectorXd d1 = distance_to(handles[g]);
    for(std::size_t s = 0; s < count; ++s) {
      m_d1[s * groups + g] = d1(Eigen::Index(s));
      // Only the region's sample points turn; the fixed part has strength 0 by definition (d0 = 0).
      m_strength[s * groups + g] = m_sample_label[s] == fixed_label ? 0.0 : internal::strength(d0(Eigen::Index(s)), d1(Eigen::Index(s)));
    }
  }
}

// Exact handles put their points on the handle's transform T_g, while the points next to them follow the blend
// of their sample points, F; where the blend differs from T_g (as rigid as possible fits the sample points next
// to a handle turns of their own) the border would be a step, one that grows, relative to the point spacing,
// with the sampling density. So a region point within reach r of a handle also takes the step of the group's
// nearest handle point h, T_g(h) - F(h), weighted by w = 1 - smoothstep(d / r), d its distance to h and r twice
// the median distance from a handle point to the farthest sample point of its stencil (how far the diffusion
// spreads one sample point's motion): the motion is continuous up to the handle (doc/editing.md, "Exact
// handles without a seam").
template <typename ConcurrencyTag>
void Detail_preserving_deformation<ConcurrencyTag>::build_handle_collar()
{
  m_collar_rows.clear();
  m_collar = internal::Neighbor_graph();
  m_collar_weights.clear();
  m_collar_handles.clear();
  m_collar_handle_points.clear();
  m_collar_slots.clear();
  m_handle_steps.resize(Eigen::Index(m_handle_rows.size()), 3);
  m_handle_normal_steps.resize(Eigen::Index(m_handle_rows.size()), 3);
  if(m_handle_rows.empty() || !m_settings.handle_collar) return;
  std::vector<double> reach(m_handle_rows.size());
  for(std::size_t h = 0; h < m_handle_rows.size(); ++h) {
    const std::size_t row = std::size_t(m_handle_rows[h]);
    reach[h] = (m_cloud.positions.row(Eigen::Index(row)) - m_samples.row(m_stencil.samples.end(row)[-1])).norm();
  }
  std::nth_element(reach.begin(), reach.begin() + std::ptrdiff_t(reach.size() / 2), reach.end());
  const double r = 2 * reach[reach.size() / 2];
  if(!(r > 0)) return;
  struct Entry { int row, handle; double weight; };
  std::vector<Entry> entries;
  for(std::size_t g = 0; g < m_transforms.size(); ++g) {
    const int label = first_handle_label + int(g);
    std::vector<int> handle; // indices into m_handle_rows
    Eigen::AlignedBox3d box;
    for(std::size_t h = 0; h < m_handle_rows.size(); ++h)
      if(m_label[std::size_t(m_handle_rows[h])] == label) {
        handle.push_back(int(h));
        box.extend(m_cloud.positions.row(m_handle_rows[h]).transpose());
      }
    box.min().array() -= r;
    box.max().array() += r;
    std::vector<int> near; // moving region points (not handle points) in the handle's box
    for(int row : m_active_points)
      if(m_label[std::size_t(row)] == roi_label && box.contains(m_cloud.positions.row(row).transpose())) near.push_back(row);
    if(near.empty()) continue;
    Matrix_n3 handle_positions(Eigen::Index(handle.size()), 3), near_positions(Eigen::Index(near.size()), 3);
    for(std::size_t i = 0; i < handle.size(); ++i)
      handle_positions.row(Eigen::Index(i)) = m_cloud.positions.row(m_handle_rows[std::size_t(handle[i])]);
    for(std::size_t i = 0; i < near.size(); ++i) near_positions.row(Eigen::Index(i)) = m_cloud.positions.row(near[i]);
    const internal::Neighbor_graph nearest = internal::k_nearest_samples<ConcurrencyTag>(handle_positions, near_positions, 1);
    for(std::size_t i = 0; i < near.size(); ++i) {
      const double t = (near_positions.row(Eigen::Index(i)) - handle_positions.row(*nearest.begin(i))).norm() / r;
      if(t < 1) entries.push_back({near[i], handle[std::size_t(*nearest.begin(i))], 1 - t * t * (3 - 2 * t)});
    }
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.row < b.row || (a.row == b.row && a.handle < b.handle); });
  for(std::size_t first = 0, last; first < entries.size(); first = last) {
    double total = 0;
    for(last = first; last < entries.size() && entries[last].row == entries[first].row; ++last) total += entries[last].weight;
    const double scale = total > 1 ? 1 / total : 1.0; // where two groups' collars overlap
    for(std::size_t e = first; e < last; ++e) {
      m_collar.indices.push_back(entries[e].handle);
      m_collar_weights.push_back(scale * entries[e].weight);
    }
    m_collar.offsets.push_back(int(last));
    m_collar_rows.push_back(entries[first].row);
  }
  m_collar_handles = m_collar.indices;
  std::sort(m_collar_handles.begin(), m_collar_handles.end());
  m_collar_handles.erase(std::unique(m_collar_handles.begin(), m_collar_handles.end()), m_collar_handles.end());
  m_collar_handle_points.resize(m_collar_handles.size());
  for(std::size_t c = 0; c < m_collar_handles.size(); ++c)
    m_collar_handle_points[c] = m_cloud.input_index[std::size_t(m_handle_rows[std::size_t(m_collar_handles[c])])];
  m_collar_slots.resize(m_collar.indices.size());
  for(std::size_t e = 0; e < m_collar.indices.size(); ++e)
    m_collar_slots[e] = int(std::lower_bound(m_collar_handles.begin(), m_collar_handles.end(), m_collar.indices[e]) -
                            m_collar_handles.begin());
}

template <typename ConcurrencyTag>
bool Detail_preserving_deformation<ConcurrencyTag>::preprocess()
{
  using namespace internal;
  const auto start = std::chrono::steady_clock::now();
  auto seconds_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  m_preprocessed = false;
  check_selection();
  Progress progress(m_callback);
  progress.stage(0.0, m_has_mean_shift ? 0.0 : 0.6);
  cluster(progress);
  if(progress.cancelled()) return false;
  m_statistics = Statistics();
  m_statistics.clustering_seconds = seconds_since(start);
  progress.stage(0.6, 1.0);
  if(!progress.report(0.0)) return false;

  const std::size_t count = std::size_t(m_samples.rows());
  if(count < 2)
    throw Invalid_input(std::string(who) + ": the points form a single sample point; lower the cluster size");
  const std::size_t k = m_settings.sample_neighbors;
  if(k >= count)
    throw Invalid_input(std::string(who) + ": sample_neighbors (" + std::to_string(k) + ") must be less than the number "
                        "of sample points (" + std::to_string(count) + "); lower it, or make the clusters smaller");
  std::vector<int> point_of_sample(count);
  for(std::size_t s = 0; s < count; ++s) point_of_sample[s] = m_cloud.input_index[std::size_t(m_sample_first_row[s])];
  m_system.setup<ConcurrencyTag>(m_samples, m_sample_normals, m_sample_label, point_of_sample, k, m_settings.filter,
                                 m_settings.rotations == Detail_rotation::as_rigid_as_possible,
                                 m_settings.rigid_edge_weights == Rigid_edge_weights::cotangent,
                                 m_settings.rigid_rotation_smoothing > 0 &&
                                   m_settings.rigid_rotation_smoothing_scale == Rotation_smoothing_scale::surface_area,
                                 m_settings.least_squares, m_settings.handle_weight, who);
  const bool exact_handles = std::isinf(m_settings.handle_weight);
  if(!progress.report(0.6)) return false;

  build_strength_field();
  m_linear_map_priors.clear();
  if(m_settings.diffusion_turn == Sample_turn::affine) {
    m_linear_map_priors.resize(m_system.roi.size());
    for_range<ConcurrencyTag>(0, m_system.roi.size(), [&](std::size_t r) {
      m_linear_map_priors[r] = Linear_map_prior(m_samples, m_system.graph, std::size_t(m_system.roi[r]));
    });
  }
  if(m_settings.diffusion_turn == Sample_turn::frames) { // the fitted turns need no frames
    m_frame_builder.setup(m_samples, m_sample_normals, m_system.graph);
    m_frames.resize(count);
    for_range<ConcurrencyTag>(0, count, [&](std::size_t s) {
      m_frames[s] = m_frame_builder.frame(m_samples, s, m_sample_normals.row(Eigen::Index(s)).transpose());
    });
  }
  m_stencil.template setup<ConcurrencyTag>(m_cloud.positions, m_samples,
                                           std::min<std::size_t>(m_settings.diffusion_samples, count), &m_sample_of);
  m_stencil.use_wide_vectors = !m_settings.portable_diffusion;
  // Points carried by fixed sample points only never move: each drag skips them. Handle points are always
  // blended (the collar takes their blend's step to their transform).
  m_active_points.clear();
  for(std::size_t row = 0; row < m_cloud.size(); ++row) {
    bool active = exact_handles && m_label[row] >= first_handle_label;
    for(const int* s = m_stencil.samples.begin(row); s != m_stencil.samples.end(row) && !active; ++s)
      active = m_sample_label[std::size_t(*s)] != fixed_label;
    if(active) m_active_points.push_back(int(row));
  }
  m_movable_points.resize(m_active_points.size());
  for(std::size_t a = 0; a < m_active_points.size(); ++a)
    m_movable_points[a] = m_cloud.input_index[std::size_t(m_active_points[a])];
  std::sort(m_movable_points.begin(), m_movable_points.end());

  m_group_rotations.resize(m_transforms.size());
  m_handle_rows.clear();
  if(exact_handles)
    for(std::size_t row = 0; row < m_cloud.size(); ++row)
      if(m_label[row] >= first_handle_label) m_handle_rows.push_back(int(row));
  build_handle_collar();

  m_has_relaxation = m_diffused = false;
  m_propagated.assign(count, Eigen::Matrix3d::Identity());
  m_has_rigid_rotations = false;
  m_solved_transforms.assign(m_transforms.size(), Transform());
  m_handles_centre.setZero();
  for(int a : m_system.anchors) m_handles_centre += m_samples.row(m_system.roi[std::size_t(a)]).transpose() / double(m_system.anchors.size());
  Eigen::AlignedBox3d region_box;
  for(int s : m_system.roi) region_box.extend(m_samples.row(s).transpose());
  m_region_size = region_box.diagonal().norm();
  m_sample_map.assign(count, Eigen::Matrix3d::Identity());
  m_deformed_samples = m_samples;
  m_detail_change.resize(Eigen::Index(m_system.roi.size()), 3);
  m_anchor_displacement.resize(Eigen::Index(m_system.anchors.size()), 3);
  m_deformed_points = m_cloud.positions;
  m_deformed_normals = m_normals;
  if(!progress.report(1.0)) return false;

  m_statistics.points = m_cloud.size();
  m_statistics.samples = count;
  m_statistics.requested_samples = m_requested_samples;
  m_statistics.roi_samples = m_system.roi.size();
  m_statistics.handle_samples = m_system.anchors.size();
  m_statistics.least_squares = m_system.statistics();
  m_statistics.preprocess_seconds = seconds_since(start);
  m_preprocessed = true;
  return true;
}

template <typename ConcurrencyTag>
bool Detail_preserving_deformation<ConcurrencyTag>::deform()
{
  using namespace internal;
  if(!m_preprocessed && !preprocess()) return false;
  const auto start = std::chrono::steady_clock::now();
  const std::size_t groups = m_transforms.size();
  auto pull_anchors = [&](const std::vector<Transform>& transforms) {
    for(std::size_t a = 0; a < m_system.anchors.size(); ++a) {
      const Transform& T = transforms[std::size_t(m_system.anchor_group[a])];
      const Eigen::Vector3d s = m_samples.row(m_system.roi[std::size_t(m_system.anchors[a])]).transpose();
      m_anchor_displacement.row(Eigen::Index(a)) = (T.rotation * s + T.translation - s).transpose();
    }
  };
  // R_i = the strength field's blend of the handles' rotations.
  auto propagate = [&](const std::vector<Eigen::Quaterniond>& rotations) {
    for_range<ConcurrencyTag>(0, m_system.roi.size(), [&](std::size_t r) {
      const std::size_t s = std::size_t(m_system.roi[r]);
      m_propagated[s] = internal::propagated_rotation(rotations, &m_d1[s * groups], &m_strength[s * groups]).toRotationMatrix();
    });
  };
  std::vector<Eigen::Quaterniond> rotations(groups);
  for(std::size_t g = 0; g < groups; ++g) rotations[g] = m_transforms[g].rotation;

  if(m_settings.rotations != Detail_rotation::as_rigid_as_possible) {
    if(m_settings.rotations == Detail_rotation::none)
      std::fill(m_propagated.begin(), m_propagated.end(), Eigen::Matrix3d::Identity());
    else
      propagate(rotations);
    pull_anchors(m_transforms);
    for_range<ConcurrencyTag>(0, m_system.roi.size(), [&](std::size_t r) {
      const Eigen::Vector3d delta = m_system.details.row(Eigen::Index(r)).transpose();
      m_detail_change.row(Eigen::Index(r)) = (m_propagated[std::size_t(m_system.roi[r])] * delta - delta).transpose();
    });
    m_system.solve<ConcurrencyTag>(m_samples, m_detail_change, m_anchor_displacement, m_deformed_samples);
  } else {
    // ARAP's energy is not convex: a large change of the handles since the last solve is taken in steps of at
    // most `rigid_step_degrees` and `rigid_step_fraction` of the region's size (each group's rotation slerped about the handles' common
    // centre, which moves on a line), along which the solution follows the deformation the user would drag
    // through. Each step starts from the rotations of the one before (the first drag from the propagated
    // ones): on the cactus that lands far closer to CGAL's mesh ARAP than one step of more iterations, or each
    // step first turning the rotations by the strength field's blend (doc/editing.md, "As rigid as possible").
    const std::size_t steps = rigid_step_count(
      m_solved_transforms, m_transforms, m_handles_centre, m_region_size,
      Rigid_step_limits{m_settings.rigid_step_degrees, m_settings.rigid_step_fraction, m_settings.max_rigid_steps});
    std::vector<Transform> along(groups);
    std::vector<Eigen::Quaterniond> previous(groups);
    unsigned int iterations_used = 0;
    for(std::size_t step = 1; step <= steps; ++step) {
      for(std::size_t g = 0; g < groups; ++g)
        along[g] = step == steps ? m_transforms[g]
                                 : rigid_step(m_solved_transforms[g], m_transforms[g], m_handles_centre,
                                              double(step) / double(steps));
      if(!m_has_rigid_rotations) {
        for(std::size_t g = 0; g < groups; ++g) rotations[g] = along[g].rotation;
        propagate(rotations);
        m_has_rigid_rotations = true;
      } else if(m_system.roi.size() == std::size_t(m_samples.rows())) {
        // Nothing is fixed: the strength field is 1 everywhere and its blend of the handles' turns is exact for
        // a rigid motion, so each step starts from it (with a fixed part it misleads, as on the cactus).
        std::vector<Eigen::Quaterniond> turns(groups);
        for(std::size_t g = 0; g < groups; ++g)
          turns[g] = along[g].rotation * (step == 1 ? m_solved_transforms[g].rotation : previous[g]).conjugate();
        for_range<ConcurrencyTag>(0, m_system.roi.size(), [&](std::size_t r) {
          const std::size_t s = std::size_t(m_system.roi[r]);
          m_propagated[s] = internal::propagated_rotation(turns, &m_d1[s * groups], &m_strength[s * groups]).toRotationMatrix() * m_propagated[s];
        });
      }
      for(std::size_t g = 0; g < groups; ++g) previous[g] = along[g].rotation;
      pull_anchors(along);
      iterations_used += rigid_iterations<ConcurrencyTag>(m_system, m_samples, m_anchor_displacement,
                                                          m_settings.rigid_iterations,
                                                          m_settings.rigid_tolerance * m_region_size,
                                                          m_settings.rigid_rotation_smoothing, m_propagated,
                                                          m_deformed_samples, m_detail_change, m_previous_samples,
                                                          m_previous_rotations);
    }
    m_solved_transforms = m_transforms;
    m_statistics.rigid_iterations = iterations_used;
  }
  m_statistics.least_squares = m_system.statistics();
  double largest = 0, largest_handle = 0;
  for(std::size_t r = 0; r < m_system.roi.size(); ++r) {
    const double d = (m_deformed_samples.row(m_system.roi[r]) - m_samples.row(m_system.roi[r])).norm();
    largest = std::max(largest, d);
    if(m_sample_label[std::size_t(m_system.roi[r])] >= first_handle_label) largest_handle = std::max(largest_handle, d);
  }
  m_statistics.displacement_ratio = largest_handle > 0 ? largest / largest_handle : 0.0;
  m_statistics.deform_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return true;
}

template <typename ConcurrencyTag>
void Detail_preserving_deformation<ConcurrencyTag>::update_sample_motions()
{
  using namespace internal;
  if(!m_preprocessed)
    throw Invalid_input(std::string(who) + ": the sample points' motions need preprocess() or deform() first");
  // Each region sample point carries its points by the best linear map or rotation of its neighbourhood, or
  // turns by its deformed frame against its original one (settings.diffusion_turn). A sample point whose
  // neighbourhood did not move (and, with frames, that was not turned) keeps the identity exactly, so unchanged
  // parts stay bit for bit; fixed sample points keep theirs (doc/editing.md, "Sample point turns").
  std::vector<Eigen::Matrix3d>& rotation = m_group_rotations; // sized by preprocess(): no allocation per drag
  for(std::size_t g = 0; g < m_transforms.size(); ++g) rotation[g] = m_transforms[g].rotation.toRotationMatrix();
  const bool exact_handles = !m_handle_rows.empty();
  const bool rigid_rotations = m_settings.rotations == Detail_rotation::as_rigid_as_possible && m_has_rigid_rotations;
  for_range<ConcurrencyTag>(0, m_system.roi.size(), [&](std::size_t r) {
    const std::size_t s = std::size_t(m_system.roi[r]);
    if(exact_handles && m_sample_label[s] >= first_handle_label) { // moved rigidly by its group, exactly
      m_sample_map[s] = rotation[std::size_t(m_sample_label[s] - first_handle_label)];
      return;
    }
    if(m_settings.diffusion_turn != Sample_turn::frames) {
      const bool affine = m_settings.diffusion_turn == Sample_turn::affine;
      double covariance[9]; // of the edges: the rotation's fit and the linear map's
      const bool moved = (affine || !rigid_rotations) &&
                         edge_covariance(m_samples, m_deformed_samples, m_system.graph, s, nullptr, covariance);
      // As rigid as possible, the last local step fitted these very rotations to the deformed sample points. The
      // fitted rotation is the identity exactly where the neighbourhood did not move: keep it so.
      const Eigen::Matrix3d fitted =
        rigid_rotations ? m_propagated[s]
        : moved         ? best_rotation(Eigen::Matrix3d(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(covariance)))
                        : Eigen::Matrix3d::Identity();
      m_sample_map[s] = affine && !fitted.isIdentity(0) ? m_linear_map_priors[r].fitted_linear_map(covariance, fitted) : fitted;
      return;
    }
    bool moved = !m_propagated[s].isIdentity(0) || m_deformed_samples.row(Eigen::Index(s)) != m_samples.row(Eigen::Index(s));
    for(const int* j = m_system.graph.begin(s); j != m_system.graph.end(s) && !moved; ++j)
      moved = m_deformed_samples.row(*j) != m_samples.row(*j);
    if(!moved) {
      m_sample_map[s].setIdentity();
      return;
    }
    const Eigen::Vector3d hint = m_propagated[s] * m_sample_normals.row(Eigen::Index(s)).transpose();
    m_sample_map[s] = m_frame_builder.frame(m_deformed_samples, s, hint) * m_frames[s].transpose();
  });
  m_stencil.template set_motions<ConcurrencyTag>(m_samples, m_deformed_samples, m_sample_map);
}

template <typename ConcurrencyTag>
void Detail_preserving_deformation<ConcurrencyTag>::collar_handle_step(std::size_t c, Eigen::Vector3d& step,
                                                                       Eigen::Vector3d& normal_step) const
{
  const Eigen::Index row = m_handle_rows[std::size_t(m_collar_handles.at(c))];
  const std::size_t g = std::size_t(m_label[std::size_t(row)] - first_handle_label);
  const Eigen::Matrix3d R = m_transforms[g].rotation.toRotationMatrix();
  Eigen::Vector3d blended, blended_normal;
  m_stencil.move_point(std::size_t(row), m_cloud.positions, m_normals, m_samples, m_deformed_samples, offset_origin(),
                       blended, blended_normal);
  step = R * m_cloud.positions.row(row).transpose() + m_transforms[g].translation - blended;
  normal_step = R * m_normals.row(row).transpose() - blended_normal;
}

template <typename ConcurrencyTag>
void Detail_preserving_deformation<ConcurrencyTag>::diffuse()
{
  using namespace internal;
  if(!m_preprocessed)
    throw Invalid_input(std::string(who) + ": diffuse() needs preprocess() or deform() first");
  const auto start = std::chrono::steady_clock::now();
  update_sample_motions();
  m_stencil.template apply<ConcurrencyTag>(m_cloud.positions, m_normals, m_samples, m_deformed_samples, m_sample_map,
                                           offset_origin(), m_deformed_points, m_deformed_normals, &m_active_points);
  const std::vector<Eigen::Matrix3d>& rotation = m_group_rotations;
  // Exact handles: the handle points themselves follow their transform, not the blend of their neighbourhood,
  // and the points of the collar about them blend into it (build_handle_collar()).
  for_range<ConcurrencyTag>(0, m_handle_rows.size(), [&](std::size_t h) {
    const Eigen::Index row = m_handle_rows[h];
    const std::size_t g = std::size_t(m_label[std::size_t(row)] - first_handle_label);
    const Eigen::RowVector3d exact = (rotation[g] * m_cloud.positions.row(row).transpose() + m_transforms[g].translation).transpose();
    const Eigen::RowVector3d exact_normal = (rotation[g] * m_normals.row(row).transpose()).transpose();
    m_handle_steps.row(Eigen::Index(h)) = exact - m_deformed_points.row(row);
    m_handle_normal_steps.row(Eigen::Index(h)) = exact_normal - m_deformed_normals.row(row);
    m_deformed_points.row(row) = exact;
    m_deformed_normals.row(row) = exact_normal;
  });
  for_range<ConcurrencyTag>(0, m_collar_rows.size(), [&](std::size_t c) {
    const Eigen::Index row = m_collar_rows[c];
    Eigen::RowVector3d step = Eigen::RowVector3d::Zero(), normal_step = Eigen::RowVector3d::Zero();
    for(int e = m_collar.offsets[c]; e < m_collar.offsets[c + 1]; ++e) {
      const double weight = m_collar_weights[std::size_t(e)];
      step += weight * m_handle_steps.row(m_collar.indices[std::size_t(e)]);
      normal_step += weight * m_handle_normal_steps.row(m_collar.indices[std::size_t(e)]);
    }
    if(step.isZero(0) && normal_step.isZero(0)) return; // no step to take: bit for bit
    m_deformed_points.row(row) += step;
    m_deformed_normals.row(row) = (m_deformed_normals.row(row) + normal_step).normalized();
  });
  m_diffused = true;
  m_statistics.diffuse_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <typename ConcurrencyTag>
void Detail_preserving_deformation<ConcurrencyTag>::restore_details()
{
  using namespace internal;
  if(!m_preprocessed)
    throw Invalid_input(std::string(who) + ": restore_details() needs preprocess() or deform() first");
  if(!m_diffused)
    throw Invalid_input(std::string(who) + ": restore_details() works on the result of diffuse(); call diffuse() first");
  const auto start = std::chrono::steady_clock::now();
  m_statistics.restore_iterations = 0;
  m_statistics.restore_residual = 0;
  const std::size_t neighbors = std::min<std::size_t>(10, m_cloud.size() - 1);
  if(neighbors == 0 || m_settings.detail_iterations == 0) return;
  if(!m_has_relaxation) {
    // The region's moving points without the exact handles, which follow their transforms.
    std::vector<char> pinned(m_cloud.size(), 0);
    for(int row : m_handle_rows) pinned[std::size_t(row)] = 1;
    std::vector<int> rows;
    for(int row : m_active_points)
      if(m_label[std::size_t(row)] != fixed_label && !pinned[std::size_t(row)]) rows.push_back(row);
    m_relaxation.template setup<ConcurrencyTag>(m_cloud.positions, std::move(rows), neighbors);
    m_has_relaxation = true;
  }
  const auto outcome = m_relaxation.template apply<ConcurrencyTag>(
    m_cloud.positions, m_settings.detail_anchor, m_settings.detail_iterations, m_settings.detail_tolerance,
    m_deformed_points);
  m_statistics.restore_iterations = outcome.iterations;
  m_statistics.restore_residual = outcome.residual;
  m_statistics.restore_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <typename ConcurrencyTag>
template <typename PointRange, typename NamedParameters>
void Detail_preserving_deformation<ConcurrencyTag>::diffuse(PointRange& points, const NamedParameters& np)
{
  const std::size_t n = static_cast<std::size_t>(std::distance(points.begin(), points.end()));
  if(n != m_cloud.size())
    throw Invalid_input(std::string(who) + ": diffuse() was given " + std::to_string(n) + " points, but the deformation has " +
                        std::to_string(m_cloud.size()));
  diffuse();
  write_deformed(points, np);
}

template <typename ConcurrencyTag>
template <typename PointRange, typename NamedParameters>
void Detail_preserving_deformation<ConcurrencyTag>::restore_details(PointRange& points, const NamedParameters& np)
{
  const std::size_t n = static_cast<std::size_t>(std::distance(points.begin(), points.end()));
  if(n != m_cloud.size())
    throw Invalid_input(std::string(who) + ": restore_details() was given " + std::to_string(n) +
                        " points, but the deformation has " + std::to_string(m_cloud.size()));
  restore_details();
  write_deformed(points, np);
}

template <typename ConcurrencyTag>
template <typename PointRange, typename NamedParameters>
void Detail_preserving_deformation<ConcurrencyTag>::write_deformed(PointRange& points, const NamedParameters& np) const
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  const auto point_map = NP_helper::get_point_map(points, np);
  using Point = typename boost::property_traits<std::remove_const_t<decltype(point_map)>>::value_type;
  constexpr bool with_normals =
    !CGAL::parameters::is_default_parameter<NamedParameters, CGAL::internal_np::normal_t>::value;
  // A Point_set_3 names a normal map even when it has no normal property: write normals only where they exist.
  const bool write_normals = with_normals && internal::has_given_normals<NamedParameters>(points);
  std::size_t i = 0;
  for(auto& item : points) {
    const Eigen::Index row = m_row_of[i++];
    put(point_map, item, Point(m_deformed_points(row, 0), m_deformed_points(row, 1), m_deformed_points(row, 2)));
    if constexpr(with_normals) {
      if(!write_normals) continue;
      const auto normal_map = NP_helper::get_normal_map(points, np);
      using Vector = typename boost::property_traits<decltype(normal_map)>::value_type;
      put(normal_map, item, Vector(m_deformed_normals(row, 0), m_deformed_normals(row, 1), m_deformed_normals(row, 2)));
    }
  }
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/parallel.h).
#define CGAL_EXT_DEFORMATION_INSTANCES(EXTERN, Tag) EXTERN template class Detail_preserving_deformation<Tag>;
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_DEFORMATION_INSTANCES)

} // namespace CGAL_ext

#endif // CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_H
