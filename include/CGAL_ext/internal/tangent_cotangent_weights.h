// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_TANGENT_COTANGENT_WEIGHTS_H
#define CGAL_EXT_INTERNAL_TANGENT_COTANGENT_WEIGHTS_H

// Cotangent weights for a point set's neighbour graph, from each point's Voronoi cell among its neighbours in
// its tangent plane (doc/design.md, "Rigid edge weights").

#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// The smallest weight an edge keeps, so that the weighted graph joins what the graph joins: cotangent weights
/// are ratios of lengths, about 0.5 to 1 on an even sampling.
constexpr double least_cotangent_weight = 1e-3;

/// A convex polygon in the plane, each edge labelled by the half-plane that cut it (-1: the starting disc).
/// One polygon serves point after point (`reset`), so the clipping allocates nothing once warm.
class Labelled_polygon
{
public:
  /// Makes it the regular polygon of `sides` sides circumscribing the circle of `radius` about the origin.
  void reset(double radius, int sides)
  {
    m_vertices.clear();
    m_labels.clear();
    constexpr double pi = 3.14159265358979323846;
    const double r = radius / std::cos(pi / sides);
    for(int s = 0; s < sides; ++s) {
      const double angle = 2 * pi * (s + 0.5) / sides;
      m_vertices.emplace_back(r * std::cos(angle), r * std::sin(angle));
      m_labels.push_back(-1);
    }
  }

  /// Keeps the part where `normal . x <= offset`; the new edge along the line is labelled `label`.
  void clip(const Eigen::Vector2d& normal, double offset, int label)
  {
    m_next_vertices.clear();
    m_next_labels.clear();
    const std::size_t n = m_vertices.size();
    for(std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d& a = m_vertices[i];
      const Eigen::Vector2d& b = m_vertices[(i + 1) % n];
      const double da = normal.dot(a) - offset, db = normal.dot(b) - offset;
      if(da <= 0) {
        m_next_vertices.push_back(a);
        m_next_labels.push_back(m_labels[i]);
      }
      if((da <= 0) != (db <= 0)) { // the edge crosses the line: entering keeps the edge's label, leaving starts the line's
        m_next_vertices.push_back(a + (da / (da - db)) * (b - a));
        m_next_labels.push_back(da <= 0 ? label : m_labels[i]);
      }
    }
    std::swap(m_vertices, m_next_vertices);
    std::swap(m_labels, m_next_labels);
  }

  std::size_t size() const { return m_vertices.size(); }
  int label(std::size_t i) const { return m_labels[i]; }
  /// The length of edge i (from vertex i to the next).
  double edge_length(std::size_t i) const { return (m_vertices[(i + 1) % m_vertices.size()] - m_vertices[i]).norm(); }

private:
  std::vector<Eigen::Vector2d> m_vertices, m_next_vertices;
  std::vector<int> m_labels, m_next_labels;
};

/// One point's cotangent weights toward its neighbours `offsets` (edges to them projected onto its tangent
/// plane, coordinates in that plane): the length of the edge its Voronoi cell among them shares with each,
/// over the distance to it, which on a planar Delaunay triangulation is `(cot a + cot b) / 2` of the edge; 0
/// for a neighbour whose bisector does not bound the cell. The cell is clipped to the disc through the farthest
/// neighbour, which bounds it where the point lies on a border. Written to `weights` (one per offset); `cell`
/// is scratch space.
inline void tangent_cotangent_weights(const std::vector<Eigen::Vector2d>& offsets, std::vector<double>& weights,
                                      Labelled_polygon& cell)
{
  weights.assign(offsets.size(), 0.0);
  double radius = 0;
  for(const Eigen::Vector2d& q : offsets) radius = std::max(radius, q.norm());
  if(!(radius > 0)) return;
  cell.reset(radius, 32);
  for(std::size_t j = 0; j < offsets.size(); ++j) {
    const double length = offsets[j].norm();
    if(length > 1e-9 * radius) cell.clip(offsets[j], 0.5 * offsets[j].squaredNorm(), int(j)); // the bisector
  }
  for(std::size_t e = 0; e < cell.size(); ++e)
    if(cell.label(e) >= 0) weights[std::size_t(cell.label(e))] += cell.edge_length(e);
  for(std::size_t j = 0; j < offsets.size(); ++j)
    if(weights[j] > 0) weights[j] /= offsets[j].norm();
}

/// Cotangent weights of the symmetric `graph` over `positions` with unit `normals` (their sign does not
/// matter): each point's `tangent_cotangent_weights` among its graph neighbours, each edge the mean of its
/// two ends' values, at least `least_cotangent_weight`. One weight per entry of `graph.indices`, equal for
/// both directions of an edge.
template <typename ConcurrencyTag>
std::vector<double> cotangent_edge_weights(const Matrix_n3& positions, const Matrix_n3& normals, const Neighbor_graph& graph)
{
  std::vector<double> one_sided(graph.indices.size(), 0.0);
  for_range<ConcurrencyTag>(0, graph.size(), [&](std::size_t i) {
    const Eigen::Vector3d n = normals.row(Eigen::Index(i)).transpose().normalized();
    const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
    thread_local std::vector<Eigen::Vector2d> offsets; // scratch, reused from point to point
    thread_local std::vector<double> weights;
    thread_local Labelled_polygon cell;
    offsets.clear();
    for(const int* j = graph.begin(i); j != graph.end(i); ++j) {
      const Eigen::Vector3d e = (positions.row(*j) - positions.row(Eigen::Index(i))).transpose();
      offsets.emplace_back(e.dot(t1), e.dot(t2));
    }
    tangent_cotangent_weights(offsets, weights, cell);
    std::copy(weights.begin(), weights.end(), one_sided.begin() + graph.offsets[i]);
  });
  // The same edge seen from its other end: graph rows are sorted, so a binary search finds it.
  std::vector<double> weights(graph.indices.size());
  for_range<ConcurrencyTag>(0, graph.size(), [&](std::size_t i) {
    for(int e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e) {
      const std::size_t j = std::size_t(graph.indices[std::size_t(e)]);
      const int* back = std::lower_bound(graph.begin(j), graph.end(j), int(i));
      const double other = (back != graph.end(j) && *back == int(i)) ? one_sided[std::size_t(back - graph.indices.data())] : 0.0;
      weights[std::size_t(e)] = std::max(least_cotangent_weight, 0.5 * (one_sided[std::size_t(e)] + other));
    }
  });
  return weights;
}

/// The area of the surface that `positions` sample: the sum of their Voronoi cells, each `sum_j w_ij |e_ij|^2 / 4`
/// under `cotangent_edge_weights` (one per entry of `graph.indices`): its side toward j times half the edge,
/// halved.
inline double sampled_surface_area(const Matrix_n3& positions, const Neighbor_graph& graph, const std::vector<double>& weights)
{
  double area = 0;
  for(std::size_t i = 0; i < graph.size(); ++i)
    for(int e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e)
      area += 0.25 * weights[std::size_t(e)] *
              (positions.row(graph.indices[std::size_t(e)]) - positions.row(Eigen::Index(i))).squaredNorm();
  return area;
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_TANGENT_COTANGENT_WEIGHTS_H
