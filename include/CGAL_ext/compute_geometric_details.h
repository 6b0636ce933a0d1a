// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_COMPUTE_GEOMETRIC_DETAILS_H
#define CGAL_EXT_COMPUTE_GEOMETRIC_DETAILS_H

#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/geometric_details.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/neighbor_radius_map.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <functional>
#include <type_traits>
#include <vector>

namespace CGAL_ext {

namespace internal {

template <typename ConcurrencyTag, typename PointRange, typename DetailMap, typename MagnitudeMap,
          typename NamedParameters>
bool compute_geometric_details_impl(const PointRange& points, unsigned int k, const Detail_settings& settings,
                                    DetailMap detail_map, MagnitudeMap magnitude_map, const NamedParameters& np)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Kernel = typename NP_helper::Geom_traits;
  using Vector = typename Kernel::Vector_3;
  using FT = typename Kernel::FT;
  constexpr const char* who = "compute_geometric_details";

  const auto point_map = NP_helper::get_const_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());

  settings.validate();
  const Spatial_point_cloud cloud = make_spatial_point_cloud<ConcurrencyTag>(points, point_map, who);
  check_neighbor_count(k, cloud.size(), who);

  Progress progress(callback);
  Matrix_n3 normals;
  const double laplacian_begin = has_given_normals<NamedParameters>(points) ? 0.0 : 0.5;
  progress.stage(0.0, laplacian_begin);
  if(!given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress, normals, who))
    return false;
  progress.stage(laplacian_begin, 1.0);
  using Radius_map = typename CGAL::internal_np::Get_param<typename NamedParameters::base,
                                                           CGAL_ext::internal_np::neighbor_radius_map_t>::type;
  constexpr bool radius_asked = !std::is_same<Radius_map, CGAL::internal_np::Param_not_found>::value;
  Matrix_n3 details;
  std::vector<double> radius;
  if(!geometric_details<ConcurrencyTag>(cloud, k, settings, normals, progress, details, who,
                                        radius_asked ? &radius : nullptr))
    return false;

  // Results exist only now: the caller's maps are untouched by a cancelled run.
  const std::vector<int> spatial_of = cloud.spatial_index();
  std::size_t i = 0;
  for(const auto& item : points) {
    const Eigen::RowVector3d d = details.row(spatial_of[i]);
    const double norm = d.norm();
    put(detail_map, item, Vector(FT(d(0)), FT(d(1)), FT(d(2))));
    put(magnitude_map, item, FT(d.dot(normals.row(spatial_of[i])) < 0 ? -norm : norm));
    if constexpr(radius_asked)
      put(get_parameter(np, CGAL_ext::internal_np::neighbor_radius_map), item, FT(radius[spatial_of[i]]));
    ++i;
  }
  return true;
}

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Computes the high-frequency geometric detail of every point, `delta = f(K) p`, where `K = I - W` is the
  point-set Laplacian on the symmetrised k-nearest-neighbour graph and `f` the transfer function of
  `settings.filter` (Miao et al. 2007, Sect. 3), and its oriented magnitude: `+||delta||` where
  `delta . n >= 0`, `-||delta||` otherwise (positive on bumps that stand out along the normal).

  Normals come from `normal_map` when given (for a `CGAL::Point_set_3`, from its normal property when it has
  one, so `point_set.parameters()` works with and without normals); otherwise they are estimated on an internal
  copy by `estimate_oriented_normals` (18 neighbours). Only the oriented magnitude uses them.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same result.
  \tparam PointRange a model of `ConstRange` whose value type is the key type of the property maps.
  \tparam DetailMap a model of `WritablePropertyMap` with value type `geom_traits::Vector_3`.
  \tparam MagnitudeMap a model of `WritablePropertyMap` with value type `geom_traits::FT`.

  \param points the input points; not modified
  \param k number of nearest neighbours, the point itself not counted; `1 <= k < points.size()`
           (default in the program: `default_laplacian_neighbors` = 10)
  \param settings transfer function and Laplacian weights (a `Detail_filter` converts implicitly)
  \param detail_map receives the detail vector of each point
  \param magnitude_map receives the oriented magnitude of each point (overloads without it exist)
  \param np an optional sequence of named parameters among the ones listed below

  \cgalNamedParamsBegin
    \cgalParamNBegin{point_map}
      \cgalParamDescription{a property map associating points to the elements of `points`}
      \cgalParamDefault{`CGAL::Identity_property_map<geom_traits::Point_3>`}
    \cgalParamNEnd
    \cgalParamNBegin{normal_map}
      \cgalParamDescription{a property map associating normals to the elements of `points`; zero or
                            non-finite normals are an error}
      \cgalParamDefault{normals are estimated}
    \cgalParamNEnd
    \cgalParamNBegin{callback}
      \cgalParamDescription{`std::function<bool(double)>` called with the progress in [0, 1] from the calling
                            thread; returning `false` cancels and leaves the output maps untouched}
    \cgalParamNEnd
    \cgalParamNBegin{neighbor_radius_map}
      \cgalParamDescription{a `WritablePropertyMap` with value type `geom_traits::FT` that receives each point's
                            distance to its k-th nearest neighbour, given by `CGAL_ext::parameters::neighbor_radius_map()`;
                            with it a caller that computes a piece of a larger scan checks that the piece held every
                            neighbour the Laplacian used (Python's tiled runs do)}
      \cgalParamDefault{not computed}
    \cgalParamNEnd
    \cgalParamNBegin{geom_traits}
      \cgalParamDescription{an instance of a geometric traits class}
      \cgalParamDefault{a kernel deduced from the point type, using `CGAL::Kernel_traits`}
    \cgalParamNEnd
  \cgalNamedParamsEnd

  \return false if the callback cancelled the computation, true otherwise.
  \throws Invalid_input for an empty range, non-finite coordinates, `k` out of range, `lambda <= 0`,
          `mu <= lambda` (quadric and cubic orders) or a zero or non-finite normal.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/geometric_details.md">Geometric details</a> (`doc/geometric_details.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename DetailMap,
          typename MagnitudeMap, typename NamedParameters = CGAL::parameters::Default_named_parameters>
bool compute_geometric_details(const PointRange& points, unsigned int k, const Detail_settings& settings,
                               DetailMap detail_map, MagnitudeMap magnitude_map,
                               const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::compute_geometric_details_impl<ConcurrencyTag>(points, k, settings, detail_map, magnitude_map, np);
}

/// \cond SKIP_IN_MANUAL
// Without the oriented magnitude.
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename DetailMap,
          typename T, typename Tag, typename Base>
bool compute_geometric_details(const PointRange& points, unsigned int k, const Detail_settings& settings,
                               DetailMap detail_map, const CGAL::Named_function_parameters<T, Tag, Base>& np)
{
  return internal::compute_geometric_details_impl<ConcurrencyTag>(points, k, settings, detail_map,
                                                                  internal::No_output_map(), np);
}

template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename DetailMap>
bool compute_geometric_details(const PointRange& points, unsigned int k, const Detail_settings& settings,
                               DetailMap detail_map)
{
  return internal::compute_geometric_details_impl<ConcurrencyTag>(points, k, settings, detail_map,
                                                                  internal::No_output_map(),
                                                                  CGAL::parameters::default_values());
}
/// \endcond

} // namespace CGAL_ext

#endif // CGAL_EXT_COMPUTE_GEOMETRIC_DETAILS_H
