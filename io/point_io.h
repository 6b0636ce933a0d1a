// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The I/O layer's front: read a point file of any supported format, write the program's PLY.
#ifndef POINT_DETAIL_POINT_IO_H
#define POINT_DETAIL_POINT_IO_H

#include "files.h"
#include "ply_format.h"
#include "point_cloud.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace point_detail {

/// The extensions read_point_cloud reads, for messages.
inline const std::string supported_extensions = ".ply, .off, .xyz, .pwn, .pcd, .pts, .ptx or .las";

/// Reads a point file by its extension: PLY, XYZ and PWN through CGAL's readers (PLY's header checked first), OFF,
/// PCD, PTS, PTX and LAS by the layer's own (off_format.h, pcd_format.h, pts_format.h, las_format.h). Throws
/// Cli_error naming the file and the problem, and, before reading, when a header announces more points than the
/// available memory holds at `bytes_per_point` (what the caller's processing needs per point, reading included).
Point_cloud read_point_cloud(const std::filesystem::path& path, std::uint64_t bytes_per_point = 1024);

/// Where the points of a file of fixed-size records are, for readers that map the file instead of reading it
/// (the tiled runs): binary PCD and LAS.
struct Record_layout
{
  struct Field
  {
    std::string name;
    std::uint64_t offset = 0; ///< bytes from the start of a record
    char kind = 'f';          ///< 'f' (floating point), 'i' (signed) or 'u' (unsigned), little-endian
    unsigned bytes = 4;
  };
  std::uint64_t points = 0, data_offset = 0, record_bytes = 0;
  std::vector<Field> fields;                            ///< every single-valued field
  std::array<std::string, 3> coordinates;               ///< the fields of x, y, z
  std::array<std::string, 3> normals;                   ///< the fields of the normal, empty names when there is none
  std::array<double, 3> scale{1, 1, 1}, shift{0, 0, 0}; ///< coordinate = field * scale + shift (LAS)
};

/// The record layout of a binary PCD or a LAS file, its header checked as read_point_cloud checks it, except for
/// the memory (a mapped file is read a range at a time). Throws Cli_error for any other file, naming why.
Record_layout record_layout(const std::filesystem::path& path);

/// The prefix CloudCompare's command line wants on a PLY file's scalar fields; read_point_cloud reads such a
/// field under its name without it.
inline const std::string cloudcompare_scalar_prefix = "scalar_";

} // namespace point_detail

#endif
