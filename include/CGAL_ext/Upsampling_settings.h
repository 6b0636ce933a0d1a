// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_UPSAMPLING_SETTINGS_H
#define CGAL_EXT_UPSAMPLING_SETTINGS_H

#include <CGAL_ext/Sparse_direction_settings.h>
#include <CGAL_ext/exceptions.h>

#include <cstddef>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  Settings of `upsample_point_set`.
*/
struct Upsampling_settings
{
  Sparse_direction_settings detection; ///< spacing (the target spacing of the new samples) and largest hole
  unsigned int neighbors = 12;         ///< k of the principal axes and of the local surface fits, >= 6
  unsigned int relaxation_iterations = 5; ///< repulsion steps per round (10 cover 6 % better in a test, at twice the cost)
  unsigned int max_rounds = 4;         ///< detect, insert and relax at most this often (a wide hole fills in rounds)

  void validate() const
  {
    detection.validate();
    if(neighbors < 6) throw Invalid_input("upsampling: neighbors must be at least 6 (the surface fit has 6 coefficients)");
    if(max_rounds < 1) throw Invalid_input("upsampling: max_rounds must be at least 1");
  }
};

/*!
  \ingroup PkgCGALExtRef
  What `upsample_point_set` did.
*/
struct Upsampling_result
{
  bool completed = false;     ///< false when the callback cancelled (nothing was written)
  double spacing = 0;         ///< the target spacing used (local spacings: their median)
  std::size_t inserted = 0;   ///< new points written to the output
  std::size_t rounds = 0;     ///< detection rounds that inserted points
  std::size_t hole_boundary_points = 0; ///< input points on hole boundaries (first round)

  explicit operator bool() const { return completed; }
};

} // namespace CGAL_ext

#endif // CGAL_EXT_UPSAMPLING_SETTINGS_H
