// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "pcd_format.h"

#include "files.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_set>

namespace point_detail {
namespace fs = std::filesystem;

bool lzf_decompress(const unsigned char* in, std::size_t in_size, std::vector<unsigned char>& out, std::size_t expected)
{
  out.assign(expected, 0);
  std::size_t ip = 0, op = 0;
  while(ip < in_size) {
    const unsigned ctrl = in[ip++];
    if(ctrl < 32) { // a run of ctrl + 1 literal bytes
      const std::size_t n = ctrl + 1;
      if(n > in_size - ip || n > expected - op) return false;
      std::memcpy(out.data() + op, in + ip, n);
      ip += n;
      op += n;
      continue;
    }
    // A back reference: length (ctrl >> 5) + 2, longer with an extra byte, to a distance of 13 bits + 1.
    std::size_t length = ctrl >> 5;
    if(length == 7) {
      if(ip >= in_size) return false;
      length += in[ip++];
    }
    if(ip >= in_size) return false;
    const std::size_t distance = ((std::size_t(ctrl & 0x1f) << 8) | in[ip++]) + 1;
    length += 2;
    if(distance > op || length > expected - op) return false;
    for(std::size_t i = 0; i < length; ++i, ++op) out[op] = out[op - distance]; // may overlap: byte by byte
  }
  return op == expected;
}

namespace {

/// Fields a header may name (each value of every point is read into memory as a double).
constexpr std::size_t max_fields = 4096;

/// One value of `field` from its little-endian bytes.
double decode(const unsigned char* bytes, const Pcd_field& field)
{
  switch(field.type) {
  case 'F':
    if(field.size == 4) {
      float v;
      std::memcpy(&v, bytes, 4);
      return double(v);
    }
    {
      double v;
      std::memcpy(&v, bytes, 8);
      return v;
    }
  default: { // 'I' and 'U': little-endian, sign-extended for 'I'
    std::uint64_t v = 0;
    for(unsigned i = 0; i < field.size; ++i) v |= std::uint64_t(bytes[i]) << (8 * i);
    if(field.type == 'U') return double(v);
    if(field.size < 8 && (v >> (8 * field.size - 1)) != 0) v |= ~std::uint64_t(0) << (8 * field.size);
    return double(std::int64_t(v));
  }
  }
}

/// The 32 bits of a packed colour field (rgb or rgba) from its bytes.
std::uint32_t packed_bits(const unsigned char* bytes)
{
  std::uint32_t v;
  std::memcpy(&v, bytes, 4);
  return v;
}

bool is_color_field(const Pcd_field& f) { return (f.name == "rgb" || f.name == "rgba") && f.size == 4 && f.count == 1; }

/// Where each field goes: a coordinate, a normal component, the colour, a scalar, or nowhere (padding).
struct Field_roles
{
  int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, color = -1;
  std::vector<std::pair<std::size_t, unsigned>> scalar_values; ///< (field, value within it) of each scalar
  std::vector<std::string> scalar_names;
};

Field_roles roles_of(const std::vector<Pcd_field>& fields)
{
  Field_roles r;
  for(std::size_t i = 0; i < fields.size(); ++i) {
    const Pcd_field& f = fields[i];
    int* role = f.name == "x"          ? &r.x
                : f.name == "y"        ? &r.y
                : f.name == "z"        ? &r.z
                : f.name == "normal_x" ? &r.nx
                : f.name == "normal_y" ? &r.ny
                : f.name == "normal_z" ? &r.nz
                                       : nullptr;
    if(role != nullptr && f.count == 1) {
      *role = int(i);
      continue;
    }
    if(is_color_field(f) && r.color < 0) {
      r.color = int(i);
      continue;
    }
    if(f.name == "_") continue; // PCL's padding
    for(unsigned c = 0; c < f.count; ++c) {
      r.scalar_values.emplace_back(i, c);
      r.scalar_names.push_back(f.count == 1 ? f.name : f.name + "_" + std::to_string(c));
    }
  }
  return r;
}

} // namespace

Pcd_header check_pcd_header(const fs::path& path, std::uint64_t bytes_per_point)
{
  std::ifstream in = open_input(path, std::ios::binary);
  const std::string name = path.string();
  Pcd_header h;
  std::size_t line_number = 0;
  auto fail = [&](const std::string& what) {
    throw Cli_error("cannot read " + name + ": malformed pcd header (line " + std::to_string(line_number) + ": " +
                    what + ")");
  };
  // After the header's lines, a problem is no line's.
  auto bad = [&](const std::string& what) {
    throw Cli_error("cannot read " + name + ": malformed pcd header (" + what + ")");
  };
  auto whole = [&](const std::string& token) {
    std::uint64_t value = 0;
    if(!whole_number(token, value)) fail("'" + token + "' is not a count");
    return value;
  };
  std::vector<std::string> names, sizes, types, counts;
  std::uint64_t width = 0, height = 0;
  bool has_points = false, has_width = false, has_height = false;
  std::string line;
  while(std::getline(in, line)) {
    ++line_number;
    if(line_number > 1000) fail("no DATA line in the first 1000 lines");
    std::vector<std::string> w;
    if(!header_words(line, w)) fail("a control character in the header");
    if(w.empty() || w[0][0] == '#') continue;
    const std::string& key = w[0];
    std::vector<std::string> values(w.begin() + 1, w.end());
    if(key == "VERSION") continue;
    if(key == "FIELDS" || key == "COLUMNS")
      names = values;
    else if(key == "SIZE")
      sizes = values;
    else if(key == "TYPE")
      types = values;
    else if(key == "COUNT")
      counts = values;
    else if(key == "WIDTH" && values.size() == 1) {
      width = whole(values[0]);
      has_width = true;
    } else if(key == "HEIGHT" && values.size() == 1) {
      height = whole(values[0]);
      has_height = true;
    } else if(key == "VIEWPOINT")
      continue;
    else if(key == "POINTS" && values.size() == 1) {
      h.points = whole(values[0]);
      has_points = true;
    } else if(key == "DATA") {
      if(values.size() != 1 || (values[0] != "ascii" && values[0] != "binary" && values[0] != "binary_compressed"))
        fail("DATA is ascii, binary or binary_compressed");
      h.data = values[0];
      h.header_bytes = std::uint64_t(in.tellg());
      break;
    } else
      fail("unknown or malformed line '" + key + "'");
  }
  if(h.data.empty()) bad("no DATA line");
  if(names.empty()) bad("no FIELDS line");
  if(sizes.size() != names.size() || types.size() != names.size() || (!counts.empty() && counts.size() != names.size()))
    bad("FIELDS, SIZE, TYPE and COUNT name " + std::to_string(names.size()) + ", " + std::to_string(sizes.size()) +
        ", " + std::to_string(types.size()) + " and " + std::to_string(counts.size()) + " fields");
  if(names.size() > max_fields)
    bad(std::to_string(names.size()) + " fields (at most " + std::to_string(max_fields) + ")");
  std::unordered_set<std::string> seen;
  for(std::size_t i = 0; i < names.size(); ++i) {
    Pcd_field f;
    f.name = names[i];
    std::uint64_t size = 0, count = 1;
    if(!whole_number(sizes[i], size) || (size != 1 && size != 2 && size != 4 && size != 8))
      bad("field '" + f.name + "' has size " + sizes[i] + " (1, 2, 4 or 8)");
    if(types[i].size() != 1 || std::string("IUF").find(types[i][0]) == std::string::npos)
      bad("field '" + f.name + "' has type '" + types[i] + "' (I, U or F)");
    f.type = types[i][0];
    if(f.type == 'F' && size != 4 && size != 8)
      bad("floating-point field '" + f.name + "' has size " + sizes[i] + " (4 or 8)");
    f.size = unsigned(size);
    if(!counts.empty() && (!whole_number(counts[i], count) || count == 0 || count > 4096))
      bad("field '" + f.name + "' has count " + counts[i] + " (1 to 4096)");
    f.count = unsigned(count);
    if(f.name != "_" && !seen.insert(f.name).second) bad("field '" + f.name + "' appears twice");
    f.offset = h.record_bytes;
    h.fields.push_back(f);
    h.record_bytes += size * count;
  }
  const Field_roles roles = roles_of(h.fields);
  if(roles.x < 0 || roles.y < 0 || roles.z < 0) bad("the fields need x, y and z");
  if((roles.nx >= 0 || roles.ny >= 0 || roles.nz >= 0) && (roles.nx < 0 || roles.ny < 0 || roles.nz < 0))
    bad("the normals need normal_x, normal_y and normal_z");
  if(has_width && has_height && width != 0 && height > ~std::uint64_t(0) / width) bad("WIDTH x HEIGHT is too large");
  if(!has_points) {
    if(!has_width) bad("no POINTS line and no WIDTH");
    h.points = width * (has_height ? height : 1);
  }
  if(has_width && has_height && h.points != width * height)
    bad("POINTS " + std::to_string(h.points) + " is not WIDTH x HEIGHT (" + std::to_string(width) + " x " +
        std::to_string(height) + ")");
  if(h.points == 0) throw Cli_error(name + " contains no points");

  // What the file holds, before the memory and before anything is allocated.
  const std::uint64_t size = file_bytes(path), left = size - std::min(size, h.header_bytes);
  std::uint64_t values_per_point = 0;
  for(const Pcd_field& f : h.fields) values_per_point += f.count;
  auto truncated = [&](const std::string& what) {
    throw Cli_error("cannot read " + name + ": truncated pcd file (the header announces " + std::to_string(h.points) +
                    " points, " + what + "; the file holds " + std::to_string(left) + " bytes after its header)");
  };
  if(h.data == "binary" && h.points > left / h.record_bytes)
    truncated("records of " + std::to_string(h.record_bytes) + " bytes");
  // ASCII: at least one character and a separator per value (the last line's newline may be missing).
  if(h.data == "ascii" && h.points > (left + 1) / (2 * values_per_point))
    truncated(std::to_string(values_per_point) + " values each");
  if(h.data == "binary_compressed") {
    unsigned char sizes_bytes[8];
    in.clear();
    in.seekg(std::streamoff(h.header_bytes));
    if(left < 8 || !in.read(reinterpret_cast<char*>(sizes_bytes), 8)) truncated("its compressed sizes missing");
    std::memcpy(&h.compressed_bytes, sizes_bytes, 4);
    std::memcpy(&h.uncompressed_bytes, sizes_bytes + 4, 4);
    if(h.compressed_bytes > left - 8) truncated(std::to_string(h.compressed_bytes) + " bytes of compressed data");
    // LZF writes at most 264 bytes from 3 (its longest back reference), so 88 times its data at most.
    if(h.points > std::uint64_t(0xffffffffu) / h.record_bytes || h.uncompressed_bytes != h.points * h.record_bytes ||
       h.uncompressed_bytes > 88 * std::uint64_t(h.compressed_bytes))
      throw Cli_error("cannot read " + name + ": corrupted pcd file (" + std::to_string(h.compressed_bytes) +
                      " compressed bytes said to hold " + std::to_string(h.uncompressed_bytes) + "; the header's " +
                      std::to_string(h.points) + " points of " + std::to_string(h.record_bytes) + " bytes need " +
                      std::to_string(h.points * h.record_bytes) + ")");
  }
  if(bytes_per_point > 0)
    check_memory_for(path, h.points, bytes_per_point + 16 * values_per_point); // every value twice
  return h;
}

Point_cloud read_pcd(const fs::path& path, std::uint64_t bytes_per_point)
{
  const Pcd_header h = check_pcd_header(path, bytes_per_point);
  const std::string name = path.string();
  const Field_roles roles = roles_of(h.fields);
  const std::size_t n = std::size_t(h.points);
  // Every value of every point as a double, point by point (a packed colour keeps its 32 bits).
  std::vector<std::uint64_t> first_value(h.fields.size());
  for(std::size_t i = 1; i < h.fields.size(); ++i) first_value[i] = first_value[i - 1] + h.fields[i - 1].count;
  const std::size_t per_point = std::size_t(first_value.back() + h.fields.back().count);
  std::vector<double> values(n * per_point);
  auto value = [&](std::size_t point, std::size_t field, unsigned c = 0) -> double& {
    return values[point * per_point + first_value[field] + c];
  };
  auto store = [&](std::size_t point, std::size_t field, unsigned c, const unsigned char* bytes) {
    const Pcd_field& f = h.fields[field];
    value(point, field, c) = int(field) == roles.color ? double(packed_bits(bytes)) : decode(bytes, f);
  };

  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(h.header_bytes));
  if(h.data == "ascii") {
    std::string line;
    std::size_t line_number = 0, point = 0;
    while(point < n && std::getline(in, line)) {
      ++line_number;
      std::istringstream words(line);
      std::vector<std::string> tokens;
      for(std::string word; words >> word;) tokens.push_back(word);
      if(tokens.empty()) continue;
      if(tokens.size() != per_point)
        throw Cli_error("cannot read " + name + ": data line " + std::to_string(line_number) + " has " +
                        std::to_string(tokens.size()) + " values, the fields need " + std::to_string(per_point));
      for(std::size_t field = 0, t = 0; field < h.fields.size(); ++field)
        for(unsigned c = 0; c < h.fields[field].count; ++c, ++t) {
          const std::string& s = tokens[t];
          char* end = nullptr;
          const double v = std::strtod(s.c_str(), &end);
          if(end != s.c_str() + s.size())
            throw Cli_error("cannot read " + name + ": data line " + std::to_string(line_number) + ": '" + s +
                            "' is not a number");
          if(int(field) == roles.color) {
            // PCL writes a packed colour as its 32 bits in decimal, Open3D as the float those bits make.
            std::uint32_t bits = 0;
            if(s.find_first_not_of("0123456789") == std::string::npos && v <= 4294967295.0)
              bits = std::uint32_t(v);
            else {
              const float f = float(v);
              std::memcpy(&bits, &f, 4);
            }
            value(point, field, c) = double(bits);
          } else
            value(point, field, c) = v;
        }
      ++point;
    }
    if(point < n)
      throw Cli_error("cannot read " + name + ": truncated pcd file (the header announces " + std::to_string(n) +
                      " points, " + std::to_string(point) + " were read)");
  } else if(h.data == "binary") {
    Buffered_bytes bytes(in);
    std::vector<unsigned char> record(std::size_t(h.record_bytes));
    for(std::size_t point = 0; point < n; ++point) {
      if(!bytes.read(record.data(), record.size())) throw Cli_error("cannot read " + name + ": truncated pcd file");
      for(std::size_t field = 0; field < h.fields.size(); ++field)
        for(unsigned c = 0; c < h.fields[field].count; ++c)
          store(point, field, c, record.data() + h.fields[field].offset + std::size_t(c) * h.fields[field].size);
    }
  } else {
    in.seekg(std::streamoff(h.header_bytes + 8));
    std::vector<unsigned char> packed(h.compressed_bytes), data;
    in.read(reinterpret_cast<char*>(packed.data()), std::streamsize(packed.size()));
    if(!lzf_decompress(packed.data(), packed.size(), data, h.uncompressed_bytes))
      throw Cli_error("cannot read " + name + ": corrupted pcd file (its compressed data do not decompress to " +
                      std::to_string(h.uncompressed_bytes) + " bytes)");
    // Field after field, each field's values of every point together.
    std::size_t at = 0;
    for(std::size_t field = 0; field < h.fields.size(); ++field)
      for(std::size_t point = 0; point < n; ++point)
        for(unsigned c = 0; c < h.fields[field].count; ++c, at += h.fields[field].size)
          store(point, field, c, data.data() + at);
  }

  Point_cloud cloud;
  std::vector<std::size_t> kept;
  kept.reserve(n);
  for(std::size_t p = 0; p < n; ++p)
    if(!(std::isnan(value(p, roles.x)) && std::isnan(value(p, roles.y)) && std::isnan(value(p, roles.z))))
      kept.push_back(p);
  cloud.points_without_position = n - kept.size();
  if(kept.empty()) throw Cli_error(name + " contains no points (all " + std::to_string(n) + " are NaN)");
  for(std::size_t p : kept) cloud.points.emplace_back(value(p, roles.x), value(p, roles.y), value(p, roles.z));
  if(roles.nx >= 0) {
    for(std::size_t p : kept) cloud.normals.emplace_back(value(p, roles.nx), value(p, roles.ny), value(p, roles.nz));
    cloud.normal_source = "file";
  }
  if(roles.color >= 0)
    for(std::size_t p : kept) {
      const std::uint32_t bits = std::uint32_t(value(p, roles.color));
      cloud.colors.push_back({(unsigned char)(bits >> 16), (unsigned char)(bits >> 8), (unsigned char)bits});
    }
  for(std::size_t s = 0; s < roles.scalar_values.size(); ++s) {
    std::vector<double> column;
    column.reserve(kept.size());
    for(std::size_t p : kept) column.push_back(value(p, roles.scalar_values[s].first, roles.scalar_values[s].second));
    cloud.scalars.emplace_back(roles.scalar_names[s], std::move(column));
  }
  return cloud;
}

} // namespace point_detail
