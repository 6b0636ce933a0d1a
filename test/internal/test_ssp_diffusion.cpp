// The diffusion stencil of internal/ssp_diffusion.h: weights that vanish before a sample point leaves a point's
// stencil (so the motion is continuous in space), exact rigid motions and exact stillness, on the portable path and
// the 4-wide one alike, which agree.
#include <CGAL_ext/internal/ssp_diffusion.h>

#include <CGAL/tags.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <random>
#include <vector>

using namespace CGAL_ext::internal;
using CGAL_ext::Diffusion_origin;

namespace {

Matrix_n3 random_samples(std::size_t n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Matrix_n3 m(Eigen::Index(n), 3);
  for(std::size_t i = 0; i < n; ++i) m.row(Eigen::Index(i)) << u(rng), u(rng), 0.1 * u(rng);
  return m;
}

/// Each sample point's weight in the stencil of `point` (0 outside it).
std::map<int, double> weights_at(const Eigen::RowVector3d& point, const Matrix_n3& samples, std::size_t m)
{
  Diffusion_stencil stencil;
  stencil.setup<CGAL::Sequential_tag>(Matrix_n3(point), samples, m);
  std::map<int, double> w;
  for(int e = stencil.samples.offsets[0]; e < stencil.samples.offsets[1]; ++e)
    w[stencil.samples.indices[std::size_t(e)]] = stencil.weights[std::size_t(e)];
  return w;
}

} // namespace

TEST(DiffusionStencil, WeightsArePositiveSumToOneAndFallWithDistance)
{
  const Matrix_n3 samples = random_samples(60, 1), points = random_samples(500, 2);
  Diffusion_stencil stencil;
  stencil.setup<CGAL::Parallel_if_available_tag>(points, samples, 4);
  for(std::size_t i = 0; i < stencil.samples.size(); ++i) {
    ASSERT_EQ(stencil.samples.degree(i), 4);
    double sum = 0, previous = 2;
    for(int e = stencil.samples.offsets[i]; e < stencil.samples.offsets[i + 1]; ++e) {
      const double w = stencil.weights[std::size_t(e)];
      EXPECT_GE(w, 0.0);
      EXPECT_LE(w, previous + 1e-15); // nearest first, so weights never grow along the row
      previous = w;
      sum += w;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
}

TEST(DiffusionStencil, EachPointsOwnSamplePointGivesTheSameStencil)
{
  const Matrix_n3 samples = random_samples(80, 3), points = random_samples(2000, 4);
  std::vector<int> owner(2000); // the nearest sample point, as a clustering gives it
  for(Eigen::Index p = 0; p < points.rows(); ++p)
    (samples.rowwise() - points.row(p)).rowwise().squaredNorm().minCoeff(&owner[std::size_t(p)]);
  Diffusion_stencil by_tree, by_owner;
  by_tree.setup<CGAL::Parallel_if_available_tag>(points, samples, 6);
  by_owner.setup<CGAL::Parallel_if_available_tag>(points, samples, 6, &owner);
  EXPECT_EQ(by_owner.samples.indices, by_tree.samples.indices);
  EXPECT_EQ(by_owner.weights, by_tree.weights);
}

TEST(DiffusionStencil, EverySamplePointsWeightIsContinuousAlongAPath)
{
  // Walk a point across the sample points in tiny steps: the stencil's membership changes many times, but no
  // sample point's weight may jump. With the earlier weights 1 / (d^2 + h^2), cut off at the 4th nearest, the
  // weight of the sample point that left the stencil dropped from about 0.2 to 0 in one step.
  const Matrix_n3 samples = random_samples(40, 3);
  const int steps = 4000;
  std::map<int, double> before = weights_at(Eigen::RowVector3d(-1, -0.2, 0), samples, 4);
  double largest_jump = 0;
  int membership_changes = 0;
  for(int s = 1; s <= steps; ++s) {
    const double t = double(s) / steps;
    const std::map<int, double> after = weights_at(Eigen::RowVector3d(-1 + 2 * t, -0.2 + 0.5 * t, 0), samples, 4);
    std::map<int, double> all = before;
    for(const auto& [j, w] : after) all.emplace(j, 0.0);
    for(const auto& [j, w0] : all) {
      const auto it = after.find(j);
      largest_jump = std::max(largest_jump, std::abs((it == after.end() ? 0.0 : it->second) - w0));
      if(it == after.end() || !before.count(j)) ++membership_changes;
    }
    before = after;
  }
  EXPECT_GT(membership_changes, 10);
  // A step is 5e-4 of the path: a continuous weight changes by a small multiple of that.
  EXPECT_LT(largest_jump, 0.02);
}

TEST(DiffusionStencil, ARigidMotionOfEverySamplePointMovesEveryPointRigidly)
{
  const Matrix_n3 samples = random_samples(50, 4), points = random_samples(300, 5);
  Matrix_n3 normals = random_samples(300, 6);
  normals.rowwise().normalize();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::RowVector3d t(0.3, -1.2, 2.0);
  const Matrix_n3 moved = (samples * R.transpose()).rowwise() + t;
  const std::vector<Eigen::Matrix3d> rotation(50, R);
  Diffusion_stencil stencil;
  stencil.setup<CGAL::Parallel_if_available_tag>(points, samples, 4);
  for(bool wide : {false, true})
  for(Diffusion_origin origin : {Diffusion_origin::nearest_sample, Diffusion_origin::own_sample}) {
    stencil.use_wide_vectors = wide;
    Matrix_n3 out_points(points.rows(), 3), out_normals(points.rows(), 3);
    stencil.apply<CGAL::Parallel_if_available_tag>(points, normals, samples, moved, rotation, origin, out_points, out_normals);
    const Matrix_n3 expected = (points * R.transpose()).rowwise() + t;
    EXPECT_LT((out_points - expected).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((out_normals - normals * R.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(DiffusionStencil, PointsWhoseSamplePointsStayKeepTheirBits)
{
  const Matrix_n3 samples = random_samples(50, 7), points = random_samples(300, 8);
  Matrix_n3 normals = random_samples(300, 9);
  normals.rowwise().normalize();
  Diffusion_stencil stencil;
  stencil.setup<CGAL::Sequential_tag>(points, samples, 4);
  // Sample point 0 moves; every point that does not have it in its stencil keeps its position and normal exactly.
  Matrix_n3 moved = samples;
  moved.row(0) += Eigen::RowVector3d(0.01, 0, 0);
  const std::vector<Eigen::Matrix3d> rotation(50, Eigen::Matrix3d::Identity());
  for(bool wide : {false, true}) {
    stencil.use_wide_vectors = wide;
    Matrix_n3 out_points(points.rows(), 3), out_normals(points.rows(), 3);
    stencil.apply<CGAL::Sequential_tag>(points, normals, samples, moved, rotation, Diffusion_origin::own_sample, out_points, out_normals);
    int unmoved = 0;
    for(std::size_t i = 0; i < stencil.samples.size(); ++i) {
      if(std::find(stencil.samples.begin(i), stencil.samples.end(i), 0) != stencil.samples.end(i)) continue;
      ++unmoved;
      EXPECT_TRUE(out_points.row(Eigen::Index(i)) == points.row(Eigen::Index(i)));
      EXPECT_TRUE(out_normals.row(Eigen::Index(i)) == normals.row(Eigen::Index(i)));
    }
    EXPECT_GT(unmoved, 200);
  }
}

TEST(DiffusionStencil, TheWidePathComputesWhatThePortableOneDoes)
{
  if(!Diffusion_stencil::wide_vectors_available()) GTEST_SKIP() << "this build or processor has no AVX2 and FMA";
  // Every sample point moves and maps offsets by a general linear map (a stretch and a shear beside a turn), on
  // a subset of the points; the two paths differ by the rounding of fused multiply-adds only.
  const std::size_t count = 80, n = 2000;
  const Matrix_n3 samples = random_samples(count, 10), points = random_samples(n, 11);
  Matrix_n3 normals = random_samples(n, 12), moved = samples + 0.05 * random_samples(count, 13);
  normals.rowwise().normalize();
  normals.row(3).setZero(); // a point without a normal keeps none (no division by zero)
  std::vector<Eigen::Matrix3d> map(count);
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for(Eigen::Matrix3d& A : map) A = Eigen::Matrix3d::Identity() + Eigen::Matrix3d::NullaryExpr([&] { return u(rng); });
  std::vector<int> active;
  for(int i = 0; i < int(n); i += 3) active.push_back(i);
  Diffusion_stencil stencil;
  stencil.setup<CGAL::Parallel_if_available_tag>(points, samples, 6);
  for(Diffusion_origin origin : {Diffusion_origin::nearest_sample, Diffusion_origin::own_sample}) {
    Matrix_n3 out[2][2]; // [wide][points, normals]
    for(int wide = 0; wide < 2; ++wide) {
      stencil.use_wide_vectors = wide == 1;
      out[wide][0] = points;
      out[wide][1] = normals;
      stencil.apply<CGAL::Parallel_if_available_tag>(points, normals, samples, moved, map, origin, out[wide][0], out[wide][1], &active);
    }
    EXPECT_LT((out[1][0] - out[0][0]).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LT((out[1][1] - out[0][1]).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_TRUE(out[1][1].row(3).isZero(0) && out[0][1].row(3).isZero(0));
    EXPECT_GT((out[1][0] - points).cwiseAbs().maxCoeff(), 1e-2); // the points moved
    for(Eigen::Index i = 1; i < Eigen::Index(n); i += 3) // and the others were left as they were
      EXPECT_TRUE(out[1][0].row(i) == points.row(i) && out[1][1].row(i) == normals.row(i));
  }
}
