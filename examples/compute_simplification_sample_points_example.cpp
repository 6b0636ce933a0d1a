// Simplification sample points (SSPs): clusters split until they are small enough and their points share
// one mean-shift mode, so SSPs are dense where the surface bends. Writes the SSPs as surfels.
// Usage: compute_simplification_sample_points_example [points.ply|.off|.xyz|.pwn] [max_cluster_size]
//        (default: a generated bumpy tube, clusters of at most 50 points as in the paper)
#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/generated_shapes.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <iostream>
#include <limits>
#include <string>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point_set = CGAL::Point_set_3<Kernel::Point_3, Kernel::Vector_3>;

int main(int argc, char** argv)
{
  Point_set points;
  if(argc > 1) {
    if(!CGAL::IO::read_point_set(argv[1], points)) { std::cerr << "cannot read " << argv[1] << "\n"; return 1; }
  } else {
    const auto tube = CGAL_ext::shapes::bumpy_tube<Kernel>(40000);
    points.add_normal_map();
    for(std::size_t i = 0; i < tube.points.size(); ++i) points.insert(tube.points[i], tube.normals[i]);
  }
  CGAL_ext::Simplification_settings settings;
  settings.max_cluster_size = argc > 2 ? std::stoul(argv[2]) : 50;
  auto ssp_index = points.add_property_map<std::size_t>("ssp_index", 0).first;

  CGAL_ext::Simplification_sample_points<Kernel> ssps;
  try {
    ssps = CGAL_ext::compute_simplification_sample_points(points, settings, ssp_index, points.parameters());
  } catch(const CGAL_ext::Invalid_input& e) {
    std::cerr << "invalid input: " << e.what() << "\n";
    return 1;
  }
  // Size alone would give about n / 50 clusters; the mode criterion adds SSPs where the surface bends.
  settings.mode_spread_threshold = std::numeric_limits<double>::infinity();
  const auto by_size = CGAL_ext::compute_simplification_sample_points(points, settings, ssp_index, points.parameters());
  std::cout << points.size() << " points -> " << ssps.size() << " SSPs (" << by_size.size()
            << " when split by size only)\n";

  Point_set surfels;
  surfels.add_normal_map();
  auto radius = surfels.add_property_map<double>("radius", 0).first;
  auto members = surfels.add_property_map<int>("member_count", 0).first;
  for(const auto& ssp : ssps.samples) {
    const Point_set::Index s = *surfels.insert(ssp.centroid, ssp.normal);
    radius[s] = ssp.radius;
    members[s] = int(ssp.member_count);
  }
  if(!CGAL::IO::write_point_set("ssp.ply", surfels, CGAL::parameters::stream_precision(17))) {
    std::cerr << "cannot write ssp.ply\n";
    return 1;
  }
  std::cout << "wrote ssp.ply (position, normal, radius, member_count)\n";
  return 0;
}
