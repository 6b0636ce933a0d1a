// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_BALANCED_FLOW_H
#define CGAL_EXT_INTERNAL_BALANCED_FLOW_H

#include <CGAL_ext/Balanced_flow_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

namespace CGAL_ext {
namespace internal {

/// `y = M x`, row-parallel; each row sums in storage order, as Eigen's own product does, so the result does
/// not depend on the thread count.
template <typename ConcurrencyTag>
void multiply_vector(const Sparse_row_matrix& M, const Eigen::VectorXd& x, Eigen::VectorXd& y)
{
  y.resize(M.rows());
  const int* outer = M.outerIndexPtr();
  const int* inner = M.innerIndexPtr();
  const double* values = M.valuePtr();
  for_range<ConcurrencyTag>(0, std::size_t(M.rows()), [&](std::size_t i) {
    double sum = 0;
    for(int e = outer[i]; e < outer[i + 1]; ++e) sum += values[e] * x[inner[e]];
    y[Eigen::Index(i)] = sum;
  });
}

/// BiCGSTAB with a Jacobi preconditioner from a zero start, step for step Eigen's `Eigen::BiCGSTAB` (same
/// restart rule, tolerance on the relative residual, at most 2n iterations, the same arithmetic per entry, so
/// the same bits), with its matrix products and vector updates row-parallel: Eigen's are single-threaded, and
/// the products were three quarters of the flow's time (doc/design.md, "A region of a large model"). The dot
/// products stay Eigen's (their summation order fixes the result). Throws `Numerical_failure` when the
/// tolerance is not reached.
template <typename ConcurrencyTag>
Eigen::VectorXd bicgstab_jacobi(const Sparse_row_matrix& M, const Eigen::VectorXd& rhs, double tolerance)
{
  const Eigen::Index n = M.rows();
  const Eigen::VectorXd inverse_diagonal =
    M.diagonal().unaryExpr([](double d) { return d != 0 ? 1.0 / d : 1.0; });
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  const double rhs_squared_norm = rhs.squaredNorm();
  if(rhs_squared_norm == 0) return x;
  Eigen::VectorXd r = rhs, r0 = r, v = Eigen::VectorXd::Zero(n), p = Eigen::VectorXd::Zero(n), y(n), z(n), s(n), t(n);
  double r0_squared_norm = r0.squaredNorm(), rho = 1, alpha = 1, w = 1;
  const double tolerance_squared = tolerance * tolerance * rhs_squared_norm;
  const double epsilon_squared = Eigen::NumTraits<double>::epsilon() * Eigen::NumTraits<double>::epsilon();
  Eigen::Index iteration = 0, restarts = 0;
  while(r.squaredNorm() > tolerance_squared && iteration < 2 * n) {
    const double rho_old = rho;
    rho = r0.dot(r);
    if(std::abs(rho) < epsilon_squared * r0_squared_norm) {
      // r has become orthogonal to r0: restart from the current residual.
      multiply_vector<ConcurrencyTag>(M, x, t);
      r = rhs - t;
      r0 = r;
      rho = r0_squared_norm = r.squaredNorm();
      if(restarts++ == 0) iteration = 0;
    }
    const double beta = (rho / rho_old) * (alpha / w);
    for_range<ConcurrencyTag>(0, std::size_t(n), [&](std::size_t i) {
      p[Eigen::Index(i)] = r[Eigen::Index(i)] + beta * (p[Eigen::Index(i)] - w * v[Eigen::Index(i)]);
      y[Eigen::Index(i)] = inverse_diagonal[Eigen::Index(i)] * p[Eigen::Index(i)];
    });
    multiply_vector<ConcurrencyTag>(M, y, v);
    alpha = rho / r0.dot(v);
    for_range<ConcurrencyTag>(0, std::size_t(n), [&](std::size_t i) {
      s[Eigen::Index(i)] = r[Eigen::Index(i)] - alpha * v[Eigen::Index(i)];
      z[Eigen::Index(i)] = inverse_diagonal[Eigen::Index(i)] * s[Eigen::Index(i)];
    });
    multiply_vector<ConcurrencyTag>(M, z, t);
    const double t_squared_norm = t.squaredNorm();
    w = t_squared_norm > 0 ? t.dot(s) / t_squared_norm : 0.0;
    for_range<ConcurrencyTag>(0, std::size_t(n), [&](std::size_t i) {
      x[Eigen::Index(i)] += alpha * y[Eigen::Index(i)] + w * z[Eigen::Index(i)];
      r[Eigen::Index(i)] = s[Eigen::Index(i)] - w * t[Eigen::Index(i)];
    });
    ++iteration;
  }
  const double residual = std::sqrt(r.squaredNorm() / rhs_squared_norm);
  if(!(residual <= tolerance) || !x.allFinite())
    throw Numerical_failure("balanced flow: the balance equation did not converge (" + std::to_string(iteration) +
                            " iterations, relative residual " + std::to_string(residual) + ")");
  return x;
}

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
  // Plain arrays, not Eigen's row expressions, for the reason edge_covariance (neighborhood_rotations.h) uses
  // them; the same arithmetic, entry by entry.
  static_assert(Dense::IsRowMajor || Dense::ColsAtCompileTime == 1, "rows of contiguous coordinates");
  const std::ptrdiff_t columns = std::ptrdiff_t(X.cols());
  Dense next(X.rows(), X.cols());
  for(unsigned int sweep = 0; sweep < sweeps; ++sweep) {
    const double* x = X.data();
    double* y = next.data();
    for_range<ConcurrencyTag>(0, std::size_t(K.rows()), [&](std::size_t i) {
      double* out = y + std::ptrdiff_t(i) * columns;
      std::copy_n(x + std::ptrdiff_t(i) * columns, columns, out);
      for(int e = K.outerIndexPtr()[i]; e < K.outerIndexPtr()[i + 1]; ++e) {
        const double w = K.valuePtr()[e], *neighbour = x + std::ptrdiff_t(K.innerIndexPtr()[e]) * columns;
        for(std::ptrdiff_t c = 0; c < columns; ++c) out[c] -= w * neighbour[c];
      }
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
  const Eigen::VectorXd h = bicgstab_jacobi<ConcurrencyTag>(system, mean - curvature, 1e-8);
  return positions + (normals.array().colwise() * h.array()).matrix();
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_BALANCED_FLOW_INSTANCES(EXTERN, Tag) \
  EXTERN template Matrix_n3 balanced_flow_base_surface<Tag>(const Sparse_row_matrix&, const Matrix_n3&, \
                                                            const Matrix_n3&, const Balanced_flow_settings&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_BALANCED_FLOW_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_BALANCED_FLOW_H
