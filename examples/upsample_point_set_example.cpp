// Up-sampling an oriented point set: a sphere with a round hole punched in it gets the hole filled at the
// sampling's own spacing, while a sampling without holes would get (almost) nothing.
// Usage: upsample_point_set_example [points.ply|.off|.xyz|.pwn with normals]   (default: a generated sphere
// of radius 1 with a hole 5 spacings wide); writes upsampled.ply (input points, then the new ones).
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/upsample_point_set.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <iostream>
#include <iterator>
#include <utility>
#include <vector>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point_set = CGAL::Point_set_3<Kernel::Point_3, Kernel::Vector_3>;

int main(int argc, char** argv)
{
  Point_set points;
  points.add_normal_map();
  if(argc > 1) {
    if(!CGAL::IO::read_point_set(argv[1], points) || !points.has_normal_map()) {
      std::cerr << "cannot read " << argv[1] << " with normals\n";
      return 1;
    }
  } else {
    // A hole is a gap across which samples reappear within `max_hole_size` spacings (6 by default); a wider
    // one would be an open border, which is never filled.
    const auto sphere = CGAL_ext::shapes::bumpy_sphere<Kernel>(20000, 1.0, 0.0);
    const double hole_radius = 2.9 * sphere.average_spacing;
    const Kernel::Point_3 pole(0, 0, 1);
    for(std::size_t i = 0; i < sphere.points.size(); ++i)
      if(CGAL::squared_distance(sphere.points[i], pole) > hole_radius * hole_radius)
        points.insert(sphere.points[i], sphere.normals[i]);
  }

  std::vector<std::pair<Kernel::Point_3, Kernel::Vector_3>> added;
  CGAL_ext::Upsampling_result result;
  try {
    // The default target spacing (0) is the sampling's typical spacing; after an edit, pass the spacing the
    // points had before it.
    result = CGAL_ext::upsample_point_set(points, CGAL_ext::Upsampling_settings(), std::back_inserter(added),
                                          points.parameters());
  } catch(const CGAL_ext::Invalid_input& e) {
    std::cerr << "invalid input: " << e.what() << "\n";
    return 1;
  }
  auto inserted = points.add_property_map<unsigned char>("inserted", 0).first;
  for(const auto& [p, n] : added) inserted[*points.insert(p, n)] = 1;
  std::cout << points.size() - added.size() << " points, spacing " << result.spacing << ": " << result.inserted
            << " new points in " << result.rounds << " rounds\n";
  if(!CGAL::IO::write_point_set("upsampled.ply", points, CGAL::parameters::stream_precision(17))) {
    std::cerr << "cannot write upsampled.ply\n";
    return 1;
  }
  return 0;
}
