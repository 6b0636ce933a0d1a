// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DIFFUSE_POINTS_H
#define CGAL_EXT_DIFFUSE_POINTS_H

#include <CGAL_ext/Diffusion_view.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/ssp_diffusion.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Moves points that an edit's `Detail_preserving_deformation` was not built on (a denser sampling of the same
  surface, a tile of a scan larger than one machine whose sample points were computed on a subsample) as its
  `diffuse()` moves its own: each point and its normal by the motions of its `state.stencil_size` nearest sample
  points, weighted as `Diffusion_view::stencil()` weights them. A point at the position of one of the
  deformation's points gets that point's stencil, and moves as `diffuse()` moves it, bit for bit, unless it is an
  exact handle point or in the handles' collar: which points those are depends on the selection, which the caller
  applies (doc/scaling.md, "Editing in tiles").

  Writes each point's new position through `point_map` and its new normal through `normal_map`, in place.

  \tparam ConcurrencyTag `CGAL::Sequential_tag` or `CGAL::Parallel_if_available_tag`.
  \param points the points, with normals (`normal_map`).
  \param state the sample points' motions, from `Diffusion_view::state()` after
         `Detail_preserving_deformation::update_sample_motions()` (or `diffuse()`).
  \param np `point_map`, `normal_map` (required).
  \throws Invalid_input on an invalid `state`, points without normals, a non-finite point, a zero normal.
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
void diffuse_points(PointRange& points, const Diffusion_state& state,
                    const NamedParameters& np = CGAL::parameters::default_values())
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using namespace internal;
  constexpr const char* who = "diffuse_points";
  state.validate();
  if(!has_given_normals<NamedParameters>(points))
    throw Invalid_input(std::string(who) + ": the points need normals (normal_map): they turn with the points");
  if(std::begin(points) == std::end(points)) return;
  const Spatial_point_cloud cloud =
    make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
  const Matrix_n3 normals = gather_normals(points, NP_helper::get_normal_map(points, np), cloud, who);
  const Eigen::Index s = Eigen::Index(state.number_of_sample_points());
  const Matrix_n3 samples = Eigen::Map<const Matrix_n3>(state.sample_positions.data(), s, 3);
  const Matrix_n3 deformed = Eigen::Map<const Matrix_n3>(state.deformed_sample_positions.data(), s, 3);
  Diffusion_stencil stencil;
  stencil.template setup<ConcurrencyTag>(cloud.positions, samples, state.stencil_size);
  stencil.use_wide_vectors = !state.portable;
  stencil.set_motion_records(state.motions.data(), std::size_t(s));
  Matrix_n3 moved(cloud.positions.rows(), 3), moved_normals(cloud.positions.rows(), 3);
  stencil.template move_points<ConcurrencyTag>(cloud.positions, normals, samples, deformed, state.origin, moved.data(),
                                               moved_normals.data(), nullptr, nullptr);
  write_points_and_normals(points, np, cloud.spatial_index(), moved, moved_normals);
}

} // namespace CGAL_ext

#endif // CGAL_EXT_DIFFUSE_POINTS_H
