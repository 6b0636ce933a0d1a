// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// Headless pictures of point sets: splats with a depth buffer and normal shading, written as PNG.
#ifndef POINT_DETAIL_RENDER_H
#define POINT_DETAIL_RENDER_H

#include "colors.h"
#include "point_io.h"

#include <string>
#include <vector>

namespace point_detail {

/// Camera direction: azimuth about the y axis and elevation towards +y, in degrees.
/// (0, 0) looks at the model from +z with +y up ("front").
struct View
{
  double azimuth = 0, elevation = 0;
};

/// Parses front|back|left|right|top|bottom|iso or "AZIMUTH,ELEVATION". Throws Cli_error.
View parse_view(const std::string& text);

struct Render_settings
{
  int width = 800, height = 800;
  View view;
  double splat_scale = 1.0; ///< scales the splat radius (0.75 times the distance to the 4th nearest sample)
};

/// Whether the legend's font can write `c` (letters, written in capitals, digits, space and .,-+/()_).
bool legend_can_write(char c);

/// A PNG picture of the points. `normals` may be empty (flat shading). A colour scale gets a legend strip at
/// the bottom with its range under the quantity's name; flagged points, a swatch with their count.
std::string render_png(const std::vector<Point>& points, const std::vector<Vector>& normals, const Coloring& coloring,
                       const Render_settings& settings);

} // namespace point_detail

#endif
