// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_H
#define CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_H

#include <CGAL_ext/Detail_preserving_deformation_settings.h>
#include <CGAL_ext/Diffusion_view.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/point_diffusion.h>
#include <CGAL_ext/internal/rigid_stepping.h>
#include <CGAL_ext/internal/sample_points.h>
#include <CGAL_ext/internal/sample_system.h>
#include <CGAL_ext/internal/strength_field.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <chrono>
#include <functional>
#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Detail-preserving editing of a point-sampled surface (Miao et al. 2007, Sect. 6), shaped like
  `CGAL::Surface_mesh_deformation`: select a region of interest (ROI) and handle groups, `preprocess()`,
  then move the handles with `set_handle_transform()` and call `deform()` and `diffuse()` as often as wanted.

  - The points are clustered into sample points (SSPs) that never mix fixed, ROI and handle points.
  - `deform()` keeps the sample points' details `delta = f(K) s` in the least-squares sense with the handles on
    their targets, `min sum_{i in ROI} ||(f(K) s')_i - R(Q_i) delta_i||^2` with `s'_h = R_g s_h + t_g` (or the
    paper's soft constraint, `handle_weight`); `preprocess()` factors the normal matrix, a drag is one solve.
  - The details turn by the handles' rotations blended by the strength field (`strength()`), or by rotations
    fitted to the solved shape, alternating with the solve (`Detail_rotation::as_rigid_as_possible`).
  - `diffuse()` carries every point by its `m` nearest sample points' motions, blended by weights that vanish at
    the (m+1)-th, so the motion is continuous in space; normals turn with the blended map.

  Identities (tested): handle points end on their targets; unmoved handles return every point exactly; with the
  whole model as ROI, moving every handle group by one rigid motion moves every point and normal rigidly; points
  whose sample points are all fixed never move. The object copies the points and normals at construction and
  writes to the caller only in the calls given its points or arrays; it is not copyable.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/editing.md">Detail-preserving editing</a> (`doc/editing.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
class Detail_preserving_deformation
{
  using Matrix_n3 = internal::Matrix_n3;
  using Clock = std::chrono::steady_clock;
  static constexpr const char* who = "Detail_preserving_deformation";

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
    using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
    m_settings.validate();
    m_callback = CGAL::parameters::choose_parameter(CGAL::parameters::get_parameter(np, CGAL::internal_np::callback),
                                                    std::function<bool(double)>());
    m_cloud = internal::make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
    if(m_cloud.size() < 2) throw Invalid_input(std::string(who) + ": editing needs at least two points");
    m_row_of = m_cloud.spatial_index();
    internal::Progress progress;
    internal::given_or_estimated_normals<ConcurrencyTag>(points, np, m_cloud, default_normal_neighbors, progress,
                                                         m_normals, who);
    m_selection.clear(m_cloud.size());
    return_to_rest();
  }

  Detail_preserving_deformation(const Detail_preserving_deformation&) = delete;
  Detail_preserving_deformation& operator=(const Detail_preserving_deformation&) = delete;

  /// \name Selection
  /// Point indices are positions in the range given at construction. Changing the selection makes the
  /// next `deform()` preprocess again.
  /// @{

  /// Adds a point to the region of interest (the deformable part; every other point stays fixed).
  void insert_roi_point(std::size_t i) { m_selection.insert_roi(checked_row(i)); m_preprocessed = false; }

  template <typename IndexRange>
  void insert_roi_points(const IndexRange& indices) { for(const auto& i : indices) insert_roi_point(std::size_t(i)); }

  /// Adds a handle group, initially with the identity transform, and returns its index.
  std::size_t create_handle_group() { m_preprocessed = false; return m_selection.create_group(); }

  /// Makes point `i`, which must be (or later be put) in the region of interest, a handle of `group`.
  /// \throws Invalid_input if the point is already a handle of another group (it cannot follow two transforms).
  void insert_handle_point(std::size_t group, std::size_t i)
  {
    m_selection.insert_handle(group, checked_row(i), i, who);
    m_preprocessed = false;
  }
  template <typename IndexRange>
  void insert_handle_points(std::size_t group, const IndexRange& indices)
  {
    for(const auto& i : indices) insert_handle_point(group, std::size_t(i));
  }

  /// Puts every point back to fixed and removes the handle groups.
  void clear_selection() { m_selection.clear(m_cloud.size()); m_preprocessed = false; }

  std::size_t number_of_handle_groups() const { return m_selection.transforms.size(); }
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
  bool preprocess()
  {
    const auto start = Clock::now();
    m_preprocessed = false;
    m_selection.check(m_cloud.input_index, who);
    internal::Progress progress(m_callback);
    progress.stage(0.0, m_mean_shift.analysed ? 0.0 : 0.6);
    if(!internal::cluster_edit_sample_points<ConcurrencyTag>(
         m_cloud, m_normals, m_settings.simplification, m_selection.labels, progress, m_mean_shift, m_sample_points))
      return false;
    m_statistics = Statistics();
    m_statistics.clustering_seconds = seconds_since(start);
    progress.stage(0.6, 1.0);
    if(!progress.report(0.0)) return false;
    const internal::Edit_sample_points& samples = m_sample_points;
    m_system.template setup<ConcurrencyTag>(samples.positions, samples.normals, samples.labels,
                                            samples.input_points(m_cloud.input_index), m_settings, who);
    if(!progress.report(0.6)) return false;
    const std::size_t groups = m_selection.transforms.size();
    m_strength.template setup<ConcurrencyTag>(samples.positions, m_system.graph, samples.labels, groups,
                                              m_settings.strength_distance == Strength_distance::geodesic);
    m_rigid_drag.setup(m_system, samples.positions, groups);
    m_diffusion.template setup<ConcurrencyTag>(m_cloud, samples, m_system.graph, m_system.roi, m_selection, m_settings);
    return_to_rest();
    if(!progress.report(1.0)) return false;
    m_statistics.points = m_cloud.size();
    m_statistics.samples = samples.size();
    m_statistics.requested_samples = samples.requested_count;
    m_statistics.roi_samples = m_system.roi.size();
    m_statistics.handle_samples = m_system.anchors.size();
    m_statistics.least_squares = m_system.statistics();
    m_statistics.preprocess_seconds = seconds_since(start);
    return m_preprocessed = true;
  }

  /// Computes now what `preprocess()` needs whatever the selection, the points' mean-shift modes (when the
  /// clustering uses them; its most costly part), so that a program can compute it while its user selects.
  /// \return false if the callback cancelled.
  bool analyse_points()
  {
    internal::Progress progress(m_callback);
    return internal::analyse_modes_once<ConcurrencyTag>(m_cloud, m_normals, m_settings.simplification, progress,
                                                        m_mean_shift);
  }

  /// The rigid transform `p -> R p + t` (world frame, the convention of the Botsch-Sorkine `.def` files) of a
  /// handle group. `R` must be a rotation (orthonormal within 1e-6, determinant +1).
  void set_handle_transform(std::size_t group, const Eigen::Matrix3d& R, const Eigen::Vector3d& t)
  {
    m_selection.transforms[m_selection.checked_group(group, who)] = internal::checked_rigid_transform(R, t, group, who);
  }

  /// As above with the rotation as a unit quaternion (norm within 1e-6 of 1).
  void set_handle_transform(std::size_t group, const Eigen::Quaterniond& q, const Eigen::Vector3d& t)
  {
    m_selection.transforms[m_selection.checked_group(group, who)] = internal::checked_rigid_transform(q, t, group, who);
  }

  /*!
    Solves the sample points' new positions for the current handle transforms (preprocessing first if the
    selection changed). Only the right-hand side changes between calls: one back-substitution.
    \return false if a needed preprocessing was cancelled.
  */
  bool deform()
  {
    if(!m_preprocessed && !preprocess()) return false;
    const auto start = Clock::now();
    const Matrix_n3& samples = m_sample_points.positions;
    if(m_settings.rotations == Detail_rotation::as_rigid_as_possible)
      m_statistics.rigid_iterations = m_rigid_drag.template drag<ConcurrencyTag>(
        m_system, m_strength, samples, m_selection.transforms, m_settings, m_detail_rotations, m_deformed_samples);
    else
      internal::propagated_drag<ConcurrencyTag>(m_system, m_strength, samples, m_selection.transforms,
                                                m_settings.rotations, m_detail_rotations, m_deformed_samples);
    m_statistics.least_squares = m_system.statistics();
    m_statistics.displacement_ratio = m_system.displacement_ratio(samples, m_deformed_samples, m_sample_points.labels);
    m_statistics.deform_seconds = seconds_since(start);
    return true;
  }

  /// Carries the sample points' deformation to every point and normal (internal arrays; read them with
  /// `deformed_point()` or write them with `diffuse(points, np)`). Parallel and allocation-free.
  void diffuse()
  {
    check_preprocessed("diffuse()");
    const auto start = Clock::now();
    update_sample_motions();
    m_diffusion.template apply<ConcurrencyTag>(m_cloud.positions, m_normals, m_sample_points.positions,
                                               m_deformed_samples, m_settings.diffusion_origin, m_selection.transforms,
                                               m_deformed_points, m_deformed_normals);
    m_diffused = true;
    m_diffused_elsewhere = false;
    m_statistics.diffuse_seconds = seconds_since(start);
    m_statistics.diffuse_bytes = m_diffusion.moved_bytes(false);
  }

  /// The first half of `diffuse()`: each sample point's motion for the last `deform()`, which `diffusion_view()`
  /// gives a renderer that moves the points itself; moves no point. O(sample points).
  void update_sample_motions()
  {
    check_preprocessed("update_sample_motions()");
    m_diffusion.template update_motions<ConcurrencyTag>(
      m_sample_points, m_deformed_samples, m_system.graph, m_system.roi, m_selection.transforms, m_detail_rotations,
      m_settings.rotations == Detail_rotation::as_rigid_as_possible && m_rigid_drag.has_rotations());
  }

  /*!
    `diffuse()`, then writes every point's deformed position through `point_map` and, when given, its
    normal through `normal_map` (`np`), in the order of `points`, which must have as many elements as the
    range given at construction.
  */
  template <typename PointRange, typename NamedParameters = CGAL::parameters::Default_named_parameters>
  void diffuse(PointRange& points, const NamedParameters& np = CGAL::parameters::default_values())
  {
    internal::check_same_size(points, m_cloud.size(), "diffuse()", who);
    diffuse();
    internal::write_points_and_normals(points, np, m_row_of, m_deformed_points, m_deformed_normals);
  }

  /// `diffuse()` into arrays in input order, as numpy keeps them: writes each point a drag can move to row `i` of
  /// `points` and `normals` (three doubles a row); the other rows must hold the input points (as after one
  /// `diffuse(points, np)`). The same bits as `diffuse()`, but the internal arrays keep the last `diffuse()`'s: until
  /// the next one, `deformed_point()`, `for_each_deformed_point()` and `restore_details()` throw Invalid_input.
  void diffuse_in_input_order(double* points, double* normals)
  {
    check_preprocessed("diffuse_in_input_order()");
    const auto start = Clock::now();
    update_sample_motions();
    m_diffusion.template apply_in_input_order<ConcurrencyTag>(m_cloud, m_normals, m_sample_points.positions,
                                                              m_deformed_samples, m_settings.diffusion_origin,
                                                              m_selection.transforms, points, normals);
    m_diffused = false;
    m_diffused_elsewhere = true;
    m_statistics.diffuse_seconds = seconds_since(start);
    m_statistics.diffuse_bytes = m_diffusion.moved_bytes(true);
  }

  /*!
    Puts back the fine details that `diffuse()` smooths out where neighbouring sample points move differently:
    over the points the last `diffuse()` moved, solves `(1 + a) x_i - mean_j x_j = R_i (p_i - mean_j p_j) + a y_i`
    (`j` over the closed ball of the point's 10th nearest neighbour, symmetrised; `y_i` where `diffuse()` put
    it; `R_i` its neighbourhood's rotation there; `a` = `settings().detail_anchor`) by the Chebyshev steps that
    reduce the error by `settings().detail_tolerance`, at most `settings().detail_iterations`. Handle points (exact handles), points that
    did not move and the fixed part keep their positions bit for bit; normals keep the diffusion's. It costs many
    diffusions: call it once a drag ends (doc/editing_diffusion.md, "Restoring the details").
    \throws Invalid_input unless `diffuse()` ran since the last `preprocess()` or `reset()`.
  */
  void restore_details()
  {
    check_preprocessed("restore_details()");
    if(!m_diffused)
      throw Invalid_input(std::string(who) + ": restore_details() works on the result of diffuse(); call diffuse() first");
    const auto start = Clock::now();
    const auto outcome = m_diffusion.template restore_details<ConcurrencyTag>(m_cloud.positions, m_selection.labels,
                                                                              m_settings, m_deformed_points);
    m_statistics.restore_iterations = outcome.iterations;
    m_statistics.restore_residual = outcome.residual;
    m_statistics.restore_seconds = seconds_since(start);
  }

  /// `restore_details()`, then writes every point and normal as `diffuse(points, np)` does.
  template <typename PointRange, typename NamedParameters = CGAL::parameters::Default_named_parameters>
  void restore_details(PointRange& points, const NamedParameters& np = CGAL::parameters::default_values())
  {
    internal::check_same_size(points, m_cloud.size(), "restore_details()", who);
    restore_details();
    internal::write_points_and_normals(points, np, m_row_of, m_deformed_points, m_deformed_normals);
  }

  /// Handle transforms back to the identity and every point back to its input position and normal; the
  /// preprocessing is kept.
  void reset()
  {
    for(internal::Rigid_transform& t : m_selection.transforms) t = internal::Rigid_transform();
    return_to_rest();
  }
  /// @}

  /// \name Results and sizes
  /// @{
  std::size_t number_of_points() const { return m_cloud.size(); }
  std::size_t number_of_sample_points() const { return m_sample_points.size(); }
  std::size_t number_of_roi_sample_points() const { return m_system.roi.size(); }
  bool is_preprocessed() const { return m_preprocessed; }
  const Statistics& statistics() const { return m_statistics; }

  Eigen::Vector3d point(std::size_t i) const { return of_point(m_cloud.positions, i); }
  Eigen::Vector3d normal(std::size_t i) const { return of_point(m_normals, i); }
  Eigen::Vector3d deformed_point(std::size_t i) const { return of_point(current(m_deformed_points), i); }
  Eigen::Vector3d deformed_normal(std::size_t i) const { return of_point(current(m_deformed_normals), i); }

  /// Calls `write(i, point, normal)` for every input index `i` with its deformed position and normal (three
  /// doubles each), in parallel and in increasing `i`. With `movable_only`, only for the points a region sample
  /// point carries: since `preprocess()` the others keep their input position and normal.
  template <typename Writer>
  void for_each_deformed_point(const Writer& write, bool movable_only = false) const
  {
    internal::for_each_row_in_input_order<ConcurrencyTag>(m_row_of,
                                                          movable_only ? &m_diffusion.movable_points : nullptr,
                                                          current(m_deformed_points), m_deformed_normals, write);
  }

  /// The sample point of input point `i` (after `preprocess()`).
  std::size_t sample_point_of(std::size_t i) const { return std::size_t(m_sample_points.of_row.at(std::size_t(m_row_of.at(i)))); }
  Eigen::Vector3d sample_position(std::size_t s) const { return m_sample_points.positions.row(Eigen::Index(s)).transpose(); }
  Eigen::Vector3d sample_normal(std::size_t s) const { return m_sample_points.normals.row(Eigen::Index(s)).transpose(); }
  Eigen::Vector3d deformed_sample_position(std::size_t s) const { return m_deformed_samples.row(Eigen::Index(s)).transpose(); }
  /// The detail vector `f(K) s` of sample point `s` (zero outside the region of interest).
  Eigen::Vector3d sample_detail(std::size_t s) const
  {
    const int r = m_system.roi_local.at(s);
    return r < 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(m_system.details.row(r).transpose());
  }
  /// The rotation `R(Q_s)` of sample point `s`'s detail in the last `deform()`: propagated, or fitted to the result
  /// in as-rigid-as-possible mode (the identity outside the region, but for the fixed sample points next to it in
  /// as-rigid-as-possible mode, whose rotations the energy fits too; they still carry their points unturned).
  Eigen::Matrix3d detail_rotation(std::size_t s) const { return m_detail_rotations.at(s); }
  /// The strength `f = beta(d0 / (d0 + d1))` of handle group `g` at sample point `s`.
  double strength(std::size_t s, std::size_t g) const { return m_strength.at(s, g); }
  /// The sample points' Laplacian `K` (rows in sample-point order).
  const Eigen::SparseMatrix<double, Eigen::RowMajor, int>& sample_laplacian() const { return m_system.K; }
  /// Whether sample point `s` is in the region of interest / a handle.
  bool is_roi_sample_point(std::size_t s) const { return m_sample_points.labels.at(s) != internal::fixed_label; }
  bool is_handle_sample_point(std::size_t s) const { return internal::is_handle_label(m_sample_points.labels.at(s)); }
  /// The handle group of sample point `s`; only for handle sample points.
  std::size_t handle_group_of(std::size_t s) const { return internal::handle_group_of_label(m_sample_points.labels.at(s)); }
  /// The target of a handle point under its group's current transform.
  Eigen::Vector3d handle_target(std::size_t group, const Eigen::Vector3d& p) const
  {
    const internal::Rigid_transform& transform = m_selection.transforms[m_selection.checked_group(group, who)];
    return transform.rotation * p + transform.translation;
  }
  const Settings& settings() const { return m_settings; }
  /// What `diffuse()` does to each point, for a renderer that moves the points itself (after `preprocess()`).
  Diffusion_view diffusion_view() const
  {
    check_preprocessed("diffusion_view()");
    return Diffusion_view(m_diffusion, m_cloud, m_row_of, m_normals, m_sample_points.positions, m_sample_points.labels,
                          m_deformed_samples, m_selection, m_settings);
  }
  /// @}

private:
  std::size_t checked_row(std::size_t i) const { return internal::checked_row(m_row_of, i, who); }
  void check_preprocessed(const char* call) const
  {
    if(!m_preprocessed) throw Invalid_input(std::string(who) + ": " + call + " needs preprocess() or deform() first");
  }
  Eigen::Vector3d of_point(const Matrix_n3& rows, std::size_t i) const { return rows.row(m_row_of.at(i)).transpose(); }
  // The internal deformed points or normals, unless the last diffusion wrote the caller's arrays instead.
  const Matrix_n3& current(const Matrix_n3& deformed) const
  {
    if(m_diffused_elsewhere)
      throw Invalid_input(std::string(who) +
                          ": the last diffusion wrote the caller's arrays (diffuse_in_input_order()); "
                          "call diffuse() to read its result here");
    return deformed;
  }
  static double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

  // Every point and sample point back to its input position, no rotation.
  void return_to_rest()
  {
    m_deformed_points = m_cloud.positions;
    m_deformed_normals = m_normals;
    m_deformed_samples = m_sample_points.positions;
    m_diffusion.turns.reset();
    m_detail_rotations.assign(m_sample_points.size(), Eigen::Matrix3d::Identity());
    m_rigid_drag.reset(m_selection.transforms.size());
    m_diffused = m_diffused_elsewhere = false;
  }

  // The input and the selection.
  Settings m_settings;
  std::function<bool(double)> m_callback;
  internal::Spatial_point_cloud m_cloud;
  std::vector<int> m_row_of;
  Matrix_n3 m_normals;
  internal::Edit_selection m_selection; // labels per row and the handle groups' transforms
  internal::Mean_shift_analysis m_mean_shift; // selection-independent: computed once
  bool m_preprocessed = false;

  // Set up by preprocess(), per selection.
  internal::Edit_sample_points m_sample_points;
  internal::Sample_system m_system; // the sample points' graph, Laplacian, region and factored least squares
  internal::Strength_field m_strength;
  internal::Rigid_drag m_rigid_drag;
  internal::Point_diffusion m_diffusion; // the sample turns, stencils and movable points, the collar, the relaxation

  // The edit's state, per drag.
  Matrix_n3 m_deformed_samples;
  std::vector<Eigen::Matrix3d> m_detail_rotations; // per sample point: R(Q_s), propagated or fitted
  bool m_diffused = false; // diffuse() ran since preprocess() or reset(): the stencil holds its motions
  bool m_diffused_elsewhere = false; // diffuse_in_input_order() ran since: m_deformed_points are not its result
  Matrix_n3 m_deformed_points, m_deformed_normals;
  Statistics m_statistics;
};

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_DEFORMATION_INSTANCES(EXTERN, Tag) EXTERN template class Detail_preserving_deformation<Tag>;
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_DEFORMATION_INSTANCES)

} // namespace CGAL_ext

#endif // CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_H
