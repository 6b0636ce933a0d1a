// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "point_io.h"

#include "cli_support.h"

#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

namespace point_detail {
namespace fs = std::filesystem;

const std::vector<double>* Point_cloud::scalar(const std::string& name) const
{
  for(const auto& s : scalars)
    if(s.first == name) return &s.second;
  return nullptr;
}

void Point_cloud::set_scalar(const std::string& name, std::vector<double> values)
{
  for(auto& s : scalars)
    if(s.first == name) { s.second = std::move(values); return; }
  scalars.emplace_back(name, std::move(values));
}

namespace {

std::string lower_extension(const fs::path& path)
{
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext.empty() ? ext : ext.substr(1);
}

/// Area-weighted vertex normals of the faces of a mesh file, or nothing if it has no usable faces.
std::vector<Vector> mesh_vertex_normals(const fs::path& path, std::size_t expected_vertices)
{
  std::vector<Point> vertices;
  std::vector<std::vector<std::size_t>> faces;
  if(!CGAL::IO::read_polygon_soup(path.string(), vertices, faces, CGAL::parameters::verbose(false)) || faces.empty() ||
     vertices.size() != expected_vertices)
    return {};
  std::vector<Vector> normals(vertices.size(), CGAL::NULL_VECTOR);
  for(const auto& face : faces) {
    if(face.size() < 3) continue;
    for(std::size_t v : face)
      if(v >= vertices.size()) return {};
    // Sum of fan cross products = twice the (vector) area of the polygon.
    Vector area = CGAL::NULL_VECTOR;
    for(std::size_t i = 1; i + 1 < face.size(); ++i)
      area = area + CGAL::cross_product(vertices[face[i]] - vertices[face[0]], vertices[face[i + 1]] - vertices[face[0]]);
    for(std::size_t v : face) normals[v] = normals[v] + area;
  }
  for(Vector& n : normals) {
    const double len = std::sqrt(n.squared_length());
    if(!(len > 0) || !std::isfinite(len)) return {}; // a vertex on no face: the caller estimates instead
    n = n / len;
  }
  return normals;
}

template <typename T>
bool copy_scalar(CGAL::Point_set_3<Point, Vector>& ps, const std::string& name, Point_cloud& cloud)
{
  auto found = ps.template property_map<T>(name);
  if(!found.second) return false;
  std::vector<double> values;
  values.reserve(ps.size());
  for(auto it = ps.begin(); it != ps.end(); ++it) values.push_back(double(found.first[*it]));
  cloud.scalars.emplace_back(name, std::move(values));
  return true;
}

/// Available memory in bytes (MemAvailable of /proc/meminfo), or 0 when it cannot be read.
std::uint64_t available_memory()
{
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  std::uint64_t kib = 0;
  std::string unit;
  while(meminfo >> key >> kib >> unit)
    if(key == "MemAvailable:") return kib * 1024;
  return 0;
}

std::string gibibytes(double bytes)
{
  std::ostringstream os;
  os.precision(bytes < 1024.0 * 1024 * 1024 * 10 ? 2 : 0);
  os << std::fixed << bytes / (1024.0 * 1024 * 1024) << " GiB";
  return os.str();
}

/// What a PLY or OFF header announces, read without trusting it.
struct Announced
{
  std::uint64_t vertices = 0;
  std::uint64_t smallest_bytes = 0; ///< the fewest bytes of data after the header that can hold them
  bool known = false;
};

std::uint64_t ply_scalar_size(const std::string& type)
{
  if(type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if(type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if(type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32") return 4;
  if(type == "double" || type == "float64") return 8;
  return 0;
}

/// The vertex count of a PLY header and the bytes its vertices need at least (the size of a binary vertex
/// record, or two characters per ASCII value: a digit and a separator).
Announced ply_announced(std::istream& in, std::uint64_t& header_bytes)
{
  Announced a;
  std::string line, format;
  bool in_vertex = false, has_list = false;
  std::uint64_t values = 0, record = 0;
  while(std::getline(in, line)) {
    if(!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string word;
    words >> word;
    if(word == "format") words >> format;
    else if(word == "element") {
      std::string name;
      words >> name;
      in_vertex = name == "vertex";
      if(in_vertex && !(words >> a.vertices)) return Announced();
    } else if(word == "property" && in_vertex) {
      std::string type;
      words >> type;
      if(type == "list") has_list = true;
      ++values;
      record += ply_scalar_size(type);
    } else if(word == "end_header") {
      header_bytes = std::uint64_t(in.tellg());
      a.known = !has_list && values > 0;
      a.smallest_bytes = a.vertices * (format == "ascii" ? 2 * values : record);
      return a;
    }
  }
  return Announced();
}

/// The vertex count of an OFF header ([C][N]OFF, comments, then "vertices faces edges").
Announced off_announced(std::istream& in, std::uint64_t& header_bytes)
{
  Announced a;
  std::string word;
  in >> word;
  if(word.find("OFF") == std::string::npos) return a;
  std::string token;
  while(in >> token) {
    if(token[0] == '#') { std::getline(in, token); continue; }
    try {
      std::size_t used = 0;
      const long long count = std::stoll(token, &used);
      if(used != token.size() || count < 0) return Announced();
      a.vertices = std::uint64_t(count);
    } catch(const std::exception&) { return Announced(); }
    break;
  }
  header_bytes = std::uint64_t(in.tellg());
  a.known = word.find("4") == std::string::npos && word.find("n") == std::string::npos; // not a higher-dimension OFF
  a.smallest_bytes = a.vertices * 6; // "x y z\n", one digit each
  return a;
}

/// Fails early, before CGAL's reader allocates, for a header that announces more points than the file holds
/// or than this machine's memory can process (about 1 KiB per point for the program's largest run, an edit).
std::uint64_t check_announced_points(const fs::path& path, const std::string& ext)
{
  std::ifstream in(path, std::ios::binary);
  std::uint64_t header_bytes = 0;
  const Announced a = ext == "ply" ? ply_announced(in, header_bytes) : ext == "off" ? off_announced(in, header_bytes)
                                                                                    : Announced();
  if(!a.known) return 0;
  std::error_code ec;
  const std::uint64_t size = fs::file_size(path, ec);
  const std::uint64_t bytes_per_point = 1024;
  const std::uint64_t available = available_memory();
  if(available > 0 && a.vertices > available / bytes_per_point)
    throw Cli_error("cannot read " + path.string() + ": it announces " + std::to_string(a.vertices) +
                    " points, which need about " + gibibytes(double(a.vertices) * bytes_per_point) +
                    " of memory; this machine has " + gibibytes(double(available)) + " available");
  if(!ec && size >= header_bytes && size - header_bytes < a.smallest_bytes)
    throw Cli_error("cannot read " + path.string() + ": truncated " + ext + " file (the header announces " +
                    std::to_string(a.vertices) + " points, which need at least " + std::to_string(a.smallest_bytes) +
                    " bytes; the file holds " + std::to_string(size - header_bytes) + " after its header)");
  return a.vertices;
}

} // namespace

Point_cloud read_point_cloud(const fs::path& path)
{
  std::error_code ec;
  if(!fs::exists(path, ec)) throw Cli_error("cannot read " + path.string() + ": no such file");
  if(!fs::is_regular_file(path, ec)) throw Cli_error("cannot read " + path.string() + ": not a regular file");
  if(!std::ifstream(path, std::ios::binary)) throw Cli_error("cannot read " + path.string() + ": permission denied");
  const std::string ext = lower_extension(path);
  if(ext != "ply" && ext != "off" && ext != "xyz" && ext != "pwn")
    throw Cli_error("cannot read " + path.string() + ": unsupported extension '." + ext + "' (use .ply, .off, .xyz or .pwn)");

  const std::uint64_t announced = check_announced_points(path, ext);
  CGAL::Point_set_3<Point, Vector> ps;
  bool ok = false;
  std::string header;
  std::ifstream(path) >> header;
  // CGAL's point-set reader refuses the OFF variants with colours (COFF, like CGAL's own cactus.off) and says
  // so on stderr; its polygon-soup reader takes them.
  const bool colored_off = ext == "off" && header.find("OFF") != std::string::npos && header != "OFF" && header != "NOFF";
  try {
    if(!colored_off) ok = CGAL::IO::read_point_set(path.string(), ps);
  } catch(const std::exception& e) {
    throw Cli_error("cannot read " + path.string() + ": malformed " + ext + " file (" + e.what() + ")");
  }
  if(!ok && ext == "off") {
    std::vector<Point> vertices;
    std::vector<std::vector<std::size_t>> faces;
    if(CGAL::IO::read_polygon_soup(path.string(), vertices, faces, CGAL::parameters::verbose(false)) && !vertices.empty()) {
      ps.clear();
      for(const Point& v : vertices) ps.insert(v);
      ok = true;
    }
  }
  if(!ok) throw Cli_error("cannot read " + path.string() + ": malformed or truncated " + ext + " file");
  if(ps.number_of_points() == 0) throw Cli_error(path.string() + " contains no points");
  if(announced > 0 && ps.number_of_points() != announced)
    throw Cli_error("cannot read " + path.string() + ": the header announces " + std::to_string(announced) +
                    " points but " + std::to_string(ps.number_of_points()) + " were read (truncated or malformed file)");

  Point_cloud cloud;
  cloud.points.assign(ps.points().begin(), ps.points().end());
  if(ps.has_normal_map()) {
    cloud.normals.assign(ps.normals().begin(), ps.normals().end());
    cloud.normal_source = "file";
  } else if(ext == "off" || ext == "ply") {
    cloud.normals = mesh_vertex_normals(path, cloud.points.size());
    if(!cloud.normals.empty()) cloud.normal_source = "mesh";
  }

  auto red = ps.property_map<unsigned char>("red"), green = ps.property_map<unsigned char>("green"),
       blue = ps.property_map<unsigned char>("blue");
  if(red.second && green.second && blue.second)
    for(auto it = ps.begin(); it != ps.end(); ++it) cloud.colors.push_back({red.first[*it], green.first[*it], blue.first[*it]});
  for(const std::string& name : ps.properties()) {
    if(name == "index" || name == "point" || name == "normal" || name == "red" || name == "green" || name == "blue")
      continue;
    copy_scalar<double>(ps, name, cloud) || copy_scalar<float>(ps, name, cloud) || copy_scalar<int>(ps, name, cloud) ||
      copy_scalar<unsigned int>(ps, name, cloud) || copy_scalar<unsigned char>(ps, name, cloud) ||
      copy_scalar<signed char>(ps, name, cloud) || copy_scalar<short>(ps, name, cloud) ||
      copy_scalar<unsigned short>(ps, name, cloud);
  }
  return cloud;
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

std::string ply_bytes(const Point_cloud& cloud)
{
  const std::size_t n = cloud.points.size();
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment written by point-detail\nelement vertex " << n << "\n"
         << "property double x\nproperty double y\nproperty double z\n";
  if(!cloud.normals.empty()) header << "property double nx\nproperty double ny\nproperty double nz\n";
  for(const auto& s : cloud.scalars) header << "property double " << s.first << "\n";
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
