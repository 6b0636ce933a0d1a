// Computes details and scales them on a generated sphere through the installed headers (and the installed
// package's Cholesky, CHOLMOD when it was found); exits non-zero if the results look wrong.
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/scale_geometric_details.h>

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
  // Scaling the details of a cap by 1 leaves every point where it is.
  std::vector<Kernel::Point_3> points = sphere.points;
  std::vector<std::size_t> cap;
  for(std::size_t i = 0; i < points.size(); ++i)
    if(points[i].z() > 0.5) cap.push_back(i);
  const auto result = CGAL_ext::scale_geometric_details(points, 10, cap, 1.0, CGAL_ext::Detail_filter{});
  for(std::size_t i = 0; i < points.size(); ++i)
    if(CGAL::squared_distance(points[i], sphere.points[i]) > 1e-18) { std::cerr << "scaling by 1 moved point " << i << "\n"; return 1; }
  std::cout << "consumer: details of " << indices.size() << " points OK; identity scaling OK ("
            << result.least_squares.method << ")\n";
  return 0;
}
