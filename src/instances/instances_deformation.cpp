// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// Detail_preserving_deformation compiled once for the project's own programs, tests, examples and
// benchmarks (doc/build_time.md), for each concurrency tag; its cores come from the other
// instance files.
#include <CGAL_ext/Detail_preserving_deformation.h>

namespace CGAL_ext {

CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_DEFORMATION_INSTANCES, )

} // namespace CGAL_ext
