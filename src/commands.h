// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The subcommands of point-detail, a file each: each adds its options to the program's parser and returns
// how to run it.
#ifndef POINT_DETAIL_COMMANDS_H
#define POINT_DETAIL_COMMANDS_H

#include "subcommand_options.h"

#include <CLI/CLI.hpp>

#include <memory>
#include <vector>

namespace point_detail {

Subcommand add_details_command(CLI::App& app, const Common_options& common);
/// `scale` and `enhance`.
std::vector<Subcommand> add_manipulate_commands(CLI::App& app, const Common_options& common);
Subcommand add_curvature_command(CLI::App& app, const Common_options& common);
Subcommand add_simplify_command(CLI::App& app, const Common_options& common);
Subcommand add_edit_command(CLI::App& app, const Common_options& common);
Subcommand add_upsample_command(CLI::App& app, const Common_options& common);
Subcommand add_render_command(CLI::App& app, const Common_options& common);
Subcommand add_demo_command(CLI::App& app, const Common_options& common);

} // namespace point_detail

#endif
