// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DETAIL_SCALING_SETTINGS_H
#define CGAL_EXT_DETAIL_SCALING_SETTINGS_H

#include <CGAL_ext/setting_names.h>
#include <CGAL_ext/Balanced_flow_settings.h>
#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/Least_squares_settings.h>

#include <cmath>
#include <string>
#include <cstddef>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  The default anchors of a partial region of interest. Soft border anchors conflict with the border's own
  detail equations (which ask those points to move); how that conflict resolves depends on the order.
  Measured (doc/detail_scaling.md): on a bumpy patch scaled to s = 0, the largest height left in the centre
  is 0.08 / 0.06 / 1.3 bump amplitudes for the linear / quadric / cubic order with border anchors and
  0.05 / 0.04 / 0.28 without; on a quarter of a unit sphere scaled by s = 2, the largest displacement is
  0.11 / 0.11 / 2.9 with border anchors and 0.52 / 0.52 / 0.11 without. The cubic order responds so weakly to
  smooth shapes (`f(k) ~ 2.7 k^2`) that anchoring turns the conflict into a bulge; the linear and quadric
  orders need the anchors to keep a curved region's own curvature from being scaled as a whole.
*/
enum class Border_anchoring
{
  automatic, ///< border anchors for the linear and quadric orders, none for the cubic order (the default)
  anchored,  ///< border anchors for every order (the paper's soft constraints)
  free       ///< no border anchors: the surroundings alone hold the region
};

/// The names of `Border_anchoring`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Border_anchoring>
{
  static constexpr Setting_spelling<Border_anchoring> table[] = {{"auto", Border_anchoring::automatic}, {"anchored", Border_anchoring::anchored},
                                                             {"free", Border_anchoring::free}};
};

/*!
  \ingroup PkgCGALExtRef
  Settings of detail scaling: what the details are (transfer function, Laplacian weights) and how the
  least-squares problem is solved. Implicitly constructible from a `Detail_filter`.
*/
struct Detail_scaling_settings
{
  Detail_settings details;
  Least_squares_settings least_squares;
  /// Without caller anchors, whether a partial region anchors its border (its points with a neighbour
  /// outside; the paper's soft constraints) or is held by its fixed surroundings alone (the detail equations
  /// are then square and consistent). See `Border_anchoring`.
  Border_anchoring border_anchoring = Border_anchoring::automatic;

  /// Whether the default anchors of a partial region are its border, for the filter of these settings.
  bool anchors_border() const
  {
    return border_anchoring == Border_anchoring::anchored ||
           (border_anchoring == Border_anchoring::automatic && details.filter.order != Detail_order::cubic);
  }

  Detail_scaling_settings(const Detail_filter& filter = {}) : details(filter) {}
  Detail_scaling_settings(const Detail_settings& d, const Least_squares_settings& ls = {}) : details(d), least_squares(ls) {}

  void validate() const { details.validate(); least_squares.validate(); }
};

/*!
  \ingroup PkgCGALExtRef
  Settings of detail enhancement: those of scaling plus the balanced flow of the base surface.
*/
struct Detail_enhancement_settings : Detail_scaling_settings
{
  Balanced_flow_settings flow;
  /// A partial region's normals, Laplacian and base surface are computed on the points within this many
  /// neighbourhood radii of it (the radius: the median distance of a region point to its k-th nearest region
  /// point), not on the whole model; 0 computes them on the whole model. The balanced flow's influence fades
  /// fast with the distance, so the default margin gives what the whole model's computation gives, to far below
  /// the displacement's size (doc/detail_scaling.md, "A region of a large model", measures it). Below 1 (but not
  /// 0) it is refused: it would keep too few points outside the region to anchor its border.
  double flow_margin = 80;

  Detail_enhancement_settings(const Detail_filter& filter = {}) : Detail_scaling_settings(filter) {}
  Detail_enhancement_settings(const Detail_scaling_settings& s, const Balanced_flow_settings& f = {})
    : Detail_scaling_settings(s), flow(f) {}

  void validate() const
  {
    Detail_scaling_settings::validate();
    flow.validate();
    if(!(std::isfinite(flow_margin) && (flow_margin == 0 || flow_margin >= 1)))
      throw Invalid_input("enhancement: flow_margin must be 0 (the whole model) or a finite number of neighbourhood "
                          "radii >= 1 (a smaller margin keeps too few points outside the region to anchor its border), "
                          "not " + std::to_string(flow_margin));
  }
};

/*!
  \ingroup PkgCGALExtRef
  What a detail scaling or enhancement did. Converts to `false` when the callback cancelled it (the points
  are then untouched).
*/
struct Detail_manipulation_result
{
  bool completed = false;
  std::size_t region_size = 0;       ///< points of the region of interest
  std::size_t computed_points = 0;   ///< points the Laplacian (and for enhancement the normals and base surface) used
  std::size_t anchor_count = 0;      ///< anchors used (given or default)
  bool default_anchors = false;      ///< whether the anchors were chosen by the function
  Least_squares_statistics least_squares;

  explicit operator bool() const { return completed; }
};

/*!
  \ingroup PkgCGALExtRef
  The indices of the points of `points` whose `selection_map` value is `true`: a region of interest or
  anchors given as a property map (a `Point_set_3` property, say).
*/
template <typename PointRange, typename SelectionMap>
std::vector<std::size_t> selected_indices(const PointRange& points, SelectionMap selection_map)
{
  std::vector<std::size_t> indices;
  std::size_t i = 0;
  for(const auto& item : points) {
    if(get(selection_map, item)) indices.push_back(i);
    ++i;
  }
  return indices;
}

} // namespace CGAL_ext

#endif // CGAL_EXT_DETAIL_SCALING_SETTINGS_H
