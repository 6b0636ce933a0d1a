// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_SPARSE_DIRECTION_SETTINGS_H
#define CGAL_EXT_SPARSE_DIRECTION_SETTINGS_H

#include <CGAL_ext/exceptions.h>

#include <cmath>
#include <cstddef>
#include <sstream>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  Settings of hole detection (Miao et al. 2007, Sect. 6.3; doc/upsampling.md).

  Around each point, the neighbours are projected onto its tangent plane; the principal axes `e1`, `e2` of
  their covariance split the plane into four quarters around `+e1`, `-e1`, `+e2`, `-e2`. A quarter with no
  sample within `2 h` (h the point's spacing) is *sparse*. A sparse direction is a hole boundary only if samples
  appear again along it (within 30 degrees) no farther than `max_hole_size` spacings: an open border, with
  nothing beyond it, is left alone.

  By default h is local (`compute_local_spacing`): an adaptively or randomly sampled surface is measured
  against its own density around each point, so its sparser parts are not taken for holes. A local-spacing
  quarter must also be empty within twice the largest quarter gap typical around the point (the median over it
  and its 15 nearest neighbours): the wide gaps that a random or anisotropic sampling has everywhere are not
  holes either (doc/upsampling.md, "Random samplings").
*/
struct Sparse_direction_settings
{
  double spacing = 0;        ///< target spacing h everywhere; 0 = each point's local spacing (`compute_local_spacing`)
  double max_hole_size = 6;  ///< in spacings, > 2: the widest gap that is a hole

  void validate() const
  {
    if(!(spacing >= 0) || !std::isfinite(spacing)) {
      std::ostringstream os;
      os << "sparse directions: spacing must be > 0 (or 0 for each point's local spacing), got " << spacing;
      throw Invalid_input(os.str());
    }
    if(!(max_hole_size > 2) || !std::isfinite(max_hole_size))
      throw Invalid_input("sparse directions: max_hole_size must be a finite number of spacings > 2");
  }
};

/*!
  \ingroup PkgCGALExtRef
  What `detect_sparse_directions` found.
*/
struct Sparse_direction_summary
{
  double spacing = 0;                ///< the spacing used (local spacings: their median)
  std::size_t sparse_points = 0;     ///< points with at least one sparse direction (hole or open border)
  std::size_t hole_boundary_points = 0; ///< points with a sparse direction across which samples reappear
};

} // namespace CGAL_ext

#endif // CGAL_EXT_SPARSE_DIRECTION_SETTINGS_H
