// Mean-shift modes of a point set over (position, normal, scaled mean curvature): on a cube, every point's
// mode stays on its own face, which is what lets the simplification keep sharp edges.
// Usage: compute_mean_shift_modes_example [points.ply|.off|.xyz|.pwn]   (default: a generated cube)
#include <CGAL_ext/compute_mean_shift_modes.h>
#include <CGAL_ext/generated_shapes.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <algorithm>
#include <cmath>
#include <iostream>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point_set = CGAL::Point_set_3<Kernel::Point_3, Kernel::Vector_3>;
using Mode = CGAL_ext::Mean_shift_mode<Kernel>;

int main(int argc, char** argv)
{
  Point_set points;
  if(argc > 1) {
    if(!CGAL::IO::read_point_set(argv[1], points)) { std::cerr << "cannot read " << argv[1] << "\n"; return 1; }
  } else {
    const auto cube = CGAL_ext::shapes::cube<Kernel>(40);
    points.add_normal_map();
    for(std::size_t i = 0; i < cube.points.size(); ++i) points.insert(cube.points[i], cube.normals[i]);
  }
  auto modes = points.add_property_map<Mode>("mode").first;
  CGAL_ext::Mean_shift_settings settings; // bandwidths derived from the spacing and the curvature
  settings.kernel = CGAL_ext::Mean_shift_kernel::gaussian;
  CGAL_ext::Mean_shift_result result;
  try {
    result = CGAL_ext::compute_mean_shift_modes(points, CGAL_ext::default_mean_shift_neighbors, settings, modes,
                                                points.parameters());
  } catch(const CGAL_ext::Invalid_input& e) {
    std::cerr << "invalid input: " << e.what() << "\n";
    return 1;
  }
  double moved = 0, turned = 0;
  for(Point_set::Index i : points) {
    moved += std::sqrt(CGAL::squared_distance(points.point(i), modes[i].position));
    if(points.has_normal_map())
      turned += std::acos(std::clamp(points.normal(i) * modes[i].normal / std::sqrt(modes[i].normal.squared_length()), -1.0, 1.0));
  }
  const double n = double(points.size());
  std::cout << points.size() << " points; h_s = " << result.spatial_bandwidth << ", h_r = " << result.range_bandwidth
            << ", curvature scale " << result.curvature_scale << "\n"
            << "mean shift: " << result.mean_iterations << " steps per point, " << result.points_at_cap
            << " at the cap; modes lie on average " << moved / n / result.spatial_bandwidth << " h_s from their point";
  if(points.has_normal_map()) std::cout << " and their normals " << turned / n * 180 / 3.14159265358979 << " degrees from it";
  std::cout << "\n";
  return 0;
}
