// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_COMPILED_INSTANCES_H
#define CGAL_EXT_INTERNAL_COMPILED_INSTANCES_H

#include <CGAL/tags.h>

/*
  Compiled instances. The numerical cores below the public API are templates on the concurrency tag alone, so
  the project's own programs, tests and benchmarks compile them once, in the `CGAL_ext_instances` library,
  instead of once per translation unit (doc/build_time.md). Each header lists its cores in a macro
  `LIST(EXTERN, Tag)` and passes it to `CGAL_EXT_DECLARE_COMPILED_INSTANCES`, which declares them `extern`
  when `CGAL_EXT_COMPILED_INSTANCES` is defined (by linking `CGAL_ext::instances`). A user of the header-only
  library defines nothing and sees no difference.
*/
#ifdef CGAL_LINKED_WITH_TBB
#define CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(LIST, EXTERN) LIST(EXTERN, CGAL::Sequential_tag) LIST(EXTERN, CGAL::Parallel_tag)
#else
#define CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(LIST, EXTERN) LIST(EXTERN, CGAL::Sequential_tag)
#endif
#ifdef CGAL_EXT_COMPILED_INSTANCES
#define CGAL_EXT_DECLARE_COMPILED_INSTANCES(LIST) CGAL_EXT_FOR_EACH_CONCURRENCY_TAG(LIST, extern)
#else
#define CGAL_EXT_DECLARE_COMPILED_INSTANCES(LIST)
#endif
// Where the cores are compiled, a translation unit sees only their declarations and skips the headers their
// definitions need (CGAL's jet fitting and its SVD, the MST orientation, the spatial sort): a third of such a
// unit's parse time. The instances library itself defines CGAL_EXT_DEFINING_INSTANCES.
#if !defined(CGAL_EXT_COMPILED_INSTANCES) || defined(CGAL_EXT_DEFINING_INSTANCES)
#define CGAL_EXT_CORE_DEFINITIONS
#endif

#endif // CGAL_EXT_INTERNAL_COMPILED_INSTANCES_H
