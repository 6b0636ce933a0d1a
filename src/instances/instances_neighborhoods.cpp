// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// The neighbourhood cores of CGAL_ext compiled once for the project's own programs, tests, examples and
// benchmarks (doc/build_time.md): the spatial sort, neighbour graphs, oriented normals, curvature,
// mean shift, hole gaps, cluster splitting, rigid fits and the strength field, for each concurrency tag.
#include <CGAL_ext/internal/cluster_split.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/mean_curvature.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/neighborhood_rotations.h>
#include <CGAL_ext/internal/sparse_directions.h>
#include <CGAL_ext/internal/strength_field.h>

namespace CGAL_ext {
namespace internal {

CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_POINT_ARRAYS_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_NEIGHBOR_GRAPH_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_ORIENTED_NORMALS_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_MEAN_CURVATURE_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_MEAN_SHIFT_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_SPARSE_DIRECTIONS_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_CLUSTER_SPLIT_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_NEIGHBORHOOD_ROTATIONS_INSTANCES, )
CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(CGAL_EXT_STRENGTH_FIELD_INSTANCES, )

} // namespace internal
} // namespace CGAL_ext
