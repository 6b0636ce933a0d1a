// The point-set Laplacian K = I - W of a plain vector of points, and a check that it maps constants to zero.
// Usage: compute_point_set_laplacian_example [points.xyz|.ply|.off]   (default: a generated tentacle)
#include <CGAL_ext/compute_point_set_laplacian.h>
#include <CGAL_ext/generated_shapes.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/read_points.h>

#include <iostream>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

int main(int argc, char** argv)
{
  std::vector<Kernel::Point_3> points;
  if(argc > 1) {
    if(!CGAL::IO::read_points(argv[1], std::back_inserter(points))) { std::cerr << "cannot read " << argv[1] << "\n"; return 1; }
  } else {
    points = CGAL_ext::shapes::bumpy_tube<Kernel>(20000).points;
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> K;
  const CGAL_ext::Laplacian_weights weights{CGAL_ext::Laplacian_weighting::distance_power, -1.0}; // the paper's
  CGAL_ext::compute_point_set_laplacian(points, 10, weights, K);
  const double constant_residual = (K * Eigen::VectorXd::Ones(K.cols())).cwiseAbs().maxCoeff();
  std::cout << points.size() << " points, " << K.nonZeros() << " non-zeros (" << double(K.nonZeros()) / double(K.rows())
            << " per row), max |K 1| = " << constant_residual << "\n";
  return constant_residual < 1e-12 ? 0 : 1;
}
