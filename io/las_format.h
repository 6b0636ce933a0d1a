// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// LAS files (the ASPRS lidar format), versions 1.0 to 1.4, point formats 0 to 10, uncompressed.
#ifndef POINT_DETAIL_LAS_FORMAT_H
#define POINT_DETAIL_LAS_FORMAT_H

#include "point_cloud.h"

#include <cstdint>
#include <filesystem>

namespace point_detail {

/// What a LAS header announces, checked against the specification and the file's size.
struct Las_header
{
  unsigned version_minor = 0;
  unsigned point_format = 0; ///< 0 to 10
  std::uint64_t points = 0;
  std::uint64_t point_offset = 0; ///< where the point records start
  std::uint64_t record_bytes = 0; ///< the file's record length (the format's fields and any extra bytes)
  double scale[3] = {1, 1, 1}, offset[3] = {0, 0, 0};
};

/// The bytes of point format `format`'s own fields (0 for an unknown format).
std::uint64_t las_format_bytes(unsigned format);

/// Reads a LAS header without trusting it: a compressed file (LAZ) is refused with the way to decompress it, a
/// header inconsistent with the specification or with the file's size, then more points than the memory holds
/// at `bytes_per_point` (0: no memory check), are refused before anything is allocated.
Las_header check_las_header(const std::filesystem::path& path, std::uint64_t bytes_per_point);

/// Reads a LAS file whole or throws Cli_error naming the problem. Coordinates are the records' integers times
/// the header's scale plus its offset; intensity, classification (its 5 bits in formats 0 to 5 from LAS 1.1 on),
/// return_number and number_of_returns become scalars (gps_time and nir too in the formats that have them);
/// red green blue become the colours (divided by 256 when any value exceeds 255, that is when the file uses the
/// specification's 16 bits).
Point_cloud read_las(const std::filesystem::path& path, std::uint64_t bytes_per_point);

} // namespace point_detail

#endif
