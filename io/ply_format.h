// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// PLY files: what the program checks before CGAL's reader allocates anything (the header, refused when malformed
// or when the file cannot hold what it announces), the direct reader of plain binary files, and the writer.
#ifndef POINT_DETAIL_PLY_FORMAT_H
#define POINT_DETAIL_PLY_FORMAT_H

#include "point_cloud.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace point_detail {

/// A scalar type of PLY ("float", "uchar", ...): its size in bytes (0 for an unknown type) and its kind.
struct Ply_scalar
{
  std::string type;
  std::uint64_t bytes = 0;
  bool is_signed = false, is_real = false;
};

/// A property of a PLY element: a scalar of `value`'s type, or a list of them after a count of `count`'s type.
struct Ply_property
{
  std::string name;
  Ply_scalar count; ///< bytes 0 for a scalar
  Ply_scalar value;
  bool is_list() const { return count.bytes > 0; }
};

struct Ply_element
{
  std::string name;
  std::uint64_t count = 0; ///< items
  std::vector<Ply_property> properties;
};

/// What a PLY header announces, read without trusting it.
struct Announced
{
  std::uint64_t vertices = 0;
  std::uint64_t smallest_bytes = 0; ///< the fewest bytes of data after the header that can hold them
  bool triangle_strips = false;     ///< faces given as an element 'tristrips' (CGAL's reader reads only 'face')
  /// A binary little-endian file whose only element is the vertices, each exactly x y z or x y z nx ny nz of
  /// one float type: the program reads it directly (read_point_cloud).
  bool plain_vertices = false;
  bool plain_normals = false;       ///< the plain vertices carry nx ny nz
  std::uint64_t plain_value_bytes = 0; ///< 4 (float) or 8 (double)
  std::uint64_t header_bytes = 0;  ///< where the data starts
  std::string format;
  std::vector<Ply_element> elements;
};

/// Checks a PLY header before CGAL's reader allocates: the memory its points need, and whether the file can
/// hold what it announces. Returns what it announces.
Announced check_ply_header(const std::filesystem::path& path, std::uint64_t bytes_per_point);

/// The points (and normals) of a plain binary PLY (Announced::plain_vertices), read in one piece: an order of
/// magnitude faster than CGAL's generic reader, with the same values (doc/hardening.md measures it).
Point_cloud read_plain_ply(const std::filesystem::path& path, const Announced& header);

/// The cloud as a binary little-endian PLY: x y z (double), nx ny nz, the scalars (double), red green blue (uchar);
/// each scalar's property named `scalar_prefix` and its name (its name alone if it starts with the prefix).
std::string ply_bytes(const Point_cloud& cloud, const std::string& scalar_prefix = std::string());

} // namespace point_detail

#endif
