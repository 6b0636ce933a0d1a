// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The LAS reader as point-detail uses it, fed by a mutator that sets the header's fields (version, sizes,
// offsets, point format, record length, counts, scale, offset) to edge values (fuzz/scan_format_mutators.h).
#include "fuzz_support.h"
#include "scan_format_mutators.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  fuzz::read_points_and_check(fuzz::write_input("in.las", data, size));
  return 0;
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                               unsigned seed)
{
  return fuzz::custom_mutate(data, size, max_size, seed, fuzz::mutate_las);
}
