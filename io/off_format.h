// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// OFF files, read by the project's own reader.
#ifndef POINT_DETAIL_OFF_FORMAT_H
#define POINT_DETAIL_OFF_FORMAT_H

#include "point_cloud.h"

#include <cstdint>
#include <filesystem>
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

} // namespace point_detail

#endif
