// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DETAIL_FILTER_H
#define CGAL_EXT_DETAIL_FILTER_H

#include <CGAL_ext/setting_names.h>
#include <CGAL_ext/Mean_shift_settings.h>
#include <CGAL_ext/exceptions.h>

#include <cmath>
#include <sstream>
#include <string>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  Order of the transfer function `f(K)` of the point-set Laplacian `K` that defines geometric details
  (Miao et al. 2007, Sect. 3).
*/
enum class Detail_order
{
  linear,  ///< `f(k) = k / lambda`
  quadric, ///< `f(k) = (1/lambda + 1/mu) k - k^2 / (lambda mu)`
  cubic    ///< `f(k) = (1/lambda^2 + 1/(lambda mu) + 1/mu^2) k^2 - (1/(lambda mu)) (1/lambda + 1/mu) k^3`
};

/// The names of `Detail_order`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Detail_order>
{
  static constexpr Setting_spelling<Detail_order> table[] = {{"linear", Detail_order::linear}, {"quadric", Detail_order::quadric}, {"cubic", Detail_order::cubic}};
};

/*!
  \ingroup PkgCGALExtRef
  A high-frequency transfer function of the Laplacian: its order, the pass-band frequency `lambda` and the
  highest frequency `mu`. The defaults are the paper's (Fig. 3i, 4): quadric, `lambda = 0.8`, `mu = 1.6`.

  The detail vectors of the points `p` are `f(K) p`, a polynomial of degree at most 3 in `K`, applied with
  sparse matrix products.
*/
struct Detail_filter
{
  Detail_order order = Detail_order::quadric;
  double lambda = 0.8; ///< pass-band frequency, > 0
  double mu = 1.6;     ///< highest frequency, > lambda; unused by the linear order

  /// Coefficients `c1, c2, c3` of `f(k) = c1 k + c2 k^2 + c3 k^3`.
  struct Coefficients { double c1 = 0, c2 = 0, c3 = 0; };

  /// Throws `Invalid_input` unless `lambda > 0`, both are finite and, for the orders that use `mu`, `mu > lambda`.
  void validate() const
  {
    if(!(std::isfinite(lambda) && lambda > 0)) {
      std::ostringstream os;
      os << "detail filter: lambda must be a finite number > 0 (got " << lambda << ")";
      throw Invalid_input(os.str());
    }
    if(order != Detail_order::linear && !(std::isfinite(mu) && mu > lambda)) {
      std::ostringstream os;
      os << "detail filter: mu must be finite and greater than lambda for the " << order_name(order)
         << " order (got lambda = " << lambda << ", mu = " << mu << ")";
      throw Invalid_input(os.str());
    }
  }

  /// The polynomial's coefficients. Does not validate.
  Coefficients coefficients() const
  {
    const double il = 1.0 / lambda, im = 1.0 / mu;
    switch(order) {
      case Detail_order::linear: return {il, 0, 0};
      case Detail_order::quadric: return {il + im, -il * im, 0};
      case Detail_order::cubic: return {0, il * il + il * im + im * im, -il * im * (il + im)};
    }
    return {};
  }

  /// Evaluates the transfer function on an eigenvalue `k` of the Laplacian.
  double response(double k) const
  {
    const Coefficients c = coefficients();
    return ((c.c3 * k + c.c2) * k + c.c1) * k;
  }

  /// Highest power of `K` the filter uses (1, 2 or 3).
  int degree() const { return order == Detail_order::linear ? 1 : order == Detail_order::quadric ? 2 : 3; }

  static const char* order_name(Detail_order o) { return setting_name(o); }
};

/*!
  \ingroup PkgCGALExtRef
  How the Laplacian `K = I - W` weighs the neighbours `j` of a point `i` (weights of a row sum to 1).
*/
enum class Laplacian_weighting
{
  uniform,       ///< `w_ij = 1 / d_i`, `d_i` the number of neighbours (the paper's simple choice)
  distance_power ///< `w_ij` proportional to `||p_i - p_j||^t`, `t = distance_power` (the paper uses `t = -1`)
};

/// The names of `Laplacian_weighting`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Laplacian_weighting>
{
  static constexpr Setting_spelling<Laplacian_weighting> table[] = {{"uniform", Laplacian_weighting::uniform}, {"distance", Laplacian_weighting::distance_power}};
};

/*!
  \ingroup PkgCGALExtRef
  Weights of the point-set Laplacian. Distances below 1e-6 of the row's mean neighbour distance (exact
  duplicates) are raised to it, so a negative power stays finite; a row whose neighbours all coincide with the
  point gets uniform weights.
*/
struct Laplacian_weights
{
  Laplacian_weighting weighting = Laplacian_weighting::uniform;
  double distance_power = -1.0; ///< exponent `t`; used by `Laplacian_weighting::distance_power` only

  void validate() const
  {
    if(!std::isfinite(distance_power))
      throw Invalid_input("Laplacian weights: distance_power must be finite");
  }
};

/*!
  \ingroup PkgCGALExtRef
  Which neighbours a row of the Laplacian connects.
*/
enum class Laplacian_neighborhood
{
  k_nearest, ///< the symmetrised k-nearest-neighbour graph
  mean_shift ///< the k nearest whose mean-shift modes agree (Miao et al. 2007, Sect. 5.1; needs normals)
};

/// The names of `Laplacian_neighborhood`'s values in the edit files, the program's options, the reports and Python.
template <>
struct Setting_names<Laplacian_neighborhood>
{
  static constexpr Setting_spelling<Laplacian_neighborhood> table[] = {{"knn", Laplacian_neighborhood::k_nearest}, {"mean_shift", Laplacian_neighborhood::mean_shift},
                                                                   {"mean-shift", Laplacian_neighborhood::mean_shift, true}};
};

/// Default neighbour count of the Laplacian (doc/geometric_details.md, "Defaults").
constexpr unsigned int default_laplacian_neighbors = 10;

/*!
  \ingroup PkgCGALExtRef
  Everything that defines the geometric details besides the neighbour count: the transfer function, the
  Laplacian's weights and its neighbourhoods. Implicitly constructible from a `Detail_filter`.

  With `Laplacian_neighborhood::mean_shift`, the `k` nearest neighbours of a point are candidates and a row keeps
  those whose mean-shift modes (`mean_shift`, run on max(k, 15) neighbours) lie within one range bandwidth of the
  point's mode, at least 3 of them (the nearest modes fill up); the graph is then symmetrised. A point's
  neighbourhood thus stops at creases and curvature changes, so details there are not smeared across them.
*/
struct Detail_settings
{
  Detail_filter filter;
  Laplacian_weights weights;
  Laplacian_neighborhood neighborhood = Laplacian_neighborhood::k_nearest;
  /// Used by `Laplacian_neighborhood::mean_shift` only, which compares the modes' range parts.
  Mean_shift_settings mean_shift = range_part_mean_shift_settings();

  Detail_settings(const Detail_filter& f = {}, const Laplacian_weights& w = {}) : filter(f), weights(w) {}

  void validate() const
  {
    filter.validate();
    weights.validate();
    if(neighborhood == Laplacian_neighborhood::mean_shift) mean_shift.validate();
  }
};

} // namespace CGAL_ext

#endif // CGAL_EXT_DETAIL_FILTER_H
