// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "ply_format.h"

#include "files.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>

namespace point_detail {
namespace fs = std::filesystem;
namespace {

Ply_scalar ply_scalar(const std::string& type)
{
  Ply_scalar s{type};
  if(type == "char" || type == "uchar" || type == "int8" || type == "uint8") s.bytes = 1;
  else if(type == "short" || type == "ushort" || type == "int16" || type == "uint16") s.bytes = 2;
  else if(type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32") s.bytes = 4;
  else if(type == "double" || type == "float64") s.bytes = 8;
  s.is_signed = type == "char" || type == "int8" || type == "short" || type == "int16" || type == "int" || type == "int32";
  s.is_real = type == "float" || type == "float32" || type == "double" || type == "float64";
  return s;
}

/// The fewest bytes of one item of a binary element (its lists empty).
std::uint64_t smallest_item_bytes(const Ply_element& e)
{
  std::uint64_t bytes = 0;
  for(const Ply_property& p : e.properties) bytes += p.is_list() ? p.count.bytes : p.value.bytes;
  return bytes;
}

/// Reads and checks a PLY header, and returns its vertex count and the fewest bytes of data that can hold all
/// its elements (binary: their records, with empty lists; ASCII: two characters per value). CGAL 5.5's reader
/// does not check the header: a property before any element made it read before its element array (found by
/// fuzz/fuzz_point_reader), so a malformed header is refused here first.
Announced ply_announced(std::istream& in, const std::string& name)
{
  Announced a;
  std::string line, format;
  std::size_t line_number = 0;
  auto fail = [&](const std::string& what) -> Announced {
    throw Cli_error("cannot read " + name + ": malformed ply header (line " + std::to_string(line_number) + ": " + what + ")");
  };
  auto whole = [&](const std::string& token) {
    std::uint64_t value = 0;
    if(!whole_number(token, value)) fail("'" + token + "' is not a count");
    return value;
  };
  std::vector<Ply_element>& elements = a.elements;
  std::map<std::string, std::string> vertex_types; // CGAL's reader needs x y z (and nx ny nz) of one float type
  std::vector<std::string> vertex_names;           // in the header's order
  auto same_float_type = [&](const char* a, const char* b, const char* c) {
    const std::string& t = vertex_types[a];
    return ply_scalar(t).is_real && vertex_types[b] == t && vertex_types[c] == t;
  };
  while(std::getline(in, line)) {
    ++line_number;
    if(!line.empty() && line.back() == '\r') line.pop_back();
    // CGAL's reader cuts names at a NUL byte ("x\0" is x), and the duplicate check below could not see that.
    std::vector<std::string> w;
    if(!header_words(line, w)) fail("a control character in the header");
    if(line_number == 1) {
      if(line != "ply") fail("a PLY file starts with the line 'ply'");
      continue;
    }
    if(w.empty()) continue;
    if(w[0] == "comment" || w[0] == "obj_info") continue;
    if(w[0] == "format") {
      if(w.size() != 3 || (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
        fail("the format is ascii, binary_little_endian or binary_big_endian, and a version");
      // CGAL's reader and this check would read a second format line differently (found by fuzz/fuzz_ply).
      if(!format.empty() || !elements.empty()) fail("one format line, before the elements");
      format = w[1];
    } else if(w[0] == "element") {
      if(w.size() != 3) fail("an element line is 'element NAME COUNT'");
      for(const Ply_element& e : elements)
        if(e.name == w[1]) fail("element '" + w[1] + "' appears twice"); // CGAL would size by one, read the other
      elements.push_back({w[1], whole(w[2]), {}});
    } else if(w[0] == "property") {
      if(elements.empty()) fail("a property before any element");
      Ply_element& e = elements.back();
      Ply_property property;
      if(w.size() == 5 && w[1] == "list") {
        property.name = w[4];
        property.count = ply_scalar(w[2]);
        property.value = ply_scalar(w[3]);
        if(property.count.bytes == 0 || property.value.bytes == 0) fail("unknown list types '" + w[2] + " " + w[3] + "'");
        if(property.count.is_real) fail("a list's count type '" + w[2] + "' is not an integer type");
      } else if(w.size() == 3) {
        property.name = w[2];
        property.value = ply_scalar(w[1]);
        if(property.value.bytes == 0) fail("unknown property type '" + w[1] + "'");
      } else
        fail("a property line is 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME'");
      // A list is recorded as "list": CGAL's reader casts nx (or x) to a float type and calls through a null pointer
      // when it is a list (found by fuzz/fuzz_ply); the checks at end_header refuse it by name.
      if(e.name == "vertex") {
        vertex_types.emplace(property.name, w.size() == 5 ? "list" : w[1]);
        vertex_names.push_back(property.name);
      }
      // CGAL's reader looks a property up by name and casts it to the type it asked for: a twin of another type
      // (a list "blue" and an int "blue") made it call through a null pointer (found by fuzz/fuzz_ply).
      for(const Ply_property& other : e.properties)
        if(other.name == property.name) fail("property '" + property.name + "' appears twice");
      e.properties.push_back(property);
    } else if(w[0] == "end_header") {
      if(format.empty()) fail("no format line");
      if(!same_float_type("x", "y", "z")) fail("the vertices need x, y and z properties, all float or all double");
      if((vertex_types.count("nx") || vertex_types.count("ny") || vertex_types.count("nz")) && !same_float_type("nx", "ny", "nz"))
        fail("the normals need nx, ny and nz properties, all float or all double");
      a.header_bytes = std::uint64_t(in.tellg());
      const std::vector<std::string> positions{"x", "y", "z"}, oriented{"x", "y", "z", "nx", "ny", "nz"};
      a.plain_vertices = format == "binary_little_endian" && elements.size() == 1 && elements[0].name == "vertex" &&
                         (vertex_names == positions || (vertex_names == oriented && same_float_type("x", "nx", "nz")));
      a.plain_normals = a.plain_vertices && vertex_names.size() == 6;
      a.plain_value_bytes = a.plain_vertices ? ply_scalar(vertex_types["x"]).bytes : 0;
      a.format = format;
      for(const Ply_element& e : elements) {
        // An element without properties takes no bytes, and CGAL's reader would loop over its count for nothing.
        if(e.properties.empty() && e.count > 0) fail("element '" + e.name + "' has no property");
        const std::uint64_t per_item = format == "ascii" ? 2 * e.properties.size() : smallest_item_bytes(e);
        if(per_item > 0 && e.count > (std::uint64_t(1) << 62) / per_item) fail("element '" + e.name + "' is too large");
        a.smallest_bytes += e.count * per_item;
        if(e.name == "vertex") a.vertices = e.count;
        if(e.name == "tristrips" && e.count > 0) a.triangle_strips = true;
      }
      return a;
    } else
      fail("unknown keyword '" + w[0] + "'");
  }
  throw Cli_error("cannot read " + name + ": malformed ply header (no end_header line)");
}

/// A list's count as its type reads it, from its n bytes (CGAL's reader casts it to std::size_t: a negative count
/// is a huge one).
std::int64_t ply_list_count(const unsigned char* bytes, std::size_t n, bool is_signed, bool big_endian)
{
  std::uint64_t u = 0;
  for(std::size_t i = 0; i < n; ++i) u |= std::uint64_t(bytes[big_endian ? n - 1 - i : i]) << (8 * i);
  if(is_signed && n < 8 && (u >> (8 * n - 1)) != 0) return std::int64_t(u) - (std::int64_t(1) << (8 * n));
  return std::int64_t(u);
}

/// Whether `token` reads as one whole value of `type` with the stream extraction CGAL's ASCII reader uses
/// (integers through short / unsigned short at least; no hexadecimal, "nan" or "inf"; nothing out of range).
bool ascii_ply_value(const std::string& token, const Ply_scalar& type)
{
  if(type.is_real) {
    if(token.find_first_not_of("0123456789+-.eE") != std::string::npos) return false;
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    const double largest = type.bytes == 4 ? double(std::numeric_limits<float>::max()) : std::numeric_limits<double>::max();
    return end != token.c_str() && *end == '\0' && std::abs(v) <= largest;
  }
  const std::size_t digits = token.empty() || token[0] == '+' || (type.is_signed && token[0] == '-') ? 1 : 0;
  if(token.size() <= digits || token.size() > 12 || token.find_first_not_of("0123456789", digits) != std::string::npos)
    return false;
  const long long v = std::strtoll(token.c_str(), nullptr, 10);
  const std::size_t bytes = std::max<std::size_t>(2, std::size_t(type.bytes)); // chars are read as shorts
  const long long highest = type.is_signed ? (1ll << (8 * bytes - 1)) - 1 : (1ll << (8 * bytes)) - 1;
  return v <= highest && v >= (type.is_signed ? -highest - 1 : 0);
}

/// Walks the elements of a PLY file up to its last list property and checks that every list's count fits in what
/// the file holds. CGAL's reader resizes a list to its count and reads that many values even past the end of the
/// file (a count of 2^31 in a small file kept it looping), and once an ASCII value fails to read, it takes the
/// next list counts from uninitialised memory (out of memory); both found by fuzz/fuzz_ply. So an ASCII file with
/// lists must read cleanly, value by value, up to its last list.
void check_ply_lists(std::istream& in, const Announced& a, std::uint64_t file_bytes, const std::string& name)
{
  auto fail = [&](const Ply_element& e, std::uint64_t item, const std::string& what) {
    throw Cli_error("cannot read " + name + ": element '" + e.name + "' item " + std::to_string(item) + ": " + what);
  };
  auto has_list = [](const Ply_element& e) {
    return std::any_of(e.properties.begin(), e.properties.end(), [](const Ply_property& p) { return p.is_list(); });
  };
  std::size_t last = 0; // one past the last element with a list
  for(std::size_t i = 0; i < a.elements.size(); ++i)
    if(has_list(a.elements[i])) last = i + 1;
  if(last == 0) return;
  in.clear();
  in.seekg(std::streamoff(a.header_bytes));
  const bool ascii = a.format == "ascii", big_endian = a.format == "binary_big_endian";
  std::uint64_t at = a.header_bytes; // binary: the position of the next byte
  Buffered_bytes bytes(in);
  std::string token;
  for(std::size_t i = 0; i < last; ++i) {
    const Ply_element& e = a.elements[i];
    if(!ascii && !has_list(e)) {
      at += e.count * smallest_item_bytes(e); // the header check made sure the file holds it
      bytes.skip(e.count * smallest_item_bytes(e));
      continue;
    }
    for(std::uint64_t item = 0; item < e.count; ++item)
      for(const Ply_property& p : e.properties) {
        if(ascii) {
          // Each value whole and in range; the file's end stops a list of any count at once.
          auto next = [&](const Ply_scalar& type) {
            if(!(in >> token)) fail(e, item, "the file ends here");
            if(!ascii_ply_value(token, type)) fail(e, item, "'" + token + "' is not a " + type.type);
          };
          next(p.is_list() ? p.count : p.value);
          if(!p.is_list()) continue;
          const long long count = std::strtoll(token.c_str(), nullptr, 10);
          if(count < 0) fail(e, item, "a list of " + token + " values");
          for(long long v = 0; v < count; ++v) next(p.value);
        } else if(!p.is_list()) {
          if(!bytes.skip(p.value.bytes)) fail(e, item, "the file ends here");
          at += p.value.bytes;
        } else {
          unsigned char count_bytes[8];
          if(!bytes.read(count_bytes, std::size_t(p.count.bytes))) fail(e, item, "the file ends here");
          const std::int64_t count = ply_list_count(count_bytes, std::size_t(p.count.bytes), p.count.is_signed, big_endian);
          at += p.count.bytes;
          const std::uint64_t left = file_bytes > at ? file_bytes - at : 0;
          if(count < 0 || std::uint64_t(count) > left / p.value.bytes)
            fail(e, item, "a list of " + std::to_string(count) + " values, more than the file holds");
          bytes.skip(std::uint64_t(count) * p.value.bytes);
          at += std::uint64_t(count) * p.value.bytes;
        }
      }
  }
}

} // namespace

Announced check_ply_header(const fs::path& path, std::uint64_t bytes_per_point)
{
  std::ifstream in(path, std::ios::binary);
  const Announced a = ply_announced(in, path.string());
  check_memory_for(path, a.vertices, bytes_per_point);
  std::error_code ec;
  const std::uint64_t size = fs::file_size(path, ec);
  if(!ec && size >= a.header_bytes && size - a.header_bytes < a.smallest_bytes)
    throw Cli_error("cannot read " + path.string() + ": truncated ply file (the header announces " +
                    std::to_string(a.vertices) + " points; its elements need at least " + std::to_string(a.smallest_bytes) +
                    " bytes, the file holds " + std::to_string(size - a.header_bytes) + " after its header)");
  if(!ec) check_ply_lists(in, a, size, path.string());
  return a;
}

namespace {

template <typename Value>
Point_cloud read_plain_values(const fs::path& path, const Announced& header)
{
  const std::size_t n = std::size_t(header.vertices), per_point = header.plain_normals ? 6 : 3;
  std::vector<Value> values(n * per_point);
  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(header.header_bytes));
  in.read(reinterpret_cast<char*>(values.data()), std::streamsize(values.size() * sizeof(Value)));
  if(std::size_t(in.gcount()) != values.size() * sizeof(Value))
    throw Cli_error("cannot read " + path.string() + ": truncated ply file (the header announces " + std::to_string(n) +
                    " points)");
  Point_cloud cloud;
  cloud.points.reserve(n);
  for(std::size_t i = 0; i < n; ++i) {
    const Value* v = &values[i * per_point];
    cloud.points.emplace_back(double(v[0]), double(v[1]), double(v[2]));
  }
  if(header.plain_normals) {
    cloud.normals.reserve(n);
    for(std::size_t i = 0; i < n; ++i) {
      const Value* v = &values[i * per_point + 3];
      cloud.normals.emplace_back(double(v[0]), double(v[1]), double(v[2]));
    }
    cloud.normal_source = "file";
  }
  return cloud;
}

} // namespace

Point_cloud read_plain_ply(const fs::path& path, const Announced& header)
{
  return header.plain_value_bytes == 8 ? read_plain_values<double>(path, header)
                                       : read_plain_values<float>(path, header);
}

namespace {
template <typename T>
void append(std::string& out, T value)
{
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T)); // the machine is little-endian (x86_64, aarch64)
  out.append(bytes, sizeof(T));
}
} // namespace

std::string ply_bytes(const Point_cloud& cloud, const std::string& scalar_prefix)
{
  const std::size_t n = cloud.points.size();
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment written by point-detail\nelement vertex " << n << "\n"
         << "property double x\nproperty double y\nproperty double z\n";
  if(!cloud.normals.empty()) header << "property double nx\nproperty double ny\nproperty double nz\n";
  for(const auto& s : cloud.scalars) {
    const bool prefixed = s.first.compare(0, scalar_prefix.size(), scalar_prefix) == 0;
    header << "property double " << (prefixed ? "" : scalar_prefix) << s.first << "\n";
  }
  if(!cloud.colors.empty()) header << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header << "end_header\n";
  std::string out = header.str();
  out.reserve(out.size() + n * (24 + (cloud.normals.empty() ? 0 : 24) + 8 * cloud.scalars.size() + 3));
  for(std::size_t i = 0; i < n; ++i) {
    append(out, cloud.points[i].x());
    append(out, cloud.points[i].y());
    append(out, cloud.points[i].z());
    if(!cloud.normals.empty()) {
      append(out, cloud.normals[i].x());
      append(out, cloud.normals[i].y());
      append(out, cloud.normals[i].z());
    }
    for(const auto& s : cloud.scalars) append(out, s.second[i]);
    if(!cloud.colors.empty()) out.append(reinterpret_cast<const char*>(cloud.colors[i].data()), 3);
  }
  return out;
}

} // namespace point_detail
