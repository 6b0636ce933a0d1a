// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_MEAN_SHIFT_SETTINGS_H
#define CGAL_EXT_MEAN_SHIFT_SETTINGS_H

#include <CGAL_ext/setting_names.h>
#include <CGAL_ext/Local_fit_settings.h>
#include <CGAL_ext/exceptions.h>

#include <cmath>
#include <sstream>
#include <string>

namespace CGAL_ext {

/// Default number of candidate neighbours of the mean shift (and of its curvature fit).
constexpr unsigned int default_mean_shift_neighbors = default_curvature_neighbors;

/*!
  \ingroup PkgCGALExtRef
  Kernel of the mean shift. The mode moves to the mean of the samples weighted by the kernel's shadow
  profile `g` (Comaniciu and Meer 2002), evaluated on the squared normalised distances `d_s^2`
  (spatial part) and `d_r^2` (range part).
*/
enum class Mean_shift_kernel
{
  /// `g = exp(-(d_s^2 + d_r^2) / 2)`: smooth, every candidate counts a little.
  gaussian,
  /// The mean shift of the Epanechnikov kernel: `g = 1` where `d_s <= 1` and `d_r <= 1`, else 0, so the mode
  /// moves to the plain mean of the samples within one bandwidth of it in both parts.
  epanechnikov
};

/// The names of `Mean_shift_kernel`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Mean_shift_kernel>
{
  static constexpr Setting_spelling<Mean_shift_kernel> table[] = {{"gaussian", Mean_shift_kernel::gaussian}, {"epanechnikov", Mean_shift_kernel::epanechnikov}};
};

/*!
  \ingroup PkgCGALExtRef
  What the stopping test of the mean shift measures.
*/
enum class Mean_shift_stop
{
  /// The step of the whole mode: position, normal and curvature (modes wanted in full,
  /// `compute_mean_shift_modes`).
  whole_mode,
  /// The step of the range part only, normal and curvature: what the clustering and the mean-shift
  /// neighbourhoods compare. Where normals and curvature vary little, the position part drifts along the
  /// surface for many steps after the range part has settled (doc/simplification.md, "When a mode stops").
  range_part
};

/*!
  \ingroup PkgCGALExtRef
  Settings of the joint spatial-range mean shift (Miao et al. 2007, Sect. 5.1; Comaniciu and Meer 2002)
  over the 7D features `(x, y, z, n_x, n_y, n_z, c H)` of the points: position, unit normal and mean
  curvature `H` scaled by `c`. A value of 0 for a bandwidth or for `curvature_scale` selects the automatic
  rule, so a user need not tune them:

  - `spatial_bandwidth = 0`: the average spacing, the mean distance of a point to its candidate neighbours;
  - `range_bandwidth` is dimensionless (normals are unit vectors): 0.5 by default, the distance between
    two unit normals 29 degrees apart;
  - `curvature_scale = 0`: `c = 0.5 / H90`, `H90` the 90th percentile of `|H|` over the points (at least
    `0.01 / spatial_bandwidth`, so a flat model does not blow the scaled curvature up): a point of curvature
    `H90` and a flat one are one default range bandwidth apart, as are normals 29 degrees apart.
*/
struct Mean_shift_settings
{
  Mean_shift_kernel kernel = Mean_shift_kernel::gaussian;
  double spatial_bandwidth = 0; ///< `h_s`, in the points' units; 0 = the average spacing
  double range_bandwidth = 0.5; ///< `h_r`, over the normal and the scaled curvature; > 0
  double curvature_scale = 0;   ///< `c`, multiplies `H` in the range part; 0 = `0.5 / H90`
  /// The iteration stops when the mode (or its range part, see `stop`) moves by less than this, in
  /// bandwidths (normalised 7D units).
  double tolerance = 1e-3;
  Mean_shift_stop stop = Mean_shift_stop::whole_mode; ///< what `tolerance` measures
  unsigned int max_iterations = 30; ///< iteration cap per point, >= 1

  /// Throws `Invalid_input` for negative, zero (the range bandwidth) or non-finite values.
  void validate() const
  {
    auto check = [](const char* name, double value, bool zero_allowed) {
      if(!(std::isfinite(value) && (value > 0 || (zero_allowed && value == 0)))) {
        std::ostringstream os;
        os << "mean shift settings: " << name << " must be finite and " << (zero_allowed ? ">= 0 (0: automatic)" : "> 0")
           << " (got " << value << ")";
        throw Invalid_input(os.str());
      }
    };
    check("spatial_bandwidth", spatial_bandwidth, true);
    check("range_bandwidth", range_bandwidth, false);
    check("curvature_scale", curvature_scale, true);
    check("tolerance", tolerance, false);
    if(max_iterations < 1) throw Invalid_input("mean shift settings: max_iterations must be at least 1");
  }
};

/*!
  \ingroup PkgCGALExtRef
  The default settings with the stop of a mean shift whose modes are compared by their range parts only
  (`Mean_shift_stop::range_part`): the default of `Simplification_settings` and `Detail_settings`.
*/
inline Mean_shift_settings range_part_mean_shift_settings()
{
  Mean_shift_settings settings;
  settings.stop = Mean_shift_stop::range_part;
  return settings;
}

/*!
  \ingroup PkgCGALExtRef
  The mean-shift mode of a point in the joint spatial-range domain, in the points' own units: the position
  part, the normal part (a kernel-weighted mean of unit normals, so of length at most 1) and the mean
  curvature part (the scaled curvature divided by the curvature scale again).
*/
template <typename Kernel>
struct Mean_shift_mode
{
  typename Kernel::Point_3 position;
  typename Kernel::Vector_3 normal;
  typename Kernel::FT mean_curvature{0};
  unsigned int iterations = 0; ///< mean-shift steps taken
};

/*!
  \ingroup PkgCGALExtRef
  What a mean shift did: the scales it used (after the automatic rules of `Mean_shift_settings`) and its
  iteration counts.
*/
struct Mean_shift_result
{
  bool completed = false; ///< false when the callback cancelled
  double spatial_bandwidth = 0;
  double range_bandwidth = 0;
  double curvature_scale = 0;
  double mean_iterations = 0;
  unsigned int max_iterations = 0;  ///< the most steps any point took
  std::size_t points_at_cap = 0;    ///< points stopped by the iteration cap rather than the tolerance

  explicit operator bool() const { return completed; }
};

} // namespace CGAL_ext

#endif // CGAL_EXT_MEAN_SHIFT_SETTINGS_H
