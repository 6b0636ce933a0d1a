// The 20,000-point bumpy sphere shared by the base-surface and enhancement tests, and radial statistics of it.
#ifndef CGAL_EXT_TEST_BUMPY_SPHERE_FIXTURE_H
#define CGAL_EXT_TEST_BUMPY_SPHERE_FIXTURE_H

#include <CGAL_ext/generated_shapes.h>

#include "test_support.h"

#include <CGAL/property_map.h>

#include <cmath>
#include <numeric>
#include <vector>

namespace {
struct Radial_statistics
{
  double mean_radius = 0, bump_rms = 0, centroid_offset = 0;
};

/// Mean distance from the origin, RMS of its deviation (the bumps), and the centroid's distance from the origin.
Radial_statistics radial(const std::vector<Point>& points)
{
  Radial_statistics s;
  double cx = 0, cy = 0, cz = 0;
  for(const Point& p : points) {
    s.mean_radius += std::sqrt((p - CGAL::ORIGIN).squared_length());
    cx += p.x(); cy += p.y(); cz += p.z();
  }
  const double n = double(points.size());
  s.mean_radius /= n;
  for(const Point& p : points) {
    const double d = std::sqrt((p - CGAL::ORIGIN).squared_length()) - s.mean_radius;
    s.bump_rms += d * d;
  }
  s.bump_rms = std::sqrt(s.bump_rms / n);
  s.centroid_offset = std::sqrt(cx * cx + cy * cy + cz * cz) / n;
  return s;
}

const auto sphere = CGAL_ext::shapes::bumpy_sphere<Kernel>(20000, 1.0, 0.02, 4.0);
const std::vector<std::size_t> indices = [] {
  std::vector<std::size_t> v(sphere.points.size());
  std::iota(v.begin(), v.end(), std::size_t(0));
  return v;
}();

/// Named parameters for an index range over `points` with the sphere's exact normals.
auto on(std::vector<Point>& points)
{
  return CGAL::parameters::point_map(CGAL::make_property_map(points)).normal_map(CGAL::make_property_map(sphere.normals));
}
} // namespace

#endif
