// The detail relaxation of internal/detail_relaxation.h (restore_details()): its Chebyshev steps land on the
// solution of its system, rebuilt independently, a rigid turn gets its bumps back, and a row's result depends on
// the rows within as many hops as steps, whatever their numbering.
#include <CGAL_ext/internal/detail_relaxation.h>

#include <CGAL/number_type_config.h>
#include <CGAL/tags.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <utility>
#include <vector>

TEST(DetailRelaxation, DetailRestorationSolvesItsSystem)
{
  // A bumpy 30 x 30 sheet, its bumps flattened to a third as a blend would, bent into an arc or turned
  // rigidly: the restore's Chebyshev steps must land on the solution of (1 + a) x_i - mean_j x_j = R_i d_i +
  // a y_i, checked here with neighbours found by brute force and rotations by an SVD. Turned rigidly, the bumps
  // come back. (Bent, the details at rest lack the bend's own curvature, and the solve flattens the bend by
  // about its curvature times the squared spacing over a: an offset along the normal, strong on this coarse
  // sheet bent a quarter turn, a fraction of a spacing on a scan; doc/editing_diffusion.md, "Restoring the details".)
  namespace in = CGAL_ext::internal;
  const int side = 30;
  const std::size_t n = std::size_t(side * side), k = 10;
  const double spacing = 1.0 / (side - 1), anchor = 0.01;
  auto bump = [](double u, double v) { return 0.01 * std::sin(19 * u) * std::cos(23 * v); };
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  // The sheet at (u, v), moved w along its normal.
  auto bent = [](double u, double v, double w) { // a quarter turn along u
    const double angle = CGAL_PI / 2 * u, radius = 2 / CGAL_PI + w;
    return Eigen::RowVector3d(radius * std::sin(angle), v, radius * std::cos(angle));
  };
  auto turned = [&](double u, double v, double w) -> Eigen::RowVector3d {
    return Eigen::RowVector3d(u, v, w) * turn.transpose();
  };
  for(const bool bend : {true, false}) {
    auto sheet = [&](double u, double v, double w) -> Eigen::RowVector3d { return bend ? bent(u, v, w) : turned(u, v, w); };
    in::Matrix_n3 rest(Eigen::Index(n), 3), positions(Eigen::Index(n), 3);
    std::vector<int> rows;
    for(int a = 0; a < side; ++a)
      for(int b = 0; b < side; ++b) {
        const Eigen::Index i = a * side + b;
        const double u = a * spacing, v = b * spacing;
        rest.row(i) << u, v, bump(u, v);
        const bool relaxed = a > 2 && a < side - 3 && b > 2 && b < side - 3;
        positions.row(i) = sheet(u, v, (relaxed ? 1.0 / 3 : 1.0) * bump(u, v));
        if(relaxed) rows.push_back(int(i));
      }
    const in::Matrix_n3 blended = positions;
    in::Detail_relaxation relaxation;
    relaxation.setup<CGAL::Parallel_if_available_tag>(rest, rows, k);
    const auto outcome = relaxation.apply<CGAL::Parallel_if_available_tag>(rest, anchor, 1000, 1e-12, positions);
    EXPECT_GT(outcome.iterations, 0u);
    EXPECT_LE(outcome.residual, 1e-12);

    // The system, rebuilt independently: the closed ball of the k-th nearest by brute force (the lattice ties),
    // symmetrised within the relaxed rows.
    std::vector<char> relaxed(n, 0);
    for(int r : rows) relaxed[std::size_t(r)] = 1;
    std::vector<std::vector<int>> neighbors(n);
    for(int r : rows) {
      std::vector<double> squared(n);
      for(std::size_t j = 0; j < n; ++j) { // the library's one distance formula, so that ties are ties
        const Eigen::RowVector3d d = rest.row(Eigen::Index(j)) - rest.row(r);
        squared[j] = d(0) * d(0) + d(1) * d(1) + d(2) * d(2);
      }
      std::vector<double> ranked = squared;
      std::nth_element(ranked.begin(), ranked.begin() + long(k), ranked.end()); // [0] is the row itself
      for(std::size_t j = 0; j < n; ++j)
        if(int(j) != r && squared[j] <= ranked[k]) {
          neighbors[std::size_t(r)].push_back(int(j));
          if(relaxed[j]) neighbors[j].push_back(r);
        }
    }
    double residual = 0, size = 0, flattened = 0, restored = 0;
    for(int r : rows) {
      std::vector<int>& around = neighbors[std::size_t(r)];
      std::sort(around.begin(), around.end());
      around.erase(std::unique(around.begin(), around.end()), around.end());
      Eigen::RowVector3d rest_mean = Eigen::RowVector3d::Zero(), mean = Eigen::RowVector3d::Zero();
      Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
      for(int j : around) {
        rest_mean += rest.row(j) / double(around.size());
        mean += positions.row(j) / double(around.size());
        covariance += (rest.row(j) - rest.row(r)).transpose() * (blended.row(j) - blended.row(r));
      }
      Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();
      flip(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
      const Eigen::Matrix3d R = svd.matrixV() * flip * svd.matrixU().transpose();
      const Eigen::RowVector3d detail = (rest.row(r) - rest_mean) * R.transpose();
      residual += ((1 + anchor) * positions.row(r) - mean - detail - anchor * blended.row(r)).squaredNorm();
      size += detail.squaredNorm();
      // The bumps, along the sheet's normal.
      const double u = rest(r, 0), v = rest(r, 1);
      const Eigen::RowVector3d smooth = sheet(u, v, 0), normal = sheet(u, v, 1) - smooth;
      flattened += std::abs((blended.row(r) - smooth).dot(normal) - bump(u, v));
      restored += std::abs((positions.row(r) - smooth).dot(normal) - bump(u, v));
    }
    EXPECT_LT(std::sqrt(residual / size), 1e-9);
    std::printf("%s: bump error %.2e, restored %.2e (%u iterations)\n", bend ? "bent" : "turned",
                flattened / double(rows.size()), restored / double(rows.size()), outcome.iterations);
    if(!bend) {
      EXPECT_LT(restored, 0.3 * flattened); // 0.21: the anchor keeps a/(a + lambda) of the flattening
    }
  }
}

TEST(DetailRelaxation, ARowDependsOnItsStepsHopsAloneWhateverTheNumbering)
{
  // A bumpy 100 x 100 lattice (its distances tie) with the bumps flattened and the sheet bent, restored whole,
  // with its rows renumbered, and as a slab of it renumbered too (a tile): every row farther from the slab's cut
  // than the steps' hops (a closed ball of 10 reaches two spacings; three hops more for the targets' rotations,
  // the unknowns and the twins) lands on the same bits; the rows at the cut do not.
  namespace in = CGAL_ext::internal;
  const int side = 100, slab = 80;
  const std::size_t k = 10;
  const double spacing = 1.0 / (side - 1), anchor = 0.1, tolerance = 0.01;
  const unsigned int steps = in::Detail_relaxation::steps(anchor, 100, tolerance);
  ASSERT_EQ(steps, 12u); // acosh(100) / acosh(1.1) = 11.94
  auto bump = [](double u, double v) { return 0.01 * std::sin(19 * u) * std::cos(23 * v); };
  auto bent = [](double u, double v, double w) {
    const double angle = CGAL_PI / 2 * u, radius = 2 / CGAL_PI + w;
    return Eigen::RowVector3d(radius * std::sin(angle), v, radius * std::cos(angle));
  };
  // Restores the lattice points (a, b) of `cells`, in that order; returns their positions.
  auto restore = [&](const std::vector<std::pair<int, int>>& cells) {
    const Eigen::Index n = Eigen::Index(cells.size());
    in::Matrix_n3 rest(n, 3), positions(n, 3);
    std::vector<int> rows;
    for(Eigen::Index i = 0; i < n; ++i) {
      const auto [a, b] = cells[std::size_t(i)];
      const double u = a * spacing, v = b * spacing;
      rest.row(i) << u, v, bump(u, v);
      const bool relaxed = a > 2 && a < side - 3 && b > 2 && b < side - 3;
      positions.row(i) = bent(u, v, (relaxed ? 1.0 / 3 : 1.0) * bump(u, v));
      if(relaxed) rows.push_back(int(i));
    }
    in::Detail_relaxation relaxation;
    relaxation.setup<CGAL::Parallel_if_available_tag>(rest, rows, k);
    const auto outcome = relaxation.apply<CGAL::Parallel_if_available_tag>(rest, anchor, 100, tolerance, positions);
    EXPECT_EQ(outcome.iterations, steps);
    EXPECT_LE(outcome.residual, tolerance);
    return positions;
  };
  std::vector<std::pair<int, int>> whole, renumbered, part;
  for(int a = 0; a < side; ++a)
    for(int b = 0; b < side; ++b) whole.emplace_back(a, b);
  std::mt19937 random(7);
  renumbered = whole;
  std::shuffle(renumbered.begin(), renumbered.end(), random);
  for(const auto& cell : renumbered)
    if(cell.first < slab) part.push_back(cell);
  const in::Matrix_n3 expected = restore(whole), shuffled = restore(renumbered), tile = restore(part);
  const int reach = 2 * int(steps + 3); // in spacings
  std::size_t renumbered_differ = 0;
  for(std::size_t i = 0; i < renumbered.size(); ++i)
    renumbered_differ +=
      shuffled.row(Eigen::Index(i)) != expected.row(Eigen::Index(renumbered[i].first * side + renumbered[i].second));
  EXPECT_EQ(renumbered_differ, 0u);
  std::size_t compared = 0, differ_inside = 0, differ_at_cut = 0;
  for(std::size_t i = 0; i < part.size(); ++i) {
    const auto [a, b] = part[i];
    const Eigen::Index at = Eigen::Index(a * side + b);
    if(slab - 1 - a >= reach) {
      ++compared;
      differ_inside += tile.row(Eigen::Index(i)) != expected.row(at);
    } else if(a == slab - 1 && b > 2 && b < side - 3) {
      differ_at_cut += tile.row(Eigen::Index(i)) != expected.row(at);
    }
  }
  EXPECT_GT(compared, std::size_t(4000));
  EXPECT_EQ(differ_inside, 0u);
  EXPECT_GT(differ_at_cut, std::size_t(side / 2));
}
