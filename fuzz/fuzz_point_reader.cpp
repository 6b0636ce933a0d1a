// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The point-file readers as point-detail uses them. The first byte picks the format (.ply, .off, .xyz, .pwn);
// the rest is mutated byte by byte (fuzz_ply and fuzz_off mutate their formats' structure).
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  if(size == 0) return 0;
  static const char* const extensions[] = {"in.ply", "in.off", "in.xyz", "in.pwn"};
  fuzz::read_points_and_check(fuzz::write_input(extensions[data[0] % 4], data + 1, size - 1));
  return 0;
}
