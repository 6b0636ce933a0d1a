// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// Shared by the fuzz targets: the readers take files, so each input is written to a file first.
#ifndef POINT_DETAIL_FUZZ_SUPPORT_H
#define POINT_DETAIL_FUZZ_SUPPORT_H

#include "program_basics.h"
#include "point_io.h"

#include <CGAL/number_type_config.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace fuzz {

/// A file of this process in the temporary directory, rewritten with `bytes`.
inline std::filesystem::path write_input(const std::string& name, const std::uint8_t* data, std::size_t size)
{
  const std::filesystem::path path =
    std::filesystem::temp_directory_path() / ("point_detail_fuzz_" + std::to_string(getpid()) + "_" + name);
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), std::streamsize(size));
  return path;
}

/// 200 points of a unit sphere (a Fibonacci lattice), the model the edit and region readers select from.
inline const std::vector<point_detail::Point>& sphere_points()
{
  static const std::vector<point_detail::Point> points = [] {
    std::vector<point_detail::Point> out;
    const double golden = CGAL_PI * (3 - std::sqrt(5.0));
    for(int i = 0; i < 200; ++i) {
      const double z = 1 - 2 * (i + 0.5) / 200, r = std::sqrt(1 - z * z);
      out.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
    }
    return out;
  }();
  return points;
}

/// Reads a point file as point-detail does; the reader promises points (and as many normals, if any) or an error.
inline void read_points_and_check(const std::filesystem::path& path)
{
  try {
    const point_detail::Point_cloud cloud = point_detail::read_point_cloud(path);
    if(cloud.points.empty()) __builtin_trap();
    if(!cloud.normals.empty() && cloud.normals.size() != cloud.points.size()) __builtin_trap();
  } catch(const point_detail::Cli_error&) {
  }
}

} // namespace fuzz

#endif
