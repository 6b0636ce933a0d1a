// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// What the program's readers check before CGAL's readers allocate anything: the memory a file's announced
// points need, the PLY header (refused when malformed or when the file cannot hold what it announces), and an
// OFF reader of the project's own.
#ifndef POINT_DETAIL_GUARDED_READING_H
#define POINT_DETAIL_GUARDED_READING_H

#include "point_io.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace point_detail {

/// An ASCII OFF file ([ST][C][N]OFF): vertices, their normals (NOFF) and faces. Colours and texture
/// coordinates are skipped. The project reads OFF itself: CGAL 5.5's scanner reads past its buffer on some
/// malformed colour entries (found by fuzz/fuzz_point_reader).
struct Off_file
{
  std::vector<Point> vertices;
  std::vector<Vector> normals;
  std::vector<std::vector<std::size_t>> faces;
};

/// Reads an OFF file, failing before allocating when its header announces more vertices than the memory holds
/// at `bytes_per_point`. Throws Cli_error naming the file and the problem.
Off_file read_off(const std::filesystem::path& path, std::uint64_t bytes_per_point);

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

} // namespace point_detail

#endif
