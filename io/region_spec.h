// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// Regions of interest and anchor sets on the command line: sphere:x,y,z,r | box:x0,y0,z0,x1,y1,z1 | indices:FILE.
#ifndef POINT_DETAIL_REGION_SPEC_H
#define POINT_DETAIL_REGION_SPEC_H

#include "point_io.h"

#include <array>
#include <string>
#include <vector>

namespace point_detail {

struct Region_spec
{
  enum class Kind { sphere, box, indices } kind = Kind::sphere;
  std::array<double, 6> numbers{};  ///< sphere: centre and radius; box: min and max corners
  std::string file;                 ///< indices: one point index per line ('#' starts a comment)
  std::string text;                 ///< as given, for messages
};

/// Parses one spec. Throws Cli_error naming the bad token.
Region_spec parse_region_spec(const std::string& text);

/// Indices of the points inside the union of `specs`, increasing. Reads index files; throws Cli_error on a
/// bad line or an index out of range.
std::vector<std::size_t> select_points(const std::vector<Point>& points, const std::vector<Region_spec>& specs);

} // namespace point_detail

#endif
