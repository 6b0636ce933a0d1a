// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The public header block of a LAS file as the specification lays it out, for the tests and the fuzzers that
// write LAS files (the package reads LAS, it writes none).
#ifndef CGAL_EXT_TEST_LAS_TEST_FILE_H
#define CGAL_EXT_TEST_LAS_TEST_FILE_H

#include "las_format.h"

#include <cstdint>
#include <cstring>
#include <string>

namespace las_test_file {

/// The header of a LAS 1.`minor` file of `points` records of point format `format`, `record_bytes` each (0: the
/// format's own size), at `scale` on every axis and no offset; the points start right after it.
inline std::string header(unsigned minor, unsigned format, std::uint64_t points, std::uint16_t record_bytes = 0,
                          double scale = 0.001)
{
  const std::uint16_t header_bytes = minor >= 4 ? 375 : minor == 3 ? 235 : 227;
  if(record_bytes == 0) record_bytes = std::uint16_t(point_detail::las_format_bytes(format));
  std::string h(header_bytes, '\0');
  auto put = [&h](std::size_t at, auto value) { std::memcpy(&h[at], &value, sizeof value); };
  h.replace(0, 4, "LASF");
  h[24] = 1;
  h[25] = char(minor);
  put(94, header_bytes);
  put(96, std::uint32_t(header_bytes));
  h[104] = char(format);
  put(105, record_bytes);
  put(107, std::uint32_t(format < 6 ? points : 0)); // LAS 1.4 keeps the 32-bit count 0 for formats 6 to 10
  for(std::size_t axis = 0; axis < 3; ++axis) put(131 + 8 * axis, scale);
  if(minor >= 4) put(247, points);
  return h;
}

} // namespace las_test_file

#endif
