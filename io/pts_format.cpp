// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "pts_format.h"

#include "files.h"

#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

namespace point_detail {
namespace fs = std::filesystem;
namespace {

/// Lines of numbers of a text file, with the line number for messages.
class Number_lines
{
public:
  static constexpr std::size_t max_values = 8;

  explicit Number_lines(const fs::path& path) : m_in(open_input(path)), m_name(path.string()) {}

  /// The next line that is not blank, split into numbers (at most max_values + 1 are kept: a longer line is
  /// reported as such); false at the end of the file.
  bool next()
  {
    while(std::getline(m_in, m_line)) {
      ++m_number;
      m_count = 0;
      const char* p = m_line.c_str();
      for(;;) {
        while(*p == ' ' || *p == '\t' || *p == '\r') ++p;
        if(*p == '\0') break;
        char* end = nullptr;
        const double v = std::strtod(p, &end);
        if(end == p || (*end != '\0' && *end != ' ' && *end != '\t' && *end != '\r')) {
          const char* stop = p;
          while(*stop != '\0' && *stop != ' ' && *stop != '\t' && *stop != '\r') ++stop;
          fail("'" + std::string(p, stop) + "' is not a number");
        }
        if(m_count <= max_values) m_values[m_count] = v;
        ++m_count;
        p = end;
      }
      if(m_count > 0) return true;
    }
    return false;
  }

  std::size_t count() const { return m_count; }
  double operator[](std::size_t i) const { return m_values[i]; }

  /// The line's single value as a count, or fails saying what it should be.
  std::uint64_t whole(const char* what) const
  {
    if(m_count != 1 || !(m_values[0] >= 0) || m_values[0] != std::floor(m_values[0]) || m_values[0] > 1e15)
      fail("expected " + std::string(what) + " (one whole number), found " + std::to_string(m_count) + " values");
    return std::uint64_t(m_values[0]);
  }

  [[noreturn]] void fail(const std::string& what) const
  {
    throw Cli_error("cannot read " + m_name + ":" + std::to_string(m_number) + ": " + what);
  }

  const std::string& name() const { return m_name; }

private:
  std::ifstream m_in;
  std::string m_name, m_line;
  std::size_t m_number = 0, m_count = 0;
  std::array<double, max_values + 1> m_values{};
};

unsigned char color_component(const Number_lines& line, std::size_t i)
{
  const double v = line[i];
  if(!(v >= 0 && v <= 255) || v != std::floor(v)) line.fail("a colour component must be a whole number from 0 to 255");
  return (unsigned char)(v);
}

/// Fails before anything is allocated when `points` more lines cannot fit in the file (each at least "0 0 0\n").
void check_announced(const Number_lines& line, const fs::path& path, std::uint64_t points,
                     std::uint64_t bytes_per_point, std::uint64_t min_line_bytes)
{
  const std::uint64_t size = file_bytes(path);
  if(points > size / min_line_bytes)
    line.fail("the file announces " + std::to_string(points) + " points, more than its " + std::to_string(size) +
              " bytes hold");
  check_memory_for(path, points, bytes_per_point);
}

} // namespace

Point_cloud read_pts(const fs::path& path, std::uint64_t bytes_per_point)
{
  Number_lines line(path);
  Point_cloud cloud;
  std::vector<double> intensity;
  std::size_t layout = 0; // values per point line, fixed by the first
  bool line_ready = line.next();
  if(!line_ready) throw Cli_error(path.string() + " contains no points");
  while(line_ready) {
    // A block: its count (or, in a file without counts, every line to the end).
    std::uint64_t announced = ~std::uint64_t(0);
    if(line.count() == 1) {
      announced = line.whole("a point count");
      check_announced(line, path, cloud.points.size() + announced, bytes_per_point, 6);
      line_ready = line.next();
    }
    std::uint64_t read = 0;
    for(; read < announced && line_ready; ++read, line_ready = line.next()) {
      if(line.count() == 1) break; // a count line begins the next block
      if(layout == 0) {
        layout = line.count();
        if(layout != 3 && layout != 4 && layout != 6 && layout != 7)
          line.fail("a point is x y z, x y z intensity, x y z r g b or x y z intensity r g b; this line has " +
                    std::to_string(layout) + " values");
      }
      if(line.count() != layout)
        line.fail("this line has " + std::to_string(line.count()) + " values, the file's first point " +
                  std::to_string(layout));
      cloud.points.emplace_back(line[0], line[1], line[2]);
      if(layout == 4 || layout == 7) intensity.push_back(line[3]);
      if(layout >= 6)
        cloud.colors.push_back(
          {color_component(line, layout - 3), color_component(line, layout - 2), color_component(line, layout - 1)});
    }
    if(announced != ~std::uint64_t(0) && read < announced && line_ready)
      line.fail("a block announces " + std::to_string(announced) + " points, " + std::to_string(read) +
                " follow before this count line");
    if(announced != ~std::uint64_t(0) && read < announced)
      throw Cli_error("cannot read " + path.string() + ": truncated pts file (a block announces " +
                      std::to_string(announced) + " points, " + std::to_string(read) + " follow)");
  }
  if(cloud.points.empty()) throw Cli_error(path.string() + " contains no points");
  if(!intensity.empty()) cloud.scalars.emplace_back("intensity", std::move(intensity));
  return cloud;
}

Point_cloud read_ptx(const fs::path& path, std::uint64_t bytes_per_point)
{
  Number_lines line(path);
  Point_cloud cloud;
  std::vector<double> intensity;
  std::size_t layout = 0, scans = 0;
  std::uint64_t total = 0;
  while(line.next()) {
    ++scans;
    const std::uint64_t columns = line.whole("the scan's column count");
    if(!line.next()) line.fail("the scan's header ends after its column count");
    const std::uint64_t rows = line.whole("the scan's row count");
    if(columns > 0 && rows > (std::uint64_t(1) << 62) / columns) line.fail("the scan is too large");
    total += rows * columns;
    // Each point line is at least "0 0 0 0\n".
    check_announced(line, path, total, bytes_per_point, 8);
    auto header_line = [&](std::size_t values, const char* what) {
      if(!line.next()) line.fail(std::string("the scan's header ends before ") + what);
      if(line.count() != values)
        line.fail(std::string(what) + " has " + std::to_string(values) + " values, this line " +
                  std::to_string(line.count()));
    };
    header_line(3, "the scanner's position");
    for(int axis = 0; axis < 3; ++axis) header_line(3, "a scanner axis");
    double m[4][4];
    for(int r = 0; r < 4; ++r) {
      header_line(4, "a row of the transform");
      for(int c = 0; c < 4; ++c) m[r][c] = line[std::size_t(c)];
    }
    for(int r = 0; r < 4; ++r)
      if(!(std::abs(m[r][3] - (r == 3 ? 1.0 : 0.0)) <= 1e-9) || !std::isfinite(m[r][0] + m[r][1] + m[r][2]))
        line.fail("the transform is not an affine map (its last column must be 0 0 0 1 and its values finite)");
    for(std::uint64_t p = 0; p < rows * columns; ++p) {
      if(!line.next())
        throw Cli_error("cannot read " + path.string() + ": truncated ptx file (scan " + std::to_string(scans) +
                        " announces " + std::to_string(rows * columns) + " points, " + std::to_string(p) + " follow)");
      if(layout == 0) layout = line.count();
      if(line.count() != layout || (layout != 4 && layout != 7))
        line.fail("a point is x y z intensity or x y z intensity r g b, in every scan alike; this line has " +
                  std::to_string(line.count()) + " values");
      const double x = line[0], y = line[1], z = line[2];
      if(x == 0 && y == 0 && z == 0) { // no return
        ++cloud.points_without_position;
        continue;
      }
      cloud.points.emplace_back(x * m[0][0] + y * m[1][0] + z * m[2][0] + m[3][0],
                                x * m[0][1] + y * m[1][1] + z * m[2][1] + m[3][1],
                                x * m[0][2] + y * m[1][2] + z * m[2][2] + m[3][2]);
      intensity.push_back(line[3]);
      if(layout == 7)
        cloud.colors.push_back({color_component(line, 4), color_component(line, 5), color_component(line, 6)});
    }
  }
  if(cloud.points.empty())
    throw Cli_error(path.string() + " contains no points" +
                    (cloud.points_without_position > 0
                       ? " (all " + std::to_string(cloud.points_without_position) + " are 0 0 0, no return)"
                       : std::string()));
  cloud.scalars.emplace_back("intensity", std::move(intensity));
  return cloud;
}

} // namespace point_detail
