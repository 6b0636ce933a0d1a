// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_NEIGHBOR_RADIUS_MAP_H
#define CGAL_EXT_NEIGHBOR_RADIUS_MAP_H

#include <CGAL/Named_function_parameters.h>

namespace CGAL_ext {

/// \cond SKIP_IN_MANUAL
namespace internal_np {
enum neighbor_radius_map_t
{
  neighbor_radius_map
};
} // namespace internal_np
/// \endcond

namespace parameters {

/*!
  \ingroup PkgCGALExtAlgorithms
  The named parameter `neighbor_radius_map` of `compute_geometric_details()` and `diffuse_points()`: a
  `WritablePropertyMap` with value type `geom_traits::FT` that receives each point's distance to its k-th nearest
  neighbour (the radius of its closed ball, doc/design.md, "One neighbourhood rule"). It follows other named
  parameters, `neighbor_radius_map(radii, CGAL::parameters::normal_map(normals))`, as CGAL 5.5's parameters
  cannot be extended by a member function.
*/
template <typename RadiusMap, typename T = bool, typename Tag = CGAL::internal_np::all_default_t,
          typename Base = CGAL::internal_np::No_property>
CGAL::Named_function_parameters<RadiusMap, internal_np::neighbor_radius_map_t,
                                CGAL::Named_function_parameters<T, Tag, Base>>
neighbor_radius_map(const RadiusMap& radius_map,
                    const CGAL::Named_function_parameters<T, Tag, Base>& np = CGAL::parameters::default_values())
{
  return {radius_map, np};
}

} // namespace parameters

} // namespace CGAL_ext

#endif // CGAL_EXT_NEIGHBOR_RADIUS_MAP_H
