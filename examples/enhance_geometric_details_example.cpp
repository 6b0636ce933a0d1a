// Enhances the model detail of a whole point set against its balanced-flow base surface (paper Sect. 4.2,
// Fig. 5 and 6), and writes the base surface too.
// Usage: enhance_geometric_details_example [points.ply|.off|.xyz|.pwn [s [out.ply [base.ply]]]]
//        (default: a generated bumpy sphere with exact normals, s = 2)
#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/generated_shapes.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <cstdlib>
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
  const double s = argc > 2 ? std::atof(argv[2]) : 2.0;

  CGAL_ext::Detail_enhancement_settings settings(CGAL_ext::Detail_filter{CGAL_ext::Detail_order::linear, 0.8, 1.6});
  settings.flow.fidelity = 0.005;           // how closely the base surface follows the input
  settings.flow.mean_curvature_sweeps = 30; // how wide a bump the base surface flattens
  try {
    Point_set base = points;
    // Normals are read from the set when it has them, estimated otherwise.
    CGAL_ext::balanced_flow_smooth_point_set(base, 10, settings.flow, base.parameters());
    // The whole model: a uniform 1 % of the points is anchored at the exact solution p~ + s (p - p~).
    const CGAL_ext::Detail_manipulation_result result =
      CGAL_ext::enhance_geometric_details(points, 10, s, settings, points.parameters());
    std::cout << "enhanced the details of " << result.region_size << " points by " << s << " (" << result.anchor_count
              << " anchors) with " << result.least_squares.method << " in "
              << result.least_squares.assembly_seconds + result.least_squares.factor_seconds + result.least_squares.solve_seconds
              << " s\n";
    if(argc > 4 && !CGAL::IO::write_point_set(argv[4], base)) { std::cerr << "cannot write " << argv[4] << "\n"; return 1; }
  } catch(const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  if(argc > 3 && !CGAL::IO::write_point_set(argv[3], points)) { std::cerr << "cannot write " << argv[3] << "\n"; return 1; }
  return 0;
}
