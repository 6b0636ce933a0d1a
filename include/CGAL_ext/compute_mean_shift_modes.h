// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_COMPUTE_MEAN_SHIFT_MODES_H
#define CGAL_EXT_COMPUTE_MEAN_SHIFT_MODES_H

#include <CGAL_ext/Mean_shift_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Computes the mean-shift mode of every point (Miao et al. 2007, Sect. 5.1) by the joint spatial-range mean
  shift of Comaniciu and Meer over the 7D features `(x, y, z, n, c H)`: starting at the point's feature, the
  mode moves to the mean of the nearby samples weighted by the product kernel
  `g(||M_s - q_s||^2 / h_s^2) g(||M_r - q_r||^2 / h_r^2)`, until it moves by less than `settings.tolerance`
  bandwidths (its range part only, with `settings.stop` set to `Mean_shift_stop::range_part`) or
  `settings.max_iterations` is reached. The samples near a moving mode are the sample nearest
  to it and that sample's `k` nearest neighbours, followed along the neighbour graph as the mode moves.

  The mean curvature `H` comes from the closed-form degree-2 fit of `estimate_mean_curvature` on the same
  `k` neighbours. Points on either side of a sharp edge have normals far apart in the range part, so their
  modes stay on their own side: that is what the clustering of `compute_simplification_sample_points` uses.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same modes.
  \tparam PointRange a model of `ConstRange` whose value type is the key type of the property maps.
  \tparam ModeMap a model of `WritablePropertyMap` with value type `Mean_shift_mode<geom_traits>`.

  \param points the input points; not modified
  \param k candidate neighbours of the mean shift and its curvature fit, `5 <= k < points.size()`
           (default in the program: `default_mean_shift_neighbors` = 15)
  \param settings kernel, bandwidths (0: automatic), curvature scale, tolerance and iteration cap
  \param mode_map receives the mode of each point
  \param np `point_map`, `normal_map` (estimated by `estimate_oriented_normals`
         when absent), `callback` (false cancels; the map is then untouched) and
         `geom_traits`, as in `compute_geometric_details`

  \return the scales and iteration counts; `completed` is false if the callback cancelled.
  \throws Invalid_input for an empty range, non-finite coordinates, `k` out of range, invalid settings, a zero
          or non-finite normal, or points that all coincide.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/simplification.md">Mean shift and simplification sample points</a> (`doc/simplification.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename ModeMap,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Mean_shift_result compute_mean_shift_modes(const PointRange& points, unsigned int k, const Mean_shift_settings& settings,
                                           ModeMap mode_map, const NamedParameters& np = CGAL::parameters::default_values())
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Kernel = typename NP_helper::Geom_traits;
  using FT = typename Kernel::FT;
  constexpr const char* who = "compute_mean_shift_modes";

  const auto point_map = NP_helper::get_const_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  settings.validate();
  const internal::Spatial_point_cloud cloud = internal::make_spatial_point_cloud<ConcurrencyTag>(points, point_map, who);
  internal::check_mean_shift_neighbors(k, cloud.size(), who);

  internal::Progress progress(callback);
  internal::Matrix_n3 normals;
  const double shift_begin = internal::has_given_normals<NamedParameters>(points) ? 0.0 : 0.4;
  progress.stage(0.0, shift_begin);
  if(!internal::given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress,
                                                            normals, who))
    return {};
  progress.stage(shift_begin, 1.0);
  internal::Mean_shift_analysis analysis;
  if(!internal::analyse_mean_shift<ConcurrencyTag>(cloud, normals, k, settings, progress, analysis)) return {};

  const internal::Mean_shift_scales& scales = analysis.scales;
  const std::vector<int> row_of = cloud.spatial_index();
  std::size_t i = 0;
  for(const auto& item : points) {
    const int r = row_of[i++];
    const auto m = analysis.modes.row(r);
    Mean_shift_mode<Kernel> mode;
    mode.position = typename Kernel::Point_3(FT(m(0) * scales.spatial_bandwidth), FT(m(1) * scales.spatial_bandwidth),
                                             FT(m(2) * scales.spatial_bandwidth));
    mode.normal = typename Kernel::Vector_3(FT(m(3) * scales.range_bandwidth), FT(m(4) * scales.range_bandwidth),
                                            FT(m(5) * scales.range_bandwidth));
    mode.mean_curvature = FT(m(6) * scales.range_bandwidth / scales.curvature_scale);
    mode.iterations = unsigned(analysis.iterations[std::size_t(r)]);
    put(mode_map, item, mode);
  }
  return internal::summarize(analysis, settings);
}

} // namespace CGAL_ext

#endif // CGAL_EXT_COMPUTE_MEAN_SHIFT_MODES_H
