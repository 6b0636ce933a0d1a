// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_LOCAL_FIT_H
#define CGAL_EXT_INTERNAL_LOCAL_FIT_H

#include <Eigen/Core>
#include <Eigen/Cholesky>

#include <cmath>

namespace CGAL_ext {
namespace internal {

/// A local surface: the height function of degree 2 (`z = c0 + c1 x + c2 y + c3 x^2 + c4 xy + c5 y^2`) or 3
/// (and `x^3, x^2 y, x y^2, y^3`) over the tangent plane (u, v) of a normal at an origin, fitted by least
/// squares to nearby samples (coordinates scaled by their mean distance, so the normal equations stay well
/// conditioned at any model size), with a light ridge so that degenerate neighbourhoods fit a flatter surface
/// rather than none.
class Height_fit
{
public:
  Height_fit(const Eigen::Vector3d& origin, const Eigen::Vector3d& normal, int degree = 2)
    : m_origin(origin), m_n(normal.normalized()), m_terms(degree >= 3 ? 10 : 6)
  {
    const Eigen::Vector3d helper = std::abs(m_n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    m_u = m_n.cross(helper).normalized();
    m_v = m_n.cross(m_u);
  }

  /// Fits to the samples `point(0) .. point(count - 1)`. With fewer samples than coefficients, the degree
  /// drops to 2, and below 6 samples the fit is the tangent plane at the samples' mean height.
  template <typename PointAt>
  void fit(int count, const PointAt& point)
  {
    double mean = 0;
    for(int m = 0; m < count; ++m) mean += (point(m) - m_origin).norm();
    m_scale = mean > 0 ? count / mean : 1.0;
    m_c.setZero();
    if(count < m_terms) m_terms = 6;
    if(count < 6) {
      for(int m = 0; m < count; ++m) m_c(0) += (point(m) - m_origin).dot(m_n) * m_scale / count;
      return;
    }
    if(m_terms == 6)
      solve<6>(count, point);
    else
      solve<10>(count, point);
    if(!m_c.allFinite()) m_c.setZero();
  }

  /// The axes of the tangent plane the heights are measured over.
  const Eigen::Vector3d& tangent_u() const { return m_u; }
  const Eigen::Vector3d& tangent_v() const { return m_v; }

  /// The surface point above (or below) `p` along the fit's normal axis.
  Eigen::Vector3d project(const Eigen::Vector3d& p) const
  {
    const Eigen::Vector3d d = p - m_origin;
    const double x = d.dot(m_u) * m_scale, y = d.dot(m_v) * m_scale;
    const double z = m_c.head(m_terms).dot(monomials(x, y));
    return m_origin + (x * m_u + y * m_v + z * m_n) / m_scale;
  }

  /// The fitted surface's unit normal above `p`, on the side of the fit's normal.
  Eigen::Vector3d normal(const Eigen::Vector3d& p) const
  {
    const Eigen::Vector3d d = p - m_origin;
    const double x = d.dot(m_u) * m_scale, y = d.dot(m_v) * m_scale;
    double zx = m_c(1) + 2 * m_c(3) * x + m_c(4) * y, zy = m_c(2) + m_c(4) * x + 2 * m_c(5) * y;
    if(m_terms == 10) {
      zx += 3 * m_c(6) * x * x + 2 * m_c(7) * x * y + m_c(8) * y * y;
      zy += m_c(7) * x * x + 2 * m_c(8) * x * y + 3 * m_c(9) * y * y;
    }
    return (m_n - zx * m_u - zy * m_v).normalized();
  }

private:
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 10, 1>;

  // The least-squares coefficients of `terms` monomials (sizes fixed at compile time: most fits are small and many).
  template <int terms, typename PointAt>
  void solve(int count, const PointAt& point)
  {
    Eigen::Matrix<double, terms, terms> AtA = Eigen::Matrix<double, terms, terms>::Zero();
    Eigen::Matrix<double, terms, 1> Atz = Eigen::Matrix<double, terms, 1>::Zero();
    for(int m = 0; m < count; ++m) {
      const Eigen::Vector3d d = point(m) - m_origin;
      const Eigen::Matrix<double, terms, 1> row = monomials(d.dot(m_u) * m_scale, d.dot(m_v) * m_scale);
      AtA.noalias() += row * row.transpose();
      Atz += d.dot(m_n) * m_scale * row;
    }
    // A light ridge on all but the constant term: samples on two lines (two rings of a stretched tube) leave a
    // curvature undetermined, which then stays zero instead of exploding.
    for(int c = 1; c < terms; ++c) AtA(c, c) += 1e-3 * count;
    m_c.template head<terms>() = AtA.ldlt().solve(Atz);
  }

  Vector monomials(double x, double y) const
  {
    Vector row(m_terms);
    row.head<6>() << 1, x, y, x * x, x * y, y * y;
    if(m_terms == 10) row.tail<4>() << x * x * x, x * x * y, x * y * y, y * y * y;
    return row;
  }

  Eigen::Vector3d m_origin, m_n, m_u, m_v;
  int m_terms;
  double m_scale = 1;
  Eigen::Matrix<double, 10, 1> m_c = Eigen::Matrix<double, 10, 1>::Zero();
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_LOCAL_FIT_H
