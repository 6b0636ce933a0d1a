// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The OFF reader as point-detail uses it, fed by a mutator that changes keywords, counts, tokens and lines
// (fuzz/structure_mutators.h).
#include "fuzz_support.h"
#include "structure_mutators.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  fuzz::read_points_and_check(fuzz::write_input("in.off", data, size));
  return 0;
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size, unsigned seed)
{
  return fuzz::custom_mutate(data, size, max_size, seed, fuzz::mutate_off);
}
