// One detail-preserving edit (paper Sect. 6): the top of a model turns and rises while its details keep their
// shape and orientation. Usage: Detail_preserving_deformation_example [points.ply|.off|.xyz|.pwn [out.ply]]
//        (default: the generated tentacle; region: above 30 % of the height; handle: the top 5 %)
#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/generated_shapes.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>
#include <CGAL/bounding_box.h>

#include <iostream>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point_set = CGAL::Point_set_3<Kernel::Point_3, Kernel::Vector_3>;

int main(int argc, char** argv)
{
  Point_set points;
  if(argc > 1) {
    if(!CGAL::IO::read_point_set(argv[1], points)) { std::cerr << "cannot read " << argv[1] << "\n"; return 1; }
  } else {
    const auto tube = CGAL_ext::shapes::bumpy_tube<Kernel>(20000);
    points.add_normal_map();
    for(std::size_t i = 0; i < tube.points.size(); ++i) points.insert(tube.points[i], tube.normals[i]);
  }
  const auto box = CGAL::bounding_box(points.points().begin(), points.points().end());
  const double height = box.zmax() - box.zmin();
  try {
    // Quadric details (the default filter); the model's own normals, or estimated ones when it has none.
    CGAL_ext::Detail_preserving_deformation<> deformation(points, CGAL_ext::Detail_filter{CGAL_ext::Detail_order::quadric, 0.8, 1.6},
                                                          points.parameters());
    const std::size_t handle = deformation.create_handle_group();
    Eigen::Vector3d pivot = Eigen::Vector3d::Zero();
    std::size_t on_handle = 0;
    for(Point_set::Index i : points) {
      const Kernel::Point_3& p = points.point(i);
      if(p.z() > box.zmin() + 0.3 * height) deformation.insert_roi_point(i);
      if(p.z() > box.zmax() - 0.05 * height) {
        deformation.insert_handle_point(handle, i);
        pivot += Eigen::Vector3d(p.x(), p.y(), p.z());
        ++on_handle;
      }
    }
    pivot /= double(on_handle);
    // Turn the handle by 45 degrees about the y axis through its centre and lift it by a tenth of the height.
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.785, Eigen::Vector3d::UnitY()).toRotationMatrix();
    deformation.set_handle_transform(handle, R, pivot - R * pivot + Eigen::Vector3d(0, 0, 0.1 * height));
    if(!deformation.deform()) return 1; // preprocesses first
    deformation.diffuse(points, points.parameters());
    deformation.restore_details(points, points.parameters()); // the fine details the blend smoothed
    const auto& st = deformation.statistics();
    std::cout << st.points << " points, " << st.samples << " sample points (" << st.roi_samples << " in the region): "
              << "preprocess " << st.preprocess_seconds << " s, deform " << st.deform_seconds << " s, diffuse "
              << st.diffuse_seconds << " s, restore details " << st.restore_seconds << " s\n";
  } catch(const std::exception& e) { // Invalid_input or Numerical_failure
    std::cerr << e.what() << "\n";
    return 1;
  }
  if(argc > 2 && !CGAL::IO::write_point_set(argv[2], points)) { std::cerr << "cannot write " << argv[2] << "\n"; return 1; }
  return 0;
}
