#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_point_set_laplacian.h>
#include <CGAL_ext/generated_shapes.h>

#include "test_support.h"

#include <CGAL/Point_set_3.h>
#include <CGAL/property_map.h>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <random>

#include <boost/iterator/counting_iterator.hpp>

#include <array>
#include <cstdio>
#include <utility>

using namespace CGAL_ext;

namespace {

struct Details
{
  std::vector<Vector> vectors;
  std::vector<double> magnitudes;
};

/// Index range + vector-backed maps: the plainest way to call a CGAL point-set algorithm.
template <typename Tag = CGAL::Parallel_if_available_tag>
Details details_of(const shapes::Oriented_sample<Kernel>& s, unsigned k, const Detail_settings& settings,
                   bool with_normals = true)
{
  const std::vector<std::size_t> indices(boost::counting_iterator<std::size_t>(0),
                                         boost::counting_iterator<std::size_t>(s.points.size()));
  Details d;
  d.vectors.resize(indices.size());
  d.magnitudes.resize(indices.size());
  const auto points = CGAL::make_property_map(s.points);
  bool done;
  if(with_normals)
    done = compute_geometric_details<Tag>(indices, k, settings, CGAL::make_property_map(d.vectors),
                                          CGAL::make_property_map(d.magnitudes),
                                          CGAL::parameters::point_map(points).normal_map(CGAL::make_property_map(s.normals)));
  else
    done = compute_geometric_details<Tag>(indices, k, settings, CGAL::make_property_map(d.vectors),
                                          CGAL::make_property_map(d.magnitudes), CGAL::parameters::point_map(points));
  EXPECT_TRUE(done);
  return d;
}

std::vector<double> normal_components(const Details& d, const shapes::Oriented_sample<Kernel>& s)
{
  std::vector<double> out;
  for(std::size_t i = 0; i < d.vectors.size(); ++i) out.push_back(d.vectors[i] * s.normals[i]);
  return out;
}

/// An output map for a range of pairs, indexed by the element's address in the vector.
template <typename Element, typename Value>
struct Address_indexed_map
{
  using key_type = Element;
  using value_type = Value;
  using reference = Value&;
  using category = boost::writable_property_map_tag;
  const Element* base;
  std::vector<Value>* values;
  friend void put(const Address_indexed_map& m, const Element& e, const Value& v) { (*m.values)[std::size_t(&e - m.base)] = v; }
};
} // namespace

TEST(GeometricDetails, InteriorDetailsVanishOnARegularGridWithItsFull8Neighbourhood)
{
  const auto grid = shapes::bumpy_grid<Kernel>(21, 21, 0.1);
  for(Laplacian_weights w : {Laplacian_weights{}, Laplacian_weights{Laplacian_weighting::distance_power, -1.0}})
    for(Detail_order o : all_orders) {
      const Details d = details_of(grid, 8, Detail_settings({o, 0.8, 1.6}, w));
      // Border points have fewer than 8 neighbours within sqrt(2), so their k nearest reach 2 rings inwards and
      // symmetrisation adds those links to rings 1-2; f(K) then spreads that degree() rings further.
      const int margin = 2 + Detail_filter({o}).degree();
      for(int j = margin; j < 21 - margin; ++j)
        for(int i = margin; i < 21 - margin; ++i)
          EXPECT_LT(std::sqrt(d.vectors[std::size_t(j * 21 + i)].squared_length()), 1e-12)
            << Detail_filter::order_name(o) << " at (" << i << ", " << j << ")";
    }
}

TEST(GeometricDetails, FilterBySparseProductsEqualsTheExplicitMatrixPolynomial)
{
  const auto s = shapes::bumpy_sphere<Kernel>(400, 1.0, 0.05, 4.0);
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> K;
  ASSERT_TRUE(compute_point_set_laplacian(s.points, 10, {}, K));
  const Eigen::MatrixXd Kd(K);
  Eigen::MatrixXd P(s.points.size(), 3);
  for(std::size_t i = 0; i < s.points.size(); ++i) P.row(Eigen::Index(i)) << s.points[i].x(), s.points[i].y(), s.points[i].z();
  for(Detail_order o : all_orders) {
    const double l = 0.3, m = 1.8;
    Eigen::MatrixXd F; // the paper's polynomials, written out
    if(o == Detail_order::linear) F = Kd / l;
    if(o == Detail_order::quadric) F = (1 / l + 1 / m) * Kd - (1 / (l * m)) * Kd * Kd;
    if(o == Detail_order::cubic) F = (1 / (l * l) + 1 / (l * m) + 1 / (m * m)) * Kd * Kd - (1 / (l * m)) * (1 / l + 1 / m) * Kd * Kd * Kd;
    const Eigen::MatrixXd expected = F * P;
    const Details d = details_of(s, 10, Detail_filter{o, l, m});
    double err = 0;
    for(std::size_t i = 0; i < d.vectors.size(); ++i)
      err = std::max(err, (Eigen::RowVector3d(d.vectors[i].x(), d.vectors[i].y(), d.vectors[i].z()) - expected.row(Eigen::Index(i))).norm());
    EXPECT_LT(err, 1e-12 * expected.norm()) << Detail_filter::order_name(o);
  }
}

TEST(GeometricDetails, NormalComponentFollowsTheBumpHeightOnABumpySphere)
{
  // Bumps of a wavelength of about 4 average spacings: delta . n must follow the known height field.
  for(Detail_order o : all_orders) {
    const auto s = shapes::bumpy_sphere<Kernel>(20000, 1.0, 0.01, 4.0);
    const double r = pearson(normal_components(details_of(s, 10, Detail_filter{o, 0.8, 1.6}), s), s.bump_height);
    EXPECT_GE(r, 0.85) << Detail_filter::order_name(o);
    std::printf("[ details ] %-7s wavelength 4 spacings: Pearson(delta.n, height) = %.3f\n", Detail_filter::order_name(o), r);
  }
  // How the correlation falls as the bumps get smoother: doc/geometric_details.md's table ("Measured (tests)"),
  // each figure asserted to its rounding.
  const std::map<double, std::array<double, 3>> table{{4.0, {0.942, 0.959, 0.941}}, {8.0, {0.909, 0.932, 0.851}},
                                                      {16.0, {0.882, 0.893, 0.732}}, {32.0, {0.880, 0.890, 0.373}}};
  for(const auto& [wavelength, documented] : table) {
    const auto s = shapes::bumpy_sphere<Kernel>(20000, 1.0, 0.01, wavelength);
    std::array<double, 3> r;
    for(std::size_t o = 0; o < 3; ++o) {
      r[o] = pearson(normal_components(details_of(s, 10, Detail_filter{all_orders[o], 0.8, 1.6}), s), s.bump_height);
      EXPECT_NEAR(r[o], documented[o], 0.00051) << "wavelength " << wavelength << ", " << Detail_filter::order_name(all_orders[o]);
    }
    std::printf("[ details ] wavelength %4.0f spacings: Pearson linear %.3f quadric %.3f cubic %.3f\n", wavelength, r[0], r[1], r[2]);
  }
}

// On an irregular sampling, most of delta is tangential (the uniform Laplacian's drift toward the denser
// side), so the paper's signed |delta| shows the sampling; its normal component still shows the relief. The
// program's maps default to delta . n for this (doc/geometric_details.md, "Colour maps").
TEST(GeometricDetails, NormalComponentShowsTheReliefOfARandomSamplingBetterThanTheSignedMagnitude)
{
  // 20,000 points drawn at random from a fine Fibonacci sampling (nearly a Poisson sampling), bumps of a
  // wavelength of 8 of its average spacings.
  const auto fine = shapes::bumpy_sphere<Kernel>(200000, 1.0, 0.01, 8.0 * std::sqrt(200000.0 / 20000.0));
  std::vector<std::size_t> order(fine.points.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  shapes::Oriented_sample<Kernel> s;
  for(std::size_t m = 0; m < 20000; ++m) {
    s.points.push_back(fine.points[order[m]]);
    s.normals.push_back(fine.normals[order[m]]);
    s.bump_height.push_back(fine.bump_height[order[m]]);
  }
  for(Detail_order o : all_orders) {
    const Details d = details_of(s, 10, Detail_filter{o, 0.8, 1.6});
    const double along_normal = pearson(normal_components(d, s), s.bump_height), signed_magnitude = pearson(d.magnitudes, s.bump_height);
    double tangential = 0, total = 0;
    for(std::size_t i = 0; i < d.vectors.size(); ++i) {
      const double a = d.vectors[i] * s.normals[i];
      total += d.vectors[i].squared_length();
      tangential += d.vectors[i].squared_length() - a * a;
    }
    std::printf("[ details ] %-7s random sampling: Pearson(delta.n, height) = %.3f, Pearson(+-|delta|, height) = %.3f, "
                "tangential share of |delta|^2 %.0f %%\n", Detail_filter::order_name(o), along_normal, signed_magnitude,
                100 * tangential / total);
    EXPECT_GT(along_normal, signed_magnitude + 0.1) << Detail_filter::order_name(o);
    EXPECT_GT(along_normal, 0.6) << Detail_filter::order_name(o);
  }
}

TEST(GeometricDetails, OrientedMagnitudeIsSignedByTheNormal)
{
  const auto s = shapes::bumpy_sphere<Kernel>(3000, 1.0, 0.0, 4.0); // a plain sphere: p - mean(neighbours) points outwards
  const Details d = details_of(s, 10, Detail_filter{Detail_order::linear, 0.8, 1.6});
  auto flipped = s;
  for(Vector& n : flipped.normals) n = -n;
  const Details f = details_of(flipped, 10, Detail_filter{Detail_order::linear, 0.8, 1.6});
  for(std::size_t i = 0; i < d.vectors.size(); ++i) {
    EXPECT_NEAR(std::abs(d.magnitudes[i]), std::sqrt(d.vectors[i].squared_length()), 1e-15);
    EXPECT_GT(d.magnitudes[i], 0.0);
    EXPECT_EQ(f.magnitudes[i], -d.magnitudes[i]);
  }
}

TEST(GeometricDetails, EstimatedNormalsGiveOutwardMagnitudesWhenNoneAreGiven)
{
  const auto s = shapes::bumpy_sphere<Kernel>(5000, 1.0, 0.02, 4.0);
  const Details given = details_of(s, 10, Detail_filter{}), estimated = details_of(s, 10, Detail_filter{}, false);
  // Where the detail is nearly tangent its sign is decided by tiny normal differences: compare the rest.
  std::size_t compared = 0, same_sign = 0;
  for(std::size_t i = 0; i < given.magnitudes.size(); ++i) {
    EXPECT_EQ(given.vectors[i], estimated.vectors[i]); // the vectors do not depend on the normals
    const double normal_part = std::abs(given.vectors[i] * s.normals[i]) / std::abs(given.magnitudes[i]);
    if(normal_part < 0.3) continue;
    ++compared;
    same_sign += (given.magnitudes[i] > 0) == (estimated.magnitudes[i] > 0);
  }
  EXPECT_GE(compared, given.magnitudes.size() / 2);
  EXPECT_GE(double(same_sign) / double(compared), 0.99);
}

TEST(GeometricDetails, SameResultThroughPointSet3PairsAndSequentialOrParallel)
{
  const auto s = shapes::bumpy_tube<Kernel>(6000);
  const Detail_settings settings(Detail_filter{Detail_order::cubic, 0.3, 1.8});
  const Details reference = details_of<CGAL::Sequential_tag>(s, 12, settings);
  const Details parallel = details_of<CGAL::Parallel_if_available_tag>(s, 12, settings);

  CGAL::Point_set_3<Point> ps;
  ps.add_normal_map();
  for(std::size_t i = 0; i < s.points.size(); ++i) ps.insert(s.points[i], s.normals[i]);
  auto detail = ps.add_property_map<Vector>("detail", CGAL::NULL_VECTOR).first;
  auto magnitude = ps.add_property_map<double>("detail_magnitude", 0).first;
  ASSERT_TRUE(compute_geometric_details(ps, 12, settings, detail, magnitude, ps.parameters()));

  using Pwn = std::pair<Point, Vector>;
  std::vector<Pwn> pwn;
  for(std::size_t i = 0; i < s.points.size(); ++i) pwn.emplace_back(s.points[i], s.normals[i]);
  Details pairs;
  pairs.vectors.resize(pwn.size());
  pairs.magnitudes.resize(pwn.size());
  ASSERT_TRUE(compute_geometric_details(pwn, 12, settings, Address_indexed_map<Pwn, Vector>{pwn.data(), &pairs.vectors},
                                        Address_indexed_map<Pwn, double>{pwn.data(), &pairs.magnitudes},
                                        CGAL::parameters::point_map(CGAL::First_of_pair_property_map<Pwn>())
                                          .normal_map(CGAL::Second_of_pair_property_map<Pwn>())));
  std::size_t i = 0;
  for(auto it = ps.begin(); it != ps.end(); ++it, ++i) {
    ASSERT_EQ(reference.vectors[i], parallel.vectors[i]);
    ASSERT_EQ(reference.magnitudes[i], parallel.magnitudes[i]);
    ASSERT_EQ(reference.vectors[i], detail[*it]);
    ASSERT_EQ(reference.magnitudes[i], magnitude[*it]);
    ASSERT_EQ(reference.vectors[i], pairs.vectors[i]);
    ASSERT_EQ(reference.magnitudes[i], pairs.magnitudes[i]);
  }
}

TEST(GeometricDetails, PointSet3WithoutNormalsGetsEstimatedNormalsEvenThroughItsParameters)
{
  const auto s = shapes::bumpy_sphere<Kernel>(3000, 1.0, 0.0, 4.0);
  CGAL::Point_set_3<Point> ps; // no normal property
  for(const Point& p : s.points) ps.insert(p);
  auto magnitude = ps.add_property_map<double>("m", 0).first;
  for(int variant = 0; variant < 2; ++variant) {
    auto detail = ps.add_property_map<Vector>("d", CGAL::NULL_VECTOR).first;
    if(variant == 0) ASSERT_TRUE(compute_geometric_details(ps, 10, Detail_filter{}, detail, magnitude, ps.parameters()));
    else ASSERT_TRUE(compute_geometric_details(ps, 10, Detail_filter{}, detail, magnitude));
    std::size_t outward = 0;
    for(auto it = ps.begin(); it != ps.end(); ++it) outward += magnitude[*it] > 0;
    EXPECT_EQ(outward, ps.size()) << "variant " << variant; // estimated normals are oriented outwards
  }
}

TEST(GeometricDetails, CancelledRunLeavesTheOutputsUntouched)
{
  const auto s = shapes::bumpy_sphere<Kernel>(150000);
  std::vector<std::size_t> indices(s.points.size());
  std::iota(indices.begin(), indices.end(), 0);
  std::vector<Vector> out(indices.size(), Vector(7, 7, 7));
  int calls = 0;
  const bool done = compute_geometric_details(indices, 10, Detail_filter{}, CGAL::make_property_map(out),
                                              CGAL::parameters::point_map(CGAL::make_property_map(s.points))
                                                .normal_map(CGAL::make_property_map(s.normals))
                                                .callback([&](double) { return ++calls < 2; }));
  EXPECT_FALSE(done);
  for(const Vector& v : out) ASSERT_EQ(v, Vector(7, 7, 7));
}

TEST(GeometricDetails, MeanShiftNeighborhoodsKeepACubeFacesDetailsInItsPlane)
{
  // With kNN rows, points near an edge average in the next face, so their detail points out of their face;
  // mean-shift rows keep one face (the modes' normals differ by sqrt 2 > one range bandwidth), and a detail
  // built from coplanar neighbours lies in the plane: delta . n = 0.
  const auto cube = shapes::cube<Kernel>(30);
  Detail_settings knn(Detail_filter{Detail_order::linear, 1.0, 2.0});
  Detail_settings mean_shift = knn;
  mean_shift.neighborhood = Laplacian_neighborhood::mean_shift;
  auto off_plane = [&](const Details& d) {
    std::size_t count = 0;
    for(double c : normal_components(d, cube)) count += std::abs(c) > 1e-9;
    return double(count) / double(cube.points.size());
  };
  const Details with_knn = details_of(cube, 10, knn);
  const Details with_modes = details_of<CGAL::Sequential_tag>(cube, 10, mean_shift);
  std::printf("points with a detail out of their face: kNN %.1f %%, mean shift %.2f %%\n", 100 * off_plane(with_knn),
              100 * off_plane(with_modes));
  EXPECT_GT(off_plane(with_knn), 0.1);
  EXPECT_LT(off_plane(with_modes), 0.005);
  const Details parallel = details_of<CGAL::Parallel_if_available_tag>(cube, 10, mean_shift);
  EXPECT_EQ(parallel.vectors, with_modes.vectors);

  // Interior points keep the same neighbours as with kNN: away from edges the details agree.
  std::size_t interior = 0, same = 0;
  for(std::size_t i = 0; i < cube.points.size(); ++i) {
    // Distance to the nearest edge: 0.5 minus the second largest |coordinate|.
    std::array<double, 3> c = {std::abs(cube.points[i].x()), std::abs(cube.points[i].y()), std::abs(cube.points[i].z())};
    std::sort(c.begin(), c.end());
    if(0.5 - c[1] < 5 * cube.average_spacing) continue;
    ++interior;
    same += (with_knn.vectors[i] - with_modes.vectors[i]).squared_length() < 1e-20;
  }
  EXPECT_GT(interior, cube.points.size() / 3);
  EXPECT_GT(double(same), 0.95 * double(interior));
}

TEST(GeometricDetails, NeighborRadiusMapReceivesEachPointsDistanceToItsKthNearest)
{
  // Brute force: the k-th smallest distance to the other points, on a noisy sampling (no ties to speak of).
  const auto s = shapes::bumpy_sphere<Kernel>(1500, 1.0, 0.05, 4.0);
  const std::size_t n = s.points.size();
  const unsigned k = 9;
  std::vector<double> expected(n);
  for(std::size_t i = 0; i < n; ++i) {
    std::vector<double> d;
    for(std::size_t j = 0; j < n; ++j)
      if(j != i) d.push_back(std::sqrt(CGAL::squared_distance(s.points[i], s.points[j])));
    std::nth_element(d.begin(), d.begin() + (k - 1), d.end());
    expected[i] = d[k - 1];
  }
  const std::vector<std::size_t> indices(boost::counting_iterator<std::size_t>(0),
                                         boost::counting_iterator<std::size_t>(n));
  const auto points = CGAL::make_property_map(s.points);
  for(const Laplacian_neighborhood neighborhood :
      {Laplacian_neighborhood::k_nearest, Laplacian_neighborhood::mean_shift}) {
    Detail_settings settings(Detail_filter{});
    settings.neighborhood = neighborhood;
    const Details reference = details_of(s, k, settings);
    Details d;
    d.vectors.resize(n);
    d.magnitudes.resize(n);
    std::vector<double> radius(n, -1.0);
    ASSERT_TRUE(compute_geometric_details(
      indices, k, settings, CGAL::make_property_map(d.vectors), CGAL::make_property_map(d.magnitudes),
      parameters::neighbor_radius_map(CGAL::make_property_map(radius), CGAL::parameters::point_map(points).normal_map(
                                                                         CGAL::make_property_map(s.normals)))));
    for(std::size_t i = 0; i < n; ++i) {
      ASSERT_NEAR(radius[i], expected[i], 1e-15) << setting_name(neighborhood) << " point " << i;
      ASSERT_EQ(d.vectors[i], reference.vectors[i]); // asking for the radii changes nothing else
      ASSERT_EQ(d.magnitudes[i], reference.magnitudes[i]);
    }
  }
}

TEST(GeometricDetails, BadInputThrowsAClearError)
{
  std::vector<Point> pts = shapes::bumpy_sphere<Kernel>(50).points;
  std::vector<Vector> out(pts.size());
  std::vector<std::size_t> idx(pts.size());
  std::iota(idx.begin(), idx.end(), 0);
  const auto np = CGAL::parameters::point_map(CGAL::make_property_map(pts));
  auto expect_error = [&](auto&& call, const char* needle) {
    try {
      call();
      ADD_FAILURE() << "no error for " << needle;
    } catch(const Invalid_input& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  const std::vector<std::size_t> none;
  expect_error([&] { compute_geometric_details(none, 10, Detail_filter{}, CGAL::make_property_map(out), np); }, "empty");
  expect_error([&] { compute_geometric_details(idx, 50, Detail_filter{}, CGAL::make_property_map(out), np); }, "k = 50");
  expect_error([&] { compute_geometric_details(idx, 10, Detail_filter{Detail_order::quadric, 0.0, 1.6}, CGAL::make_property_map(out), np); }, "lambda");
  expect_error([&] { compute_geometric_details(idx, 10, Detail_filter{Detail_order::cubic, 0.8, 0.8}, CGAL::make_property_map(out), np); }, "mu");
  std::vector<Vector> normals(pts.size(), Vector(0, 0, 1));
  normals[3] = CGAL::NULL_VECTOR;
  expect_error([&] { compute_geometric_details(idx, 10, Detail_filter{}, CGAL::make_property_map(out), np.normal_map(CGAL::make_property_map(normals))); }, "normal of point #3");
  Detail_settings mean_shift;
  mean_shift.neighborhood = Laplacian_neighborhood::mean_shift;
  mean_shift.mean_shift.range_bandwidth = 0;
  expect_error([&] { compute_geometric_details(idx, 10, mean_shift, CGAL::make_property_map(out), np); }, "range_bandwidth");
  mean_shift.mean_shift.range_bandwidth = 0.5;
  const std::vector<std::size_t> five(idx.begin(), idx.begin() + 5);
  const std::vector<Vector> up(pts.size(), Vector(0, 0, 1)); // given, as five points are too few to estimate them
  expect_error([&] { compute_geometric_details(five, 3, mean_shift, CGAL::make_property_map(out), np.normal_map(CGAL::make_property_map(up))); }, "at least 5");
  pts[9] = Point(std::numeric_limits<double>::infinity(), 0, 0);
  expect_error([&] { compute_geometric_details(idx, 10, Detail_filter{}, CGAL::make_property_map(out), np); }, "point #9");
}
