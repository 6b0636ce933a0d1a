// Signed mean curvature of a point set by jet fitting (positive where the surface bends away from its
// normal), with CGAL's Monge fit and the closed-form fit side by side.
// Usage: estimate_mean_curvature_example [points.ply|.off|.xyz|.pwn]   (default: a generated sphere of radius 2)
#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/generated_shapes.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <algorithm>
#include <iostream>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point_set = CGAL::Point_set_3<Kernel::Point_3, Kernel::Vector_3>;

int main(int argc, char** argv)
{
  Point_set points;
  if(argc > 1) {
    if(!CGAL::IO::read_point_set(argv[1], points)) { std::cerr << "cannot read " << argv[1] << "\n"; return 1; }
  } else {
    const auto sphere = CGAL_ext::shapes::bumpy_sphere<Kernel>(20000, 2.0, 0.0);
    points.add_normal_map();
    for(std::size_t i = 0; i < sphere.points.size(); ++i) points.insert(sphere.points[i], sphere.normals[i]);
  }
  auto monge = points.add_property_map<double>("mean_curvature", 0.).first;
  auto closed = points.add_property_map<double>("mean_curvature_closed_form", 0.).first;
  try {
    // Normals (for the sign) are read from the set when it has them, estimated otherwise.
    const unsigned k = CGAL_ext::default_curvature_neighbors;
    CGAL_ext::estimate_mean_curvature(points, k, CGAL_ext::Curvature_fitting::monge_jet_fitting, monge, points.parameters());
    CGAL_ext::estimate_mean_curvature(points, k, CGAL_ext::Curvature_fitting::closed_form, closed, points.parameters());
  } catch(const CGAL_ext::Invalid_input& e) {
    std::cerr << "invalid input: " << e.what() << "\n";
    return 1;
  }
  std::vector<double> values(monge.begin(), monge.end());
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(values.size() / 2), values.end());
  double largest_difference = 0;
  for(Point_set::Index i : points) largest_difference = std::max(largest_difference, std::abs(monge[i] - closed[i]));
  std::cout << points.size() << " points; median mean curvature " << values[values.size() / 2]
            << " (a sphere of radius 2 has 0.5); largest Monge / closed-form difference " << largest_difference << "\n";
  return 0;
}
