// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// Colour maps of per-point values, as the pictures and the PLY colours show them.
#ifndef POINT_DETAIL_COLORS_H
#define POINT_DETAIL_COLORS_H

#include "point_io.h"

#include <string>
#include <vector>

namespace point_detail {

/// Point colours and what the picture's legend says about them.
struct Coloring
{
  enum class Scale { none, diverging, sequential, flag };
  std::vector<Color> colors;    ///< one per point; empty: grey
  std::vector<char> emphasized; ///< one per point or empty: drawn over the others, at least 2 pixels wide
  Scale scale = Scale::none;
  double lo = 0, hi = 0;        ///< the colour range (diverging: -hi .. hi)
  std::size_t emphasized_count = 0;
  /// What the colours show and in what unit, as the legend names it ("distance moved, model units"); the
  /// flagged points' name for a flag map.
  std::string quantity;
  std::string flagged; ///< beside a colour bar, the word after the flagged points' count ("new")
};

/// The legend's name of a per-point property the program writes ("detail_normal": "detail along the normal,
/// model units"); the property's own name for one it does not know.
std::string quantity_of(const std::string& property);

/// The colour of flagged points (new points of an up-sampling, a region): it stands out on grey and on both maps.
constexpr Color flag_color{255, 0, 200};

/// Diverging blue-white-red colours, symmetric about zero, saturating at the 98th percentile of the non-zero
/// |values| (of all of them when most are non-zero): a map of a small change (a few points moved, the rest 0)
/// spans that change instead of collapsing to white (doc/geometric_details.md, "Colour maps").
Coloring diverging_colors(const std::vector<double>& values);
/// The same map saturating at `limit` (> 0) instead: the tiled runs colour each tile with the whole scan's limit.
Coloring diverging_colors(const std::vector<double>& values, double limit);
/// Sequential colours from the 2nd to the 98th percentile; when those are equal (most points share one value),
/// from that value to the percentiles of the values that differ from it.
Coloring sequential_colors(const std::vector<double>& values);
/// Values of 0 and 1: the points with 1 in `flag_color`, drawn over the others; the rest grey.
Coloring flag_colors(const std::vector<double>& flags);
/// The map a property calls for: flags for 0/1 values, diverging when both signs occur, else sequential.
Coloring colors_for(const std::vector<double>& values);
/// Marks the points whose `flags` value is 1 in `flag_color`, drawn over the others; `flagged` names them ("new").
void emphasize(Coloring& coloring, const std::vector<double>& flags, const std::string& flagged);
/// Distinct colours per label (clusters), the same colour for the same label.
Coloring label_colors(const std::vector<std::size_t>& labels);

/// The colour of t in [0, 1] on a scale's map (diverging: Moreland's cool-warm; else a viridis-like map).
Color scale_color(Coloring::Scale scale, double t);
/// The q-quantile of `values` (0 for none).
double percentile(std::vector<double> values, double q);

} // namespace point_detail

#endif
