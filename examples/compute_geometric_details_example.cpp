// Geometric details of a point set with normals, through CGAL::Point_set_3.
// Usage: compute_geometric_details_example [points.ply|.off|.xyz|.pwn]   (default: a generated bumpy sphere)
#include <CGAL_ext/compute_geometric_details.h>
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
    const auto sphere = CGAL_ext::shapes::bumpy_sphere<Kernel>(20000, 1.0, 0.02, 4.0);
    points.add_normal_map();
    for(std::size_t i = 0; i < sphere.points.size(); ++i) points.insert(sphere.points[i], sphere.normals[i]);
  }
  auto detail = points.add_property_map<Kernel::Vector_3>("detail", CGAL::NULL_VECTOR).first;
  auto magnitude = points.add_property_map<double>("detail_magnitude", 0.).first;

  const CGAL_ext::Detail_filter filter{CGAL_ext::Detail_order::quadric, 0.8, 1.6};
  try {
    // Normals are read from the set when it has them, estimated otherwise.
    CGAL_ext::compute_geometric_details(points, 10, filter, detail, magnitude, points.parameters());
  } catch(const CGAL_ext::Invalid_input& e) {
    std::cerr << "invalid input: " << e.what() << "\n";
    return 1;
  }
  const auto [lo, hi] = std::minmax_element(magnitude.begin(), magnitude.end());
  std::cout << points.size() << " points; oriented detail magnitude in [" << *lo << ", " << *hi << "]\n";
  return 0;
}
