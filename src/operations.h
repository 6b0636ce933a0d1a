// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// What the subcommands and the demo run on a cloud: details with their colour map, detail scaling and
// enhancement, an edit, up-sampling.
#ifndef POINT_DETAIL_OPERATIONS_H
#define POINT_DETAIL_OPERATIONS_H

#include "subcommand_options.h"

#include <CGAL_ext/Detail_scaling_settings.h>
#include <CGAL_ext/Upsampling_settings.h>

#include <functional>
#include <string>
#include <vector>

namespace point_detail {

/// Adds detail_x/y/z, detail_magnitude (the paper's signed |delta|), detail_normal (delta . n) and the colour
/// map of `options.color_by` to `cloud` (which has normals); returns that map.
Coloring add_details(Point_cloud& cloud, const Detail_options& options, Progress_printer& progress, Report& report);

/// The detail colours shown on the balanced-flow base surface (paper Fig. 3).
std::string render_on_base_surface(const Point_cloud& cloud, const Coloring& coloring, unsigned int k,
                                   const Render_settings& render, Report& report);

/// Scales (or enhances) the details of `region` of `cloud` (which has normals) by `factor`; `out` receives the
/// moved points with normals re-fitted where they moved, their displacement along the input normal and the
/// region flag.
CGAL_ext::Detail_manipulation_result manipulate(bool enhance, const Point_cloud& cloud, const std::vector<std::size_t>& region,
                                                const std::vector<std::size_t>* anchors, double factor, unsigned int k,
                                                const CGAL_ext::Detail_enhancement_settings& settings,
                                                const std::function<bool(double)>& callback, Point_cloud& out);

/// Every point's local spacing (CGAL_ext::compute_local_spacing): what an edit keeps.
std::vector<double> local_spacing(const Point_cloud& cloud);

/// Fills the holes of `cloud` (which has normals), looking for gaps from the points `region` only (all when
/// null), at the spacing each point had before an edit (`spacing_before`, with `region`) or else that of the
/// settings (0: local): the new points are appended with the flag `inserted` = 1, 0 in the other scalars and
/// `flag_color` (when the cloud has colours); the report gets the figures.
void upsample_cloud(Point_cloud& cloud, const CGAL_ext::Upsampling_settings& settings, const std::vector<std::size_t>* region,
                    const std::vector<double>* spacing_before, Progress_printer& progress, Report& rep);

/// Runs an edit on `cloud` (which has normals): preprocess, deform, diffuse. `out` receives the deformed points
/// and normals, the distance each point moved, its status (0 fixed, 1 region, 2 handle) and its sample point;
/// the report gets the paper's Table 1 fields.
void run_edit(const Point_cloud& cloud, const Edit_description& edit, Progress_printer& progress, Report& rep, Point_cloud& out);

/// An edit's picture: the distance each point moved, and the points an up-sampling added, flagged.
Coloring edit_coloring(const Point_cloud& out);
/// The colours of a scaled or enhanced cloud: its displacement along the normal, diverging.
Coloring manipulate_coloring(const Point_cloud& out);

} // namespace point_detail

#endif
