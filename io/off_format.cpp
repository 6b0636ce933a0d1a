// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "off_format.h"

#include "files.h"

#include <cerrno>
#include <cstdlib>
#include <sstream>
#include <string>

namespace point_detail {
namespace fs = std::filesystem;

Off_file read_off(const fs::path& path, std::uint64_t bytes_per_point)
{
  std::ifstream in = open_input(path);
  const std::string name = path.string();
  std::size_t line_number = 0;
  std::vector<std::string> tokens;
  // The next line with content, comments ('#' to the end of the line) removed, split at blanks.
  auto next_line = [&]() {
    std::string line;
    while(std::getline(in, line)) {
      ++line_number;
      line = line.substr(0, line.find('#'));
      std::istringstream words(line);
      tokens.clear();
      for(std::string word; words >> word;) tokens.push_back(word);
      if(!tokens.empty()) return true;
    }
    return false;
  };
  auto where = [&]() { return name + ":" + std::to_string(line_number) + ": "; };
  auto real = [&](const std::string& token) {
    char* end = nullptr;
    const double value = std::strtod(token.c_str(), &end);
    if(end != token.c_str() + token.size()) throw Cli_error(where() + "'" + token + "' is not a number");
    return value;
  };
  auto count = [&](const std::string& token, const char* what) {
    char* end = nullptr;
    errno = 0;
    const long long value = std::strtoll(token.c_str(), &end, 10);
    if(end != token.c_str() + token.size() || errno == ERANGE || value < 0)
      throw Cli_error(where() + "'" + token + "' is not a " + what);
    return std::uint64_t(value);
  };

  if(!next_line()) throw Cli_error(name + " contains no points");
  const std::string keyword = tokens[0];
  const std::size_t off_at = keyword.rfind("OFF");
  if(off_at == std::string::npos || off_at + 3 != keyword.size())
    throw Cli_error(where() + "not an OFF file (it starts with '" + keyword + "')");
  const std::string prefix = keyword.substr(0, off_at);
  if(prefix.find('4') != std::string::npos || prefix.find('n') != std::string::npos)
    throw Cli_error(where() + keyword + " (4D or n-dimensional OFF) is not supported");
  for(char c : prefix)
    if(c != 'S' && c != 'T' && c != 'C' && c != 'N') throw Cli_error(where() + "unknown OFF variant '" + keyword + "'");
  const bool with_normals = prefix.find('N') != std::string::npos;
  tokens.erase(tokens.begin());
  if(!tokens.empty() && tokens[0] == "BINARY")
    throw Cli_error(where() + "binary OFF is not supported; convert it to PLY");
  if(tokens.empty() && !next_line()) throw Cli_error(name + ": the header has no vertex count");
  const std::uint64_t vertex_count = count(tokens[0], "vertex count");
  const std::uint64_t face_count = tokens.size() > 1 ? count(tokens[1], "face count") : 0;
  check_memory_for(path, vertex_count, bytes_per_point);

  Off_file off;
  const std::size_t per_vertex = with_normals ? 6 : 3;
  for(std::uint64_t v = 0; v < vertex_count; ++v) {
    if(!next_line())
      throw Cli_error("cannot read " + name + ": truncated off file (the header announces " +
                      std::to_string(vertex_count) + " points, " + std::to_string(v) + " were read)");
    if(tokens.size() < per_vertex)
      throw Cli_error(where() + "a vertex needs " + std::to_string(per_vertex) + " numbers, this line has " +
                      std::to_string(tokens.size()));
    off.vertices.emplace_back(real(tokens[0]), real(tokens[1]), real(tokens[2]));
    if(with_normals) off.normals.emplace_back(real(tokens[3]), real(tokens[4]), real(tokens[5]));
  }
  // Faces give the vertex normals when the file has none; a file cut short in its faces loses only them.
  for(std::uint64_t f = 0; f < face_count && next_line(); ++f) {
    const std::uint64_t corners = count(tokens[0], "corner count");
    if(tokens.size() < corners + 1)
      throw Cli_error(where() + "a face of " + std::to_string(corners) + " corners has " +
                      std::to_string(tokens.size() - 1) + " indices");
    std::vector<std::size_t> face;
    for(std::uint64_t c = 1; c <= corners; ++c) {
      const std::uint64_t index = count(tokens[c], "vertex index");
      if(index >= vertex_count)
        throw Cli_error(where() + "vertex index " + tokens[c] + " is out of range (" + std::to_string(vertex_count) +
                        " vertices)");
      face.push_back(std::size_t(index));
    }
    off.faces.push_back(std::move(face));
  }
  return off;
}

} // namespace point_detail
