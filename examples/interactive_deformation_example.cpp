// Interactive editing: preprocess once, then move a handle along a path; each step is one back-substitution
// and one diffusion, as a drag in an editor would be (with --arap: three as-rigid-as-possible iterations).
// Usage: interactive_deformation_example [--arap] [points.ply|.off|.xyz|.pwn]
//        (default: the generated tentacle; region: above 30 % of the height; handle: the top 5 %)
#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/generated_shapes.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>
#include <CGAL/bounding_box.h>

#include <iostream>
#include <string>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point_set = CGAL::Point_set_3<Kernel::Point_3, Kernel::Vector_3>;

int main(int argc, char** argv)
{
  CGAL_ext::Detail_preserving_deformation_settings settings(CGAL_ext::Detail_filter{CGAL_ext::Detail_order::cubic, 0.8, 1.6});
  std::string file;
  for(int a = 1; a < argc; ++a) {
    if(std::string(argv[a]) == "--arap") settings.rotations = CGAL_ext::Detail_rotation::as_rigid_as_possible;
    else file = argv[a];
  }
  Point_set points;
  if(!file.empty()) {
    if(!CGAL::IO::read_point_set(file, points)) { std::cerr << "cannot read " << file << "\n"; return 1; }
  } else {
    const auto tube = CGAL_ext::shapes::bumpy_tube<Kernel>(50000);
    points.add_normal_map();
    for(std::size_t i = 0; i < tube.points.size(); ++i) points.insert(tube.points[i], tube.normals[i]);
  }
  const auto box = CGAL::bounding_box(points.points().begin(), points.points().end());
  const double height = box.zmax() - box.zmin();
  try {
    CGAL_ext::Detail_preserving_deformation<> deformation(points, settings, points.parameters());
    const std::size_t handle = deformation.create_handle_group();
    for(Point_set::Index i : points) {
      const double z = points.point(i).z();
      if(z > box.zmin() + 0.3 * height) deformation.insert_roi_point(i);
      if(z > box.zmax() - 0.05 * height) deformation.insert_handle_point(handle, i);
    }
    if(!deformation.preprocess()) return 1;
    std::cout << deformation.number_of_sample_points() << " sample points, " << deformation.number_of_roi_sample_points()
              << " in the region; preprocess " << deformation.statistics().preprocess_seconds << " s\n";
    // The drag: the handle slides sideways and back up, one small step per frame.
    for(int frame = 1; frame <= 10; ++frame) {
      const double t = frame / 10.0;
      deformation.set_handle_transform(handle, Eigen::Matrix3d::Identity(),
                                       Eigen::Vector3d(0.3 * height * t, 0, 0.15 * height * std::sin(3.14159 * t)));
      deformation.deform();
      deformation.diffuse();
      std::cout << "frame " << frame << ": deform " << 1e3 * deformation.statistics().deform_seconds << " ms, diffuse "
                << 1e3 * deformation.statistics().diffuse_seconds << " ms\n";
    }
    // The drag ended: its fine details restored, into the point set.
    deformation.restore_details(points, points.parameters());
    std::cout << "details restored in " << 1e3 * deformation.statistics().restore_seconds << " ms\n";
  } catch(const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
