// Tests of detect_sparse_directions (paper Sect. 6.3, Fig. 9a; doc/upsampling.md).
#include "upsampling_fixtures.h"

#include <CGAL_ext/detect_sparse_directions.h>

#include <gtest/gtest.h>

TEST(DetectSparseDirections, HoleRimsPointIntoTheHoleAndOpenBordersAreNotHoles)
{
  const Oriented_points plane = plane_with_hole(2.6);
  std::vector<Vector> direction(plane.points.size());
  CGAL_ext::Sparse_direction_settings settings;
  settings.spacing = 1;
  const auto summary = CGAL_ext::detect_sparse_directions(plane.indices(), 10, settings, CGAL::make_property_map(direction), plane.np());
  EXPECT_GT(summary.hole_boundary_points, 10u);
  // The square's own border is sparse (nothing beyond it) but no hole.
  EXPECT_GT(summary.sparse_points, summary.hole_boundary_points + 100);
  for(std::size_t i = 0; i < plane.points.size(); ++i) {
    const double length = std::sqrt(direction[i].squared_length());
    if(length == 0) continue;
    const Eigen::Vector2d to_centre(20 - plane.points[i].x(), 20 - plane.points[i].y());
    EXPECT_LT(to_centre.norm(), 2.6 + 2.0) << "point " << i << " is no hole rim";
    // Toward the hole's side: the gap runs along a chord of the hole (not always through its centre).
    EXPECT_GT(Eigen::Vector2d(direction[i].x(), direction[i].y()).dot(to_centre.normalized()), 0.0) << "point " << i;
    EXPECT_NEAR(length, 1.0, 1e-12);
  }
  // Without the hole nothing is a hole boundary.
  const Oriented_points full = plane_with_hole(0);
  std::vector<Vector> none(full.points.size());
  EXPECT_EQ(CGAL_ext::detect_sparse_directions(full.indices(), 10, settings, CGAL::make_property_map(none), full.np())
              .hole_boundary_points, 0u);
}

TEST(DetectSparseDirections, ARandomSamplingsOwnGapsAreNoHolesButAHoleTwiceAsWideIs)
{
  // Density 1 on [0, 60]^2, with and without a hole of radius 3 around the centre. A fifth of the points of a
  // random sampling have a quarter empty within two local spacings; with local spacings a gap must also be twice
  // as wide as the gaps typical around it, which leaves 5 of these 3,600 points (and 6 on the hole's rim).
  for(const double hole : {0.0, 3.0}) {
    const Oriented_points plane = random_plane_with_hole(60, hole, 11);
    std::vector<Vector> direction(plane.points.size());
    const auto summary = CGAL_ext::detect_sparse_directions(plane.indices(), 10, CGAL_ext::Sparse_direction_settings(),
                                                            CGAL::make_property_map(direction), plane.np());
    std::size_t on_rim = 0;
    for(std::size_t i = 0; i < plane.points.size(); ++i)
      on_rim += direction[i].squared_length() > 0 && std::hypot(plane.points[i].x() - 30, plane.points[i].y() - 30) < hole + 2;
    std::printf("random plane, hole of radius %g: %zu hole-boundary points, %zu of them on its rim\n", hole,
                summary.hole_boundary_points, on_rim);
    EXPECT_LT(summary.hole_boundary_points - on_rim, plane.points.size() / 100);
    if(hole > 0) {
      EXPECT_GE(on_rim, 3u);
    }
  }
}

TEST(DetectSparseDirections, MissingNormalsAndBadSettingsAreClearErrors)
{
  const Oriented_points plane = plane_with_hole(2.6);
  std::vector<Vector> direction(plane.points.size());
  auto message = [](auto&& f) -> std::string {
    try { f(); } catch(const CGAL_ext::Invalid_input& e) { return e.what(); }
    return "no error";
  };
  EXPECT_NE(message([&] { CGAL_ext::detect_sparse_directions(plane.indices(), 10, {}, CGAL::make_property_map(direction), plane.points_only()); })
              .find("need normals"), std::string::npos);
  CGAL_ext::Sparse_direction_settings bad;
  bad.spacing = -1;
  EXPECT_NE(message([&] { CGAL_ext::detect_sparse_directions(plane.indices(), 10, bad, CGAL::make_property_map(direction), plane.np()); })
              .find("spacing"), std::string::npos);
  bad.spacing = 1;
  bad.max_hole_size = 1;
  EXPECT_NE(message([&] { CGAL_ext::detect_sparse_directions(plane.indices(), 10, bad, CGAL::make_property_map(direction), plane.np()); })
              .find("max_hole_size"), std::string::npos);
}
