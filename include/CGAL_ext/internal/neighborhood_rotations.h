// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_NEIGHBORHOOD_ROTATIONS_H
#define CGAL_EXT_INTERNAL_NEIGHBORHOOD_ROTATIONS_H

#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/tangent_cotangent_weights.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// The rotation `R` that minimises `sum_j |R e_j - e'_j|^2` given `covariance = sum_j e_j e'_j^T`: `V U^T` for
/// `covariance = U S V^T`, with the singular vector of the smallest singular value flipped where that product
/// would be a reflection (Sorkine and Alexa 2007). A flat neighbourhood (rank 2) still gives one rotation.
/// The right singular vectors come from the closed-form eigenvectors of `C^T C` (C the covariance), the left
/// ones of the two largest singular values from `C v` (Gram-Schmidt), the third from their cross product with
/// the handedness of V: about half the time of Eigen's JacobiSVD, and as exact on random and flat
/// neighbourhoods (doc/editing_arap.md, "As rigid as possible", measures both). A nearly collinear neighbourhood (its
/// middle singular value below a hundredth of the largest), where the closed-form eigenvectors of the two small
/// singular values lose their accuracy and the rotation about the line its optimum, takes the SVD. (A template,
/// so that only the files that call it instantiate the solvers.)
/// `best_rotation_by_svd` is the same rotation from Eigen's JacobiSVD.
template <typename Matrix3>
Matrix3 best_rotation_by_svd(const Matrix3& covariance)
{
  const Eigen::JacobiSVD<Matrix3> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3 v = svd.matrixV();
  if((v * svd.matrixU().transpose()).determinant() < 0) v.col(2) = -v.col(2);
  return v * svd.matrixU().transpose();
}

template <typename Matrix3>
Matrix3 best_rotation(const Matrix3& covariance)
{
  Eigen::SelfAdjointEigenSolver<Matrix3> eigen;
  eigen.computeDirect(covariance.transpose() * covariance); // eigenvalues ascending
  const Matrix3& v = eigen.eigenvectors();
  const Eigen::Vector3d largest = covariance * v.col(2), middle = covariance * v.col(1);
  const double largest_norm = largest.norm();
  const Eigen::Vector3d u2 = largest / largest_norm;
  Eigen::Vector3d u1 = middle - u2.dot(middle) * u2;
  const double middle_norm = u1.norm();
  if(!(middle_norm > 1e-2 * largest_norm)) return best_rotation_by_svd(covariance); // also a zero covariance
  u1 /= middle_norm;
  // (u0, u1, u2) as handed as V's columns, so that R = sum_k v_k u_k^T is a rotation, not a reflection.
  const Eigen::Vector3d u0 = v.col(0).dot(v.col(1).cross(v.col(2))) * u1.cross(u2);
  return v.col(2) * u2.transpose() + v.col(1) * u1.transpose() + v.col(0) * u0.transpose();
}

/// `sum_j w_j e_j e'_j^T` over the edges `e_j` from sample point `s` to its graph neighbours and their deformed
/// `e'_j`, each weighted by `weights` (one per entry of `graph.indices`; null: uniform), into the row-major
/// `covariance`; returns whether `s` or a neighbour moved. Plain arrays, not Eigen's small expressions: the
/// same time in a Release build, half of it under the sanitizers, where each expression's temporary is a
/// checked copy (doc/build_time.md).
template <typename Positions>
bool edge_covariance(const Positions& rest, const Positions& deformed, const Neighbor_graph& graph, std::size_t s,
                     const double* weights, double covariance[9])
{
  static_assert(Positions::IsRowMajor && Positions::ColsAtCompileTime == 3, "rows of three contiguous coordinates");
  const double *p = rest.data() + 3 * s, *q = deformed.data() + 3 * s;
  bool moved = p[0] != q[0] || p[1] != q[1] || p[2] != q[2];
  std::fill(covariance, covariance + 9, 0.0);
  for(const int* j = graph.begin(s); j != graph.end(s); ++j) {
    const double *a = rest.data() + 3 * std::ptrdiff_t(*j), *b = deformed.data() + 3 * std::ptrdiff_t(*j);
    moved = moved || a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
    const double w = weights ? weights[j - graph.indices.data()] : 1.0;
    const double e[3] = {w * (a[0] - p[0]), w * (a[1] - p[1]), w * (a[2] - p[2])};
    const double f[3] = {b[0] - q[0], b[1] - q[1], b[2] - q[2]};
    for(int r = 0; r < 3; ++r)
      for(int c = 0; c < 3; ++c) covariance[3 * r + c] += e[r] * f[c];
  }
  return moved;
}

/// The best rotation of the edges from sample point `s` to its graph neighbours, from `rest` to `deformed`,
/// each edge weighted by `weights` (one per entry of `graph.indices`; null: uniform). A sample point whose
/// neighbourhood did not move gets the identity exactly, so unmoved parts stay exact. (A template for the
/// reason `best_rotation` is one.)
template <typename Positions>
Eigen::Matrix3d fitted_rotation(const Positions& rest, const Positions& deformed, const Neighbor_graph& graph, std::size_t s,
                                const double* weights = nullptr)
{
  double covariance[9];
  if(!edge_covariance(rest, deformed, graph, s, weights, covariance)) return Eigen::Matrix3d::Identity();
  return best_rotation(Eigen::Matrix3d(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(covariance)));
}

/// The linear map `A` that best maps the edges `e_j` from sample point `s` to its graph neighbours onto their
/// deformed edges `e'_j`, held to the neighbourhood's `rotation` where the edges do not span space:
/// `min sum_j |A e_j - e'_j|^2 + mu |A - rotation|^2`, so `A = (sum_j e'_j e_j^T + mu R)(sum_j e_j e_j^T + mu I)^-1`,
/// with `mu` a tenth of `sum_j |e_j|^2`: a flat neighbourhood leaves its normal direction to `R`, and a
/// neighbourhood whose sample points the solve moved unevenly passes on less of that unevenness (doc/editing_diffusion.md,
/// "Sample point turns"). A neighbourhood moved rigidly gives that rotation.
/// `Linear_map_prior` is the part fixed by the rest positions, set up once per edit; a drag adds the deformed
/// edges as `edge_covariance`'s unweighted `covariance` (`sum_j e_j e'_j^T`, row-major).
struct Linear_map_prior
{
  Eigen::Matrix3d inverse_spread = Eigen::Matrix3d::Identity(); ///< `(sum_j e_j e_j^T + mu I)^-1`
  double mu = 0; ///< 0 where `s` has no edges or all of length zero: `A` is then `rotation`

  template <typename Positions>
  Linear_map_prior(const Positions& rest, const Neighbor_graph& graph, std::size_t s)
  {
    const Eigen::RowVector3d p = rest.row(Eigen::Index(s));
    Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
    for(const int* j = graph.begin(s); j != graph.end(s); ++j) {
      const Eigen::RowVector3d e = rest.row(*j) - p;
      spread += e.transpose() * e;
    }
    mu = 0.1 * spread.trace();
    if(mu > 0) inverse_spread = (spread + mu * Eigen::Matrix3d::Identity()).inverse();
    else mu = 0;
  }
  Linear_map_prior() = default;

  Eigen::Matrix3d fitted_linear_map(const double covariance[9], const Eigen::Matrix3d& rotation) const
  {
    if(mu == 0) return rotation;
    return (Eigen::Map<const Eigen::Matrix3d>(covariance) + mu * rotation) * inverse_spread; // column-major: the transpose
  }
};

/// `Linear_map_prior(rest, graph, s).fitted_linear_map(...)` in one call.
template <typename Positions>
Eigen::Matrix3d fitted_linear_map(const Positions& rest, const Positions& deformed, const Neighbor_graph& graph, std::size_t s,
                                  const Eigen::Matrix3d& rotation)
{
  double covariance[9];
  edge_covariance(rest, deformed, graph, s, nullptr, covariance);
  return Linear_map_prior(rest, graph, s).fitted_linear_map(covariance, rotation);
}

/// The local step of as-rigid-as-possible editing: `fitted_rotation` of each of the sample points `rows`
/// under the edge `weights` (empty: uniform), written to `rotations[s]`. With `smoothing` > 0, the
/// smooth-rotation term of SRE-ARAP (Levi and Gotsman 2015; CGAL's `SRE_ARAP`) joins each fit: the covariance
/// gains `smoothing * scale / d * R_j^T` for each of the d neighbours j that the term visits (all of them; with
/// weights, those of the Voronoi cell, as SRE-ARAP visits the 1-ring), `R_j` its rotation before this step
/// (`previous`, a buffer). The scale is `area` when it is > 0 (CGAL's: the surface's area, the same for every
/// sample point), otherwise the point's own `sum_j w_j |e_j|^2`, a weight that is the same at every sampling
/// density. A neighbourhood that did not move among neighbours that did not turn keeps the identity exactly.
template <typename ConcurrencyTag>
void fit_neighborhood_rotations(const Matrix_n3& rest, const Matrix_n3& deformed, const Neighbor_graph& graph,
                                const std::vector<double>& weights, const std::vector<int>& rows, double smoothing,
                                double area, std::vector<Eigen::Matrix3d>& rotations, std::vector<Eigen::Matrix3d>& previous)
{
  const double* w = weights.empty() ? nullptr : weights.data();
  if(!(smoothing > 0)) {
    for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t r) {
      const std::size_t s = std::size_t(rows[r]);
      rotations[s] = fitted_rotation(rest, deformed, graph, s, w);
    });
    return;
  }
  previous = rotations;
  for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t r) {
    const std::size_t s = std::size_t(rows[r]);
    double edges[9];
    bool moved = edge_covariance(rest, deformed, graph, s, w, edges);
    Eigen::Matrix3d turns = Eigen::Matrix3d::Zero();
    const double* p = rest.data() + 3 * s;
    double spread = 0, degree = 0;
    for(const int* j = graph.begin(s); j != graph.end(s); ++j) {
      moved = moved || !previous[std::size_t(*j)].isIdentity(0);
      const double weight = w ? w[j - graph.indices.data()] : 1.0;
      const double* a = rest.data() + 3 * std::ptrdiff_t(*j);
      spread += weight * ((a[0] - p[0]) * (a[0] - p[0]) + (a[1] - p[1]) * (a[1] - p[1]) + (a[2] - p[2]) * (a[2] - p[2]));
      if(w && !(weight > least_cotangent_weight)) continue; // not a Delaunay neighbour
      turns += previous[std::size_t(*j)].transpose();
      ++degree;
    }
    const double pull = degree > 0 ? smoothing * (area > 0 ? area : spread) / degree : 0.0;
    const Eigen::Matrix3d covariance = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(edges);
    rotations[s] = moved ? best_rotation(Eigen::Matrix3d(covariance + pull * turns)) : Eigen::Matrix3d::Identity();
  });
}

/// The global step of as-rigid-as-possible editing as least squares: one row `sqrt(w_ij) (u_i - u_j)` per
/// edge `i < j` of the (symmetric) graph with an end in the region, on the region's columns (`local[s]`, -1
/// outside; fixed sample points do not move), `w_ij` from `weights` (one per entry of `graph.indices`, equal
/// both ways; empty: 1). Writes the edges and their `sqrt(w_ij)` (`scales`, empty when uniform). Its normal
/// matrix is the region's weighted graph Laplacian, and the solution for the right-hand side of
/// `rigid_edge_change` minimises the ARAP energy (Sorkine and Alexa 2007) for given rotations, so the
/// alternation with `fit_neighborhood_rotations` under the same weights never increases it.
inline Sparse_row_matrix rigid_edge_rows(const Neighbor_graph& graph, const std::vector<double>& weights,
                                         const std::vector<int>& local, std::size_t region_size,
                                         std::vector<std::pair<int, int>>& edges, std::vector<double>& scales)
{
  edges.clear();
  scales.clear();
  std::vector<Eigen::Triplet<double, int>> entries;
  for(std::size_t i = 0; i < graph.size(); ++i)
    for(const int* j = graph.begin(i); j != graph.end(i); ++j) {
      if(*j <= int(i) || (local[i] < 0 && local[std::size_t(*j)] < 0)) continue;
      const int row = int(edges.size());
      const double scale = weights.empty() ? 1.0 : std::sqrt(weights[std::size_t(j - graph.indices.data())]);
      edges.emplace_back(int(i), *j);
      if(!weights.empty()) scales.push_back(scale);
      if(local[i] >= 0) entries.emplace_back(row, local[i], scale);
      if(local[std::size_t(*j)] >= 0) entries.emplace_back(row, local[std::size_t(*j)], -scale);
    }
  Sparse_row_matrix A(Eigen::Index(edges.size()), Eigen::Index(region_size));
  A.setFromTriplets(entries.begin(), entries.end());
  return A;
}

/// Right-hand side of the global step: for each edge, `((R_i + R_j) / 2 - I)(s_i - s_j)`, the change of the
/// edge both ends' rotations ask for on average, times its `scales` entry (empty: 1).
template <typename ConcurrencyTag>
Matrix_n3 rigid_edge_change(const std::vector<std::pair<int, int>>& edges, const std::vector<double>& scales,
                            const Matrix_n3& rest, const std::vector<Eigen::Matrix3d>& rotations)
{
  Matrix_n3 change(Eigen::Index(edges.size()), 3);
  for_range<ConcurrencyTag>(0, edges.size(), [&](std::size_t e) {
    // Plain arrays for the reason edge_covariance uses them; the rotations are column-major.
    const auto [i, j] = edges[e];
    const double *a = rotations[std::size_t(i)].data(), *b = rotations[std::size_t(j)].data();
    const double *x = rest.data() + 3 * std::ptrdiff_t(i), *y = rest.data() + 3 * std::ptrdiff_t(j);
    const double d[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
    const double scale = scales.empty() ? 1.0 : scales[e];
    double* out = change.data() + 3 * e;
    for(int r = 0; r < 3; ++r) {
      double sum = 0;
      for(int c = 0; c < 3; ++c) sum += (0.5 * (a[3 * c + r] + b[3 * c + r]) - (r == c ? 1.0 : 0.0)) * d[c];
      out[r] = scale * sum;
    }
  });
  return change;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_NEIGHBORHOOD_ROTATIONS_INSTANCES(EXTERN, Tag) \
  EXTERN template void fit_neighborhood_rotations<Tag>(const Matrix_n3&, const Matrix_n3&, const Neighbor_graph&, \
                                                       const std::vector<double>&, const std::vector<int>&, double, \
                                                       double, std::vector<Eigen::Matrix3d>&, std::vector<Eigen::Matrix3d>&); \
  EXTERN template Matrix_n3 rigid_edge_change<Tag>(const std::vector<std::pair<int, int>>&, const std::vector<double>&, \
                                                   const Matrix_n3&, const std::vector<Eigen::Matrix3d>&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_NEIGHBORHOOD_ROTATIONS_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_NEIGHBORHOOD_ROTATIONS_H
