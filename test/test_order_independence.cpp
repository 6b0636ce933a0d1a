// The library's functions that the program's subcommands do not each run on their own (the Laplacian, the mean-shift
// modes, the sparse directions, the balanced flow, the refitted normals): the same points in another order give the
// same answer, point by point once the order is undone, to 1e-12 of the largest value, on a lattice whose distances
// tie exactly, on the lattice with duplicated points and on a random sampling (doc/design.md, "One neighbourhood
// rule"). test_determinism.cpp runs every subcommand so, and python/tests/test_order_independence.py every function
// of the Python package.
#include "upsampling_fixtures.h"

#include <CGAL_ext/balanced_flow_smooth_point_set.h>
#include <CGAL_ext/compute_mean_shift_modes.h>
#include <CGAL_ext/compute_point_set_laplacian.h>
#include <CGAL_ext/detect_sparse_directions.h>
#include <CGAL_ext/refit_normals.h>

#include <gtest/gtest.h>

#include <map>
#include <numeric>
#include <random>
#include <utility>

namespace {

// z(x, y): flat for x < 0.55, smooth bumps beyond, with its exact normals; 70 x 60 points at spacing 1/64, and
// every 50th again when `duplicates`; or 4,200 random points of the same surface.
Oriented_points order_fixture(const std::string& kind)
{
  Oriented_points shape;
  auto add = [&](double x, double y) {
    const double s = std::max(x - 0.55, 0.0), kx = 2 * CGAL_PI / 0.4, ky = 2 * CGAL_PI / 0.3;
    const double z = s * s * std::sin(ky * y) * (1 - std::cos(kx * s));
    const double zx = std::sin(ky * y) * (2 * s * (1 - std::cos(kx * s)) + s * s * kx * std::sin(kx * s));
    const double zy = s * s * ky * std::cos(ky * y) * (1 - std::cos(kx * s));
    const double length = std::sqrt(zx * zx + zy * zy + 1);
    shape.points.emplace_back(x, y, z);
    shape.normals.emplace_back(-zx / length, -zy / length, 1 / length);
  };
  if(kind == "random") {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> x(0, 69 / 64.0), y(0, 59 / 64.0);
    for(int i = 0; i < 4200; ++i) {
      const double u = x(rng);
      add(u, y(rng));
    }
    return shape;
  }
  for(int j = 0; j < 60; ++j)
    for(int i = 0; i < 70; ++i) add(i / 64.0, j / 64.0);
  if(kind == "duplicates")
    for(std::size_t i = 0; i < 70 * 60; i += 50) {
      shape.points.push_back(shape.points[i]);
      shape.normals.push_back(shape.normals[i]);
    }
  return shape;
}

class LibraryOrderIndependence : public ::testing::TestWithParam<const char*>
{
protected:
  void SetUp() override
  {
    shape = order_fixture(GetParam());
    order.resize(shape.points.size());
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), std::mt19937(11));
    for(const int i : order) {
      shuffled.points.push_back(shape.points[std::size_t(i)]);
      shuffled.normals.push_back(shape.normals[std::size_t(i)]);
    }
  }

  /// `a` per point in the shape's order, `b` per point in `order`, `width` values each: equal to 1e-12 of the
  /// largest value once the order is undone.
  void expect_same(const std::vector<double>& a, const std::vector<double>& b, std::size_t width,
                   const char* what) const
  {
    ASSERT_EQ(a.size(), b.size());
    double scale = 0, difference = 0;
    for(std::size_t r = 0; r < order.size(); ++r)
      for(std::size_t c = 0; c < width; ++c) {
        const double va = a[std::size_t(order[r]) * width + c], vb = b[r * width + c];
        scale = std::max(scale, std::abs(va));
        difference = std::max(difference, std::abs(va - vb));
      }
    EXPECT_LE(difference, 1e-12 * scale) << GetParam() << ", " << what;
  }

  static std::vector<double> flat(const std::vector<Vector>& vectors)
  {
    std::vector<double> out;
    for(const Vector& v : vectors) out.insert(out.end(), {v.x(), v.y(), v.z()});
    return out;
  }

  Oriented_points shape, shuffled;
  std::vector<int> order; // row r of `shuffled` is row order[r] of `shape`
};

} // namespace

TEST_P(LibraryOrderIndependence, Laplacian)
{
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> a, b;
  const CGAL_ext::Laplacian_weights distance{CGAL_ext::Laplacian_weighting::distance_power};
  ASSERT_TRUE(CGAL_ext::compute_point_set_laplacian(shape.indices(), 10, distance, a, shape.points_only()));
  ASSERT_TRUE(CGAL_ext::compute_point_set_laplacian(shuffled.indices(), 10, distance, b, shuffled.points_only()));
  std::map<std::pair<int, int>, double> entries_a, entries_b;
  for(int r = 0; r < a.outerSize(); ++r)
    for(decltype(a)::InnerIterator it(a, r); it; ++it) entries_a[{r, int(it.col())}] = it.value();
  for(int r = 0; r < b.outerSize(); ++r)
    for(decltype(b)::InnerIterator it(b, r); it; ++it)
      entries_b[{order[std::size_t(r)], order[std::size_t(it.col())]}] = it.value();
  ASSERT_EQ(entries_a.size(), entries_b.size()) << GetParam();
  double difference = 0;
  for(const auto& [key, value] : entries_a) {
    ASSERT_TRUE(entries_b.count(key)) << GetParam() << ": entry " << key.first << ", " << key.second;
    difference = std::max(difference, std::abs(value - entries_b[key]));
  }
  EXPECT_LE(difference, 1e-12) << GetParam();
}

TEST_P(LibraryOrderIndependence, MeanShiftModes)
{
  using Mode = CGAL_ext::Mean_shift_mode<Kernel>;
  std::vector<Mode> a(shape.points.size()), b(shape.points.size());
  ASSERT_TRUE(CGAL_ext::compute_mean_shift_modes(shape.indices(), 15, CGAL_ext::Mean_shift_settings(),
                                                 CGAL::make_property_map(a), shape.np()));
  ASSERT_TRUE(CGAL_ext::compute_mean_shift_modes(shuffled.indices(), 15, CGAL_ext::Mean_shift_settings(),
                                                 CGAL::make_property_map(b), shuffled.np()));
  auto values = [](const std::vector<Mode>& modes) {
    std::vector<double> out;
    for(const Mode& m : modes)
      out.insert(out.end(), {m.position.x(), m.position.y(), m.position.z(), m.normal.x(), m.normal.y(), m.normal.z(),
                             m.mean_curvature, double(m.iterations)});
    return out;
  };
  expect_same(values(a), values(b), 8, "modes");
}

TEST_P(LibraryOrderIndependence, SparseDirections)
{
  std::vector<Vector> a(shape.points.size()), b(shape.points.size());
  CGAL_ext::detect_sparse_directions(shape.indices(), 10, CGAL_ext::Sparse_direction_settings(),
                                     CGAL::make_property_map(a), shape.np());
  CGAL_ext::detect_sparse_directions(shuffled.indices(), 10, CGAL_ext::Sparse_direction_settings(),
                                     CGAL::make_property_map(b), shuffled.np());
  expect_same(flat(a), flat(b), 3, "sparse directions");
}

TEST_P(LibraryOrderIndependence, BalancedFlowAndRefittedNormals)
{
  Oriented_points a = shape, b = shuffled;
  auto writable = [](Oriented_points& o) {
    return CGAL::parameters::point_map(CGAL::make_property_map(o.points))
      .normal_map(CGAL::make_property_map(o.normals));
  };
  std::vector<std::size_t> all = a.indices();
  ASSERT_TRUE(CGAL_ext::balanced_flow_smooth_point_set(all, 10, CGAL_ext::Balanced_flow_settings(), writable(a)));
  ASSERT_TRUE(CGAL_ext::balanced_flow_smooth_point_set(all, 10, CGAL_ext::Balanced_flow_settings(), writable(b)));
  std::vector<double> pa, pb;
  for(const Point& p : a.points) pa.insert(pa.end(), {p.x(), p.y(), p.z()});
  for(const Point& p : b.points) pb.insert(pb.end(), {p.x(), p.y(), p.z()});
  expect_same(pa, pb, 3, "smoothed points");
  // The normals of the smoothed points' right half refitted.
  std::vector<std::size_t> moved_a, moved_b;
  for(std::size_t i = 0; i < a.points.size(); ++i)
    if(a.points[i].x() > 0.5) moved_a.push_back(i);
  for(std::size_t i = 0; i < b.points.size(); ++i)
    if(b.points[i].x() > 0.5) moved_b.push_back(i);
  CGAL_ext::refit_normals(a.indices(), moved_a, 10, writable(a));
  CGAL_ext::refit_normals(b.indices(), moved_b, 10, writable(b));
  expect_same(flat(a.normals), flat(b.normals), 3, "refitted normals");
}

INSTANTIATE_TEST_SUITE_P(Shapes, LibraryOrderIndependence, ::testing::Values("lattice", "duplicates", "random"));
