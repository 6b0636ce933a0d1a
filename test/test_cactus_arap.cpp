// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// As-rigid-as-possible editing against CGAL's own mesh ARAP (Surface_mesh_deformation), converged, on the
// Botsch-Sorkine cactus at 21 and 70 degrees (doc/editing_arap.md, "Against CGAL on the Botsch–Sorkine cactus").
// CGAL's references are converged (3,000 iterations): its own 10 iterations stop 10-27 % of the diagonal short.
#include "cactus_comparison.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {

using bench_editing::Cactus_comparison;
using bench_editing::Cgal_arap;
using Settings = CGAL_ext::Detail_preserving_deformation_settings;

constexpr unsigned converged = 3000;

const Cactus_comparison& cactus()
{
  static const Cactus_comparison comparison(CGAL_EXT_DATA_DIR);
  return comparison;
}

struct Variant
{
  const char* what;
  double smoothing;
  CGAL_ext::Rigid_edge_weights weights;
  Cgal_arap reference;
  double bound = 0;                // the most the distance may be after `bound_iterations` (0: not checked)
  CGAL_ext::Rotation_smoothing_scale scale = CGAL_ext::Rotation_smoothing_scale::edge_lengths;
  unsigned bound_iterations = 300;
};

Settings arap_settings(const Variant& v, unsigned iterations)
{
  Settings s = cactus().settings();
  s.rotations = CGAL_ext::Detail_rotation::as_rigid_as_possible;
  s.rigid_rotation_smoothing = v.smoothing;
  s.rigid_rotation_smoothing_scale = v.scale;
  s.rigid_edge_weights = v.weights;
  s.rigid_iterations = iterations;
  return s;
}

// From 3 to 10 to 30 iterations per step, ARAP mode must not move away from the CGAL energy it shares: plain ARAP
// from SRE_ARAP's and ORIGINAL_ARAP's, the smooth-rotation term from SRE_ARAP's, cotangent weights from
// ORIGINAL_ARAP's (whose cotangent energy they mirror). Where a bound is given, enough iterations land within it.
void check(const Variant& v)
{
  for(double fraction : {0.3, 1.0}) {
    SCOPED_TRACE(::testing::Message() << v.what << " at " << cactus().degrees(fraction) << " degrees");
    double previous = INFINITY;
    for(unsigned iterations : {3u, 10u, 30u}) {
      const double distance = cactus().distance_to_cgal(fraction, arap_settings(v, iterations), v.reference, converged);
      std::printf("%.0f degrees, %s, %u iterations: %.2f %% of the diagonal from CGAL's converged %s\n",
                  cactus().degrees(fraction), v.what, iterations, 100 * distance,
                  v.reference == Cgal_arap::sre ? "SRE_ARAP" : "ORIGINAL_ARAP");
      EXPECT_LE(distance, previous + 1e-3) << iterations << " iterations moved away from CGAL's result";
      previous = distance;
    }
    if(v.bound > 0) {
      EXPECT_LE(cactus().distance_to_cgal(fraction, arap_settings(v, v.bound_iterations), v.reference, converged),
                v.bound)
        << v.bound_iterations << " iterations";
    }
  }
}

using Weights = CGAL_ext::Rigid_edge_weights;

TEST(CactusArap, ApproachesSreArap) { check({"ARAP", 0, Weights::uniform, Cgal_arap::sre}); }

TEST(CactusArap, ApproachesOriginalArap) { check({"ARAP", 0, Weights::uniform, Cgal_arap::original}); }

TEST(CactusArap, WithSmoothRotationsLandsNearSreArap)
{
  check({"ARAP with smooth rotations", 1, Weights::uniform, Cgal_arap::sre, 0.03});
}

TEST(CactusArap, WithCotangentWeightsLandsNearOriginalArap)
{
  check({"ARAP with cotangent weights", 0, Weights::cotangent, Cgal_arap::original, 0.025});
}

TEST(CactusArap, WithSreArapsEnergyLandsNearSreArap)
{
  check({"ARAP with SRE_ARAP's energy", 0.02, Weights::cotangent, Cgal_arap::sre, 0.02,
         CGAL_ext::Rotation_smoothing_scale::surface_area, 1000});
}

} // namespace
