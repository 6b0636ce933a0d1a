// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The point-file readers as point-detail uses them. The first byte picks the format (.ply, .off, .xyz, .pwn).
#include "cli_support.h"
#include "fuzz_support.h"
#include "point_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  if(size == 0) return 0;
  static const char* const extensions[] = {"in.ply", "in.off", "in.xyz", "in.pwn"};
  const auto path = fuzz::write_input(extensions[data[0] % 4], data + 1, size - 1);
  try {
    const point_detail::Point_cloud cloud = point_detail::read_point_cloud(path);
    if(cloud.points.empty()) __builtin_trap(); // the reader promises points or an error
    if(!cloud.normals.empty() && cloud.normals.size() != cloud.points.size()) __builtin_trap();
  } catch(const point_detail::Cli_error&) {
  }
  return 0;
}
