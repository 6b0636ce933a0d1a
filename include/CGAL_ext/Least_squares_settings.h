// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_LEAST_SQUARES_SETTINGS_H
#define CGAL_EXT_LEAST_SQUARES_SETTINGS_H

#include <CGAL_ext/setting_names.h>
#include <CGAL_ext/exceptions.h>

#include <cmath>
#include <cstddef>
#include <string>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  How the detail least-squares problems (scaling, enhancement, editing) are solved.
*/
enum class Linear_solver
{
  /// Sparse Cholesky of the normal equations, factored once: CHOLMOD's supernodal `LL^T` when the package
  /// was configured with SuiteSparse, Eigen's `SimplicialLDLT` otherwise (and as the fallback when `LL^T`
  /// meets a pivot that rounding made non-positive). Iterative refinement against the exact residual.
  cholesky,
  /// Jacobi-preconditioned conjugate gradients on the normal equations (the paper's method), matrix-free:
  /// the normal matrix is never formed, which saves its assembly and memory on very large regions.
  conjugate_gradient
};

/// The names of `Linear_solver`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Linear_solver>
{
  static constexpr Setting_spelling<Linear_solver> table[] = {{"cholesky", Linear_solver::cholesky}, {"cg", Linear_solver::conjugate_gradient}};
};

/*!
  \ingroup PkgCGALExtRef
  Settings of the least-squares solve `min alpha ||f(K) u - r||^2 + sum_anchors ||u_a - t_a||^2`.
*/
struct Least_squares_settings
{
  Linear_solver solver = Linear_solver::cholesky;
  double detail_weight = 1.0;   ///< alpha, the weight of the detail equations (anchors weigh 1), > 0
  double tolerance = 1e-10;     ///< conjugate gradients stop at this relative residual of the normal equations
  int max_iterations = 100000;  ///< conjugate-gradient iteration cap (an unconverged solve is an error)
  /// Cholesky: iterative refinement stops once the relative residual of the normal equations is below this
  /// (or when a step no longer halves it, or after 5 steps). Each step costs one more back-substitution.
  double refinement_tolerance = 1e-14;
  /// A solve whose final relative residual of the normal equations is above this (for conjugate gradients:
  /// above twice `tolerance`, if that is larger) is a `Numerical_failure`, never a result. Healthy Cholesky
  /// solves end near 1e-14; a larger residual means the factorisation or the solve went wrong.
  double accepted_residual = 1e-8;
  /// Cholesky, quadric order, scaling and enhancement: a region of at least this many points is solved by
  /// conjugate gradients on N preconditioned by the Cholesky factor of the linear order's normal matrix (same
  /// anchors), to `tolerance`. That matrix couples points two neighbourhoods apart where N couples them four
  /// apart, so its factor is far smaller: on a 100k-point region of 1M samples of the armadillo, 1.3e10 flops and
  /// 2.0e7 non-zeros against 1.9e11 and 9.5e7 (doc/detail_scaling.md, "The solver").
  std::size_t preconditioned_from = 20000;
  /// With `preconditioned_from`: the preconditioner is `B^-1 + w D^-1`, the linear order's factor solve plus `w`
  /// times N's own diagonal (Jacobi), `w` this weight. The factor matches N on smooth displacements and falls
  /// short on the roughest ones, where Jacobi is at its best: on that 100k-point region, 14 iterations reach
  /// 1e-10 instead of 27. 0 leaves the factor alone.
  double preconditioner_diagonal_weight = 0.5;

  void validate() const
  {
    if(!(std::isfinite(detail_weight) && detail_weight > 0))
      throw Invalid_input("least squares: detail_weight (alpha) must be a finite number > 0");
    if(!(std::isfinite(tolerance) && tolerance > 0 && tolerance < 1))
      throw Invalid_input("least squares: tolerance must be in (0, 1)");
    if(!(refinement_tolerance > 0 && refinement_tolerance < 1))
      throw Invalid_input("least squares: refinement_tolerance must be in (0, 1)");
    if(!(accepted_residual > 0 && accepted_residual < 1))
      throw Invalid_input("least squares: accepted_residual must be in (0, 1)");
    if(max_iterations < 1)
      throw Invalid_input("least squares: max_iterations must be at least 1");
    if(!(std::isfinite(preconditioner_diagonal_weight) && preconditioner_diagonal_weight >= 0))
      throw Invalid_input("least squares: preconditioner_diagonal_weight must be a finite number >= 0");
  }
};

/*!
  \ingroup PkgCGALExtRef
  What a least-squares solve cost and how well it converged (for reports and benchmarks).
*/
struct Least_squares_statistics
{
  std::size_t unknowns = 0;          ///< points of the region of interest
  std::size_t anchors = 0;           ///< position constraints (soft, or exact and out of the unknowns)
  std::size_t operator_nonzeros = 0; ///< non-zeros of the ROI rows of `f(K)`
  /// Non-zeros of the factored matrix (both triangles): the normal matrix, or with `preconditioned_from` the
  /// preconditioner's; 0 for Jacobi conjugate gradients.
  std::size_t normal_nonzeros = 0;
  double assembly_seconds = 0;       ///< building `f(K)` rows and, for Cholesky, the normal matrix
  double factor_seconds = 0;
  double solve_seconds = 0;          ///< last solve, refinement included
  int iterations = 0;                ///< conjugate-gradient iterations, or refinement steps after the Cholesky solve
  double relative_residual = 0;      ///< `||b - N u|| / ||b||` of the normal equations after the last solve
  std::string method;                ///< the factorisation or iteration actually used
};

} // namespace CGAL_ext

#endif // CGAL_EXT_LEAST_SQUARES_SETTINGS_H
