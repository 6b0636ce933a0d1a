// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// Edit descriptions for `point-detail edit`: a JSON file, or the .sel/.def pair of the Botsch & Sorkine 2008
// deformation benchmark (the format of CGAL's Surface_mesh_deformation examples).
#ifndef POINT_DETAIL_EDIT_SPEC_H
#define POINT_DETAIL_EDIT_SPEC_H

#include "files.h"
#include "point_io.h"

#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/Detail_preserving_deformation_settings.h>

#include <Eigen/Core>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace point_detail {

/// One handle group: its points and the rigid transform `p -> R p + t` (world frame).
struct Handle_edit
{
  std::vector<std::size_t> points;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

/// What to edit: the region of interest (handles included) and the handle groups; settings as the file gives
/// them over the defaults.
struct Edit_description
{
  std::vector<std::size_t> roi;
  std::vector<Handle_edit> handles;
  CGAL_ext::Detail_preserving_deformation_settings settings;
};

/// One step of an edit chain (`{"steps": [...]}`, doc/editing.md, "Chains of steps"). Its selections are
/// evaluated on the points the step starts from: the result of the steps before it.
struct Edit_step
{
  enum class Kind
  {
    edit,
    scale,
    enhance,
    fill
  };
  Kind kind = Kind::edit;
  std::string where; ///< "FILE: steps[i]", for messages
  /// edit: the edit on the points it starts from (its selections evaluated on them).
  std::function<Edit_description(const std::vector<Point>&)> edit;
  CGAL_ext::Detail_preserving_deformation_settings settings; ///< edit: its settings (as `edit` gives them)
  /// scale and enhance: the factor, the detail filter and Laplacian size, the region on the points it starts from.
  double factor = 1;
  CGAL_ext::Detail_filter filter;
  unsigned int k = CGAL_ext::default_laplacian_neighbors;
  std::function<std::vector<std::size_t>(const std::vector<Point>&)> region;
};

/// The value of the setting `Enum` that `name` spells (`CGAL_ext::Setting_names`); throws Cli_error naming
/// `where` and the names it takes otherwise.
template <typename Enum>
Enum setting_value(const std::string& name, const std::string& where)
{
  Enum value{};
  if(!CGAL_ext::find_setting(name, value))
    throw Cli_error(where + " must be " + CGAL_ext::setting_choices<Enum>() + ", not \"" + name + "\"");
  return value;
}

/*!
  Reads a JSON edit (documented in doc/editing.md):
  `{"roi": [SPEC...], "handles": [{"select": [SPEC...], "translation": [x,y,z],
    "rotation": {"axis": [x,y,z], "degrees": a} | "quaternion": [w,x,y,z] | "matrix": [[..],[..],[..]],
    "pivot": [x,y,z]}], "filter": {"order", "lambda", "mu"}, "k", "strength_distance", "handle_weight",
    "rotations" ("none" | "propagate" | "arap"), "rigid_iterations", "rigid_rotation_smoothing",
    "rigid_rotation_smoothing_scale" ("edge_lengths" | "surface_area"), "rigid_edge_weights"
    ("uniform" | "cotangent"), "diffusion_samples", "diffusion_origin", "diffusion_turn", "detail_iterations",
    "simplification": {"max_cluster_size", "target_count", "mode_threshold"}}` (older files: "diffusion":
    {"samples", "origin", "turn", "detail_iterations"}). SPECs are region specs (`sphere:`, `box:`, `indices:FILE`, files
  relative to the JSON file); a missing "roi" is the whole model. Unknown keys are errors (they are typos). A
  chain of steps (`read_edit_chain`) is read when it is one edit step. Throws Cli_error naming the key and the
  problem.
*/
Edit_description read_edit_json(const std::filesystem::path& path, const std::vector<Point>& points);

/// Reads an edit JSON as a chain of steps: `{"steps": [{"type": "edit", ...}, {"type": "scale" | "enhance", "s",
/// "roi", "filter", "k"}, {"type": "fill"}, ...]}`, or a one-edit file as a chain of one edit step. Every key,
/// setting and region spec of every step is checked before any step runs (a fill must follow an edit); the
/// selections are evaluated when the step runs. Throws Cli_error naming the step, the key and the problem.
std::vector<Edit_step> read_edit_chain(const std::filesystem::path& path);

/// Reads a `.sel` file (one status per point in file order: 0 fixed, 1 deformable, 2 handle; `#` lines are
/// comments) and a `.def` file (the handle's 4x4 world transform, row by row; `#` comments). A matrix printed
/// with few digits is snapped to the nearest rotation when it is one within 1e-3; otherwise it is refused.
Edit_description read_botsch_sorkine(const std::filesystem::path& sel, const std::filesystem::path& def, std::size_t point_count);

} // namespace point_detail

#endif
