// Computes details on a generated sphere through the installed headers; exits non-zero if they look wrong.
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/generated_shapes.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <iostream>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

int main()
{
  const auto sphere = CGAL_ext::shapes::bumpy_sphere<Kernel>(2000, 1.0, 0.0);
  std::vector<Kernel::Vector_3> details(sphere.points.size());
  std::vector<std::size_t> indices(sphere.points.size());
  for(std::size_t i = 0; i < indices.size(); ++i) indices[i] = i;
  CGAL_ext::compute_geometric_details(indices, 10, CGAL_ext::Detail_filter{}, CGAL::make_property_map(details),
                                      CGAL::parameters::point_map(CGAL::make_property_map(sphere.points)));
  // On a sphere every detail points outwards.
  for(std::size_t i = 0; i < indices.size(); ++i)
    if(details[i] * (sphere.points[i] - CGAL::ORIGIN) <= 0) { std::cerr << "inward detail at " << i << "\n"; return 1; }
  std::cout << "consumer: details of " << indices.size() << " points OK\n";
  return 0;
}
