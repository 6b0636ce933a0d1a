// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_SETTINGS_H
#define CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_SETTINGS_H

#include <CGAL_ext/setting_names.h>
#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/Least_squares_settings.h>
#include <CGAL_ext/Simplification_settings.h>
#include <CGAL_ext/exceptions.h>

#include <cmath>
#include <cstddef>
#include <limits>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  How the strength field measures the distances `d0` (to the fixed part) and `d1` (to a handle).
*/
enum class Strength_distance
{
  euclidean, ///< straight-line distance between sample points (the paper's)
  geodesic   ///< shortest path along the sample points' neighbour graph (Dijkstra): does not leak across parts
             ///< that are close in space but far along the surface, like an arm held near the body
};

/// The names of `Strength_distance`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Strength_distance>
{
  static constexpr Setting_spelling<Strength_distance> table[] = {{"euclidean", Strength_distance::euclidean}, {"geodesic", Strength_distance::geodesic}};
};

/*!
  \ingroup PkgCGALExtRef
  How the sample points' details turn during an edit (the `R_i` of `delta'_i = R_i delta_i`).
*/
enum class Detail_rotation
{
  none,       ///< the details keep their world orientation (plain Laplacian editing)
  propagated, ///< the paper's (Sect. 6.1): the handle rotations blended by the strength field
  as_rigid_as_possible ///< each sample point's best rotation of its neighbourhood (Sorkine and Alexa 2007),
                       ///< alternated with the solve: follows the solved shape, so large twists and bends that
                       ///< the strength field cannot foresee keep their details
};

/// The names of `Detail_rotation`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Detail_rotation>
{
  static constexpr Setting_spelling<Detail_rotation> table[] = {{"none", Detail_rotation::none}, {"propagate", Detail_rotation::propagated},
                                                            {"arap", Detail_rotation::as_rigid_as_possible}};
};

/*!
  \ingroup PkgCGALExtRef
  How `Detail_rotation::as_rigid_as_possible` weighs the edges of the sample points' neighbour graph, in its
  rotation fits and its solve alike.
*/
enum class Rigid_edge_weights
{
  uniform,  ///< every edge 1 (Sorkine and Alexa's uniform variant on the kNN graph)
  cotangent ///< the point-set analogue of the mesh's cotangent weights: each sample point's Voronoi cell among
            ///< its graph neighbours in its tangent plane, an edge's weight the length of the cell's side it
            ///< crosses over its own (on a planar Delaunay 1-ring exactly `(cot a + cot b) / 2`), the mean of
            ///< both ends' values. Less dependent on the graph's size k, and nearer a mesh ARAP on large
            ///< bends (doc/editing_arap.md, "As rigid as possible")
};

/// The names of `Rigid_edge_weights`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Rigid_edge_weights>
{
  static constexpr Setting_spelling<Rigid_edge_weights> table[] = {{"uniform", Rigid_edge_weights::uniform}, {"cotangent", Rigid_edge_weights::cotangent}};
};

/*!
  \ingroup PkgCGALExtRef
  What the weight of the smooth-rotation term of `Detail_rotation::as_rigid_as_possible`
  (`rigid_rotation_smoothing`) is relative to.
*/
enum class Rotation_smoothing_scale
{
  edge_lengths, ///< each sample point's squared neighbourhood edge lengths (under the edge weights): the same pull
                ///< against the edges at every sampling density
  surface_area  ///< CGAL's `SRE_ARAP`: the sample points' whole area (the sum of their tangent-plane Voronoi
                ///< cells), shared among each sample point's neighbours, so that `rigid_rotation_smoothing` is
                ///< CGAL's `alpha` (0.02 there) and the energy is SRE_ARAP's; its pull against the edges grows
                ///< with the number of sample points, as the mesh ARAP's grows with the vertices
};

/// The names of `Rotation_smoothing_scale`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Rotation_smoothing_scale>
{
  static constexpr Setting_spelling<Rotation_smoothing_scale> table[] = {{"edge_lengths", Rotation_smoothing_scale::edge_lengths},
                                                                     {"surface_area", Rotation_smoothing_scale::surface_area}};
};

/*!
  \ingroup PkgCGALExtRef
  Where a point's offset is measured from when the deformation is diffused from the sample points to every
  point (Miao et al. 2007, Sect. 6.2). Both reproduce rigid motions exactly and keep points whose sample
  points did not move in place; they differ in how they blend bending.
*/
enum class Diffusion_origin
{
  nearest_sample, ///< the paper's: `p - ssp_0` (the nearest sample point) decoded in every frame from `ssp'_0`
  own_sample      ///< `p - ssp_i` decoded in frame i from `ssp'_i`: each sample point carries the point rigidly
};

/// The names of `Diffusion_origin`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Diffusion_origin>
{
  static constexpr Setting_spelling<Diffusion_origin> table[] = {{"own", Diffusion_origin::own_sample}, {"nearest", Diffusion_origin::nearest_sample}};
};

/*!
  \ingroup PkgCGALExtRef
  How the turn of a sample point is measured when the deformation is diffused from the sample points to
  every point (Miao et al. 2007, Sect. 6.2). All three give the identity exactly where nothing around the
  sample point moved and the exact rotation where its neighbourhood moved rigidly.
*/
enum class Sample_turn
{
  frames, ///< the paper's: a local frame built the same way before and after the edit (the normal of a plane
          ///< fitted to the sample point and its graph neighbours, the first axis toward one reference
          ///< neighbour), turned by `F' F^T`; its twist about the normal hangs on that one neighbour
  fitted, ///< the rotation that best maps the edges to the sample point's graph neighbours onto their deformed
          ///< edges, in the least-squares sense (as the local step of `as_rigid_as_possible`): every neighbour
          ///< counts, which changes the details less (doc/editing_diffusion.md, "Sample point turns")
  affine  ///< the linear map (rotation and stretch) that best maps those edges onto their deformed edges, held
          ///< to the fitted rotation along directions the edges do not span: where the edit stretches the
          ///< surface, neighbouring sample points then agree on how the points between them move, and the
          ///< blend adds no wrinkles (doc/editing_diffusion.md, "Sample point turns"). Normals follow the blended map's
          ///< cofactor, so they stay normal to the stretched surface
};

/// The names of `Sample_turn`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Sample_turn>
{
  static constexpr Setting_spelling<Sample_turn> table[] = {{"affine", Sample_turn::affine}, {"fitted", Sample_turn::fitted}, {"frames", Sample_turn::frames}};
};

/*!
  \ingroup PkgCGALExtRef
  Settings of detail-preserving editing (Miao et al. 2007, Sect. 6). Implicitly constructible from a
  `Detail_filter`.
*/
struct Detail_preserving_deformation_settings
{
  /// The details preserved on the sample points (their Laplacian is built on the sample points' kNN graph).
  Detail_filter filter;
  /// Neighbours of a sample point in the sample points' Laplacian, itself not counted: at least 1 and fewer than
  /// the sample points (`preprocess()` throws otherwise, as the free functions do for points).
  unsigned int sample_neighbors = default_laplacian_neighbors;
  /// How the points are clustered into sample points; every point is its own sample point when the input
  /// has at most `simplification.target_count` points and no `max_cluster_size` is set. Editing's defaults
  /// (target 3,000, mode-spread threshold 2) give 3,000 to 4,500 sample points on any input, as in the
  /// paper's Table 1, so that a drag stays interactive (doc/editing.md measures the quality cost).
  Simplification_settings simplification = editing_simplification();
  /// alpha (`least_squares.detail_weight`) and the solver.
  /// Editing refines each drag's solve to a relative residual of 1e-10 (positions to about 1e-10 of their
  /// displacement), which saves back-substitutions on every drag.
  Least_squares_settings least_squares = editing_least_squares();
  /// Weight of the handle constraints relative to the detail equations. Infinity (the default) makes them hard
  /// constraints: the handle sample points leave the unknowns and every handle point ends exactly where its
  /// group's transform puts it (as in `CGAL::Surface_mesh_deformation`). A finite weight is the paper's soft
  /// constraint (the paper: 1): the handles land near their targets, closer for larger weights.
  double handle_weight = std::numeric_limits<double>::infinity();
  /// Distances of the strength field.
  Strength_distance strength_distance = Strength_distance::euclidean;
  /// How the details turn.
  Detail_rotation rotations = Detail_rotation::propagated;
  /// With `as_rigid_as_possible`: rotation fits and solves per step of `deform()` (a change of the handles
  /// larger than `rigid_step_degrees` or `rigid_step_fraction` of the region's size is taken in steps). Each drag starts from the last
  /// drag's rotations (the first from the propagated ones), so a drag in small steps converges as it goes.
  /// ARAP converges slowly: more iterations bring the result closer to its fixed point, and to a converged mesh
  /// ARAP (doc/editing_arap.md, "As rigid as possible").
  unsigned int rigid_iterations = 3;
  /// With `as_rigid_as_possible`: a step stops iterating before `rigid_iterations` once no sample point moved
  /// more than this fraction of the region's size in the last iteration (0: always `rigid_iterations`).
  double rigid_tolerance = 0;
  /// With `as_rigid_as_possible`: the weight of SRE-ARAP's smooth-rotation term (CGAL's `SRE_ARAP`), which
  /// pulls each sample point's rotation toward its graph neighbours', relative to its neighbourhood's squared
  /// edge lengths (or, with `rigid_rotation_smoothing_scale`, to the surface's area, as CGAL's), >= 0 (0: plain
  /// ARAP). About 1 brings the result near CGAL's SRE_ARAP's on the Botsch–Sorkine cactus. It pays with 10 or
  /// more `rigid_iterations` (it uses the previous iteration's rotations): with 3 it lands farther from SRE_ARAP
  /// than plain ARAP on most scans (doc/editing_arap.md, "As rigid as possible", gives the distances).
  double rigid_rotation_smoothing = 0;
  /// With `as_rigid_as_possible`: what `rigid_rotation_smoothing` is relative to. `surface_area` with
  /// `Rigid_edge_weights::cotangent` and `rigid_rotation_smoothing` 0.02 is CGAL's SRE_ARAP energy on the sample
  /// points: converged on the Botsch–Sorkine cactus it lands close to SRE_ARAP's converged result
  /// (doc/editing_arap.md, "As rigid as possible", gives the distance).
  Rotation_smoothing_scale rigid_rotation_smoothing_scale = Rotation_smoothing_scale::edge_lengths;
  /// With `as_rigid_as_possible`: the weights of the graph's edges.
  Rigid_edge_weights rigid_edge_weights = Rigid_edge_weights::uniform;
  /// With `as_rigid_as_possible`: the largest turn of a handle group in one step of `deform()`, in degrees, > 0.
  /// ARAP's energy is not convex: a large change of the handles taken at once can land in another minimum.
  double rigid_step_degrees = 10;
  /// With `as_rigid_as_possible`: the largest move of the handles' centre in one step, as a fraction of the
  /// region's bounding diagonal, > 0.
  double rigid_step_fraction = 0.05;
  /// With `as_rigid_as_possible`: the most steps one `deform()` takes, >= 1; a drag that would need more takes
  /// larger ones.
  unsigned int max_rigid_steps = 1000;
  /// Nearest sample points that carry each point (m of Sect. 6.2), >= 1. More of them make the blend smoother
  /// and keep the fine details better at the cost of the diffusion's time (doc/editing_diffusion.md, "Seamless
  /// diffusion", measures both).
  unsigned int diffusion_samples = 6;
  Diffusion_origin diffusion_origin = Diffusion_origin::own_sample;
  /// How each region sample point's turn (and, affine, its stretch) is measured for the diffusion.
  Sample_turn diffusion_turn = Sample_turn::affine;
  /// `Detail_preserving_deformation::restore_details()`, which puts back the fine details the diffusion's blend
  /// smooths out, solves for them by a fixed number of Chebyshev steps (doc/editing_diffusion.md, "Restoring the
  /// details"): at most this many (0: it leaves the diffused points).
  unsigned int detail_iterations = 100;
  /// The factor by which `restore_details()` reduces the error at least (>= 0): it takes the fewest steps that
  /// guarantee it for any points, `acosh(1 / detail_tolerance) / acosh(1 + detail_anchor)` (38 by default).
  double detail_tolerance = 1e-2;
  /// How firmly `restore_details()` holds the diffused shape at coarse scales (> 0): it keeps what is coarser than
  /// about `1 / sqrt(detail_anchor)` point spacings (10 by default) where the blend put it and restores what
  /// is finer. Smaller values restore coarser details and take more steps (doc/editing_diffusion.md, "Restoring
  /// the details").
  double detail_anchor = 1e-2;
  /// With exact handles, whether each handle point's step from its blended position to its transform also moves
  /// the region's points about the handle, fading out over twice the diffusion's reach (doc/editing_diffusion.md, "Exact
  /// handles without a seam"). Off, the kNN edges across a handle's border stretch in a step: off only to see it.
  bool handle_collar = true;
  /// Whether the diffusion keeps to portable arithmetic instead of the processor's 4-wide vectors with fused
  /// multiply-add (AVX2 and FMA), where the build and the processor have them: then every processor gives the
  /// same doubles; the two paths agree to rounding (doc/editing.md, "How an edit runs", step 5). The environment variable
  /// `CGAL_EXT_PORTABLE_DIFFUSION=1` turns it on for every deformation of a process (the program's too).
  bool portable_diffusion = false;

  Detail_preserving_deformation_settings(const Detail_filter& f = {}) : filter(f) {}

  static Least_squares_settings editing_least_squares()
  {
    Least_squares_settings s;
    s.refinement_tolerance = 1e-10;
    return s;
  }

  static Simplification_settings editing_simplification()
  {
    Simplification_settings s;
    s.target_count = 3000;
    s.mode_spread_threshold = 2.0;
    return s;
  }

  void validate() const
  {
    filter.validate();
    simplification.validate();
    least_squares.validate();
    if(sample_neighbors < 1)
      throw Invalid_input("detail-preserving deformation: sample_neighbors must be at least 1");
    if(!(handle_weight > 0))
      throw Invalid_input("detail-preserving deformation: handle_weight must be > 0 (infinity: exact handles)");
    if(diffusion_samples < 1)
      throw Invalid_input("detail-preserving deformation: diffusion_samples must be at least 1");
    if(rigid_iterations < 1)
      throw Invalid_input("detail-preserving deformation: rigid_iterations must be at least 1");
    if(!(rigid_tolerance >= 0) || std::isinf(rigid_tolerance))
      throw Invalid_input("detail-preserving deformation: rigid_tolerance must be a finite number >= 0");
    if(!(rigid_rotation_smoothing >= 0) || std::isinf(rigid_rotation_smoothing))
      throw Invalid_input("detail-preserving deformation: rigid_rotation_smoothing must be a finite number >= 0");
    if(!(rigid_step_degrees > 0) || std::isinf(rigid_step_degrees))
      throw Invalid_input("detail-preserving deformation: rigid_step_degrees must be a finite number > 0");
    if(!(rigid_step_fraction > 0) || std::isinf(rigid_step_fraction))
      throw Invalid_input("detail-preserving deformation: rigid_step_fraction must be a finite number > 0");
    if(max_rigid_steps < 1)
      throw Invalid_input("detail-preserving deformation: max_rigid_steps must be at least 1");
    if(!(detail_tolerance >= 0) || std::isinf(detail_tolerance))
      throw Invalid_input("detail-preserving deformation: detail_tolerance must be a finite number >= 0");
    if(!(detail_anchor > 0) || std::isinf(detail_anchor))
      throw Invalid_input("detail-preserving deformation: detail_anchor must be a finite number > 0");
  }
};

/*!
  \ingroup PkgCGALExtRef
  Sizes and timings of a `Detail_preserving_deformation` (the fields of the paper's Table 1 and more).
*/
struct Detail_preserving_deformation_statistics
{
  std::size_t points = 0;      ///< input points
  std::size_t samples = 0;     ///< simplification sample points
  /// Sample points the mode-spread rule asked for (above `samples` when the budget of
  /// `Simplification_settings::variation_budget` capped it).
  std::size_t requested_samples = 0;
  std::size_t roi_samples = 0; ///< sample points of the region of interest (the unknowns)
  std::size_t handle_samples = 0;
  double clustering_seconds = 0; ///< mean shift and clustering (the mean shift runs once per deformation object)
  double preprocess_seconds = 0; ///< all of `preprocess()`, clustering and factorisation included
  Least_squares_statistics least_squares; ///< assembly, factorisation and last solve of the sample points' system
  double deform_seconds = 0;  ///< last `deform()`: propagated rotations, right-hand side, back-substitution
  /// Last `deform()` with `as_rigid_as_possible`: rotation fits and solves, over all its steps.
  unsigned int rigid_iterations = 0;
  /// Last `deform()`: the largest displacement of a sample point over the largest of a handle sample point (0
  /// when no handle moved). Well above 1, the solve swings parts of the region farther than the user moved
  /// anything (the cubic order on a long region can: doc/editing_arap.md, "Against CGAL on the Botsch–Sorkine
  /// cactus").
  double displacement_ratio = 0;
  double diffuse_seconds = 0; ///< last `diffuse()`: deformed frames and every point's new position and normal
  /// Last `diffuse()`: the bytes it read and wrote for the points it moved, as its data's layout counts them
  /// (each moved point's stencil, rest position and normal read, its new position and normal written; not the
  /// cache lines a store reads first): over `diffuse_seconds`, the memory bandwidth a drag achieved.
  std::size_t diffuse_bytes = 0;
  /// Last `restore_details()`, with the search for the points' neighbours when it was the first after preprocessing.
  double restore_seconds = 0;
  unsigned int restore_iterations = 0; ///< last `restore_details()`: Chebyshev steps
  /// Last `restore_details()`: its final residual relative to the details' size (at most about `detail_tolerance`
  /// unless `detail_iterations` cut the steps short).
  double restore_residual = 0;
};

} // namespace CGAL_ext

#endif // CGAL_EXT_DETAIL_PRESERVING_DEFORMATION_SETTINGS_H
