// Shapes with holes and stretches for the up-sampling tests, and the covering radius that judges them.
#ifndef CGAL_EXT_TEST_UPSAMPLING_FIXTURES_H
#define CGAL_EXT_TEST_UPSAMPLING_FIXTURES_H

#include "test_support.h"

#include <CGAL_ext/internal/Neighbor_graph.h>

#include <CGAL/number_type_config.h>

#include <cmath>
#include <random>
#include <vector>

struct Oriented_points
{
  std::vector<Point> points;
  std::vector<Vector> normals;
  /// The range the algorithms run on: indices into `points` and `normals`.
  std::vector<std::size_t> indices() const
  {
    std::vector<std::size_t> i(points.size());
    for(std::size_t k = 0; k < i.size(); ++k) i[k] = k;
    return i;
  }
  auto points_only() const { return CGAL::parameters::point_map(CGAL::make_property_map(points)); }
  auto np() const
  {
    return CGAL::parameters::point_map(CGAL::make_property_map(points)).normal_map(CGAL::make_property_map(normals));
  }
};

/// A jittered unit grid on [0, 40]^2 (cell centres, z = 0) without the samples inside a disc of radius
/// `hole` around (20, 20).
inline Oriented_points plane_with_hole(double hole)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.25, 0.25);
  Oriented_points out;
  for(int i = 0; i < 40; ++i)
    for(int j = 0; j < 40; ++j) {
      const double x = i + 0.5 + jitter(rng), y = j + 0.5 + jitter(rng);
      if(std::hypot(x - 20, y - 20) < hole) continue;
      out.points.emplace_back(x, y, 0);
      out.normals.emplace_back(0, 0, 1);
    }
  return out;
}

/// A random (uniform) sampling of density 1 of the square [0, side]^2 (z = 0, side^2 draws) without the samples
/// inside a disc of radius `hole` around its centre.
inline Oriented_points random_plane_with_hole(double side, double hole, unsigned int seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0, side);
  Oriented_points out;
  for(int i = 0; i < int(side * side); ++i) {
    const double x = uniform(rng), y = uniform(rng);
    if(std::hypot(x - side / 2, y - side / 2) < hole) continue;
    out.points.emplace_back(x, y, 0);
    out.normals.emplace_back(0, 0, 1);
  }
  return out;
}

/// An open cylinder of radius 1 along z, rings `h` apart on z in [0, 6], then stretched threefold along its
/// axis between z = 2 and z = 4 (so it ends at z = 10).
inline Oriented_points stretched_cylinder(double h)
{
  Oriented_points out;
  const int around = int(std::lround(2 * CGAL_PI / h)), rings = int(std::lround(6 / h));
  for(int r = 0; r < rings; ++r) {
    const double z = (r + 0.5) * h;
    const double stretched = z < 2 ? z : z < 4 ? 2 + 3 * (z - 2) : z + 4;
    for(int a = 0; a < around; ++a) {
      const double angle = 2 * CGAL_PI * (a + 0.5 * (r % 2)) / around;
      out.points.emplace_back(std::cos(angle), std::sin(angle), stretched);
      out.normals.emplace_back(std::cos(angle), std::sin(angle), 0);
    }
  }
  return out;
}

/// The largest distance from the points `surface` of the true surface to their nearest sample.
inline double covering_radius(const std::vector<Point>& samples, const std::vector<Eigen::Vector3d>& surface)
{
  CGAL_ext::internal::Matrix_n3 s(Eigen::Index(samples.size()), 3), q(Eigen::Index(surface.size()), 3);
  for(std::size_t i = 0; i < samples.size(); ++i) s.row(Eigen::Index(i)) << samples[i].x(), samples[i].y(), samples[i].z();
  for(std::size_t i = 0; i < surface.size(); ++i) q.row(Eigen::Index(i)) = surface[i].transpose();
  const auto nearest = CGAL_ext::internal::k_nearest_samples<CGAL::Parallel_if_available_tag>(s, q, 1);
  double radius = 0;
  for(Eigen::Index i = 0; i < q.rows(); ++i) radius = std::max(radius, (q.row(i) - s.row(nearest.indices[std::size_t(i)])).norm());
  return radius;
}

#endif
