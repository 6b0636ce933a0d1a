// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// The sparse-algebra cores of CGAL_ext compiled once for the project's own programs, tests, examples and
// benchmarks (doc/build_time.md): Laplacians, sparse products, the detail least squares and its
// factorisation, the balanced flow and the diffusion stencil, for each concurrency tag.
#include <CGAL_ext/internal/Detail_least_squares.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/balanced_flow.h>
#include <CGAL_ext/internal/detail_manipulation.h>
#include <CGAL_ext/internal/geometric_details.h>
#include <CGAL_ext/internal/ssp_diffusion.h>

namespace CGAL_ext {
namespace internal {

CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_SPARSE_PRODUCTS_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_LAPLACIAN_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_BUILD_LAPLACIAN_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_GEOMETRIC_DETAILS_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_DETAIL_LEAST_SQUARES_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_DETAIL_MANIPULATION_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_BALANCED_FLOW_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_SSP_DIFFUSION_INSTANCES, )

} // namespace internal
} // namespace CGAL_ext
