// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// Structure-aware mutators for libFuzzer (LLVMFuzzerCustomMutator): they change a PLY header, an OFF file or an
// edit JSON as a writer would get it wrong (counts, types, property lists, keywords, values of the wrong kind)
// while the rest of the file stays valid, so that the fuzzer's inputs get past the first check of the reader.
// A part of each mutation is still libFuzzer's byte-level one (LLVMFuzzerMutate), on the body or the whole file,
// which keeps the comparison operands libFuzzer traces within reach.
// With FUZZ_MUTATOR=bytes in the environment every target mutates bytes only, as without this header: the
// comparison of the two (doc/hardening.md) runs the same binary both ways.
#ifndef POINT_DETAIL_FUZZ_STRUCTURE_MUTATORS_H
#define POINT_DETAIL_FUZZ_STRUCTURE_MUTATORS_H

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

namespace fuzz {

using Random = std::mt19937;

inline bool byte_level_only()
{
  static const bool bytes = [] {
    const char* v = std::getenv("FUZZ_MUTATOR");
    return v != nullptr && std::strcmp(v, "bytes") == 0;
  }();
  return bytes;
}

inline std::size_t below(Random& random, std::size_t n) { return n == 0 ? 0 : std::size_t(random() % n); }
inline bool one_in(Random& random, unsigned n) { return random() % n == 0; }
template <typename T, std::size_t N> const T& pick(Random& random, const T (&choices)[N]) { return choices[below(random, N)]; }

/// libFuzzer's byte-level mutation of a string, within `max_size` bytes.
inline void mutate_bytes(std::string& s, std::size_t max_size)
{
  const std::size_t size = s.size();
  s.resize(std::max(max_size, size));
  s.resize(LLVMFuzzerMutate(reinterpret_cast<std::uint8_t*>(&s[0]), size, s.size()));
}

/// Counts and numbers a careless writer or an attacker would put in a count or a value field.
inline std::string interesting_count(Random& random, std::size_t plausible)
{
  static const char* const edges[] = {"0", "1", "-1", "2147483647", "2147483648", "4294967295", "4294967296",
                                      "9223372036854775807", "18446744073709551615", "18446744073709551616",
                                      "1e3", "0x10", "+3", "3.5", "", "nan"};
  switch(random() % 4) {
  case 0: return pick(random, edges);
  case 1: return std::to_string(plausible + 1);
  case 2: return std::to_string(plausible > 0 ? plausible - 1 : 0);
  default: return std::to_string(below(random, 64));
  }
}

inline std::string interesting_real(Random& random)
{
  static const char* const edges[] = {"0", "-0", "1", "-1", "nan", "inf", "-inf", "1e308", "1e309", "-1e308",
                                      "4.9e-324", "1e-320", "3.4028235e38", "0.5", "1e", "--1", "0x1p3"};
  if(one_in(random, 2)) return pick(random, edges);
  return std::to_string(double(random() % 2001) / 1000.0 - 1.0);
}

// ---------------------------------------------------------------------------------------------------------------
// PLY: the header as lines of words, the body as bytes.

struct Ply_file
{
  std::vector<std::vector<std::string>> header; // "ply" and "end_header" included
  std::string body;
};

inline std::vector<std::string> words(const std::string& line)
{
  std::istringstream in(line);
  std::vector<std::string> out;
  for(std::string w; in >> w;) out.push_back(w);
  return out;
}

/// Text as lines of words, and back (one space between words).
inline std::vector<std::vector<std::string>> split_lines(const std::string& text)
{
  std::istringstream in(text);
  std::vector<std::vector<std::string>> lines;
  for(std::string line; std::getline(in, line);) lines.push_back(words(line));
  return lines;
}

inline std::string join_lines(const std::vector<std::vector<std::string>>& lines)
{
  std::string out;
  for(const auto& line : lines) {
    for(std::size_t i = 0; i < line.size(); ++i) out += (i ? " " : "") + line[i];
    out += '\n';
  }
  return out;
}

inline bool parse_ply(const std::string& text, Ply_file& ply)
{
  const std::size_t end = text.find("end_header");
  if(text.compare(0, 3, "ply") != 0 || end == std::string::npos) return false;
  std::size_t body = text.find('\n', end);
  body = body == std::string::npos ? text.size() : body + 1;
  ply.header = split_lines(text.substr(0, body));
  ply.body = text.substr(body);
  return true;
}

inline std::string write_ply(const Ply_file& ply) { return join_lines(ply.header) + ply.body; }

inline const char* ply_type(Random& random)
{
  static const char* const types[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double",
                                      "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32",
                                      "float64", "long", "string", "list"};
  return pick(random, types);
}

inline const char* ply_property_name(Random& random)
{
  static const char* const names[] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha",
                                      "vertex_indices", "vertex_index", "quality", "intensity", "s", "t", "label"};
  return pick(random, names);
}

inline std::size_t scalar_bytes(const std::string& type)
{
  if(type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if(type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if(type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" || type == "float32")
    return 4;
  if(type == "double" || type == "float64") return 8;
  return 0;
}

/// One value of `type` in the body's format: plausible values, and now and then a NaN, an infinity or an extreme.
inline void append_value(std::string& body, const std::string& format, const std::string& type, Random& random,
                         long long integer_hint = -1)
{
  const bool real = type == "float" || type == "float32" || type == "double" || type == "float64";
  const bool edge = one_in(random, 8);
  double value = integer_hint >= 0 ? double(integer_hint) : real ? double(random() % 2001) / 1000.0 - 1.0 : double(random() % 8);
  if(edge) {
    static const double edges[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                                   -1.0, 1e308, 255.0, 65535.0, 4294967295.0, -2147483648.0};
    value = pick(random, edges);
  }
  if(format == "ascii") {
    std::ostringstream s;
    s << (real ? value : std::abs(value) < 9e18 ? double((long long)value) : -1.0);
    body += s.str() + " ";
    return;
  }
  const std::size_t n = scalar_bytes(type);
  if(n == 0) return;
  unsigned char bytes[8] = {};
  if(real && n == 4) {
    const float f = std::isfinite(value) && std::abs(value) > std::numeric_limits<float>::max()
                      ? std::numeric_limits<float>::infinity() // a float cast out of range is undefined
                      : float(value);
    std::memcpy(bytes, &f, 4);
  } else if(real)
    std::memcpy(bytes, &value, 8);
  else { // little endian
    const long long v = std::abs(value) < 9e18 ? (long long)value : -1;
    std::memcpy(bytes, &v, n);
  }
  if(format == "binary_big_endian") std::reverse(bytes, bytes + n);
  body.append(reinterpret_cast<const char*>(bytes), n);
}

/// A body that matches the header (each element's count, at most 64 rows of it, each property in turn).
inline std::string ply_body_for(const Ply_file& ply, Random& random)
{
  auto rows_of = [](const std::vector<std::string>& element_line) {
    return element_line.size() >= 3 ? std::size_t(std::min(64ll, std::max(0ll, std::atoll(element_line[2].c_str())))) : 0;
  };
  std::string format = "ascii", body;
  std::size_t rows = 0, vertex_count = 1;
  for(const auto& line : ply.header) {
    if(line.size() >= 2 && line[0] == "format") format = line[1];
    if(line.size() >= 2 && line[0] == "element" && line[1] == "vertex") vertex_count = std::max<std::size_t>(rows_of(line), 1);
  }
  // Second pass: rows of each element, properties in header order.
  std::vector<std::vector<std::string>> properties;
  auto flush = [&](std::size_t n) {
    for(std::size_t r = 0; r < n; ++r) {
      for(const auto& p : properties) {
        if(p.size() >= 5 && p[1] == "list") {
          const long long count = one_in(random, 8) ? (long long)(random() % 300) : 3;
          append_value(body, format, p[2], random, count);
          for(long long i = 0; i < std::min(count, 300ll); ++i)
            append_value(body, format, p[3], random, (long long)below(random, vertex_count + 1));
        } else if(p.size() >= 3)
          append_value(body, format, p[1], random);
      }
      if(format == "ascii") body += "\n";
    }
  };
  for(const auto& line : ply.header) {
    if(line.size() >= 1 && (line[0] == "element" || line[0] == "end_header")) {
      flush(rows);
      properties.clear();
      rows = rows_of(line);
    } else if(line.size() >= 1 && line[0] == "property")
      properties.push_back(line);
  }
  return body;
}

/// A small, valid PLY: points, maybe normals and colours, maybe faces.
inline Ply_file fresh_ply(Random& random)
{
  static const char* const formats[] = {"ascii", "binary_little_endian", "binary_big_endian"};
  Ply_file ply;
  const std::string real = one_in(random, 2) ? "float" : "double";
  ply.header = {{"ply"}, {"format", pick(random, formats), "1.0"}, {"element", "vertex", std::to_string(1 + below(random, 12))}};
  for(const char* c : {"x", "y", "z"}) ply.header.push_back({"property", real, c});
  if(one_in(random, 2))
    for(const char* c : {"nx", "ny", "nz"}) ply.header.push_back({"property", real, c});
  if(one_in(random, 3))
    for(const char* c : {"red", "green", "blue"}) ply.header.push_back({"property", "uchar", c});
  if(one_in(random, 3)) {
    ply.header.push_back({"element", "face", std::to_string(below(random, 6))});
    ply.header.push_back({"property", "list", "uchar", "int", "vertex_indices"});
  }
  ply.header.push_back({"end_header"});
  ply.body = ply_body_for(ply, random);
  return ply;
}

/// One structural change of a PLY file (or, now and then, of its body's bytes).
inline std::string mutate_ply(const std::string& input, std::size_t max_size, Random& random)
{
  Ply_file ply;
  if(!parse_ply(input, ply) || ply.header.size() < 2) return write_ply(fresh_ply(random));
  auto& h = ply.header;
  auto lines_starting = [&](const char* word) {
    std::vector<std::size_t> at;
    for(std::size_t i = 0; i < h.size(); ++i)
      if(!h[i].empty() && h[i][0] == word) at.push_back(i);
    return at;
  };
  const std::vector<std::size_t> elements = lines_starting("element"), properties = lines_starting("property");
  const std::size_t inner = 1 + below(random, h.size() - 1); // a line after "ply"
  bool regenerate_body = one_in(random, 2);
  switch(random() % 12) {
  case 0: // an element's count
    if(!elements.empty()) {
      auto& e = h[elements[below(random, elements.size())]];
      if(e.size() >= 3) e[2] = interesting_count(random, std::size_t(std::atoll(e[2].c_str())));
    }
    break;
  case 1: // a property's type
    if(!properties.empty()) {
      auto& p = h[properties[below(random, properties.size())]];
      if(p.size() >= 5 && p[1] == "list") p[2 + below(random, 2)] = ply_type(random);
      else if(p.size() >= 3) p[1] = ply_type(random);
    }
    break;
  case 2: // a property's name
    if(!properties.empty()) h[properties[below(random, properties.size())]].back() = ply_property_name(random);
    break;
  case 3: // a scalar property becomes a list, or a list a scalar
    if(!properties.empty()) {
      auto& p = h[properties[below(random, properties.size())]];
      if(p.size() >= 5) p = {"property", p[3], p[4]};
      else if(p.size() >= 3) p = {"property", "list", ply_type(random), p[1], p[2]};
    }
    break;
  case 4: // a new property line
    h.insert(h.begin() + std::ptrdiff_t(inner), {"property", ply_type(random), ply_property_name(random)});
    break;
  case 5: { // a new element
    static const char* const names[] = {"vertex", "face", "edge", "material", "range_grid"};
    h.insert(h.begin() + std::ptrdiff_t(inner), {"element", pick(random, names), interesting_count(random, 3)});
    break;
  }
  case 6: // a line removed, duplicated or moved
    if(h.size() > 2) {
      const std::vector<std::string> line = h[inner];
      const unsigned what = random() % 3;
      if(what != 1) h.erase(h.begin() + std::ptrdiff_t(inner));
      if(what != 0) h.insert(h.begin() + std::ptrdiff_t(1 + below(random, h.size() - 1)), line);
    }
    break;
  case 7: { // the format line
    static const char* const formats[] = {"ascii", "binary_little_endian", "binary_big_endian", "binary", "ASCII"};
    static const char* const versions[] = {"1.0", "1.1", "2.0", "", "1.0 extra"};
    const std::vector<std::size_t> at = lines_starting("format");
    std::vector<std::string> line = {"format", pick(random, formats), pick(random, versions)};
    if(at.empty()) h.insert(h.begin() + 1, line);
    else h[at[0]] = line;
    break;
  }
  case 8: // comments and obj_info lines, which a reader must skip
    h.insert(h.begin() + std::ptrdiff_t(inner), {one_in(random, 2) ? "comment" : "obj_info", "element", "vertex", "9"});
    break;
  case 9: // the body's bytes, header untouched
    mutate_bytes(ply.body, max_size);
    regenerate_body = false;
    break;
  case 10: // the body cut short or extended
    if(one_in(random, 2)) ply.body.resize(below(random, ply.body.size() + 1));
    else ply.body += ply.body.substr(0, below(random, ply.body.size() + 1));
    regenerate_body = false;
    break;
  default: { // the whole file's bytes
    std::string all = write_ply(ply);
    mutate_bytes(all, max_size);
    return all;
  }
  }
  if(regenerate_body) ply.body = ply_body_for(ply, random);
  return write_ply(ply);
}

// ---------------------------------------------------------------------------------------------------------------
// OFF: lines of whitespace-separated tokens.

inline std::string fresh_off(Random& random)
{
  static const char* const keywords[] = {"OFF", "COFF", "NOFF", "CNOFF", "STOFF"};
  const std::string keyword = pick(random, keywords);
  const std::size_t vertices = 1 + below(random, 10), faces = below(random, 4);
  std::string out = keyword + "\n" + std::to_string(vertices) + " " + std::to_string(faces) + " 0\n";
  const bool normals = keyword.find('N') != std::string::npos, colours = keyword.find('C') != std::string::npos,
             texture = keyword.find("ST") != std::string::npos;
  for(std::size_t v = 0; v < vertices; ++v) {
    for(int c = 0; c < 3 + (normals ? 3 : 0) + (colours ? 4 : 0) + (texture ? 2 : 0); ++c)
      out += std::to_string(double(random() % 2001) / 1000.0 - 1.0) + " ";
    out += "\n";
  }
  for(std::size_t f = 0; f < faces; ++f)
    out += "3 " + std::to_string(below(random, vertices)) + " " + std::to_string(below(random, vertices)) + " " +
           std::to_string(below(random, vertices)) + "\n";
  return out;
}

inline std::string mutate_off(const std::string& input, std::size_t max_size, Random& random)
{
  if(input.find("OFF") == std::string::npos || one_in(random, 32)) return fresh_off(random);
  std::vector<std::vector<std::string>> lines = split_lines(input);
  if(lines.empty()) return fresh_off(random);
  // The counts are the first line of numbers (the keyword's own line may hold them too).
  const std::size_t counts = lines.size() > 1 ? 1 : 0;
  const std::size_t at = below(random, lines.size());
  auto& line = lines[at];
  switch(random() % 9) {
  case 0: { // a count
    auto& c = lines[counts];
    if(!c.empty()) {
      const std::size_t i = below(random, c.size());
      c[i] = interesting_count(random, std::size_t(std::atoll(c[i].c_str())));
    }
    break;
  }
  case 1: // a coordinate or an index
    if(!line.empty()) line[below(random, line.size())] = one_in(random, 2) ? interesting_real(random) : interesting_count(random, 3);
    break;
  case 2: // a token more or fewer
    if(!line.empty() && one_in(random, 2)) line.erase(line.begin() + std::ptrdiff_t(below(random, line.size())));
    else line.insert(line.begin() + std::ptrdiff_t(below(random, line.size() + 1)), interesting_real(random));
    break;
  case 3: { // the keyword
    static const char* const keywords[] = {"OFF", "COFF", "NOFF", "CNOFF", "STOFF", "STCNOFF", "4OFF", "nOFF",
                                           "OFF BINARY", "off", "XOFF", "OFF 3 1 0"};
    lines[0] = words(pick(random, keywords));
    break;
  }
  case 4: // comments and blank lines where a reader must skip them
    lines.insert(lines.begin() + std::ptrdiff_t(below(random, lines.size() + 1)),
                 one_in(random, 2) ? std::vector<std::string>{} : std::vector<std::string>{"#", "3", "1", "0"});
    break;
  case 5: // a line removed or duplicated
    if(one_in(random, 2) && lines.size() > 1) lines.erase(lines.begin() + std::ptrdiff_t(at));
    else lines.insert(lines.begin() + std::ptrdiff_t(at), line);
    break;
  case 6: { // a face with a wrong vertex count
    std::vector<std::string> face = {interesting_count(random, 3)};
    for(std::size_t i = 0, n = 1 + below(random, 5); i < n; ++i) face.push_back(interesting_count(random, 3));
    lines.push_back(face);
    break;
  }
  case 7: // the counts and the first vertex on the keyword's line
    if(lines.size() > 2) {
      lines[0].insert(lines[0].end(), lines[1].begin(), lines[1].end());
      lines.erase(lines.begin() + 1);
    }
    break;
  default: {
    std::string all = input;
    mutate_bytes(all, max_size);
    return all;
  }
  }
  return join_lines(lines);
}

// ---------------------------------------------------------------------------------------------------------------
// The edit JSON: a parsed tree, changed at one node.

inline nlohmann::json interesting_json(Random& random)
{
  static const char* const names[] = {"linear", "quadric", "cubic", "none", "propagate", "arap", "uniform",
                                      "cotangent", "edge_lengths", "surface_area", "geodesic", "euclidean",
                                      "nearest", "fitted", "own", "affine", "frames", "inf", "",
                                      "sphere:0,0,1,0.3", "sphere:0,0,0,-1", "box:-1,-1,0,1,1,1", "box:1,1,1,0,0,0",
                                      "indices:", "indices:/dev/zero", "sphere:nan,0,0,1", "box:0,0,0,1e309,1,1"};
  static const char* const keys[] = {"roi", "handles", "filter", "k", "strength_distance", "handle_weight",
                                     "rotations", "rigid_iterations", "rigid_rotation_smoothing",
                                     "rigid_rotation_smoothing_scale", "rigid_edge_weights", "diffusion",
                                     "simplification", "select", "translation", "rotation", "quaternion", "matrix",
                                     "pivot", "axis", "degrees", "order", "lambda", "mu", "samples", "origin", "turn",
                                     "max_cluster_size", "mode_threshold", "target_count", "detail_iterations",
                                     "diffusion_samples", "diffusion_origin", "diffusion_turn"};
  static const double numbers[] = {0.0, -0.0, 1.0, -1.0, 0.5, 3.0, 200.0, 1e308, -1e308, 4.9e-324, 4294967296.0,
                                   9007199254740993.0, 1e19, 2.5};
  switch(random() % 7) {
  case 0: return pick(random, numbers);
  case 1: return (long long)(random() % 400) - 100;
  case 2: return pick(random, names);
  case 3: return nlohmann::json::array({double(random() % 3) - 1, 0.0, 1.0});
  case 4: return nlohmann::json::object({{pick(random, keys), pick(random, numbers)}});
  case 5: return one_in(random, 2) ? nlohmann::json(nullptr) : nlohmann::json(one_in(random, 2));
  default: return nlohmann::json::array({pick(random, names)});
  }
}

inline void collect_nodes(nlohmann::json& node, std::vector<nlohmann::json*>& out)
{
  out.push_back(&node);
  if(node.is_structured())
    for(auto& child : node) collect_nodes(child, out);
}

/// A well-formed edit of the 200-point sphere the JSON targets read.
inline nlohmann::json fresh_edit()
{
  return nlohmann::json::parse(R"({"roi": ["box:-1,-1,0,1,1,1"], "handles": [{"select": ["sphere:0,0,1,0.3"],
    "rotation": {"axis": [1, 0, 0], "degrees": 30}, "pivot": [0, 0, 0.5], "translation": [0.1, 0, 0]}],
    "filter": {"order": "cubic", "lambda": 0.8, "mu": 1.6}, "k": 10, "rotations": "arap",
    "diffusion_samples": 4, "simplification": {"max_cluster_size": 10}})");
}

inline std::string mutate_edit_json(const std::string& input, std::size_t max_size, Random& random)
{
  nlohmann::json edit = nlohmann::json::parse(input, nullptr, false);
  if(edit.is_discarded()) edit = fresh_edit();
  if(one_in(random, 8)) { // now and then the text itself: the parser's errors
    std::string text = edit.dump();
    mutate_bytes(text, max_size);
    return text;
  }
  std::vector<nlohmann::json*> nodes;
  collect_nodes(edit, nodes);
  nlohmann::json& node = *nodes[below(random, nodes.size())];
  switch(random() % 5) {
  case 0: node = interesting_json(random); break; // a value, of any kind
  case 1: // a key added to an object, or an element to an array
    if(node.is_object()) node[interesting_json(random).dump()] = interesting_json(random);
    if(node.is_object() && one_in(random, 2)) {
      nlohmann::json keyed = interesting_json(random);
      if(keyed.is_object()) node.update(keyed);
    }
    if(node.is_array()) node.push_back(one_in(random, 2) && !node.empty() ? node[0] : interesting_json(random));
    break;
  case 2: // a key or an element removed
    if(node.is_structured() && !node.empty()) {
      if(node.is_object()) node.erase(std::next(node.begin(), std::ptrdiff_t(below(random, node.size()))).key());
      else node.erase(below(random, node.size()));
    }
    break;
  case 3: // a subtree copied over another
    node = *nodes[below(random, nodes.size())];
    break;
  default: // a number nudged
    if(node.is_number()) node = node.get<double>() * (one_in(random, 2) ? -1.0 : 1e10) + (one_in(random, 2) ? 0.5 : 0.0);
    else node = interesting_json(random);
  }
  return edit.dump();
}

/// LLVMFuzzerCustomMutator's body: `mutate` applied to the input, or libFuzzer's byte-level mutation if the result
/// does not fit or FUZZ_MUTATOR=bytes.
template <typename Mutate>
std::size_t custom_mutate(std::uint8_t* data, std::size_t size, std::size_t max_size, unsigned seed, Mutate mutate)
{
  if(byte_level_only()) return LLVMFuzzerMutate(data, size, max_size);
  Random random(seed);
  const std::string out = mutate(std::string(reinterpret_cast<const char*>(data), size), max_size, random);
  if(out.size() > max_size || out.empty()) return LLVMFuzzerMutate(data, size, max_size);
  std::memcpy(data, out.data(), out.size());
  return out.size();
}

} // namespace fuzz

#endif
