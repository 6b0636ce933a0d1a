// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The region spec parser of --roi and --anchors (sphere:, box:, indices:FILE), selecting on a 200-point sphere.
#include "program_basics.h"
#include "fuzz_support.h"
#include "region_spec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const point_detail::Region_spec spec = point_detail::parse_region_spec(text);
    for(std::size_t i : point_detail::select_points(fuzz::sphere_points(), {spec}))
      if(i >= fuzz::sphere_points().size()) __builtin_trap();
  } catch(const point_detail::Cli_error&) {
  }
  return 0;
}
