// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_GENERATED_SHAPES_H
#define CGAL_EXT_GENERATED_SHAPES_H

#include <CGAL/number_type_config.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

namespace CGAL_ext {
/// Sampled analytic shapes with exact normals and a known bump height, for tests, examples and the demo.
namespace shapes {

/// Points, unit outward normals and the signed bump height (along the base shape's normal) of each sample.
template <typename Kernel>
struct Oriented_sample
{
  std::vector<typename Kernel::Point_3> points;
  std::vector<typename Kernel::Vector_3> normals;
  std::vector<double> bump_height;
  double average_spacing = 0; ///< of the base shape's sampling

  void push_back(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double h)
  {
    points.emplace_back(p.x(), p.y(), p.z());
    normals.emplace_back(n.x(), n.y(), n.z());
    bump_height.push_back(h);
  }
};

namespace detail {
constexpr double pi = CGAL_PI;

/// Unit normal of the parametric surface `f(u, v)` by central differences, oriented like `outward`.
template <typename F>
Eigen::Vector3d parametric_normal(const F& f, double u, double v, double du, double dv, const Eigen::Vector3d& outward)
{
  const Eigen::Vector3d fu = f(u + du, v) - f(u - du, v), fv = f(u, v + dv) - f(u, v - dv);
  Eigen::Vector3d n = fu.cross(fv).normalized();
  return n.dot(outward) < 0 ? Eigen::Vector3d(-n) : n;
}
} // namespace detail

/*!
  A sphere of radius `radius` (centre at the origin) with bumps `h(u) = sin(w u_x) sin(w u_y) sin(w u_z)` on
  its unit directions `u`, displaced radially by `amplitude * radius * h`, sampled at `n` Fibonacci points
  (nearly uniform spacing `s = sqrt(4 pi r^2 / n)`). `wavelength_in_spacings` sets the bumps' wavelength
  `L = 2 pi r / w` in multiples of `s`. `bump_height` is `amplitude * radius * h`.
*/
template <typename Kernel>
Oriented_sample<Kernel> bumpy_sphere(std::size_t n, double radius = 1.0, double amplitude = 0.02,
                                     double wavelength_in_spacings = 4.0)
{
  Oriented_sample<Kernel> out;
  out.average_spacing = std::sqrt(4 * detail::pi * radius * radius / double(n));
  const double w = 2 * detail::pi * radius / (wavelength_in_spacings * out.average_spacing);
  auto height = [&](const Eigen::Vector3d& u) {
    return amplitude * radius * std::sin(w * u.x()) * std::sin(w * u.y()) * std::sin(w * u.z());
  };
  const double golden = detail::pi * (3 - std::sqrt(5.0));
  for(std::size_t i = 0; i < n; ++i) {
    const double z = 1 - (2 * double(i) + 1) / double(n);
    const double theta = std::acos(z), phi = golden * double(i);
    const Eigen::Vector3d u(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), z);
    // Near the poles the angles degenerate: rotate the parametrisation so the point sits on its equator, by
    // the rotation [u a b] that takes the x axis to u (a frame, not Quaternion::FromTwoVectors, whose SVD
    // costs every file that includes this one seconds of compilation).
    const Eigen::Vector3d helper = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d a = u.cross(helper).normalized();
    const Eigen::Vector3d b = u.cross(a);
    auto rotated = [&](double t, double p) {
      const Eigen::Vector3d d = std::sin(t) * std::cos(p) * u + std::sin(t) * std::sin(p) * a + std::cos(t) * b;
      return Eigen::Vector3d((radius + height(d)) * d);
    };
    const double eps = 1e-5;
    const Eigen::Vector3d normal = detail::parametric_normal(rotated, detail::pi / 2, 0.0, eps, eps, u);
    out.push_back((radius + height(u)) * u, normal, height(u));
  }
  return out;
}

/*!
  A regular `nx` by `ny` grid of spacing `spacing` in the plane z = 0, centred at the origin, normals +z,
  displaced along z by `amplitude * sin(2 pi x / wavelength) * sin(2 pi y / wavelength)` (flat when
  `amplitude` is 0).
*/
template <typename Kernel>
Oriented_sample<Kernel> bumpy_grid(std::size_t nx, std::size_t ny, double spacing = 1.0, double amplitude = 0.0,
                                   double wavelength = 1.0)
{
  Oriented_sample<Kernel> out;
  out.average_spacing = spacing;
  const double k = 2 * detail::pi / wavelength;
  auto f = [&](double x, double y) {
    return Eigen::Vector3d(x, y, amplitude * std::sin(k * x) * std::sin(k * y));
  };
  for(std::size_t j = 0; j < ny; ++j)
    for(std::size_t i = 0; i < nx; ++i) {
      const double x = (double(i) - 0.5 * double(nx - 1)) * spacing, y = (double(j) - 0.5 * double(ny - 1)) * spacing;
      const Eigen::Vector3d p = f(x, y);
      out.push_back(p, detail::parametric_normal(f, x, y, 1e-4 * spacing, 1e-4 * spacing, Eigen::Vector3d::UnitZ()), p.z());
    }
  return out;
}

/*!
  A tentacle like the paper's Fig. 8: a tube bent along a quarter circle of radius `bend_radius`, its own radius
  tapering from `tube_radius` to a third of it, with bumps of relative height `amplitude` in a
  `rings` x `around` pattern; open at both ends. About `n` samples on rings one spacing apart, each sample
  moved along the surface by up to `jitter` spacings (fixed seed), as a scanner's samples are: a perfect
  lattice makes the k nearest neighbours break ties arbitrarily.
*/
template <typename Kernel>
Oriented_sample<Kernel> bumpy_tube(std::size_t n, double bend_radius = 1.0, double tube_radius = 0.25,
                                   double amplitude = 0.06, int rings = 40, int around = 14, double jitter = 0.3)
{
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> uniform(-jitter, jitter);
  Oriented_sample<Kernel> out;
  const double length = bend_radius * detail::pi / 2;
  auto radius_at = [&](double t) { return tube_radius * (1 - (2.0 / 3.0) * t); };
  // Isotropic sampling: rings one spacing apart, each with as many samples as its circumference holds.
  const double area = length * 2 * detail::pi * tube_radius * (2.0 / 3.0);
  const double h = std::sqrt(area / double(n));
  out.average_spacing = h;
  auto bump = [&](double t, double a) { return amplitude * std::sin(rings * detail::pi * t) * std::sin(around * a); };
  auto frame = [&](double t, double a, Eigen::Vector3d& centre, Eigen::Vector3d& radial) {
    const double phi = t * detail::pi / 2;
    centre = bend_radius * Eigen::Vector3d(std::cos(phi), 0, std::sin(phi)) - Eigen::Vector3d(bend_radius, 0, 0);
    const Eigen::Vector3d e1(std::cos(phi), 0, std::sin(phi)), e2(0, 1, 0);
    radial = std::cos(a) * e1 + std::sin(a) * e2;
  };
  auto f = [&](double t, double a) {
    Eigen::Vector3d c, r;
    frame(t, a, c, r);
    return Eigen::Vector3d(c + radius_at(t) * (1 + bump(t, a)) * r);
  };
  const std::size_t nu = std::max<std::size_t>(8, std::size_t(length / h));
  for(std::size_t i = 0; i < nu; ++i) {
    const double t_ring = (double(i) + 0.5) / double(nu);
    const std::size_t nv = std::max<std::size_t>(8, std::size_t(std::lround(2 * detail::pi * radius_at(t_ring) / h)));
    for(std::size_t j = 0; j < nv; ++j) {
      const double t = std::clamp(t_ring + uniform(rng) / double(nu), 0.0, 1.0);
      const double a = 2 * detail::pi * (double(j) + 0.5 * double(i % 2) + uniform(rng)) / double(nv);
      Eigen::Vector3d c, r;
      frame(t, a, c, r);
      out.push_back(f(t, a), detail::parametric_normal(f, t, a, 1e-5, 1e-5, r), radius_at(t) * bump(t, a));
    }
  }
  return out;
}

/*!
  The surface of an axis-aligned cube of edge `edge` centred at the origin, each face sampled on a
  `per_side` x `per_side` grid of cell centres, each sample moved within its face by up to `jitter` spacings
  (fixed seed), with the exact face normals: sharp edges for feature tests.
*/
template <typename Kernel>
Oriented_sample<Kernel> cube(std::size_t per_side, double edge = 1.0, double jitter = 0.3)
{
  std::mt19937 rng(2718);
  std::uniform_real_distribution<double> uniform(-jitter, jitter);
  Oriented_sample<Kernel> out;
  const double h = edge / double(per_side);
  out.average_spacing = h;
  for(int axis = 0; axis < 3; ++axis)
    for(double side : {-1.0, 1.0}) {
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      normal(axis) = side;
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for(std::size_t i = 0; i < per_side; ++i)
        for(std::size_t j = 0; j < per_side; ++j) {
          Eigen::Vector3d p;
          p(axis) = side * edge / 2;
          p(u) = std::clamp((double(i) + 0.5 + uniform(rng)) * h, 0.0, edge) - edge / 2;
          p(v) = std::clamp((double(j) + 0.5 + uniform(rng)) * h, 0.0, edge) - edge / 2;
          out.push_back(p, normal, 0.0);
        }
    }
  return out;
}

} // namespace shapes
} // namespace CGAL_ext

#endif // CGAL_EXT_GENERATED_SHAPES_H
