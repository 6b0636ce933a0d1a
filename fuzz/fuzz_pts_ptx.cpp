// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The PTS and PTX readers as point-detail uses them. The first byte picks the format (even: .pts, odd: .ptx) and
// is kept by the mutator, which changes the rest's counts, lines and values (fuzz/scan_format_mutators.h).
#include "fuzz_support.h"
#include "scan_format_mutators.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  if(size == 0) return 0;
  fuzz::read_points_and_check(fuzz::write_input(data[0] % 2 ? "in.ptx" : "in.pts", data + 1, size - 1));
  return 0;
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                               unsigned seed)
{
  if(size == 0 || max_size < 2) return LLVMFuzzerMutate(data, size, max_size);
  const bool ptx = data[0] % 2;
  return 1 + fuzz::custom_mutate(data + 1, size - 1, max_size - 1, seed,
                                 [ptx](const std::string& in, std::size_t max, fuzz::Random& random) {
                                   return fuzz::mutate_pts_ptx(in, max, random, ptx);
                                 });
}
