// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The neighbourhood rule every algorithm uses (doc/design.md, "One neighbourhood rule") on fuzzed point sets whose
// coordinates are multiples of 1/4 in [0, 4), so that distances tie and points coincide often: each row is the
// brute-force closed ball of its point's k-th nearest, and the same set of points in another order gets the same
// balls; or a pile of duplicates is refused with Invalid_input, and only then.
#include "neighborhood_reference.h"

#include <CGAL_ext/internal/Neighbor_graph.h>

#include <CGAL/tags.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <numeric>
#include <random>
#include <vector>

namespace {

using namespace CGAL_ext::internal;

void check(bool holds)
{
  if(!holds) std::abort(); // libFuzzer saves the input
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
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
