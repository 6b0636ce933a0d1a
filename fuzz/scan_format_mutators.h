// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// Structure-aware mutators for the scanners' formats (fuzz_pcd, fuzz_pts_ptx, fuzz_las): each changes what a
// writer gets wrong (a PCD header's fields, sizes, types, counts and data kind; a PTS or PTX file's counts, lines
// and values; a LAS header's version, format, record length, counts, scale and offset) and regenerates a body
// that matches the header half of the time, so that inputs get past the first check of the reader. Byte-level
// mutation (LLVMFuzzerMutate) keeps a share, as in structure_mutators.h.
#ifndef POINT_DETAIL_FUZZ_SCAN_FORMAT_MUTATORS_H
#define POINT_DETAIL_FUZZ_SCAN_FORMAT_MUTATORS_H

#include "las_test_file.h"
#include "structure_mutators.h"

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace fuzz {

// ---------------------------------------------------------------------------------------------------------------
// PCD: the header as lines of words up to DATA, the body as bytes.

struct Pcd_file
{
  std::vector<std::vector<std::string>> header; // DATA line included
  std::string body;
};

inline bool parse_pcd(const std::string& text, Pcd_file& pcd)
{
  const std::size_t data = text.find("DATA ");
  if(data == std::string::npos) return false;
  std::size_t body = text.find('\n', data);
  body = body == std::string::npos ? text.size() : body + 1;
  pcd.header = split_lines(text.substr(0, body));
  pcd.body = text.substr(body);
  return true;
}

inline std::string write_pcd(const Pcd_file& pcd) { return join_lines(pcd.header) + pcd.body; }

inline std::vector<std::string>* pcd_line(Pcd_file& pcd, const char* key)
{
  for(auto& line : pcd.header)
    if(!line.empty() && line[0] == key) return &line;
  return nullptr;
}

/// LZF data as long as `bytes` once decompressed: runs of literals (what a compressor writes for data it cannot
/// shorten) and now and then a back reference of any length (2 + 1 to 7, or longer with the extra length byte)
/// and any distance, now and then one that reaches before the start or past the end.
inline std::string lzf_literals(const std::string& bytes, Random& random)
{
  std::string out;
  for(std::size_t at = 0; at < bytes.size();) {
    const std::size_t run = std::min<std::size_t>(1 + below(random, 32), bytes.size() - at);
    out += char(run - 1);
    out += bytes.substr(at, run);
    at += run;
    if(at < bytes.size() && one_in(random, 4)) {
      const std::size_t length = 3 + below(random, one_in(random, 2) ? 6 : 262); // 3 to 8 in ctrl, to 264 beyond
      const std::size_t distance = 1 + below(random, std::min<std::size_t>(at + (one_in(random, 16) ? 2 : 0), 8192));
      const std::size_t short_length = std::min<std::size_t>(length - 2, 7);
      out += char((short_length << 5) | ((distance - 1) >> 8));
      if(short_length == 7) out += char(length - 9);
      out += char((distance - 1) & 0xff);
      at += length;
    }
  }
  return out;
}

/// A body that matches the header: at most 64 points, each field's values in turn, in the DATA kind's layout.
inline std::string pcd_body_for(Pcd_file& pcd, Random& random)
{
  const auto* fields = pcd_line(pcd, "FIELDS");
  const auto* sizes = pcd_line(pcd, "SIZE");
  const auto* types = pcd_line(pcd, "TYPE");
  const auto* counts = pcd_line(pcd, "COUNT");
  const auto* points = pcd_line(pcd, "POINTS");
  const auto* data = pcd_line(pcd, "DATA");
  if(!fields || !sizes || !types || !data || data->size() < 2) return std::string();
  const std::size_t n =
    points && points->size() >= 2 ? std::size_t(std::min(64ll, std::max(0ll, std::atoll((*points)[1].c_str())))) : 4;
  const std::string kind = (*data)[1];
  std::vector<std::string> columns(fields->size()); // field-major bytes, for binary_compressed
  std::string text, rows;
  for(std::size_t p = 0; p < n; ++p) {
    for(std::size_t f = 1; f < fields->size() && f < sizes->size() && f < types->size(); ++f) {
      const std::size_t count =
        counts && f < counts->size() ? std::size_t(std::min(8ll, std::max(1ll, std::atoll((*counts)[f].c_str())))) : 1;
      const std::string& t = (*types)[f];
      const std::size_t size = std::size_t(std::atoi((*sizes)[f].c_str()));
      const std::string ply_type = t == "F"    ? (size == 8 ? "double" : "float")
                                   : size == 1 ? (t == "U" ? "uchar" : "char")
                                   : size == 2 ? (t == "U" ? "ushort" : "short")
                                               : (t == "U" ? "uint" : "int");
      for(std::size_t c = 0; c < count; ++c) {
        if(kind == "ascii")
          append_value(text, "ascii", ply_type, random);
        else {
          std::string value;
          append_value(value, "binary_little_endian", ply_type, random);
          value.resize(std::min<std::size_t>(size, 8), '\0');
          rows += value;
          columns[f] += value;
        }
      }
    }
    text += '\n';
  }
  if(kind == "ascii") return text;
  if(kind != "binary_compressed") return rows;
  std::string all;
  for(const std::string& c : columns) all += c;
  const std::string packed = lzf_literals(all, random);
  std::string body(8, '\0');
  const std::uint32_t sizes_of[2] = {std::uint32_t(packed.size()), std::uint32_t(all.size())};
  std::memcpy(&body[0], sizes_of, 8);
  return body + packed;
}

inline Pcd_file fresh_pcd(Random& random)
{
  static const char* const kinds[] = {"ascii", "binary", "binary_compressed"};
  Pcd_file pcd;
  const std::string n = std::to_string(1 + below(random, 12));
  const std::string size = one_in(random, 3) ? "8" : "4";
  pcd.header = {{"VERSION", "0.7"},
                {"FIELDS", "x", "y", "z"},
                {"SIZE", size, size, size},
                {"TYPE", "F", "F", "F"},
                {"COUNT", "1", "1", "1"}};
  auto add = [&](const char* name, const char* s, const char* t, const char* c) {
    pcd.header[1].push_back(name);
    pcd.header[2].push_back(s);
    pcd.header[3].push_back(t);
    pcd.header[4].push_back(c);
  };
  if(one_in(random, 2))
    for(const char* c : {"normal_x", "normal_y", "normal_z"}) add(c, "4", "F", "1");
  if(one_in(random, 2)) add("rgb", "4", one_in(random, 2) ? "F" : "U", "1");
  if(one_in(random, 3)) add("intensity", "2", "U", "1");
  if(one_in(random, 4)) add("fpfh", "4", "F", "3");
  pcd.header.push_back({"WIDTH", n});
  pcd.header.push_back({"HEIGHT", "1"});
  pcd.header.push_back({"POINTS", n});
  pcd.header.push_back({"DATA", pick(random, kinds)});
  pcd.body = pcd_body_for(pcd, random);
  return pcd;
}

/// One structural change of a PCD file (or, now and then, of its body's bytes).
inline std::string mutate_pcd(const std::string& input, std::size_t max_size, Random& random)
{
  Pcd_file pcd;
  if(!parse_pcd(input, pcd) || pcd.header.size() < 2) return write_pcd(fresh_pcd(random));
  auto& h = pcd.header;
  static const char* const keys[] = {"FIELDS", "SIZE", "TYPE", "COUNT"};
  bool regenerate_body = one_in(random, 2);
  switch(random() % 10) {
  case 0: { // a count: POINTS, WIDTH or HEIGHT
    static const char* const counts[] = {"POINTS", "WIDTH", "HEIGHT"};
    if(auto* line = pcd_line(pcd, pick(random, counts)); line && line->size() >= 2)
      (*line)[1] = interesting_count(random, std::size_t(std::atoll((*line)[1].c_str())));
    break;
  }
  case 1: { // a field's size, type or count
    static const char* const values[] = {"1", "2", "4", "8", "3", "0", "I", "U", "F", "D", "4096", "4097"};
    if(auto* line = pcd_line(pcd, keys[1 + below(random, 3)]); line && line->size() >= 2)
      (*line)[1 + below(random, line->size() - 1)] = pick(random, values);
    break;
  }
  case 2: { // a field's name
    static const char* const names[] = {"x",   "y",    "z", "normal_x",  "normal_z",
                                        "rgb", "rgba", "_", "intensity", "curvature"};
    if(auto* line = pcd_line(pcd, "FIELDS"); line && line->size() >= 2)
      (*line)[1 + below(random, line->size() - 1)] = pick(random, names);
    break;
  }
  case 3: // a field added to one of the four lines only, or to all
    if(one_in(random, 2)) {
      if(auto* line = pcd_line(pcd, pick(random, keys))) line->push_back("4");
    } else
      for(const char* key : keys)
        if(auto* line = pcd_line(pcd, key))
          line->push_back(std::string(key) == "FIELDS" ? "label" : std::string(key) == "TYPE" ? "U" : "1");
    break;
  case 4: { // the data kind
    static const char* const kinds[] = {"ascii", "binary", "binary_compressed", "binary_compressed", "lzf", ""};
    if(auto* line = pcd_line(pcd, "DATA")) *line = {"DATA", pick(random, kinds)};
    regenerate_body = true;
    break;
  }
  case 5: // a header line removed, duplicated or moved
    if(h.size() > 2) {
      const std::size_t at = below(random, h.size() - 1);
      const std::vector<std::string> line = h[at];
      const unsigned what = random() % 3;
      if(what != 1) h.erase(h.begin() + std::ptrdiff_t(at));
      if(what != 0) h.insert(h.begin() + std::ptrdiff_t(below(random, h.size())), line);
    }
    break;
  case 6: // the compressed sizes, or the body's bytes
  case 7:
    if(pcd.body.size() >= 8 && one_in(random, 2)) {
      std::uint32_t v = std::uint32_t(std::atoll(interesting_count(random, pcd.body.size()).c_str()));
      std::memcpy(&pcd.body[4 * below(random, 2)], &v, 4);
    } else
      mutate_bytes(pcd.body, max_size);
    regenerate_body = false;
    break;
  case 8: // the body cut short or extended
    if(one_in(random, 2))
      pcd.body.resize(below(random, pcd.body.size() + 1));
    else
      pcd.body += pcd.body.substr(0, below(random, pcd.body.size() + 1));
    regenerate_body = false;
    break;
  default: { // the whole file's bytes
    std::string all = write_pcd(pcd);
    mutate_bytes(all, max_size);
    return all;
  }
  }
  if(regenerate_body) pcd.body = pcd_body_for(pcd, random);
  return write_pcd(pcd);
}

// ---------------------------------------------------------------------------------------------------------------
// PTS and PTX: lines of numbers.

inline std::string point_line(Random& random, std::size_t values)
{
  std::string line;
  for(std::size_t v = 0; v < values; ++v)
    line +=
      (v ? " " : "") + (v >= values - 3 && values >= 6 ? std::to_string(below(random, 256)) : interesting_real(random));
  return line;
}

inline std::string fresh_pts(Random& random)
{
  static const std::size_t layouts[] = {3, 4, 6, 7};
  const std::size_t layout = pick(random, layouts), n = 1 + below(random, 12);
  std::string text = one_in(random, 4) ? "" : std::to_string(n) + "\n";
  for(std::size_t i = 0; i < n; ++i) text += point_line(random, layout) + "\n";
  return text;
}

inline std::string fresh_ptx(Random& random)
{
  const std::size_t columns = 1 + below(random, 4), rows = 1 + below(random, 4), layout = one_in(random, 2) ? 4 : 7;
  std::string text = std::to_string(columns) + "\n" + std::to_string(rows) + "\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  text += one_in(random, 4) ? "0 -1 0 0\n1 0 0 0\n0 0 1 0\n" : "1 0 0 0\n0 1 0 0\n0 0 1 0\n";
  text += std::to_string(below(random, 10)) + " 2 3 1\n";
  for(std::size_t i = 0; i < rows * columns; ++i)
    text +=
      (one_in(random, 4) ? "0 0 0 0.5" + std::string(layout == 7 ? " 0 0 0" : "") : point_line(random, layout)) + "\n";
  return text;
}

/// One change of a PTS or PTX file (`ptx` picks the fresh file's kind): a count, a line, a value, the bytes.
inline std::string mutate_pts_ptx(const std::string& input, std::size_t max_size, Random& random, bool ptx)
{
  std::vector<std::vector<std::string>> lines = split_lines(input);
  if(lines.empty() || one_in(random, 32)) return ptx ? fresh_ptx(random) : fresh_pts(random);
  const std::size_t at = below(random, lines.size());
  auto& line = lines[at];
  switch(random() % 7) {
  case 0: // a count line's value
    for(auto& l : lines)
      if(l.size() == 1 && one_in(random, 2)) {
        l[0] = interesting_count(random, std::size_t(std::atoll(l[0].c_str())));
        break;
      }
    break;
  case 1: // a value
    if(!line.empty())
      line[below(random, line.size())] = one_in(random, 2) ? interesting_real(random) : interesting_count(random, 3);
    break;
  case 2: // a value added or removed
    if(!line.empty() && one_in(random, 2))
      line.pop_back();
    else
      line.push_back(interesting_real(random));
    break;
  case 3: // a line removed, duplicated or moved
  {
    const std::vector<std::string> copy = line;
    const unsigned what = random() % 3;
    if(what != 1) lines.erase(lines.begin() + std::ptrdiff_t(at));
    if(what != 0) lines.insert(lines.begin() + std::ptrdiff_t(below(random, lines.size() + 1)), copy);
    break;
  }
  case 4: // another scan or block appended
    for(const auto& l : split_lines(ptx ? fresh_ptx(random) : fresh_pts(random))) lines.push_back(l);
    break;
  case 5: { // cut short
    lines.resize(below(random, lines.size() + 1));
    break;
  }
  default: {
    std::string all = join_lines(lines);
    mutate_bytes(all, max_size);
    return all;
  }
  }
  return join_lines(lines);
}

// ---------------------------------------------------------------------------------------------------------------
// LAS: a binary header at fixed offsets, records after it.

inline std::string fresh_las(Random& random)
{
  const unsigned minor = one_in(random, 2) ? 4 : unsigned(below(random, 4));
  const unsigned format = minor == 4 ? unsigned(below(random, 11)) : unsigned(below(random, 6));
  const auto record_bytes =
    std::uint16_t(point_detail::las_format_bytes(format) + (one_in(random, 4) ? below(random, 8) : 0));
  const std::size_t n = 1 + below(random, 12);
  std::string las = las_test_file::header(minor, format, n, record_bytes, 0.01);
  for(std::size_t i = 0; i < n * record_bytes; ++i) las += char(random());
  return las;
}

/// One change of a LAS file: a header field (version, sizes, offsets, format, record length, counts, scale,
/// offset) set to an edge value, the records' bytes, or the file cut short.
inline std::string mutate_las(const std::string& input, std::size_t max_size, Random& random)
{
  std::string las = input;
  if(las.size() < 227 || las.compare(0, 4, "LASF") != 0 || one_in(random, 32)) return fresh_las(random);
  auto put = [&las](std::size_t at, auto value) {
    if(at + sizeof value <= las.size()) std::memcpy(&las[at], &value, sizeof value);
  };
  static const std::uint64_t edges[] = {
    0,    1, 2, 3, 5, 6, 10, 11, 127, 128, 131, 255, 227, 235, 375, 65535, 0x7fffffffu, 0xffffffffu, 0x100000000ull,
    ~0ull};
  const std::uint64_t edge = pick(random, edges);
  switch(random() % 9) {
  case 0:
    las[25] = char(edge);
    break; // version minor
  case 1:
    put(94, std::uint16_t(edge));
    break; // header size
  case 2:
    put(96, std::uint32_t(edge));
    break; // offset to the points
  case 3:
    las[104] = char(one_in(random, 2) ? edge : (las[104] | 0x80));
    break; // point format, LAZ bit
  case 4:
    put(105, std::uint16_t(edge));
    break; // record length
  case 5:
    if(one_in(random, 2))
      put(107, std::uint32_t(edge));
    else
      put(247, std::uint64_t(edge));
    break;  // counts
  case 6: { // a scale or an offset
    static const double reals[] = {0.0,
                                   -0.0,
                                   1e-300,
                                   1e300,
                                   -1.0,
                                   std::numeric_limits<double>::quiet_NaN(),
                                   std::numeric_limits<double>::infinity()};
    put(131 + 8 * below(random, 6), pick(random, reals));
    break;
  }
  case 7: // cut short or extended
    if(one_in(random, 2))
      las.resize(below(random, las.size() + 1));
    else
      las += las.substr(227, below(random, las.size() - 227 + 1));
    break;
  default:
    mutate_bytes(las, max_size);
  }
  return las;
}

} // namespace fuzz

#endif
