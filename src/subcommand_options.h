// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// What the subcommands of point-detail share around the library: options, outputs, reading with a memory
// check, normals for clouds that come without.
#ifndef POINT_DETAIL_SUBCOMMAND_OPTIONS_H
#define POINT_DETAIL_SUBCOMMAND_OPTIONS_H

#include "program_basics.h"
#include "edit_spec.h"
#include "point_io.h"
#include "render.h"

#include <CGAL_ext/Detail_filter.h>

#include <CLI/CLI.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace point_detail {

namespace fs = std::filesystem;

/// The program's own options, given before the subcommand.
struct Common_options
{
  int threads = 0; // 0: all cores
  bool quiet = false;
  bool cloudcompare_fields = false; // scalar fields named scalar_NAME, which CloudCompare's command line loads

  /// What the PLY files' scalar properties are prefixed with.
  std::string scalar_prefix() const { return cloudcompare_fields ? cloudcompare_scalar_prefix : std::string(); }
};

/// A subcommand as `main` sees it: its parsed options, and how to run it.
struct Subcommand
{
  CLI::App* app;
  std::function<void()> run;
};

/// An option that takes the names of `Enum`'s values (`CGAL_ext::Setting_names`, older spellings too) into
/// `value`; its help lists the names.
template <typename Enum>
CLI::Option* add_setting_option(CLI::App& app, const std::string& name, Enum& value, const std::string& description)
{
  std::string names;
  for(const std::string& n : CGAL_ext::setting_names<Enum>()) names += (names.empty() ? "{" : ",") + n;
  CLI::Validator spelled(
    [](std::string& text) -> std::string {
      Enum found{};
      if(!CGAL_ext::find_setting(text, found))
        return "must be " + CGAL_ext::setting_choices<Enum>() + ", not \"" + text + "\"";
      text = std::to_string(static_cast<int>(found)); // what CLI11 converts to the enum
      return std::string();
    },
    names + "}");
  return app.add_option(name, value, description)->transform(spelled);
}

/// The detail options of `details`, `scale` and `enhance`.
struct Detail_options
{
  CGAL_ext::Detail_filter filter;
  unsigned int k = CGAL_ext::default_laplacian_neighbors;
  CGAL_ext::Laplacian_weighting weights = CGAL_ext::Laplacian_weights().weighting;
  CGAL_ext::Laplacian_neighborhood neighbors = CGAL_ext::Detail_settings().neighborhood;
  std::string color_by = "detail_normal"; // the relief on any sampling (doc/geometric_details.md, "Colour maps")

  CGAL_ext::Detail_settings settings() const
  {
    CGAL_ext::Detail_settings s;
    s.filter = filter;
    s.weights.weighting = weights;
    s.neighborhood = neighbors;
    return s;
  }
};

void add_detail_options(CLI::App& app, Detail_options& o);

/// `-k,--neighbor-count`, one rule in every subcommand: each point's (for `edit`, each sample point's) k nearest
/// neighbours, itself not counted, form its neighbourhood `of`; `minimum <= k <` the number of points (sample
/// points), an error otherwise.
CLI::Option* add_neighbor_count_option(CLI::App& app, unsigned int& k, const std::string& of, unsigned int minimum,
                                       const std::string& point = "point");
void add_render_options(CLI::App& app, Render_settings& r, std::string& view);

/// 0, 1, ..., n - 1: the points of a cloud as the library's point range (property maps index the arrays).
std::vector<std::size_t> index_range(std::size_t n);

/// The temporary file to write an optional output to, or an empty path when the option was not given.
fs::path add_if_given(Output_files& outputs, const std::string& destination);

/// The outputs of a subcommand that writes points, with an optional picture and report: each checked (never an
/// input; its directory exists) and written to a temporary until `files.commit()`, so outputs are whole or absent.
struct Point_outputs
{
  Output_files files;
  fs::path ply, png, report; // the temporaries (empty when not asked for)

  Point_outputs(std::vector<fs::path> inputs, const std::string& output, const std::string& png_destination,
                const std::string& report_destination)
    : files(std::move(inputs)), ply(files.add(output)), png(add_if_given(files, png_destination)),
      report(add_if_given(files, report_destination))
  {}
};

/// What each subcommand needs per input point, reading and writing included: its peak memory on a raw scan of
/// 1M points (normals estimated; benchmark/raw_scan_results.md, upsample and render on the same points with
/// normals) plus a quarter. The check before reading asks the machine for this much. A region's factorisation
/// needs more, by the region's size; CHOLMOD running out of memory then is an error of its own.
namespace bytes_per_point {
constexpr std::uint64_t details = 704;   // measured 550
constexpr std::uint64_t curvature = 416; // 327
constexpr std::uint64_t simplify = 448;  // 355
constexpr std::uint64_t manipulate = 800; // 632 (whole-model enhancement)
constexpr std::uint64_t edit = 640;      // 492
constexpr std::uint64_t upsample = 512;  // 400
constexpr std::uint64_t render = 416;    // 185 with normals; estimating them, as curvature
} // namespace bytes_per_point

/// Reads `input` (Report stage "read"), noting on stderr and in the report the points the file gives no position.
Point_cloud read_input(const std::string& input, std::uint64_t bytes, Report& rep);

/// Reads `input` (timed in the report), asking the machine for `bytes` per point, and checks that it has more
/// than `k` points.
Point_cloud read_for_neighbors(const std::string& input, unsigned int k, std::uint64_t bytes, Report& rep);

/// Gives the cloud normals when it has none (CGAL_ext::estimate_oriented_normals), and the vertices of a mesh
/// that lie on no face theirs: estimated normals turned, as a whole, to the side of the mesh's.
void ensure_normals(Point_cloud& cloud, Progress_printer& progress, Report& report);

} // namespace point_detail

#endif
