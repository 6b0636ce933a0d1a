// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "edit_spec.h"

#include "files.h"
#include "region_spec.h"

#include <CGAL/number_type_config.h>

#include <nlohmann/json.hpp>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <cmath>
#include <fstream>
#include <numeric>
#include <set>
#include <sstream>

namespace point_detail {

namespace {

using json = nlohmann::json;

/// Keys of `object` must be among `allowed`: a misspelt key would otherwise be ignored silently.
void check_keys(const json& object, const std::set<std::string>& allowed, const std::string& where)
{
  if(!object.is_object()) throw Cli_error(where + " must be a JSON object");
  for(const auto& item : object.items())
    if(!allowed.count(item.key())) {
      std::string names;
      for(const std::string& a : allowed) names += (names.empty() ? "" : ", ") + a;
      throw Cli_error(where + ": unknown key '" + item.key() + "' (expected one of: " + names + ")");
    }
}

double number(const json& value, const std::string& where)
{
  if(!value.is_number() || !std::isfinite(value.get<double>())) throw Cli_error(where + " must be a finite number");
  return value.get<double>();
}

Eigen::Vector3d vector3(const json& value, const std::string& where)
{
  if(!value.is_array() || value.size() != 3) throw Cli_error(where + " must be an array of 3 numbers");
  return {number(value[0], where + "[0]"), number(value[1], where + "[1]"), number(value[2], where + "[2]")};
}

/// The region specs of `specs` (syntax checked, index files relative to `base`).
std::vector<Region_spec> region_specs(const json& specs, const std::filesystem::path& base, const std::string& where)
{
  if(!specs.is_array() || specs.empty()) throw Cli_error(where + " must be a non-empty array of region specs");
  std::vector<Region_spec> parsed;
  for(const json& s : specs) {
    if(!s.is_string()) throw Cli_error(where + ": every region spec is a string such as \"sphere:x,y,z,r\"");
    Region_spec spec = parse_region_spec(s.get<std::string>());
    if(spec.kind == Region_spec::Kind::indices && std::filesystem::path(spec.file).is_relative())
      spec.file = (base / spec.file).string();
    parsed.push_back(spec);
  }
  return parsed;
}

/// A rotation from its JSON form: {"axis", "degrees"}, "quaternion" [w, x, y, z] or "matrix" (3 rows).
Eigen::Matrix3d rotation(const json& handle, const std::string& where)
{
  const int given = int(handle.contains("rotation")) + int(handle.contains("quaternion")) + int(handle.contains("matrix"));
  if(given > 1) throw Cli_error(where + ": give one of rotation, quaternion and matrix");
  if(handle.contains("rotation")) {
    const json& r = handle["rotation"];
    check_keys(r, {"axis", "degrees"}, where + ".rotation");
    if(!r.contains("axis") || !r.contains("degrees")) throw Cli_error(where + ".rotation needs axis and degrees");
    const Eigen::Vector3d axis = vector3(r["axis"], where + ".rotation.axis");
    if(!(axis.norm() > 0)) throw Cli_error(where + ".rotation.axis must not be zero");
    return Eigen::AngleAxisd(number(r["degrees"], where + ".rotation.degrees") * CGAL_PI / 180, axis.normalized()).toRotationMatrix();
  }
  if(handle.contains("quaternion")) {
    const json& q = handle["quaternion"];
    if(!q.is_array() || q.size() != 4) throw Cli_error(where + ".quaternion must be [w, x, y, z]");
    const Eigen::Quaterniond quaternion(number(q[0], where + ".quaternion"), number(q[1], where + ".quaternion"),
                                        number(q[2], where + ".quaternion"), number(q[3], where + ".quaternion"));
    if(std::abs(quaternion.norm() - 1) > 1e-6)
      throw Cli_error(where + ".quaternion has norm " + std::to_string(quaternion.norm()) + "; a rotation needs a unit quaternion");
    return quaternion.toRotationMatrix();
  }
  if(handle.contains("matrix")) {
    const json& m = handle["matrix"];
    if(!m.is_array() || m.size() != 3) throw Cli_error(where + ".matrix must be 3 rows of 3 numbers");
    Eigen::Matrix3d R;
    for(int r = 0; r < 3; ++r) R.row(r) = vector3(m[std::size_t(r)], where + ".matrix[" + std::to_string(r) + "]").transpose();
    return R; // checked to be a rotation by the deformation
  }
  return Eigen::Matrix3d::Identity();
}

/// The rotation nearest to `M` (polar decomposition) when `M` is one within `tolerance`.
Eigen::Matrix3d snapped_rotation(const Eigen::Matrix3d& M, double tolerance, const std::string& where)
{
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d R = svd.matrixU() * svd.matrixV().transpose();
  const double error = (M - R).norm();
  if(!(R.determinant() > 0) || !(error < tolerance)) {
    std::ostringstream os;
    os << where << ": the 3x3 part is not a rotation (distance to the nearest one " << error
       << "); deformation handles move rigidly: no scaling, shear or mirroring";
    throw Cli_error(os.str());
  }
  return R;
}

/// Non-comment, non-blank lines of a text file with their line numbers.
std::vector<std::pair<std::size_t, std::string>> content_lines(const std::filesystem::path& path)
{
  std::ifstream in = open_input(path);
  std::vector<std::pair<std::size_t, std::string>> lines;
  std::string line;
  for(std::size_t number = 1; std::getline(in, line); ++number) {
    line.erase(0, line.find_first_not_of(" \t\r"));
    line.erase(line.find_last_not_of(" \t\r") + 1);
    if(line.empty() || line[0] == '#') continue;
    lines.emplace_back(number, line);
  }
  return lines;
}

std::vector<std::size_t> all_indices(std::size_t n)
{
  std::vector<std::size_t> indices(n);
  std::iota(indices.begin(), indices.end(), std::size_t(0));
  return indices;
}

/// A whole number >= 1 (counts and sizes).
double whole(const json& v, const std::string& where)
{
  const double x = number(v, where);
  if(!(x >= 1 && x == std::floor(x) && x < 1e9)) throw Cli_error(where + " must be a whole number >= 1");
  return x;
}

/// A setting spelled by name (CGAL_ext::Setting_names), when `parent` has `key`.
template <typename Value>
void named_setting(const json& parent, const char* key, const std::string& where, Value& value)
{
  if(!parent.contains(key)) return;
  const json& v = parent[key];
  value = setting_value<Value>(v.is_string() ? v.get<std::string>() : v.dump(), where);
}

/// The "filter" object {"order", "lambda", "mu"} over `filter`.
void read_filter(const json& f, const std::string& where, CGAL_ext::Detail_filter& filter)
{
  check_keys(f, {"order", "lambda", "mu"}, where);
  named_setting(f, "order", where + ".order", filter.order);
  if(f.contains("lambda")) filter.lambda = number(f["lambda"], where + ".lambda");
  if(f.contains("mu")) filter.mu = number(f["mu"], where + ".mu");
}

/// The edit of the JSON object `edit` (`file` names it in messages, index files are relative to `base`). With
/// `points`, its selections are evaluated on them; without, everything else is checked and they are left empty.
Edit_description parse_edit(const json& edit, const std::filesystem::path& base, const std::string& file,
                            const std::vector<Point>* points)
{
  check_keys(edit, {"roi", "handles", "filter", "k", "strength_distance", "handle_weight", "rotations", "rigid_iterations",
                    "rigid_rotation_smoothing", "rigid_rotation_smoothing_scale", "rigid_edge_weights",
                    "diffusion_samples", "diffusion_origin", "diffusion_turn", "detail_iterations", "diffusion",
                    "simplification"}, file);
  if(edit.contains("diffusion"))
    for(const char* flat : {"diffusion_samples", "diffusion_origin", "diffusion_turn", "detail_iterations"})
      if(edit.contains(flat))
        throw Cli_error(file + ": " + flat + " and the older \"diffusion\" object are both given; keep " + flat);
  Edit_description out;
  auto& settings = out.settings;
  if(edit.contains("roi")) {
    const std::vector<Region_spec> roi = region_specs(edit["roi"], base, file + ": roi");
    if(points) out.roi = select_points(*points, roi);
    if(points && out.roi.empty())
      throw Cli_error(file + ": roi selects none of the " + std::to_string(points->size()) + " points");
  } else if(points) {
    out.roi = all_indices(points->size());
  }
  if(!edit.contains("handles") || !edit["handles"].is_array() || edit["handles"].empty())
    throw Cli_error(file + ": handles must be a non-empty array of handle groups");
  for(std::size_t g = 0; g < edit["handles"].size(); ++g) {
    const json& h = edit["handles"][g];
    const std::string where = file + ": handles[" + std::to_string(g) + "]";
    check_keys(h, {"select", "translation", "rotation", "quaternion", "matrix", "pivot"}, where);
    if(!h.contains("select")) throw Cli_error(where + " needs select (region specs of its points)");
    Handle_edit handle;
    const std::vector<Region_spec> select = region_specs(h["select"], base, where + ".select");
    if(points) handle.points = select_points(*points, select);
    if(points && handle.points.empty()) throw Cli_error(where + ".select selects no point");
    handle.rotation = rotation(h, where);
    const Eigen::Vector3d t = h.contains("translation") ? vector3(h["translation"], where + ".translation") : Eigen::Vector3d::Zero();
    const Eigen::Vector3d pivot = h.contains("pivot") ? vector3(h["pivot"], where + ".pivot") : Eigen::Vector3d::Zero();
    handle.translation = pivot - handle.rotation * pivot + t; // p -> R (p - pivot) + pivot + t
    out.handles.push_back(std::move(handle));
  }
  const auto named = [](const json& parent, const char* key, const std::string& where, auto& value) {
    named_setting(parent, key, where, value);
  };
  if(edit.contains("filter")) read_filter(edit["filter"], file + ": filter", settings.filter);
  if(edit.contains("k")) settings.sample_neighbors = unsigned(whole(edit["k"], file + ": k"));
  named(edit, "strength_distance", file + ": strength_distance", settings.strength_distance);
  if(edit.contains("handle_weight")) settings.handle_weight = number(edit["handle_weight"], file + ": handle_weight");
  named(edit, "rotations", file + ": rotations", settings.rotations);
  if(edit.contains("rigid_iterations")) settings.rigid_iterations = unsigned(whole(edit["rigid_iterations"], file + ": rigid_iterations"));
  if(edit.contains("rigid_rotation_smoothing"))
    settings.rigid_rotation_smoothing = number(edit["rigid_rotation_smoothing"], file + ": rigid_rotation_smoothing");
  named(edit, "rigid_rotation_smoothing_scale", file + ": rigid_rotation_smoothing_scale", settings.rigid_rotation_smoothing_scale);
  named(edit, "rigid_edge_weights", file + ": rigid_edge_weights", settings.rigid_edge_weights);
  // The diffusion's settings, flat as everywhere else; older files nest them as "diffusion": {"samples",
  // "origin", "turn", "detail_iterations"}.
  const bool nested = edit.contains("diffusion");
  const json& diffusion = nested ? edit["diffusion"] : edit;
  const std::string prefix = nested ? "diffusion." : "";
  if(nested) check_keys(diffusion, {"samples", "origin", "turn", "detail_iterations"}, file + ": diffusion");
  const char* samples = nested ? "samples" : "diffusion_samples";
  if(diffusion.contains(samples)) settings.diffusion_samples = unsigned(whole(diffusion[samples], file + ": " + prefix + samples));
  if(diffusion.contains("detail_iterations"))
    settings.detail_iterations = unsigned(whole(diffusion["detail_iterations"], file + ": " + prefix + "detail_iterations"));
  const char* origin = nested ? "origin" : "diffusion_origin";
  named(diffusion, origin, file + ": " + prefix + origin, settings.diffusion_origin);
  const char* turn = nested ? "turn" : "diffusion_turn";
  named(diffusion, turn, file + ": " + prefix + turn, settings.diffusion_turn);
  if(edit.contains("simplification")) {
    const json& s = edit["simplification"];
    check_keys(s, {"max_cluster_size", "target_count", "mode_threshold"}, file + ": simplification");
    if(s.contains("max_cluster_size"))
      settings.simplification.max_cluster_size = std::size_t(whole(s["max_cluster_size"], file + ": simplification.max_cluster_size"));
    if(s.contains("target_count"))
      settings.simplification.target_count = std::size_t(whole(s["target_count"], file + ": simplification.target_count"));
    if(s.contains("mode_threshold"))
      settings.simplification.mode_spread_threshold =
        s["mode_threshold"] == "inf" ? INFINITY : number(s["mode_threshold"], file + ": simplification.mode_threshold");
  }
  try {
    settings.validate();
  } catch(const CGAL_ext::Invalid_input& e) {
    throw Cli_error(file + ": " + e.what());
  }
  return out;
}

json read_json(const std::filesystem::path& path)
{
  std::ifstream in = open_input(path);
  try {
    return json::parse(in);
  } catch(const json::exception& e) { // a syntax error, or a number out of range (1e999)
    throw Cli_error(path.string() + ": not valid JSON: " + e.what());
  }
}

/// A scale or enhance step: {"type", "s", "roi", "filter", "k"}.
Edit_step detail_step(const json& step, const std::filesystem::path& base, Edit_step out)
{
  const std::string& where = out.where;
  check_keys(step, {"type", "s", "roi", "filter", "k"}, where);
  if(!step.contains("s")) throw Cli_error(where + " needs s, the factor of the details");
  out.factor = number(step["s"], where + ".s");
  if(step.contains("filter")) read_filter(step["filter"], where + ".filter", out.filter);
  if(step.contains("k")) out.k = unsigned(whole(step["k"], where + ".k"));
  try {
    CGAL_ext::Detail_settings settings;
    settings.filter = out.filter;
    settings.validate();
  } catch(const CGAL_ext::Invalid_input& e) {
    throw Cli_error(where + ": " + e.what());
  }
  if(!step.contains("roi")) {
    out.region = [](const std::vector<Point>& points) { return all_indices(points.size()); };
    return out;
  }
  out.region = [specs = region_specs(step["roi"], base, where + ".roi"), where](const std::vector<Point>& points) {
    std::vector<std::size_t> region = select_points(points, specs);
    if(region.empty()) throw Cli_error(where + ".roi selects none of the " + std::to_string(points.size()) + " points");
    return region;
  };
  return out;
}

} // namespace

std::vector<Edit_step> read_edit_chain(const std::filesystem::path& path)
{
  const json document = read_json(path);
  const std::string file = path.filename().string();
  const std::filesystem::path base = path.parent_path();
  const auto edit_step = [&base](const json& edit, const std::string& where) {
    Edit_step step;
    step.settings = parse_edit(edit, base, where, nullptr).settings; // everything but the selections, checked now
    step.where = where;
    step.edit = [edit, base, where](const std::vector<Point>& points) {
      return parse_edit(edit, base, where, &points);
    };
    return step;
  };
  if(!document.is_object() || !document.contains("steps")) return {edit_step(document, file)};
  check_keys(document, {"steps"}, file);
  const json& steps = document["steps"];
  if(!steps.is_array() || steps.empty()) throw Cli_error(file + ": steps must be a non-empty array of steps");
  std::vector<Edit_step> chain;
  for(std::size_t i = 0; i < steps.size(); ++i) {
    const json& step = steps[i];
    const std::string where = file + ": steps[" + std::to_string(i) + "]";
    if(!step.is_object() || !step.contains("type") || !step["type"].is_string())
      throw Cli_error(where + " must be an object with a type (edit, scale, enhance or fill)");
    const std::string type = step["type"].get<std::string>();
    if(type == "edit") {
      json edit = step;
      edit.erase("type");
      chain.push_back(edit_step(edit, where));
    } else if(type == "scale" || type == "enhance") {
      Edit_step detail;
      detail.kind = type == "scale" ? Edit_step::Kind::scale : Edit_step::Kind::enhance;
      detail.where = where;
      chain.push_back(detail_step(step, base, std::move(detail)));
    } else if(type == "fill") {
      check_keys(step, {"type"}, where);
      if(chain.empty() || chain.back().kind != Edit_step::Kind::edit)
        throw Cli_error(where +
                        ": a fill step fills what the edit step just before it stretched; it follows an edit step");
      Edit_step fill;
      fill.kind = Edit_step::Kind::fill;
      fill.where = where;
      chain.push_back(std::move(fill));
    } else {
      throw Cli_error(where + ": unknown type '" + type + "' (expected one of: edit, scale, enhance, fill)");
    }
  }
  return chain;
}

Edit_description read_edit_json(const std::filesystem::path& path, const std::vector<Point>& points)
{
  const std::vector<Edit_step> chain = read_edit_chain(path);
  if(chain.size() != 1 || chain[0].kind != Edit_step::Kind::edit)
    throw Cli_error(path.filename().string() + " holds a chain of " + std::to_string(chain.size()) +
                    " steps, not one edit");
  return chain[0].edit(points);
}

Edit_description read_botsch_sorkine(const std::filesystem::path& sel, const std::filesystem::path& def, std::size_t point_count)
{
  Edit_description out;
  Handle_edit handle;
  const auto statuses = content_lines(sel);
  if(statuses.size() != point_count)
    throw Cli_error(sel.string() + " has " + std::to_string(statuses.size()) + " status lines but the model has " +
                    std::to_string(point_count) + " points (one line per point, in file order)");
  for(std::size_t i = 0; i < statuses.size(); ++i) {
    const auto& [line, text] = statuses[i];
    if(text != "0" && text != "1" && text != "2")
      throw Cli_error(sel.string() + ":" + std::to_string(line) + ": '" + text + "' is not a status (0 fixed, 1 deformable, 2 handle)");
    if(text != "0") out.roi.push_back(i);
    if(text == "2") handle.points.push_back(i);
  }
  if(out.roi.empty()) throw Cli_error(sel.string() + " marks no point deformable (1) or handle (2)");
  if(handle.points.empty()) throw Cli_error(sel.string() + " marks no handle point (2)");

  std::vector<double> numbers;
  for(const auto& [line, text] : content_lines(def)) {
    std::istringstream in(text);
    std::string token;
    while(in >> token) {
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if(end != token.c_str() + token.size() || !std::isfinite(value))
        throw Cli_error(def.string() + ":" + std::to_string(line) + ": '" + token + "' is not a finite number");
      numbers.push_back(value);
    }
  }
  if(numbers.size() != 16)
    throw Cli_error(def.string() + " holds " + std::to_string(numbers.size()) + " numbers; a 4x4 transform has 16");
  Eigen::Matrix4d M;
  for(int r = 0; r < 4; ++r)
    for(int c = 0; c < 4; ++c) M(r, c) = numbers[std::size_t(4 * r + c)];
  if((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9)
    throw Cli_error(def.string() + ": the last row of the transform must be 0 0 0 1 (an affine, not a projective, map)");
  handle.rotation = snapped_rotation(M.topLeftCorner<3, 3>(), 1e-3, def.string());
  handle.translation = M.topRightCorner<3, 1>();
  out.handles.push_back(std::move(handle));
  return out;
}

} // namespace point_detail
