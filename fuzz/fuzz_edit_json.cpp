// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The JSON edit parser of `point-detail edit --edit FILE`, on a 200-point sphere.
#include "cli_support.h"
#include "edit_spec.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const auto path = fuzz::write_input("edit.json", data, size);
  try {
    const point_detail::Edit_description edit = point_detail::read_edit_json(path, fuzz::sphere_points());
    for(std::size_t i : edit.roi)
      if(i >= fuzz::sphere_points().size()) __builtin_trap(); // indices are checked
  } catch(const point_detail::Cli_error&) {
  } catch(const CGAL_ext::Invalid_input&) {
  }
  return 0;
}
