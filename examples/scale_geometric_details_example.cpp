// Scales the geometric details of a region of a point set (paper Sect. 4.1), as in the paper's Fig. 4.
// Usage: scale_geometric_details_example [points.ply|.off|.xyz|.pwn [s [out.ply]]]
//        (default: a generated bumpy sphere, s = 2, the cap above z = 0.3 as region)
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/scale_geometric_details.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>
#include <CGAL/bounding_box.h>

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
    for(const auto& p : CGAL_ext::shapes::bumpy_sphere<Kernel>(20000, 1.0, 0.02, 4.0).points) points.insert(p);
  }
  const double s = argc > 2 ? std::atof(argv[2]) : 2.0;

  // The region as a property (what a selection tool would produce): the upper part of the bounding box.
  const auto box = CGAL::bounding_box(points.points().begin(), points.points().end());
  auto in_region = points.add_property_map<bool>("in_region", false).first;
  for(Point_set::Index i : points) in_region[i] = points.point(i).z() > box.zmin() + 0.65 * (box.zmax() - box.zmin());
  const std::vector<std::size_t> roi = CGAL_ext::selected_indices(points, in_region);

  CGAL_ext::Detail_scaling_settings settings(CGAL_ext::Detail_filter{CGAL_ext::Detail_order::quadric, 0.8, 1.6});
  try {
    // No anchors given: the region's border is anchored, the rest of the model stays fixed.
    const CGAL_ext::Detail_manipulation_result result =
      CGAL_ext::scale_geometric_details(points, 10, roi, s, settings, points.parameters());
    const CGAL_ext::Least_squares_statistics& ls = result.least_squares;
    std::cout << "scaled the details of " << result.region_size << " of " << points.size() << " points by " << s << " ("
              << result.anchor_count << " border anchors)\n"
              << ls.method << ": assembly " << ls.assembly_seconds << " s, factor " << ls.factor_seconds << " s, solve "
              << ls.solve_seconds << " s, relative residual " << ls.relative_residual << "\n";
  } catch(const std::exception& e) { // Invalid_input or Numerical_failure
    std::cerr << e.what() << "\n";
    return 1;
  }
  if(argc > 3 && !CGAL::IO::write_point_set(argv[3], points)) { std::cerr << "cannot write " << argv[3] << "\n"; return 1; }
  return 0;
}
