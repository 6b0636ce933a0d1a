// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_BALANCED_FLOW_H
#define CGAL_EXT_INTERNAL_BALANCED_FLOW_H

#include <CGAL_ext/Balanced_flow_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/IterativeLinearSolvers>

#include <string>

namespace CGAL_ext {
namespace internal {

/*
  The base surface of the balanced flow (see Balanced_flow_settings for the model). With the normals n fixed
  and x = p + h n, the curvature term n_i . (K x)_i is c_i + (K_n h)_i, where c = n . (K p) and
  K_n[i][j] = K[i][j] (n_i . n_j). The flow dh/dt = -(c + K_n h - c_mean) - fidelity h is linear in h; it
  reaches its balance where

      (K_n + fidelity I) h = c_mean - c,     c_mean = W^m c,

  which is solved directly (BiCGSTAB, Jacobi preconditioner). K_n + fidelity I is strictly diagonally dominant
  (unit diagonal, off-diagonal row sums at most 1 in magnitude), so the balance exists, is unique, and the
  iteration converges; integrating the flow in time would only approach the same state.
*/
/// `m` sweeps of neighbour averaging, `X <- W X = X - K X`, on the columns of X.
template <typename ConcurrencyTag, typename Dense>
Dense neighbor_average(const Sparse_row_matrix& K, Dense X, unsigned int sweeps)
{
  Dense next(X.rows(), X.cols());
  for(unsigned int sweep = 0; sweep < sweeps; ++sweep) {
    for_range<ConcurrencyTag>(0, std::size_t(K.rows()), [&](std::size_t i) {
      next.row(Eigen::Index(i)) = X.row(Eigen::Index(i));
      for(int e = K.outerIndexPtr()[i]; e < K.outerIndexPtr()[i + 1]; ++e)
        next.row(Eigen::Index(i)) -= K.valuePtr()[e] * X.row(K.innerIndexPtr()[e]);
    });
    X.swap(next);
  }
  return X;
}

template <typename ConcurrencyTag>
Matrix_n3 balanced_flow_base_surface(const Sparse_row_matrix& K, const Matrix_n3& positions,
                                     const Matrix_n3& input_normals, const Balanced_flow_settings& settings)
{
  const std::size_t n = std::size_t(K.rows());
  // The flow moves along the base surface's normals, not the bumps' own (which tilt with every bump):
  // the input normals averaged over the same neighbourhood as the mean curvature.
  Matrix_n3 normals = neighbor_average<ConcurrencyTag>(K, input_normals, settings.mean_curvature_sweeps);
  for(std::size_t i = 0; i < n; ++i) {
    const double length = normals.row(Eigen::Index(i)).norm();
    normals.row(Eigen::Index(i)) = length > 1e-12 ? Eigen::RowVector3d(normals.row(Eigen::Index(i)) / length)
                                                  : Eigen::RowVector3d(input_normals.row(Eigen::Index(i)));
  }
  Matrix_n3 Kp;
  multiply<ConcurrencyTag>(K, positions, Kp);
  const Eigen::VectorXd curvature = (Kp.array() * normals.array()).rowwise().sum();
  const Eigen::VectorXd mean = neighbor_average<ConcurrencyTag>(K, curvature, settings.mean_curvature_sweeps);

  Sparse_row_matrix system = K;
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    for(int e = K.outerIndexPtr()[i]; e < K.outerIndexPtr()[i + 1]; ++e) {
      const int j = K.innerIndexPtr()[e];
      system.valuePtr()[e] = j == int(i) ? K.valuePtr()[e] + settings.fidelity
                                         : K.valuePtr()[e] * normals.row(Eigen::Index(i)).dot(normals.row(j));
    }
  });
  Eigen::BiCGSTAB<Sparse_row_matrix, Eigen::DiagonalPreconditioner<double>> solver(system);
  solver.setTolerance(1e-8);
  const Eigen::VectorXd h = solver.solve(mean - curvature);
  if(solver.info() != Eigen::Success || !h.allFinite())
    throw Numerical_failure("balanced flow: the balance equation did not converge (" +
                            std::to_string(solver.iterations()) + " iterations)");
  return positions + (normals.array().colwise() * h.array()).matrix();
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/parallel.h).
#define CGAL_EXT_BALANCED_FLOW_INSTANCES(EXTERN, Tag) \
  EXTERN template Matrix_n3 balanced_flow_base_surface<Tag>(const Sparse_row_matrix&, const Matrix_n3&, \
                                                            const Matrix_n3&, const Balanced_flow_settings&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_BALANCED_FLOW_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_BALANCED_FLOW_H
