// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The point-file readers as point-detail uses them. The first byte picks the format (.ply, .off, .xyz, .pwn,
// .pcd, .pts, .ptx, .las); the rest is mutated byte by byte (fuzz_ply, fuzz_off, fuzz_pcd, fuzz_pts_ptx and fuzz_las
// mutate their formats' structure).
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  if(size == 0) return 0;
  static const char* const extensions[] = {"in.ply", "in.off", "in.xyz", "in.pwn",
                                           "in.pcd", "in.pts", "in.ptx", "in.las"};
  fuzz::read_points_and_check(fuzz::write_input(extensions[data[0] % 8], data + 1, size - 1));
  return 0;
}
