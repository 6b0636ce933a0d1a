// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_NEIGHBOR_GRAPH_H
#define CGAL_EXT_INTERNAL_NEIGHBOR_GRAPH_H

#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Kd_tree.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>

#include <boost/iterator/counting_iterator.hpp>

#include <algorithm>
#include <sstream>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// A neighbour graph in compressed sparse row form: the neighbours of vertex i are
/// `indices[offsets[i] .. offsets[i+1])`. Indices are `int`, Eigen's sparse storage index, so the arrays
/// feed a sparse matrix without conversion.
struct Neighbor_graph
{
  std::vector<int> offsets{0};
  std::vector<int> indices;

  std::size_t size() const { return offsets.size() - 1; }
  int degree(std::size_t i) const { return offsets[i + 1] - offsets[i]; }
  const int* begin(std::size_t i) const { return indices.data() + offsets[i]; }
  const int* end(std::size_t i) const { return indices.data() + offsets[i + 1]; }
};

/// Throws unless 0 < k < n (k counts neighbours, the point itself not included).
inline void check_neighbor_count(std::size_t k, std::size_t n, const char* who)
{
  if(k == 0 || k >= n) {
    std::ostringstream os;
    os << who << ": the number of neighbours k = " << k << " must be at least 1 and smaller than the number of points ("
       << n << ")";
    throw Invalid_input(os.str());
  }
}

/// Directed k-nearest-neighbour graph (each row holds exactly k other points, nearest first) with CGAL's
/// kd-tree, built once and queried in parallel. Returns an empty graph when cancelled.
template <typename ConcurrencyTag>
Neighbor_graph k_nearest_neighbor_graph(const Matrix_n3& positions, std::size_t k, Progress& progress)
{
  using SC = CGAL::Simple_cartesian<double>;
  using Point = SC::Point_3;
  const std::size_t n = std::size_t(positions.rows());

  std::vector<Point> points(n);
  for(std::size_t i = 0; i < n; ++i) points[i] = Point(positions(Eigen::Index(i), 0), positions(Eigen::Index(i), 1), positions(Eigen::Index(i), 2));
  using Point_pmap = CGAL::Pointer_property_map<Point>::const_type;
  using Base_traits = CGAL::Search_traits_3<SC>;
  using Traits = CGAL::Search_traits_adapter<int, Point_pmap, Base_traits>;
  using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
  using Tree = typename Search::Tree;
  using Distance = typename Search::Distance;

  const Point_pmap pmap(points.data());
  Tree tree(boost::counting_iterator<int>(0), boost::counting_iterator<int>(int(n)), typename Tree::Splitter(),
            Traits(pmap));
  tree.template build<ConcurrencyTag>();
  const Distance distance(pmap);

  Neighbor_graph graph;
  graph.offsets.resize(n + 1);
  for(std::size_t i = 0; i <= n; ++i) graph.offsets[i] = int(i * k);
  graph.indices.resize(n * k);
  // Ask for k + 1 to skip the point itself; with exact duplicates the point need not come first.
  const bool completed = for_each_index<ConcurrencyTag>(n, progress, [&](std::size_t i) {
    Search search(tree, points[i], unsigned(k + 1), 0, true, distance, true);
    int* out = graph.indices.data() + i * k;
    std::size_t m = 0;
    for(auto it = search.begin(); it != search.end() && m < k; ++it)
      if(std::size_t(it->first) != i) out[m++] = it->first;
  });
  if(!completed) return {};
  return graph;
}

/// Union of a directed graph and its transpose: j is a neighbour of i if either lists the other.
/// Rows come out sorted by index, free of duplicates and of self-loops.
template <typename ConcurrencyTag>
Neighbor_graph symmetrize(const Neighbor_graph& directed)
{
  const std::size_t n = directed.size();
  // Transpose by counting sort; filling in increasing i keeps each reversed row sorted.
  std::vector<int> reverse_offsets(n + 1, 0);
  for(int j : directed.indices) ++reverse_offsets[std::size_t(j) + 1];
  for(std::size_t i = 0; i < n; ++i) reverse_offsets[i + 1] += reverse_offsets[i];
  std::vector<int> reverse(directed.indices.size());
  {
    std::vector<int> fill(reverse_offsets.begin(), reverse_offsets.end() - 1);
    for(std::size_t i = 0; i < n; ++i)
      for(const int* j = directed.begin(i); j != directed.end(i); ++j) reverse[std::size_t(fill[std::size_t(*j)]++)] = int(i);
  }

  // Merge each sorted forward row with its reversed row: count first, then fill in place.
  std::vector<int> forward(directed.indices);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    std::sort(forward.begin() + directed.offsets[i], forward.begin() + directed.offsets[i + 1]);
  });
  auto merge_row = [&](std::size_t i, int* out) {
    const int *a = forward.data() + directed.offsets[i], *a_end = forward.data() + directed.offsets[i + 1];
    const int *b = reverse.data() + reverse_offsets[i], *b_end = reverse.data() + reverse_offsets[i + 1];
    int count = 0, last = -1;
    while(a != a_end || b != b_end) {
      const int v = (b == b_end || (a != a_end && *a < *b)) ? *a++ : *b++;
      if(v != last && v != int(i)) {
        if(out) out[count] = v;
        ++count;
        last = v;
      }
    }
    return count;
  };
  Neighbor_graph graph;
  graph.offsets.assign(n + 1, 0);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) { graph.offsets[i + 1] = merge_row(i, nullptr); });
  for(std::size_t i = 0; i < n; ++i) graph.offsets[i + 1] += graph.offsets[i];
  graph.indices.resize(std::size_t(graph.offsets[n]));
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) { merge_row(i, graph.indices.data() + graph.offsets[i]); });
  return graph;
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_NEIGHBOR_GRAPH_H
