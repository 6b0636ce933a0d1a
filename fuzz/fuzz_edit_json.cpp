// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The JSON edit parser of `point-detail edit --edit FILE` (one edit or a chain of steps), on a 200-point sphere, fed by a mutator that changes
// the parsed tree (fuzz/structure_mutators.h).
#include "program_basics.h"
#include "edit_spec.h"
#include "fuzz_support.h"
#include "structure_mutators.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const auto path = fuzz::write_input("edit.json", data, size);
  try {
    // Each step's selections on the same points (the chain's states all have these points or more).
    for(const point_detail::Edit_step& step : point_detail::read_edit_chain(path)) {
      if(step.kind == point_detail::Edit_step::Kind::edit) {
        const point_detail::Edit_description edit = step.edit(fuzz::sphere_points());
        for(std::size_t i : edit.roi)
          if(i >= fuzz::sphere_points().size()) __builtin_trap(); // indices are checked
      } else if(step.region) {
        for(std::size_t i : step.region(fuzz::sphere_points()))
          if(i >= fuzz::sphere_points().size()) __builtin_trap();
      }
    }
  } catch(const point_detail::Cli_error&) {
  } catch(const CGAL_ext::Invalid_input&) {
  }
  return 0;
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size, unsigned seed)
{
  return fuzz::custom_mutate(data, size, max_size, seed, fuzz::mutate_edit_json);
}
