// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The .sel/.def reader of `point-detail edit --sel --def` for a 50-point model. The input is the .sel file,
// a NUL byte, and the .def file.
#include "program_basics.h"
#include "edit_spec.h"
#include "fuzz_support.h"

#include <algorithm>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const std::uint8_t* split = std::find(data, data + size, std::uint8_t(0));
  const auto sel = fuzz::write_input("in.sel", data, std::size_t(split - data));
  const std::size_t rest = split == data + size ? 0 : std::size_t(data + size - split - 1);
  const auto def = fuzz::write_input("in.def", split == data + size ? data : split + 1, rest);
  try {
    const point_detail::Edit_description edit = point_detail::read_botsch_sorkine(sel, def, 50);
    for(std::size_t i : edit.roi)
      if(i >= 50) __builtin_trap();
  } catch(const point_detail::Cli_error&) {
  } catch(const CGAL_ext::Invalid_input&) {
  }
  return 0;
}
