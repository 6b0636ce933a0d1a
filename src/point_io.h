// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef POINT_DETAIL_POINT_IO_H
#define POINT_DETAIL_POINT_IO_H

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <array>
#include <cstdint>
#include <filesystem>
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

  const std::vector<double>* scalar(const std::string& name) const;
  void set_scalar(const std::string& name, std::vector<double> values);
};

/// Reads PLY, OFF, XYZ or PWN through CGAL's readers. Throws Cli_error naming the file and the problem, and,
/// before reading, when a PLY or OFF header announces more points than the available memory holds at
/// `bytes_per_point` (what the caller's processing needs per point, reading included).
Point_cloud read_point_cloud(const std::filesystem::path& path, std::uint64_t bytes_per_point = 1024);

/// The prefix CloudCompare's command line wants on a PLY file's scalar fields; read_point_cloud reads such a
/// field under its name without it.
inline const std::string cloudcompare_scalar_prefix = "scalar_";

/// The cloud as a binary little-endian PLY: x y z (double), nx ny nz, the scalars (double), red green blue (uchar);
/// each scalar's property named `scalar_prefix` and its name (its name alone if it starts with the prefix).
std::string ply_bytes(const Point_cloud& cloud, const std::string& scalar_prefix = std::string());

} // namespace point_detail

#endif
