// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "point_io.h"

#include "files.h"
#include "las_format.h"
#include "off_format.h"
#include "pcd_format.h"
#include "ply_format.h"
#include "pts_format.h"

#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

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

std::size_t count_zero(const std::vector<Vector>& normals)
{
  return std::size_t(std::count(normals.begin(), normals.end(), CGAL::NULL_VECTOR));
}

/// Area-weighted vertex normals of a polygon soup (zero at a vertex on no usable face), or nothing if no face
/// is usable.
std::vector<Vector> face_normals(const std::vector<Point>& vertices, const std::vector<std::vector<std::size_t>>& faces)
{
  if(faces.empty()) return {};
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
  std::size_t without = 0;
  for(Vector& n : normals) {
    const double len = std::sqrt(n.squared_length());
    if(!(len > 0) || !std::isfinite(len)) {
      n = CGAL::NULL_VECTOR; // a vertex on no face (or on degenerate ones only): the caller estimates it
      ++without;
    } else
      n = n / len;
  }
  if(without == normals.size()) return {};
  return normals;
}

/// Area-weighted vertex normals of the faces of a PLY mesh, or nothing if it has no usable faces.
std::vector<Vector> ply_face_normals(const fs::path& path, std::size_t expected_vertices)
{
  std::vector<Point> vertices;
  std::vector<std::vector<std::size_t>> faces;
  if(!CGAL::IO::read_polygon_soup(path.string(), vertices, faces, CGAL::parameters::verbose(false)) ||
     vertices.size() != expected_vertices)
    return {};
  return face_normals(vertices, faces);
}

// Property `name` as the scalar `key`.
template <typename T>
bool copy_scalar(CGAL::Point_set_3<Point, Vector>& ps, const std::string& name, const std::string& key,
                 Point_cloud& cloud)
{
  auto found = ps.template property_map<T>(name);
  if(!found.second) return false;
  std::vector<double> values;
  values.reserve(ps.size());
  for(auto it = ps.begin(); it != ps.end(); ++it) values.push_back(double(found.first[*it]));
  cloud.scalars.emplace_back(key, std::move(values));
  return true;
}

} // namespace

Point_cloud read_point_cloud(const fs::path& path, std::uint64_t bytes_per_point)
{
  open_input(path, std::ios::binary);
  const std::string ext = lower_extension(path);
  if(ext == "pcd") return read_pcd(path, bytes_per_point);
  if(ext == "pts") return read_pts(path, bytes_per_point);
  if(ext == "ptx") return read_ptx(path, bytes_per_point);
  if(ext == "las" || ext == "laz") return read_las(path, bytes_per_point);
  if(ext != "ply" && ext != "off" && ext != "xyz" && ext != "pwn")
    throw Cli_error("cannot read " + path.string() + ": unsupported extension '." + ext + "' (use " +
                    supported_extensions + ")");

  if(ext == "off") {
    Off_file off = read_off(path, bytes_per_point);
    if(off.vertices.empty()) throw Cli_error(path.string() + " contains no points");
    Point_cloud cloud;
    cloud.points = std::move(off.vertices);
    if(!off.normals.empty()) {
      cloud.normals = std::move(off.normals);
      cloud.normal_source = "file";
    } else {
      cloud.normals = face_normals(cloud.points, off.faces);
      if(!cloud.normals.empty()) cloud.normal_source = "mesh";
      cloud.vertices_without_normal = count_zero(cloud.normals);
    }
    return cloud;
  }

  const Announced header = ext == "ply" ? check_ply_header(path, bytes_per_point) : Announced();
  const std::uint64_t announced = header.vertices;
  if(header.plain_vertices && announced > 0) return read_plain_ply(path, header);
  CGAL::Point_set_3<Point, Vector> ps;
  bool ok = false;
  try {
    ok = CGAL::IO::read_point_set(path.string(), ps);
  } catch(const std::exception& e) {
    throw Cli_error("cannot read " + path.string() + ": malformed " + ext + " file (" + e.what() + ")");
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
  } else if(ext == "ply") {
    cloud.normals = ply_face_normals(path, cloud.points.size());
    if(!cloud.normals.empty()) cloud.normal_source = "mesh";
    cloud.vertices_without_normal = count_zero(cloud.normals);
    cloud.unread_triangle_strips = header.triangle_strips && cloud.normals.empty();
  }

  auto red = ps.property_map<unsigned char>("red"), green = ps.property_map<unsigned char>("green"),
       blue = ps.property_map<unsigned char>("blue");
  if(red.second && green.second && blue.second)
    for(auto it = ps.begin(); it != ps.end(); ++it) cloud.colors.push_back({red.first[*it], green.first[*it], blue.first[*it]});
  const std::vector<std::string> properties = ps.properties();
  for(const std::string& name : properties) {
    if(name == "index" || name == "point" || name == "normal" || name == "red" || name == "green" || name == "blue")
      continue;
    // A field named as CloudCompare names its own (scalar_NAME: --cloudcompare-fields, or CloudCompare's files)
    // is read as NAME, unless the file has a NAME too.
    const std::string& prefix = cloudcompare_scalar_prefix;
    const bool prefixed = name.size() > prefix.size() && name.compare(0, prefix.size(), prefix) == 0;
    const std::string bare = prefixed ? name.substr(prefix.size()) : std::string();
    const bool taken = std::find(properties.begin(), properties.end(), bare) != properties.end();
    const std::string& key = prefixed && !taken ? bare : name;
    copy_scalar<double>(ps, name, key, cloud) || copy_scalar<float>(ps, name, key, cloud) ||
      copy_scalar<int>(ps, name, key, cloud) || copy_scalar<unsigned int>(ps, name, key, cloud) ||
      copy_scalar<unsigned char>(ps, name, key, cloud) || copy_scalar<signed char>(ps, name, key, cloud) ||
      copy_scalar<short>(ps, name, key, cloud) || copy_scalar<unsigned short>(ps, name, key, cloud);
  }
  return cloud;
}

Record_layout record_layout(const fs::path& path)
{
  open_input(path, std::ios::binary);
  const std::string ext = lower_extension(path);
  Record_layout layout;
  if(ext == "pcd") {
    const Pcd_header h = check_pcd_header(path, 0);
    if(h.data != "binary")
      throw Cli_error(path.string() + " is a " + h.data +
                      " PCD file, whose points cannot be mapped; binary PCD, LAS and "
                      "binary PLY can (rewrite it as PLY: cgal_ext.read_points, then cgal_ext.write_ply)");
    layout.points = h.points;
    layout.data_offset = h.header_bytes;
    layout.record_bytes = h.record_bytes;
    for(const Pcd_field& f : h.fields)
      if(f.count == 1 && f.name != "_")
        layout.fields.push_back({f.name, f.offset, f.type == 'F' ? 'f' : f.type == 'I' ? 'i' : 'u', f.size});
    layout.coordinates = {"x", "y", "z"};
    const bool with_normals = std::any_of(layout.fields.begin(), layout.fields.end(),
                                          [](const Record_layout::Field& f) { return f.name == "normal_x"; });
    if(with_normals) layout.normals = {"normal_x", "normal_y", "normal_z"};
    return layout;
  }
  if(ext == "las" || ext == "laz") {
    const Las_header h = check_las_header(path, 0);
    layout.points = h.points;
    layout.data_offset = h.point_offset;
    layout.record_bytes = h.record_bytes;
    layout.fields = {{"X", 0, 'i', 4}, {"Y", 4, 'i', 4}, {"Z", 8, 'i', 4}, {"intensity", 12, 'u', 2}};
    layout.coordinates = {"X", "Y", "Z"};
    for(int axis = 0; axis < 3; ++axis) {
      layout.scale[std::size_t(axis)] = h.scale[axis];
      layout.shift[std::size_t(axis)] = h.offset[axis];
    }
    return layout;
  }
  throw Cli_error("cannot map " + path.string() + ": only binary PCD and LAS files are read by record layout");
}

} // namespace point_detail
