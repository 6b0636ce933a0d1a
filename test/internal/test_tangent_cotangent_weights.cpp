// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The point-set cotangent weights against the cotangent weights of known planar triangulations, and the
// identities of a Voronoi cell.
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/tangent_cotangent_weights.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace {

namespace in = CGAL_ext::internal;

/// Points of a plane through the origin with unit normal `normal`, at the plane coordinates `uv`.
in::Matrix_n3 embed(const std::vector<Eigen::Vector2d>& uv, const Eigen::Vector3d& normal)
{
  const Eigen::Vector3d t1 = normal.unitOrthogonal(), t2 = normal.cross(t1);
  in::Matrix_n3 points(Eigen::Index(uv.size()), 3);
  for(std::size_t i = 0; i < uv.size(); ++i) points.row(Eigen::Index(i)) = (uv[i].x() * t1 + uv[i].y() * t2).transpose();
  return points;
}

std::vector<double> weights_of(const in::Matrix_n3& points, const Eigen::Vector3d& normal, std::size_t k, in::Neighbor_graph& graph)
{
  in::Progress silent;
  graph = in::symmetrize<CGAL::Sequential_tag>(in::k_nearest_neighbor_graph<CGAL::Sequential_tag>(points, k, silent));
  const in::Matrix_n3 normals = normal.transpose().replicate(points.rows(), 1);
  return in::cotangent_edge_weights<CGAL::Sequential_tag>(points, normals, graph);
}

TEST(TangentCotangentWeights, EquilateralAndSquareLatticesGiveTheirTriangulationsWeights)
{
  // A triangular lattice of spacing h: each interior point's six nearest neighbours have cot 60 + cot 60 over
  // 2 = 1/sqrt(3); farther neighbours are not Delaunay neighbours. A square lattice: the four nearest have
  // weight 1, the diagonal ones 0 (their triangles' opposite angles are right angles).
  const Eigen::Vector3d normal = Eigen::Vector3d(1, 2, 3).normalized();
  for(const bool square : {false, true}) {
    std::vector<Eigen::Vector2d> uv;
    const int n = 15;
    for(int r = 0; r < n; ++r)
      for(int c = 0; c < n; ++c)
        uv.emplace_back(square ? c : c + 0.5 * (r % 2), square ? r : r * std::sqrt(3.0) / 2);
    in::Neighbor_graph graph;
    const std::vector<double> w = weights_of(embed(uv, normal), normal, 12, graph);
    std::size_t checked = 0;
    for(std::size_t i = 0; i < uv.size(); ++i) {
      const int r = int(i) / n, c = int(i) % n;
      if(r < 3 || r >= n - 3 || c < 3 || c >= n - 3) continue; // the lattice's border: cells clipped
      for(int e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e) {
        const double d = (uv[std::size_t(graph.indices[std::size_t(e)])] - uv[i]).norm();
        const double expected = d < 1.01 ? (square ? 1.0 : 1 / std::sqrt(3.0)) : in::least_cotangent_weight;
        EXPECT_NEAR(w[std::size_t(e)], expected, 1e-9) << (square ? "square" : "triangular") << " lattice, point " << i
                                                        << ", neighbour at " << d;
        ++checked;
      }
    }
    EXPECT_GT(checked, 81u * 6);
  }
}

TEST(TangentCotangentWeights, CellsOfAJitteredPlaneCloseAndAgreeFromBothEnds)
{
  // On a jittered plane each interior point's cell among its 12 nearest is its Voronoi cell, so (1) the two
  // ends of an edge see the same cell side (the weights agree before averaging: the mean equals either),
  // (2) sum_j w_ij (p_j - p_i) = 0 (the sides' outward normals times their lengths close the polygon: the
  // cotangent Laplacian of a linear function), and (3) sum_j w_ij |p_j - p_i|^2 / 4 sums to the plane's area.
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const int n = 30;
  std::vector<Eigen::Vector2d> uv;
  for(int r = 0; r < n; ++r)
    for(int c = 0; c < n; ++c) uv.emplace_back(c + jitter(random), r + jitter(random));
  const Eigen::Vector3d normal = Eigen::Vector3d(0, 0, 1);
  in::Neighbor_graph graph;
  const in::Matrix_n3 points = embed(uv, normal);
  const std::vector<double> w = weights_of(points, normal, 12, graph);

  std::vector<double> one_sided;
  in::Labelled_polygon cell;
  double interior_area = 0;
  for(std::size_t i = 0; i < uv.size(); ++i) {
    const int r = int(i) / n, c = int(i) % n;
    if(r < 4 || r >= n - 4 || c < 4 || c >= n - 4) continue;
    std::vector<Eigen::Vector2d> offsets;
    for(const int* j = graph.begin(i); j != graph.end(i); ++j) offsets.push_back(uv[std::size_t(*j)] - uv[i]);
    in::tangent_cotangent_weights(offsets, one_sided, cell);
    Eigen::Vector2d linear = Eigen::Vector2d::Zero();
    double area = 0;
    for(std::size_t e = 0; e < offsets.size(); ++e) {
      linear += one_sided[e] * offsets[e];
      area += one_sided[e] * offsets[e].squaredNorm() / 4;
      const double symmetric = w[std::size_t(graph.offsets[i]) + e];
      EXPECT_NEAR(std::max(one_sided[e], in::least_cotangent_weight), symmetric, 1e-9) << "point " << i << ", edge " << e;
    }
    EXPECT_LT(linear.norm(), 1e-12) << "point " << i;
    EXPECT_GT(area, 0.3);
    interior_area += area;
  }
  // The interior cells tile (n - 8)^2 unit squares, give or take the jitter along the interior's border.
  EXPECT_NEAR(interior_area / ((n - 8) * (n - 8)), 1.0, 0.05);
}

TEST(TangentCotangentWeights, TheCellsOfASphereCoverItsArea)
{
  // Fibonacci points on spheres of two radii, normals radial: the Voronoi cells in the tangent planes add up to
  // the sphere's area (CGAL's SRE_ARAP weighs its smooth-rotation term by that area), to within the cells'
  // flatness, and scale with the radius squared.
  for(const double radius : {1.0, 3.0}) {
    const std::size_t n = 4000;
    in::Matrix_n3 points(Eigen::Index(n), 3);
    const double golden = 3.14159265358979323846 * (3 - std::sqrt(5.0));
    for(std::size_t i = 0; i < n; ++i) {
      const double z = 1 - (2 * double(i) + 1) / double(n), r = std::sqrt(1 - z * z);
      points.row(Eigen::Index(i)) << radius * r * std::cos(golden * double(i)), radius * r * std::sin(golden * double(i)), radius * z;
    }
    in::Progress silent;
    const in::Neighbor_graph graph =
      in::symmetrize<CGAL::Sequential_tag>(in::k_nearest_neighbor_graph<CGAL::Sequential_tag>(points, 10, silent));
    const in::Matrix_n3 normals = points / radius;
    const double area = in::sampled_surface_area(points, graph, in::cotangent_edge_weights<CGAL::Sequential_tag>(points, normals, graph));
    const double exact = 4 * 3.14159265358979323846 * radius * radius;
    std::printf("sphere of radius %.0f, %zu points: cells cover %.5f of its area\n", radius, n, area / exact);
    EXPECT_NEAR(area / exact, 1.0, 0.01) << "radius " << radius;
  }
}

TEST(TangentCotangentWeights, BorderPointsAndDegenerateNeighbourhoodsStayFinite)
{
  // A point on a border (all neighbours on one side), a neighbour straight along the normal, and a point with
  // no spread at all.
  std::vector<double> w;
  in::Labelled_polygon cell;
  in::tangent_cotangent_weights({{1, 0}, {1, 1}, {0, 1}, {0, 0}}, w, cell);
  ASSERT_EQ(w.size(), 4u);
  for(double x : w) EXPECT_TRUE(std::isfinite(x) && x >= 0);
  EXPECT_GT(w[0], 0);
  EXPECT_GT(w[2], 0);
  EXPECT_EQ(w[3], 0); // the point itself, seen along the normal: no direction
  in::tangent_cotangent_weights({{0, 0}, {0, 0}}, w, cell);
  EXPECT_EQ(w, std::vector<double>(2, 0.0));
}

} // namespace
