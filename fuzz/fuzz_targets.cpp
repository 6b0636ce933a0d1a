// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The libFuzzer targets, in one program: the name it is started by (a link in the build's fuzz/ folder, as
// fuzz_ply or fuzz_neighborhoods) picks the target. One unit instead of ten saves the sanitized build the
// program's readers and the mutators compiled ten times (doc/build_time.md).
//
// The readers take files, fed by mutators that know the formats' structure (fuzz/structure_mutators.h,
// fuzz/scan_format_mutators.h); fuzz_neighborhoods takes point sets (the neighbourhood rule, whatever the order
// of the points).
#include "edit_spec.h"
#include "fuzz_support.h"
#include "neighborhood_reference.h"
#include "program_basics.h"
#include "region_spec.h"
#include "scan_format_mutators.h"
#include "structure_mutators.h"

#include <CGAL_ext/internal/Neighbor_graph.h>

#include <CGAL/tags.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace {

using Test_one = int (*)(const std::uint8_t* data, std::size_t size);
using Mutate = std::size_t (*)(std::uint8_t* data, std::size_t size, std::size_t max_size, unsigned seed);

void check(bool holds)
{
  if(!holds) std::abort(); // libFuzzer saves the input
}

// The point-file readers as point-detail uses them. The first byte picks the format; the rest is mutated byte by
// byte (the other reader targets mutate their formats' structure).
int point_reader(const std::uint8_t* data, std::size_t size)
{
  if(size == 0) return 0;
  static const char* const extensions[] = {"in.ply", "in.off", "in.xyz", "in.pwn",
                                           "in.pcd", "in.pts", "in.ptx", "in.las"};
  fuzz::read_points_and_check(fuzz::write_input(extensions[data[0] % 8], data + 1, size - 1));
  return 0;
}

// One reader on a file of one format.
template <const char* name>
int read_file(const std::uint8_t* data, std::size_t size)
{
  fuzz::read_points_and_check(fuzz::write_input(name, data, size));
  return 0;
}
constexpr char ply_name[] = "in.ply", off_name[] = "in.off", pcd_name[] = "in.pcd", las_name[] = "in.las";

// A mutator of structure_mutators.h or scan_format_mutators.h as libFuzzer's custom mutator.
template <std::string (*mutate)(const std::string&, std::size_t, fuzz::Random&)>
std::size_t mutate_structure(std::uint8_t* data, std::size_t size, std::size_t max_size, unsigned seed)
{
  return fuzz::custom_mutate(data, size, max_size, seed, mutate);
}

// The PTS and PTX readers: the first byte picks the format (even: .pts, odd: .ptx) and is kept by the mutator.
int pts_ptx(const std::uint8_t* data, std::size_t size)
{
  if(size == 0) return 0;
  fuzz::read_points_and_check(fuzz::write_input(data[0] % 2 ? "in.ptx" : "in.pts", data + 1, size - 1));
  return 0;
}

std::size_t mutate_pts_ptx(std::uint8_t* data, std::size_t size, std::size_t max_size, unsigned seed)
{
  if(size == 0 || max_size < 2) return LLVMFuzzerMutate(data, size, max_size);
  const bool ptx = data[0] % 2;
  return 1 + fuzz::custom_mutate(data + 1, size - 1, max_size - 1, seed,
                                 [ptx](const std::string& in, std::size_t max, fuzz::Random& random) {
                                   return fuzz::mutate_pts_ptx(in, max, random, ptx);
                                 });
}

// The JSON edit parser of `point-detail edit --edit FILE` (one edit or a chain of steps), on a 200-point sphere.
int edit_json(const std::uint8_t* data, std::size_t size)
{
  const auto path = fuzz::write_input("edit.json", data, size);
  try {
    // Each step's selections on the same points (the chain's states all have these points or more).
    for(const point_detail::Edit_step& step : point_detail::read_edit_chain(path)) {
      if(step.kind == point_detail::Edit_step::Kind::edit) {
        const point_detail::Edit_description edit = step.edit(fuzz::sphere_points());
        for(std::size_t i : edit.roi)
          if(i >= fuzz::sphere_points().size()) __builtin_trap(); // indices are checked
      } else if(step.region) {
        for(std::size_t i : step.region(fuzz::sphere_points()))
          if(i >= fuzz::sphere_points().size()) __builtin_trap();
      }
    }
  } catch(const point_detail::Cli_error&) {
  } catch(const CGAL_ext::Invalid_input&) {}
  return 0;
}

// The .sel/.def reader of `point-detail edit --sel --def` for a 50-point model. The input is the .sel file, a NUL
// byte, and the .def file.
int sel_def(const std::uint8_t* data, std::size_t size)
{
  const std::uint8_t* split = std::find(data, data + size, std::uint8_t(0));
  const auto sel = fuzz::write_input("in.sel", data, std::size_t(split - data));
  const std::size_t rest = split == data + size ? 0 : std::size_t(data + size - split - 1);
  const auto def = fuzz::write_input("in.def", split == data + size ? data : split + 1, rest);
  try {
    const point_detail::Edit_description edit = point_detail::read_botsch_sorkine(sel, def, 50);
    for(std::size_t i : edit.roi)
      if(i >= 50) __builtin_trap();
  } catch(const point_detail::Cli_error&) {
  } catch(const CGAL_ext::Invalid_input&) {}
  return 0;
}

// The region spec parser of --roi and --anchors (sphere:, box:, indices:FILE), selecting on a 200-point sphere.
int region_spec(const std::uint8_t* data, std::size_t size)
{
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const point_detail::Region_spec spec = point_detail::parse_region_spec(text);
    for(std::size_t i : point_detail::select_points(fuzz::sphere_points(), {spec}))
      if(i >= fuzz::sphere_points().size()) __builtin_trap();
  } catch(const point_detail::Cli_error&) {}
  return 0;
}

// The neighbourhood rule every algorithm uses (doc/design.md, "One neighbourhood rule") on point sets whose
// coordinates are multiples of 1/4 in [0, 4), so that distances tie and points coincide often: each row is the
// brute-force closed ball of its point's k-th nearest, and the same set of points in another order gets the same
// balls; or a pile of duplicates is refused with Invalid_input, and only then.
int neighborhoods(const std::uint8_t* data, std::size_t size)
{
  using namespace CGAL_ext::internal;
  if(size < 1 + 2 * 3) return 0;
  const std::size_t n = std::min<std::size_t>((size - 1) / 3, 400);
  Matrix_n3 points(Eigen::Index(n), 3);
  for(std::size_t i = 0; i < n; ++i)
    for(int c = 0; c < 3; ++c) points(Eigen::Index(i), c) = (data[1 + 3 * i + std::size_t(c)] % 16) / 4.0;
  const std::size_t k = 1 + data[0] % std::min<std::size_t>(n - 1, 20);
  std::vector<int> order(n); // row r of `shuffled` is row order[r] of `points`
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(unsigned(size)));
  Matrix_n3 shuffled(points.rows(), 3);
  for(std::size_t r = 0; r < n; ++r) shuffled.row(Eigen::Index(r)) = points.row(order[r]);
  std::size_t largest_ball = 0;
  for(std::size_t i = 0; i < n; ++i) largest_ball = std::max(largest_ball, brute_force_ball(points, i, k).size());
  const bool pile = largest_ball > k + max_tied_neighbors;
  Progress progress;
  Neighbor_graph graph, other;
  try {
    graph = k_nearest_neighbor_graph<CGAL::Sequential_tag>(points, k, progress);
    other = k_nearest_neighbor_graph<CGAL::Sequential_tag>(shuffled, k, progress);
  } catch(const CGAL_ext::Invalid_input&) {
    check(pile);
    return 0;
  }
  check(!pile && graph.size() == n && other.size() == n);
  for(std::size_t i = 0; i < n; ++i)
    check(std::vector<int>(graph.begin(i), graph.end(i)) == brute_force_ball(points, i, k));
  for(std::size_t r = 0; r < n; ++r) {
    std::vector<int> mapped, expected(graph.begin(std::size_t(order[r])), graph.end(std::size_t(order[r])));
    for(const int* j = other.begin(r); j != other.end(r); ++j) mapped.push_back(order[std::size_t(*j)]);
    std::sort(mapped.begin(), mapped.end());
    std::sort(expected.begin(), expected.end());
    check(mapped == expected);
  }
  return 0;
}

struct Target
{
  const char* name;
  Test_one test_one;
  Mutate mutate; // null: libFuzzer's byte-level mutation
};

// Kept in step with scripts/run_fuzzers.sh, fuzz/CMakeLists.txt and the corpora in fuzz/corpus/.
const Target targets[] = {
  {"fuzz_point_reader", point_reader, nullptr},
  {"fuzz_ply", read_file<ply_name>, mutate_structure<fuzz::mutate_ply>},
  {"fuzz_off", read_file<off_name>, mutate_structure<fuzz::mutate_off>},
  {"fuzz_pcd", read_file<pcd_name>, mutate_structure<fuzz::mutate_pcd>},
  {"fuzz_pts_ptx", pts_ptx, mutate_pts_ptx},
  {"fuzz_las", read_file<las_name>, mutate_structure<fuzz::mutate_las>},
  {"fuzz_edit_json", edit_json, mutate_structure<fuzz::mutate_edit_json>},
  {"fuzz_sel_def", sel_def, nullptr},
  {"fuzz_region_spec", region_spec, nullptr},
  {"fuzz_neighborhoods", neighborhoods, nullptr},
};

const Target* chosen = nullptr;

} // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv)
{
  const char* program = *argc > 0 ? (*argv)[0] : "";
  const char* slash = std::strrchr(program, '/');
  const std::string name = slash ? slash + 1 : program;
  for(const Target& target : targets)
    if(name == target.name) chosen = &target;
  if(!chosen) {
    std::fprintf(stderr, "%s: start this program by the name of a target:", program);
    for(const Target& target : targets) std::fprintf(stderr, " %s", target.name);
    std::fprintf(stderr, "\n");
    std::exit(2);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  return chosen->test_one(data, size);
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                               unsigned seed)
{
  return chosen->mutate ? chosen->mutate(data, size, max_size, seed) : LLVMFuzzerMutate(data, size, max_size);
}
