// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_LOCAL_FIT_SETTINGS_H
#define CGAL_EXT_LOCAL_FIT_SETTINGS_H

#include <CGAL_ext/setting_names.h>

namespace CGAL_ext {

// How the local surface is fitted around each point: the neighbour counts of normal estimation and of the
// curvature fit, and the curvature fit's method.

/// Default neighbour count (the point itself not counted) of normal estimation when a point set comes without
/// normals: each jet is fitted to the point and 17 neighbours, 18 points, as CGAL's `jet_estimate_normals` with
/// its k = 18.
constexpr unsigned int default_normal_neighbors = 17;

/*!
  \ingroup PkgCGALExtRef
  How the local surface is fitted to a point and its k nearest neighbours.
*/
enum class Curvature_fitting
{
  /// `CGAL::Monge_via_jet_fitting`, degree 2 (PCA frame, SVD fit, Monge form): the reference.
  monge_jet_fitting,
  /// A degree-2 height function `z = f + d x + e y + a x^2 + b xy + c y^2` fitted by least squares in the
  /// frame of the point's normal, with fixed-size Eigen matrices; `H` from the fit's derivatives at the point.
  /// Validated against the Monge fit in the tests; several times faster.
  closed_form
};

/// The names of `Curvature_fitting`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Curvature_fitting>
{
  static constexpr Setting_spelling<Curvature_fitting> table[] = {{"closed_form", Curvature_fitting::closed_form}, {"monge", Curvature_fitting::monge_jet_fitting},
                                                              {"closed-form", Curvature_fitting::closed_form, true}};
};

/// Default neighbour count of the curvature fit.
constexpr unsigned int default_curvature_neighbors = 15;

} // namespace CGAL_ext

#endif // CGAL_EXT_LOCAL_FIT_SETTINGS_H
