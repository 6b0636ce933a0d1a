// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "region_spec.h"

#include "files.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>

namespace point_detail {

namespace {

double parse_number(const std::string& token, const std::string& spec)
{
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  if(token.empty() || end != token.c_str() + token.size() || errno == ERANGE || !std::isfinite(value))
    throw Cli_error("region '" + spec + "': '" + token + "' is not a finite number");
  return value;
}

std::vector<std::string> split(const std::string& s, char separator)
{
  std::vector<std::string> parts;
  std::size_t begin = 0;
  for(;;) {
    const std::size_t end = s.find(separator, begin);
    parts.push_back(s.substr(begin, end - begin));
    if(end == std::string::npos) return parts;
    begin = end + 1;
  }
}

} // namespace

Region_spec parse_region_spec(const std::string& text)
{
  const std::size_t colon = text.find(':');
  if(colon == std::string::npos)
    throw Cli_error("region '" + text + "': expected sphere:x,y,z,r, box:xmin,ymin,zmin,xmax,ymax,zmax or indices:FILE");
  const std::string kind = text.substr(0, colon), rest = text.substr(colon + 1);
  Region_spec spec;
  spec.text = text;
  if(kind == "indices") {
    if(rest.empty()) throw Cli_error("region '" + text + "': indices needs a file name");
    spec.kind = Region_spec::Kind::indices;
    spec.file = rest;
    return spec;
  }
  const std::size_t expected = kind == "sphere" ? 4 : kind == "box" ? 6 : 0;
  if(expected == 0)
    throw Cli_error("region '" + text + "': unknown kind '" + kind + "' (use sphere, box or indices)");
  const std::vector<std::string> tokens = split(rest, ',');
  if(tokens.size() != expected)
    throw Cli_error("region '" + text + "': " + kind + " takes " + std::to_string(expected) + " numbers, got " +
                    std::to_string(tokens.size()));
  for(std::size_t i = 0; i < expected; ++i) spec.numbers[i] = parse_number(tokens[i], text);
  if(kind == "sphere") {
    spec.kind = Region_spec::Kind::sphere;
    if(!(spec.numbers[3] > 0)) throw Cli_error("region '" + text + "': the radius '" + tokens[3] + "' must be > 0");
  } else {
    spec.kind = Region_spec::Kind::box;
    for(int a = 0; a < 3; ++a)
      if(!(spec.numbers[std::size_t(a)] <= spec.numbers[std::size_t(a + 3)]))
        throw Cli_error("region '" + text + "': the minimum '" + tokens[std::size_t(a)] + "' exceeds the maximum '" +
                        tokens[std::size_t(a + 3)] + "'");
  }
  return spec;
}

std::vector<std::size_t> select_points(const std::vector<Point>& points, const std::vector<Region_spec>& specs)
{
  std::vector<char> selected(points.size(), 0);
  for(const Region_spec& spec : specs) {
    const auto& v = spec.numbers;
    switch(spec.kind) {
      case Region_spec::Kind::sphere:
        for(std::size_t i = 0; i < points.size(); ++i)
          if(CGAL::squared_distance(points[i], Point(v[0], v[1], v[2])) <= v[3] * v[3]) selected[i] = 1;
        break;
      case Region_spec::Kind::box:
        for(std::size_t i = 0; i < points.size(); ++i) {
          const Point& p = points[i];
          if(p.x() >= v[0] && p.y() >= v[1] && p.z() >= v[2] && p.x() <= v[3] && p.y() <= v[4] && p.z() <= v[5])
            selected[i] = 1;
        }
        break;
      case Region_spec::Kind::indices: {
        std::ifstream in = open_input(spec.file);
        std::string line;
        for(std::size_t number = 1; std::getline(in, line); ++number) {
          line = line.substr(0, line.find('#'));
          line.erase(0, line.find_first_not_of(" \t\r"));
          line.erase(line.find_last_not_of(" \t\r") + 1);
          if(line.empty()) continue;
          char* end = nullptr;
          errno = 0;
          const long long index = std::strtoll(line.c_str(), &end, 10);
          if(end != line.c_str() + line.size() || errno == ERANGE || index < 0)
            throw Cli_error(spec.file + ":" + std::to_string(number) + ": '" + line + "' is not a point index");
          if(std::size_t(index) >= points.size())
            throw Cli_error(spec.file + ":" + std::to_string(number) + ": index " + line + " is out of range (" +
                            std::to_string(points.size()) + " points)");
          selected[std::size_t(index)] = 1;
        }
        break;
      }
    }
  }
  std::vector<std::size_t> indices;
  for(std::size_t i = 0; i < points.size(); ++i)
    if(selected[i]) indices.push_back(i);
  return indices;
}

} // namespace point_detail
