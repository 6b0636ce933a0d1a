// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "las_format.h"

#include "files.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace point_detail {
namespace fs = std::filesystem;
namespace {

template <typename T>
T field(const unsigned char* bytes, std::size_t at)
{
  T v;
  std::memcpy(&v, bytes + at, sizeof(T)); // LAS is little-endian, as the machine (x86_64, aarch64)
  return v;
}

bool has_gps_time(unsigned format) { return format != 0 && format != 2; }
bool has_rgb(unsigned format)
{
  return format == 2 || format == 3 || format == 5 || format == 7 || format == 8 || format == 10;
}
bool has_nir(unsigned format) { return format == 8 || format == 10; }

/// Where the fields of a record are, by format.
struct Layout
{
  std::size_t gps_time = 0, rgb = 0, nir = 0;
};

Layout layout_of(unsigned format)
{
  Layout l;
  if(format <= 5) {
    l.gps_time = 20;
    l.rgb = format == 2 ? 20 : 28;
  } else {
    l.gps_time = 22;
    l.rgb = 30;
    l.nir = 36;
  }
  return l;
}

} // namespace

std::uint64_t las_format_bytes(unsigned format)
{
  static const std::uint64_t bytes[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return format <= 10 ? bytes[format] : 0;
}

Las_header check_las_header(const fs::path& path, std::uint64_t bytes_per_point)
{
  const std::string name = path.string();
  auto fail = [&](const std::string& what) { throw Cli_error("cannot read " + name + ": " + what); };
  const std::string laz_advice =
    "LAZ (compressed LAS) is not read; decompress it first, e.g. `laszip -i scan.laz -o scan.las` (LAStools) or "
    "`pdal translate scan.laz scan.las`";
  if(lower_extension(path) == "laz") fail(laz_advice);
  std::ifstream in = open_input(path, std::ios::binary);
  const std::uint64_t size = file_bytes(path);
  unsigned char h[375] = {};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  const std::uint64_t got = std::uint64_t(in.gcount());
  if(got < 4 || std::memcmp(h, "LASF", 4) != 0) fail("not a LAS file (it does not start with 'LASF')");
  if(got < 227) fail("truncated las file (" + std::to_string(size) + " bytes, the header alone needs 227)");
  Las_header las;
  const unsigned major = h[24], minor = h[25];
  if(major != 1 || minor > 4)
    fail("LAS version " + std::to_string(major) + "." + std::to_string(minor) + " (1.0 to 1.4 are read)");
  las.version_minor = minor;
  const std::uint64_t header_size = field<std::uint16_t>(h, 94);
  const std::uint64_t minimal_header = minor >= 4 ? 375 : minor == 3 ? 235 : 227;
  if(header_size < minimal_header)
    fail("the header size is " + std::to_string(header_size) + " bytes; LAS 1." + std::to_string(minor) + " needs " +
         std::to_string(minimal_header));
  if(got < minimal_header)
    fail("truncated las file (" + std::to_string(size) + " bytes, its header needs " + std::to_string(minimal_header) +
         ")");
  las.point_offset = field<std::uint32_t>(h, 96);
  const unsigned format_byte = h[104];
  // LASzip marks a compressed file by setting bit 7 (and bit 6) of the point format.
  if(format_byte & 0xc0) fail(laz_advice);
  las.point_format = format_byte;
  if(las.point_format > 10) fail("point format " + std::to_string(las.point_format) + " (0 to 10 are defined)");
  if(las.point_format > 5 && minor < 4)
    fail("point format " + std::to_string(las.point_format) + " needs LAS 1.4, the file says 1." +
         std::to_string(minor));
  las.record_bytes = field<std::uint16_t>(h, 105);
  if(las.record_bytes < las_format_bytes(las.point_format))
    fail("records of " + std::to_string(las.record_bytes) + " bytes; point format " + std::to_string(las.point_format) +
         " needs at least " + std::to_string(las_format_bytes(las.point_format)));
  const std::uint64_t legacy_points = field<std::uint32_t>(h, 107);
  las.points = legacy_points;
  if(minor >= 4) {
    const std::uint64_t points = field<std::uint64_t>(h, 247);
    if(legacy_points != 0 && points != legacy_points)
      fail("the header's point counts disagree (" + std::to_string(legacy_points) + " and " + std::to_string(points) +
           ")");
    las.points = points;
  }
  for(int axis = 0; axis < 3; ++axis) {
    las.scale[axis] = field<double>(h, 131 + 8 * std::size_t(axis));
    las.offset[axis] = field<double>(h, 155 + 8 * std::size_t(axis));
    if(!std::isfinite(las.scale[axis]) || las.scale[axis] == 0 || !std::isfinite(las.offset[axis]))
      fail("the header's scale and offset must be finite and the scale not zero");
  }
  if(las.point_offset < header_size)
    fail("the point records start inside the header (offset " + std::to_string(las.point_offset) + ")");
  if(las.points == 0) throw Cli_error(name + " contains no points");
  const std::uint64_t left = size > las.point_offset ? size - las.point_offset : 0;
  if(las.points > left / las.record_bytes)
    fail("truncated las file (the header announces " + std::to_string(las.points) + " points of " +
         std::to_string(las.record_bytes) + " bytes, the file holds " + std::to_string(left) + " bytes of records)");
  check_memory_for(path, las.points, bytes_per_point);
  return las;
}

Point_cloud read_las(const fs::path& path, std::uint64_t bytes_per_point)
{
  const Las_header las = check_las_header(path, bytes_per_point);
  const std::size_t n = std::size_t(las.points);
  const unsigned format = las.point_format;
  const Layout at = layout_of(format);
  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(las.point_offset));
  Buffered_bytes bytes(in);
  std::vector<unsigned char> record(std::size_t(las.record_bytes));
  Point_cloud cloud;
  cloud.points.reserve(n);
  std::vector<double> intensity(n), classification(n), return_number(n), returns(n), gps_time, nir;
  if(has_gps_time(format)) gps_time.resize(n);
  if(has_nir(format)) nir.resize(n);
  std::vector<std::array<std::uint16_t, 3>> rgb;
  if(has_rgb(format)) rgb.resize(n);
  for(std::size_t i = 0; i < n; ++i) {
    if(!bytes.read(record.data(), record.size()))
      throw Cli_error("cannot read " + path.string() + ": truncated las file");
    const unsigned char* r = record.data();
    cloud.points.emplace_back(field<std::int32_t>(r, 0) * las.scale[0] + las.offset[0],
                              field<std::int32_t>(r, 4) * las.scale[1] + las.offset[1],
                              field<std::int32_t>(r, 8) * las.scale[2] + las.offset[2]);
    intensity[i] = field<std::uint16_t>(r, 12);
    if(format <= 5) {
      return_number[i] = r[14] & 7;
      returns[i] = (r[14] >> 3) & 7;
      classification[i] = las.version_minor == 0 ? r[15] : r[15] & 31; // LAS 1.0: the whole byte
    } else {
      return_number[i] = r[14] & 15;
      returns[i] = r[14] >> 4;
      classification[i] = r[16];
    }
    if(!gps_time.empty()) gps_time[i] = field<double>(r, at.gps_time);
    if(!nir.empty()) nir[i] = field<std::uint16_t>(r, at.nir);
    if(!rgb.empty())
      rgb[i] = {field<std::uint16_t>(r, at.rgb), field<std::uint16_t>(r, at.rgb + 2),
                field<std::uint16_t>(r, at.rgb + 4)};
  }
  if(!rgb.empty()) {
    bool sixteen_bits = false;
    for(const auto& c : rgb) sixteen_bits = sixteen_bits || c[0] > 255 || c[1] > 255 || c[2] > 255;
    const int shift = sixteen_bits ? 8 : 0;
    cloud.colors.reserve(n);
    for(const auto& c : rgb)
      cloud.colors.push_back(
        {(unsigned char)(c[0] >> shift), (unsigned char)(c[1] >> shift), (unsigned char)(c[2] >> shift)});
  }
  cloud.scalars.emplace_back("intensity", std::move(intensity));
  cloud.scalars.emplace_back("classification", std::move(classification));
  cloud.scalars.emplace_back("return_number", std::move(return_number));
  cloud.scalars.emplace_back("number_of_returns", std::move(returns));
  if(!gps_time.empty()) cloud.scalars.emplace_back("gps_time", std::move(gps_time));
  if(!nir.empty()) cloud.scalars.emplace_back("nir", std::move(nir));
  return cloud;
}

} // namespace point_detail
