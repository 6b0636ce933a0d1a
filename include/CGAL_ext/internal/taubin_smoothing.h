// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_TAUBIN_SMOOTHING_H
#define CGAL_EXT_INTERNAL_TAUBIN_SMOOTHING_H

#include <CGAL_ext/internal/Laplacian.h>

namespace CGAL_ext {
namespace internal {

/// Taubin's lambda|mu low-pass (1995): alternate a shrinking and an inflating Laplacian step, which removes
/// high frequencies without the shrinkage of plain Laplacian smoothing. A simple base surface for the detail
/// colour maps.
template <typename ConcurrencyTag>
Matrix_n3 taubin_smoothing(const Sparse_row_matrix& K, Matrix_n3 X, int iterations = 30, double shrink = 0.5,
                           double inflate = -0.53)
{
  Matrix_n3 KX;
  for(int it = 0; it < iterations; ++it)
    for(double step : {shrink, inflate}) {
      multiply<ConcurrencyTag>(K, X, KX);
      X -= step * KX;
    }
  return X;
}

} // namespace internal
} // namespace CGAL_ext

#endif
