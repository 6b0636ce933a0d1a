// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// PCD files (the Point Cloud Library's format, also Open3D's): ASCII, binary and binary_compressed.
#ifndef POINT_DETAIL_PCD_FORMAT_H
#define POINT_DETAIL_PCD_FORMAT_H

#include "point_cloud.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace point_detail {

/// A field of a PCD file: `count` values of one type each.
struct Pcd_field
{
  std::string name;
  unsigned size = 0;        ///< bytes of one value: 1, 2, 4 or 8
  char type = 'F';          ///< 'I' (signed), 'U' (unsigned) or 'F' (floating point)
  unsigned count = 1;       ///< values per point
  std::uint64_t offset = 0; ///< bytes before it in a binary record
};

/// What a PCD header announces, checked against itself and the file's size.
struct Pcd_header
{
  std::vector<Pcd_field> fields;
  std::uint64_t points = 0;
  std::string data;                                           ///< "ascii", "binary" or "binary_compressed"
  std::uint64_t header_bytes = 0;                             ///< where the data starts
  std::uint64_t record_bytes = 0;                             ///< bytes of one point in the binary layouts
  std::uint32_t compressed_bytes = 0, uncompressed_bytes = 0; ///< binary_compressed: the LZF data and what they hold
};

/// Reads a PCD header without trusting it: malformed lines, inconsistent counts, fields without x y z, a file too
/// short for its points (binary_compressed: compressed data larger than the file, or sizes that cannot hold the
/// points) and then more points than the memory holds at `bytes_per_point` (0: no memory check) are refused
/// before anything is allocated.
Pcd_header check_pcd_header(const std::filesystem::path& path, std::uint64_t bytes_per_point);

/// Reads a PCD file whole or throws Cli_error naming the problem. x y z, normal_x normal_y normal_z and rgb /
/// rgba (packed colours) become the points, normals and colours; every other field becomes a scalar (a field
/// of several values, NAME_0, NAME_1, ...; PCL's padding fields "_" are skipped). A point whose x, y and z are
/// all NaN (PCL's "no measurement", in organised clouds) is skipped and counted in
/// Point_cloud::points_without_position.
Point_cloud read_pcd(const std::filesystem::path& path, std::uint64_t bytes_per_point);

/// Decompresses LZF data (the compression of PCD's binary_compressed) into exactly `expected` bytes; false for
/// malformed data or any other size.
bool lzf_decompress(const unsigned char* in, std::size_t in_size, std::vector<unsigned char>& out,
                    std::size_t expected);

} // namespace point_detail

#endif
