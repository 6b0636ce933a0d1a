// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// PTS and PTX files, the text formats of terrestrial laser scanners (Leica and others).
#ifndef POINT_DETAIL_PTS_FORMAT_H
#define POINT_DETAIL_PTS_FORMAT_H

#include "point_cloud.h"

#include <cstdint>
#include <filesystem>

namespace point_detail {

/// Reads a PTS file whole or throws Cli_error naming the line and the problem: blocks of a point count followed
/// by that many lines of `x y z`, `x y z intensity`, `x y z r g b` or `x y z intensity r g b` (one layout per
/// file; a file without a count line is one block of all its lines). The intensity becomes the scalar
/// "intensity", r g b (0 to 255) the colours.
Point_cloud read_pts(const std::filesystem::path& path, std::uint64_t bytes_per_point);

/// Reads a PTX file whole or throws Cli_error naming the line and the problem: one or more scans, each a header
/// (columns, rows, the scanner's position and axes, a 4 x 4 transform whose last row is the translation) and
/// rows x columns lines of `x y z intensity` or `x y z intensity r g b`. Each scan's points are moved by its
/// transform (p' = [p 1] M, as the file writes M); points 0 0 0 (no return) are skipped and counted in
/// Point_cloud::points_without_position. The intensity becomes the scalar "intensity".
Point_cloud read_ptx(const std::filesystem::path& path, std::uint64_t bytes_per_point);

} // namespace point_detail

#endif
