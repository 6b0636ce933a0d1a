// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DIFFUSE_POINTS_H
#define CGAL_EXT_DIFFUSE_POINTS_H

#include <CGAL_ext/Diffusion_view.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/detail_relaxation.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/handle_collar.h>
#include <CGAL_ext/internal/ssp_diffusion.h>
#include <CGAL_ext/neighbor_radius_map.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <string>
#include <type_traits>
#include <vector>

namespace CGAL_ext {

/// \cond SKIP_IN_MANUAL
namespace internal_np {
enum selection_map_t
{
  selection_map
};
enum restore_details_t
{
  restore_details
};
} // namespace internal_np
/// \endcond

namespace parameters {

/*!
  \ingroup PkgCGALExtAlgorithms
  The named parameter `selection_map` of `diffuse_points()`: a `ReadablePropertyMap` with value type `int`, each
  point's place in the edit's selection: `Diffusion_state::fixed`, `Diffusion_state::region`, or its handle group.
  It follows other named parameters, `selection_map(labels, CGAL::parameters::point_map(...))`.
*/
template <typename SelectionMap, typename T = bool, typename Tag = CGAL::internal_np::all_default_t,
          typename Base = CGAL::internal_np::No_property>
CGAL::Named_function_parameters<SelectionMap, internal_np::selection_map_t,
                                CGAL::Named_function_parameters<T, Tag, Base>>
selection_map(const SelectionMap& map,
              const CGAL::Named_function_parameters<T, Tag, Base>& np = CGAL::parameters::default_values())
{
  return {map, np};
}

/*!
  \ingroup PkgCGALExtAlgorithms
  The named parameter `restore_details` of `diffuse_points()`: whether it also puts back the fine details the blend
  smooths out, as `Detail_preserving_deformation::restore_details()` does (`false` by default).
*/
template <typename T = bool, typename Tag = CGAL::internal_np::all_default_t,
          typename Base = CGAL::internal_np::No_property>
CGAL::Named_function_parameters<bool, internal_np::restore_details_t, CGAL::Named_function_parameters<T, Tag, Base>>
restore_details(bool restore,
                const CGAL::Named_function_parameters<T, Tag, Base>& np = CGAL::parameters::default_values())
{
  return {restore, np};
}

} // namespace parameters

/// What `diffuse_points()` did to restore the details: the Chebyshev steps and the final residual,
/// as `Detail_preserving_deformation::Statistics` reports them (zero without `restore_details`).
struct Diffuse_points_outcome
{
  unsigned int restore_iterations = 0;
  double restore_residual = 0;
};

/*!
  \ingroup PkgCGALExtAlgorithms
  Moves points that an edit's `Detail_preserving_deformation` was not built on (a denser sampling of the same
  surface, a tile of a scan larger than one machine whose sample points were computed on a subsample) as its
  `diffuse()` moves its own: each point and its normal by the motions of its `state.stencil_size` nearest sample
  points, weighted as `Diffusion_view::stencil()` weights them; with the points' `selection_map`, the exact handle
  points onto their group's transform and the region's points within `state.collar_reach` of a handle by the
  handle's step (the collar). The deformation's own points, given with their selection, move as `diffuse()`
  moves them, bit for bit. A point's result depends on the sample points and on the handle points within the
  collar's reach only, so a part of a scan moves as the whole scan would where it holds those handle points
  (doc/scaling.md, "Editing in tiles").

  With `restore_details(true)`, it then puts back the fine details as `Detail_preserving_deformation::restore_details()`
  does, with the state's `detail_anchor`, `detail_iterations` and `detail_tolerance`: the deformation's own
  points with their selection land where `diffuse()` and `restore_details()` put them, bit for bit. Each of its
  Chebyshev steps reaches one neighbourhood further, and no step sums over the points: a point's restored
  position depends on the points within as many hops of the 10-nearest graph as steps, and three more, so a part
  of a scan that holds them gives that point the whole scan's result (doc/scaling.md, "Editing in tiles").

  With `neighbor_radius_map`, it also writes each point's distance to its 10th nearest other point, the radius of
  the restoration's neighbourhoods, with which a caller holding a part of a scan certifies which of its points
  hold all the points their results depend on (the tiled edit, doc/scaling.md, "Editing in tiles").

  Writes each point's new position through `point_map` and its new normal through `normal_map`, in place.

  \tparam ConcurrencyTag `CGAL::Sequential_tag` or `CGAL::Parallel_if_available_tag`.
  \param points the points, with normals (`normal_map`).
  \param state the sample points' motions, from `Diffusion_view::state()` after
         `Detail_preserving_deformation::update_sample_motions()` (or `diffuse()`).
  \param np `point_map`, `normal_map` (required); `CGAL_ext::parameters::selection_map()` (without it, every point
         is a region point that is no handle: neither exact handles nor a collar);
         `CGAL_ext::parameters::restore_details()`; `CGAL_ext::parameters::neighbor_radius_map()`.
  \returns the restoration's iterations and residual.
  \throws Invalid_input on an invalid `state`, points without normals, a non-finite point, a zero normal, or a
          selection value that is no handle group of `state`.
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Diffuse_points_outcome diffuse_points(PointRange& points, const Diffusion_state& state,
                                      const NamedParameters& np = CGAL::parameters::default_values())
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using namespace internal;
  constexpr const char* who = "diffuse_points";
  state.validate();
  if(!has_given_normals<NamedParameters>(points))
    throw Invalid_input(std::string(who) + ": the points need normals (normal_map): they turn with the points");
  if(std::begin(points) == std::end(points)) return {};
  const Spatial_point_cloud cloud =
    make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
  const Matrix_n3 normals = gather_normals(points, NP_helper::get_normal_map(points, np), cloud, who);
  const std::vector<int> row_of = cloud.spatial_index();

  // The selection as the deformation labels its points, per row.
  const std::size_t groups = state.number_of_handle_groups();
  std::vector<int> labels(cloud.size(), roi_label);
  if constexpr(!CGAL::parameters::is_default_parameter<NamedParameters, internal_np::selection_map_t>::value) {
    const auto selection = CGAL::parameters::get_parameter(np, internal_np::selection_map);
    std::size_t i = 0;
    for(const auto& item : points) {
      const int value = int(get(selection, item));
      if(value < Diffusion_state::fixed || value >= int(groups))
        throw Invalid_input(std::string(who) + ": the selection of point " + std::to_string(i) + " is " +
                            std::to_string(value) + "; it must be Diffusion_state::fixed, Diffusion_state::region or " +
                            "a handle group (" + std::to_string(groups) + " in the state)");
      labels[std::size_t(row_of[i++])] = value == Diffusion_state::fixed    ? int(fixed_label)
                                         : value == Diffusion_state::region ? int(roi_label)
                                                                            : int(first_handle_label) + value;
    }
  }
  std::vector<int> sample_labels;
  for(std::uint8_t in_region : state.region_samples) sample_labels.push_back(in_region ? roi_label : fixed_label);
  std::vector<Rigid_transform> transforms(groups);
  std::vector<Eigen::Matrix3d> rotations(groups);
  for(std::size_t g = 0; g < groups; ++g) {
    const double* T = &state.handle_transforms[7 * g];
    transforms[g].rotation = Eigen::Quaterniond(T[0], T[1], T[2], T[3]);
    transforms[g].translation = Eigen::Vector3d(T[4], T[5], T[6]);
    rotations[g] = transforms[g].rotation.toRotationMatrix();
  }

  const Eigen::Index s = Eigen::Index(state.number_of_sample_points());
  const Matrix_n3 samples = Eigen::Map<const Matrix_n3>(state.sample_positions.data(), s, 3);
  const Matrix_n3 deformed = Eigen::Map<const Matrix_n3>(state.deformed_sample_positions.data(), s, 3);
  Diffusion_stencil stencil;
  stencil.template setup<ConcurrencyTag>(cloud.positions, samples, state.stencil_size);
  stencil.use_wide_vectors = !state.portable;
  stencil.set_motion_records(state.motions.data(), std::size_t(s));
  // As Point_diffusion: the rows a region sample point carries are blended, the others keep their input.
  const std::vector<int> moving = moving_rows(stencil, sample_labels, labels, state.exact_handles);
  Matrix_n3 moved = cloud.positions, moved_normals = normals;
  stencil.template move_points<ConcurrencyTag>(cloud.positions, normals, samples, deformed, state.origin, moved.data(),
                                               moved_normals.data(), &moving, nullptr);
  Handle_collar collar;
  collar.template setup<ConcurrencyTag>(cloud, labels, groups, state.exact_handles, state.collar_reach > 0, stencil,
                                        samples, moving, state.collar_reach);
  collar.template apply<ConcurrencyTag>(cloud.positions, normals, rotations, transforms, moved, moved_normals);
  Diffuse_points_outcome outcome;
  // As Point_diffusion::restore_details: the moved region points relax over the closed balls of their 10th
  // nearest, the rest pin them. The balls of every point come from one k-nearest graph, which also gives the radii.
  using Radius_map =
    typename CGAL::internal_np::Get_param<typename NamedParameters::base, internal_np::neighbor_radius_map_t>::type;
  constexpr bool radius_asked = !std::is_same<Radius_map, CGAL::internal_np::Param_not_found>::value;
  const std::size_t neighbors = std::min<std::size_t>(10, cloud.size() - 1);
  const bool restore =
    CGAL::parameters::choose_parameter(CGAL::parameters::get_parameter(np, internal_np::restore_details), false) &&
    state.detail_iterations > 0;
  if((restore || radius_asked) && neighbors > 0) { // a single point has no neighbours: nothing to relax or measure
    Progress progress;
    const Neighbor_graph balls = k_nearest_neighbor_graph<ConcurrencyTag>(cloud.positions, neighbors, progress);
    if(restore) {
      Detail_relaxation relaxation;
      relaxation.template setup<ConcurrencyTag>(cloud.positions, relaxed_rows(moving, labels, collar.handle_rows),
                                                balls);
      const Detail_relaxation::Outcome restored = relaxation.template apply<ConcurrencyTag>(
        cloud.positions, state.detail_anchor, state.detail_iterations, state.detail_tolerance, moved);
      outcome.restore_iterations = restored.iterations;
      outcome.restore_residual = restored.residual;
    }
    if constexpr(radius_asked) {
      const std::vector<double> radius = last_neighbor_distances(cloud.positions, cloud.positions, balls);
      const auto radius_map = CGAL::parameters::get_parameter(np, internal_np::neighbor_radius_map);
      std::size_t i = 0;
      using FT = typename NP_helper::Geom_traits::FT;
      for(const auto& item : points) put(radius_map, item, FT(radius[std::size_t(row_of[i++])]));
    }
  }
  write_points_and_normals(points, np, row_of, moved, moved_normals);
  return outcome;
}

} // namespace CGAL_ext

#endif // CGAL_EXT_DIFFUSE_POINTS_H
