// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_BALANCED_FLOW_SETTINGS_H
#define CGAL_EXT_BALANCED_FLOW_SETTINGS_H

#include <CGAL_ext/exceptions.h>

#include <cmath>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  The balanced curvature flow that gives the smooth base surface of detail enhancement and of the detail
  colour maps (after Xiao et al. 2006, cited by Miao et al. 2007, Sect. 4.2).

  Each point moves along its (fixed) normal `n_i`, `x_i = p_i + h_i n_i`, driven by two terms:
  - the curvature flow, with the discrete mean-curvature term `c_i = n_i . (K x)_i`, taken relative to its
    local mean over a wider neighbourhood (`mean_curvature_sweeps` rounds of neighbour averaging). On a
    sphere, a cylinder or a plane the curvature equals its local mean, so the flow does not move them: no
    shrinkage, thin parts stay as thick as they are. Bumps and wrinkles, whose curvature oscillates about the
    mean, are flattened;
  - the forcing term `-fidelity h_i`, which pulls every point back towards the input and keeps the base
    surface in a band around it.
  The base surface is the flow's balance (steady state), solved for directly: see `internal/balanced_flow.h`.

  More sweeps flatten longer wavelengths (the cut-off grows like the square root of the sweeps, in
  neighbourhood radii); a smaller fidelity flattens more completely. With the defaults, 95 %, 90 %, 92 % and
  85 % of the RMS of bumps of wavelength 4, 6, 8 and 12 average spacings are removed from a sphere, whose
  radius moves by 2e-5 (doc/detail_scaling.md).
*/
struct Balanced_flow_settings
{
  double fidelity = 0.005;                 ///< forcing-term weight, > 0 (eigenvalues of K lie in [0, 2])
  unsigned int mean_curvature_sweeps = 30; ///< neighbour-averaging rounds that define the local mean curvature

  void validate() const
  {
    if(!(std::isfinite(fidelity) && fidelity > 0))
      throw Invalid_input("balanced flow: fidelity must be a finite number > 0");
  }
};

} // namespace CGAL_ext

#endif // CGAL_EXT_BALANCED_FLOW_SETTINGS_H
