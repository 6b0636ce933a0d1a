// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_UPSAMPLE_POINT_SET_H
#define CGAL_EXT_UPSAMPLE_POINT_SET_H

#include <CGAL_ext/Upsampling_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/sparse_directions.h>
#include <CGAL_ext/internal/upsampling.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <numeric>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Stands for "no spacing map": the spacing comes from the settings or the points themselves.
struct No_spacing_map {};

/// With a spacing map, the points whose local spacing exceeds theirs by this factor are the stretched ones.
constexpr double stretched_spacing = 1.25;

template <typename ConcurrencyTag, typename PointRange, typename IndexRange, typename SpacingMap,
          typename OutputIterator, typename NamedParameters>
Upsampling_result upsample_point_set_impl(const PointRange& points, const IndexRange* region,
                                          const SpacingMap& spacing_map, const Upsampling_settings& settings,
                                          OutputIterator output, const NamedParameters& np,
                                          bool surroundings_only = true) // false: the whole set (for the tests)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Kernel = typename NP_helper::Geom_traits;
  using namespace internal;
  constexpr const char* who = "upsample_point_set";
  settings.validate();
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  using SC_point = CGAL::Simple_cartesian<double>::Point_3;
  std::vector<SC_point> copy = copy_points(points, NP_helper::get_const_point_map(points, np), who);
  const std::size_t n = copy.size(), k = settings.neighbors;
  check_neighbor_count(k, n, who);
  if(!has_given_normals<NamedParameters>(points))
    throw Invalid_input(std::string(who) + ": the points need normals (normal_map): hole detection and the new "
                                           "samples' surface come from them");
  // The spacing each input point should have: the caller's (what it had before an edit), the settings', or
  // its local spacing. New points take the one interpolated along their gap.
  constexpr bool spacing_given = !std::is_same<SpacingMap, No_spacing_map>::value;
  std::vector<double> given_spacing;
  if constexpr(spacing_given) {
    given_spacing.reserve(n);
    for(const auto& item : points) {
      const double h = double(get(spacing_map, item));
      if(!(h > 0) || !std::isfinite(h))
        throw Invalid_input(std::string(who) + ": the spacing of point " + std::to_string(given_spacing.size()) +
                            " is not a positive number");
      given_spacing.push_back(h);
    }
  }
  std::vector<int> region_points;
  if(region) {
    std::vector<int> identity(n);
    std::iota(identity.begin(), identity.end(), 0);
    region_points = rows_of_indices(*region, identity, who, "region");
  }
  // With a region whose spacings are known before any search, only its surroundings take part: the points within
  // `max_rounds` holes (and a fit's reach beyond each) of it, at the region's widest spacing; a small region of a
  // large scan then costs what its surroundings cost (doc/upsampling.md, "A region's surroundings").
  Spatial_point_cloud cloud;
  double widest = settings.detection.spacing;
  if constexpr(spacing_given)
    for(const int i : region_points) widest = std::max(widest, given_spacing[std::size_t(i)]);
  if(surroundings_only && !region_points.empty() && widest > 0) {
    const std::vector<int> near =
      points_near(copy, region_points, settings.max_rounds * (settings.detection.max_hole_size + 2) * widest);
    if(near.size() < n && near.size() > k) {
      try {
        cloud = sort_spatially<ConcurrencyTag>(copy, near, who);
      } catch(const Invalid_input&) {
        cloud = Spatial_point_cloud(); // the surroundings lie on a line: the whole set instead
      }
    }
  }
  if(cloud.size() == 0) cloud = sort_spatially<ConcurrencyTag>(copy, who);
  std::vector<SC_point>().swap(copy);
  std::vector<int> row_of(n, -1);
  for(std::size_t s = 0; s < cloud.size(); ++s) row_of[std::size_t(cloud.input_index[s])] = int(s);
  const Matrix_n3 input_normals = gather_normals(points, NP_helper::get_normal_map(points, np), cloud, who);
  const Position_tree input_tree(cloud.positions, ConcurrencyTag());

  Upsampling_result result;
  std::vector<double> all_spacing;
  if constexpr(spacing_given) {
    all_spacing.resize(cloud.size());
    for(std::size_t s = 0; s < cloud.size(); ++s) all_spacing[s] = given_spacing[std::size_t(cloud.input_index[s])];
    result.spacing = median(given_spacing);
  } else {
    all_spacing = spacings<ConcurrencyTag>(cloud.positions, input_tree, settings.detection.spacing, who);
    result.spacing = median(all_spacing);
  }
  Progress progress(callback);

  std::vector<int> examine;
  for(const int i : region_points) examine.push_back(row_of[std::size_t(i)]);
  std::sort(examine.begin(), examine.end());
  if constexpr(spacing_given) {
    // Only what grew sparser than it was: a region point whose local spacing is now more than 25 % above the
    // given one (an edit stretched it). A part that moved rigidly, or a sampling's own irregular gaps, stay.
    const std::vector<double> now = local_spacings<ConcurrencyTag>(cloud.positions, input_tree, &examine);
    examine.erase(std::remove_if(examine.begin(), examine.end(),
                                 [&](int row) { return !(now[std::size_t(row)] > stretched_spacing * all_spacing[std::size_t(row)]); }),
                  examine.end());
  }
  std::vector<Eigen::Vector3d> new_points, new_normals;
  if(!fill_holes<ConcurrencyTag>(cloud.positions, input_normals, input_tree, settings, region != nullptr,
                                 std::move(examine), std::move(all_spacing),
                                 !spacing_given && settings.detection.spacing == 0, progress, result, new_points,
                                 new_normals))
    return {};
  if(!progress.report(1.0)) return {};
  // In the order of their coordinates: the output is then the same whoever computes which of the points (a tiled
  // run merges its tiles' new points in this order).
  std::vector<std::size_t> order(new_points.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return lexicographically_before(new_points[a], new_points[b]);
  });
  for(const std::size_t m : order)
    *output++ = std::make_pair(typename Kernel::Point_3(new_points[m].x(), new_points[m].y(), new_points[m].z()),
                               typename Kernel::Vector_3(new_normals[m].x(), new_normals[m].y(), new_normals[m].z()));
  result.inserted = new_points.size();
  result.completed = true;
  return result;
}

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Fills the holes of an oriented point set, such as the stretched parts of an edit (Miao et al. 2007,
  Sect. 6.3, Fig. 9): hole boundaries are found by `detect_sparse_directions`; across each gap, new samples
  are placed at the target spacing on the segment to the sample that reappears beyond it, with interpolated
  normals, and kept only where no sample lies within half a spacing; then they are relaxed by repulsion
  (Pauly et al. 2002): each moves in its tangent plane away from samples closer than 1.5 spacings, and is
  projected back onto a height function fitted to the input samples: of degree 2 to the nearest ones, or, more
  than 1.5 spacings inside a hole, of degree 3 to the nearest ones in 8 directions around it (so the fit spans
  the hole's rim instead of extrapolating from its near side); a new point that a second projection would
  move by more than a quarter spacing (an unstable fit) is dropped, and so is one whose offset from one of its
  3 nearest input samples leans more than 30 degrees out of that sample's tangent plane (a fit misled where
  the surface folds). Detection, insertion and relaxation repeat until no gap is left (at most
  `settings.max_rounds` times). Open borders, with nothing within `max_hole_size` beyond them, never grow.
  Input points are not moved.

  Spacings are local: unless `settings.detection.spacing` sets one everywhere, every point is measured
  against its own local spacing (`compute_local_spacing`), so the sparser parts of an adaptively or randomly
  sampled surface are not filled, and a gap must also be twice as wide as the gaps typical around it (see
  `Sparse_direction_settings`); a new point takes the spacing of its gap's ends.

  \tparam OutputIterator accepts `std::pair<Kernel::Point_3, Kernel::Vector_3>`: each new point with its
          unit normal, in the order of their coordinates (x, then y, then z); the input points are not
          repeated, so every output point is a new one.

  \param points the points, with normals (`normal_map`, required)
  \param settings target spacing (0: each point's local spacing, see `Sparse_direction_settings`), largest hole,
         neighbours, relaxation
  \param output receives the new points
  \param np `point_map`, `normal_map`, `callback` (false cancels; nothing is then written), `geom_traits`

  An overload takes `region`, the indices of the points whose gaps may be filled (say, the points an edit
  moved): gaps are looked for from those points only, so a sampling's own gaps elsewhere stay as they are.
  Another also takes `spacing_map` (a `ReadablePropertyMap` to `double`): the spacing each point should have,
  such as its local spacing before an edit (`compute_local_spacing` on the unedited points); then gaps are
  looked for only from the region's points whose local spacing now exceeds it by more than 25 % (what the
  edit stretched), and filled at that spacing (doc/upsampling.md, "Local spacing"). With a region and spacings
  given (a spacing map, or `settings.detection.spacing`), only the points within `max_rounds * (max_hole_size + 2)`
  times the region's largest spacing of it take part, so a small region of a large set costs what its surroundings
  cost (doc/upsampling.md, "A region's surroundings").

  \return the spacing used, the number of new points and rounds; converts to `false` (and nothing is
          written) when the callback cancelled.
  \throws Invalid_input for an empty range, non-finite coordinates, missing, zero or non-finite normals, fewer
          points than neighbours, or invalid settings.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/upsampling.md">Up-sampling after deformation</a> (`doc/upsampling.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename OutputIterator,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Upsampling_result upsample_point_set(const PointRange& points, const Upsampling_settings& settings, OutputIterator output,
                                     const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::upsample_point_set_impl<ConcurrencyTag>(points, static_cast<const std::vector<std::size_t>*>(nullptr),
                                                           internal::No_spacing_map(), settings, output, np);
}

/// \cond SKIP_IN_MANUAL
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename OutputIterator, typename NamedParameters = CGAL::parameters::Default_named_parameters>
Upsampling_result upsample_point_set(const PointRange& points, const IndexRange& region, const Upsampling_settings& settings,
                                     OutputIterator output, const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::upsample_point_set_impl<ConcurrencyTag>(points, &region, internal::No_spacing_map(), settings, output, np);
}

template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename SpacingMap, typename OutputIterator, typename NamedParameters = CGAL::parameters::Default_named_parameters>
Upsampling_result upsample_point_set(const PointRange& points, const IndexRange& region, const SpacingMap& spacing_map,
                                     const Upsampling_settings& settings, OutputIterator output,
                                     const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::upsample_point_set_impl<ConcurrencyTag>(points, &region, spacing_map, settings, output, np);
}
/// \endcond

} // namespace CGAL_ext

#endif // CGAL_EXT_UPSAMPLE_POINT_SET_H
