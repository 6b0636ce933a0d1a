// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// A point set as the I/O layer's readers return it and its writers take it.
#ifndef POINT_DETAIL_POINT_CLOUD_H
#define POINT_DETAIL_POINT_CLOUD_H

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace point_detail {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using Color = std::array<unsigned char, 3>;

/// A point set as the program reads and writes it, in file order.
struct Point_cloud
{
  std::vector<Point> points;
  std::vector<Vector> normals;   ///< empty when the file has none
  std::string normal_source;     ///< "file", "mesh" (area-weighted vertex normals of the file's faces) or ""
  std::vector<std::pair<std::string, std::vector<double>>> scalars; ///< extra per-point properties, written in order
  std::vector<Color> colors;     ///< written as red green blue when not empty
  std::size_t vertices_without_normal = 0; ///< "mesh" normals: vertices on no face, whose normal is zero
  bool unread_triangle_strips = false;     ///< a PLY mesh of triangle strips: its faces are not read
  /// Points of the file that have no position and were skipped: in a PCD file, x y z all NaN; in a PTX file,
  /// 0 0 0 (the scanner's "no return"). The others keep their file order.
  std::size_t points_without_position = 0;

  const std::vector<double>* scalar(const std::string& name) const;
  void set_scalar(const std::string& name, std::vector<double> values);
};

} // namespace point_detail

#endif
