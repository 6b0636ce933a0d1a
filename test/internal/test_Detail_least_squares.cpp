// The least-squares core of scaling, enhancement and editing, against dense references. Built twice: with the
// configured Cholesky (CHOLMOD when found) and, with TEST_WITHOUT_CHOLMOD, with Eigen's fallback.
#include "test_support.h"

#ifdef TEST_WITHOUT_CHOLMOD
#undef CGAL_EXT_USE_CHOLMOD
#endif

#include <CGAL_ext/compute_point_set_laplacian.h>
#include <CGAL_ext/generated_shapes.h>
#include <CGAL_ext/internal/Detail_least_squares.h>
#include <CGAL_ext/internal/detail_manipulation.h>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <thread>

using namespace CGAL_ext;
using namespace CGAL_ext::internal;

namespace {
struct Small_problem
{
  Spatial_point_cloud cloud;
  Sparse_row_matrix K;
  std::vector<int> roi, anchors;
  Matrix_n3 roi_positions;

  Small_problem()
  {
    const auto sphere = shapes::bumpy_sphere<Kernel>(1200, 1.0, 0.02, 4.0);
    cloud = make_spatial_point_cloud<CGAL::Sequential_tag>(sphere.points, CGAL::Identity_property_map<Point>(), "test");
    Progress progress;
    build_laplacian<CGAL::Sequential_tag>(cloud, 10, {}, progress, K);
    for(int i = 0; i < int(cloud.size()); ++i)
      if(cloud.positions(i, 2) > 0.1) roi.push_back(i);
    for(std::size_t r = 0; r < roi.size(); r += 37) anchors.push_back(int(r));
    roi_positions.resize(Eigen::Index(roi.size()), 3);
    for(std::size_t r = 0; r < roi.size(); ++r) roi_positions.row(Eigen::Index(r)) = cloud.positions.row(roi[r]);
  }
};


Matrix_n3 random_block(Eigen::Index rows, unsigned seed)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Matrix_n3 m(rows, 3);
  for(Eigen::Index i = 0; i < rows; ++i)
    for(int c = 0; c < 3; ++c) m(i, c) = g(rng);
  return m;
}
} // namespace

TEST(DetailLeastSquares, OperatorRowsAreTheRestrictionOfTheFilterPolynomial)
{
  const Small_problem p;
  // The reference forms K's powers whole, with Eigen's sparse products.
  const Sparse_row_matrix K2 = p.K * p.K, K3 = K2 * p.K;
  for(Detail_order order : all_orders) {
    const Detail_filter filter{order, 0.8, 1.6};
    const auto c = filter.coefficients();
    const Eigen::MatrixXd F = Eigen::MatrixXd(Sparse_row_matrix(c.c1 * p.K + c.c2 * K2 + c.c3 * K3));
    Eigen::MatrixXd expected(p.roi.size(), p.roi.size());
    for(std::size_t a = 0; a < p.roi.size(); ++a)
      for(std::size_t b = 0; b < p.roi.size(); ++b) expected(Eigen::Index(a), Eigen::Index(b)) = F(p.roi[a], p.roi[b]);
    const Eigen::MatrixXd got = Eigen::MatrixXd(detail_operator_rows<CGAL::Parallel_if_available_tag>(p.K, filter, p.roi));
    EXPECT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-14) << Detail_filter::order_name(order);
  }
}

TEST(DetailLeastSquares, SolvesMatchADenseQRReferenceForBothSolvers)
{
  const Small_problem p;
  const double alpha = 0.7;
  for(Detail_order order : all_orders) {
    const Sparse_row_matrix A = detail_operator_rows<CGAL::Parallel_if_available_tag>(p.K, Detail_filter{order, 0.8, 1.6}, p.roi);
    const Matrix_n3 r = random_block(A.rows(), 1), t = random_block(Eigen::Index(p.anchors.size()), 2);
    // Dense reference: the stacked system [sqrt(alpha) A; S] u = [sqrt(alpha) r; t], by Householder QR.
    Eigen::MatrixXd stacked = Eigen::MatrixXd::Zero(A.rows() + Eigen::Index(p.anchors.size()), A.cols());
    Eigen::MatrixXd rhs(stacked.rows(), 3);
    stacked.topRows(A.rows()) = std::sqrt(alpha) * Eigen::MatrixXd(A);
    rhs.topRows(A.rows()) = std::sqrt(alpha) * r;
    for(std::size_t a = 0; a < p.anchors.size(); ++a) {
      stacked(A.rows() + Eigen::Index(a), p.anchors[a]) = 1.0;
      rhs.row(A.rows() + Eigen::Index(a)) = t.row(Eigen::Index(a));
    }
    const Eigen::MatrixXd reference = stacked.colPivHouseholderQr().solve(rhs);
    for(Linear_solver solver : {Linear_solver::cholesky, Linear_solver::conjugate_gradient}) {
      Least_squares_settings settings;
      settings.solver = solver;
      settings.detail_weight = alpha;
      settings.tolerance = 1e-12;
      Detail_least_squares system;
      system.factor<CGAL::Parallel_if_available_tag>(A, p.anchors, p.roi_positions, settings);
      const Matrix_n3 u = system.solve<CGAL::Parallel_if_available_tag>(r, t);
      EXPECT_LT((u - reference).norm(), 1e-7 * reference.norm())
        << Detail_filter::order_name(order) << " " << system.statistics().method;
      EXPECT_LT(system.statistics().relative_residual, 1e-10);
#if defined(CGAL_EXT_USE_CHOLMOD)
      const char* expected_method = "CHOLMOD";
#else
      const char* expected_method = "Eigen SimplicialLDLT";
#endif
      if(solver == Linear_solver::cholesky) {
        EXPECT_EQ(system.statistics().method.find(expected_method), 0u) << system.statistics().method;
      }
      // Factor once, solve many: a second right-hand side, and nothing to change gives exactly nothing.
      const Matrix_n3 twice = system.solve<CGAL::Parallel_if_available_tag>(Matrix_n3(2 * r), Matrix_n3(2 * t));
      EXPECT_LT((twice - 2 * u).norm(), 1e-9 * u.norm());
      const Matrix_n3 zero = system.solve<CGAL::Parallel_if_available_tag>(Matrix_n3::Zero(r.rows(), 3),
                                                                          Matrix_n3::Zero(t.rows(), 3));
      EXPECT_EQ(zero.cwiseAbs().maxCoeff(), 0.0);
    }
  }
}

TEST(DetailLeastSquares, ConsistentSystemsAreSolvedExactly)
{
  // Detail changes and anchor targets taken from one displacement field u*: every equation holds at u*, so the
  // least-squares solution is u* (whole-model enhancement writes p~ + s (p - p~) on this ground).
  const Small_problem p;
  const Matrix_n3 exact = random_block(Eigen::Index(p.roi.size()), 3);
  Matrix_n3 anchor_targets(Eigen::Index(p.anchors.size()), 3);
  for(std::size_t a = 0; a < p.anchors.size(); ++a) anchor_targets.row(Eigen::Index(a)) = exact.row(p.anchors[a]);
  for(Detail_order order : all_orders) {
    const Sparse_row_matrix A = detail_operator_rows<CGAL::Sequential_tag>(p.K, Detail_filter{order, 0.8, 1.6}, p.roi);
    const Matrix_n3 change = A * exact;
    for(Linear_solver solver : {Linear_solver::cholesky, Linear_solver::conjugate_gradient}) {
      Least_squares_settings settings;
      settings.solver = solver;
      settings.tolerance = 1e-13;
      Detail_least_squares system;
      system.factor<CGAL::Sequential_tag>(A, p.anchors, p.roi_positions, settings);
      const Matrix_n3 u = system.solve<CGAL::Sequential_tag>(change, anchor_targets);
      EXPECT_LT((u - exact).norm(), 1e-8 * exact.norm()) << Detail_filter::order_name(order) << " " << system.statistics().method;
    }
  }
}

TEST(DetailLeastSquares, SparseProductsDoNotDependOnTheThreadCount)
{
  const Small_problem p;
  const Sparse_row_matrix A = detail_operator_rows<CGAL::Sequential_tag>(p.K, Detail_filter{Detail_order::cubic, 0.8, 1.6}, p.roi);
  const Sparse_row_matrix At = A.transpose();
  const Sparse_row_matrix sequential = sparse_product<CGAL::Sequential_tag>(At, A, {}, -1, true);
  const Sparse_row_matrix parallel = sparse_product<CGAL::Parallel_if_available_tag>(At, A, {}, -1, true);
  ASSERT_EQ(sequential.nonZeros(), parallel.nonZeros());
  EXPECT_TRUE(std::equal(sequential.valuePtr(), sequential.valuePtr() + sequential.nonZeros(), parallel.valuePtr()));
  EXPECT_TRUE(std::equal(sequential.innerIndexPtr(), sequential.innerIndexPtr() + sequential.nonZeros(), parallel.innerIndexPtr()));
  // The upper triangle of A^T A, against Eigen's own product.
  const Eigen::MatrixXd full = Eigen::MatrixXd(At) * Eigen::MatrixXd(A);
  EXPECT_LT((Eigen::MatrixXd(sequential) - Eigen::MatrixXd(full.triangularView<Eigen::Upper>())).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(DetailLeastSquares, NestedDissectionIsAPermutation)
{
  const Small_problem p;
  const Sparse_row_matrix A = detail_operator_rows<CGAL::Sequential_tag>(p.K, Detail_filter{}, p.roi);
  const Sparse_row_matrix At = A.transpose();
  const std::vector<int> order = geometric_nested_dissection(sparse_product<CGAL::Sequential_tag>(At, A, {}, -1, true), p.roi_positions);
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  ASSERT_EQ(sorted.size(), p.roi.size());
  for(std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], int(i));
}

TEST(DetailLeastSquares, UnpinnedPartsAreFoundWithTheirSize)
{
  // Two separate sphere samplings; the region is everything, anchored on the first only.
  const auto a = shapes::bumpy_sphere<Kernel>(400, 1.0, 0.0), b = shapes::bumpy_sphere<Kernel>(150, 0.3, 0.0);
  std::vector<Point> points = a.points;
  for(const Point& p : b.points) points.push_back(p + Vector(5, 0, 0));
  const Spatial_point_cloud cloud = make_spatial_point_cloud<CGAL::Sequential_tag>(points, CGAL::Identity_property_map<Point>(), "test");
  Progress progress;
  Sparse_row_matrix K;
  build_laplacian<CGAL::Sequential_tag>(cloud, 10, {}, progress, K);
  std::vector<int> roi(cloud.size());
  std::iota(roi.begin(), roi.end(), 0);
  const std::vector<char> in_roi(cloud.size(), 1);
  const int anchor = cloud.spatial_index()[0]; // a point of the first sphere
  const auto parts = unpinned_parts(K, roi, in_roi, {anchor});
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].size, 150u);
  EXPECT_GE(cloud.input_index[std::size_t(parts[0].first)], 400);
  EXPECT_TRUE(unpinned_parts(K, roi, in_roi, {anchor, parts[0].first}).empty());
}

TEST(DetailLeastSquares, AFailedSolveIsANumericalFailureNeverAResult)
{
  // An accepted residual that no solve in floating point reaches: the check must refuse the result.
  const Small_problem p;
  const Sparse_row_matrix A = detail_operator_rows<CGAL::Sequential_tag>(p.K, Detail_filter{}, p.roi);
  Least_squares_settings settings;
  settings.accepted_residual = 1e-300;
  Detail_least_squares system;
  system.factor<CGAL::Sequential_tag>(A, p.anchors, p.roi_positions, settings);
  const Matrix_n3 r = random_block(A.rows(), 1), t = random_block(Eigen::Index(p.anchors.size()), 2);
  try {
    system.solve<CGAL::Sequential_tag>(r, t);
    ADD_FAILURE() << "a solve above the accepted residual was returned";
  } catch(const Numerical_failure& e) {
    EXPECT_NE(std::string(e.what()).find("relative residual"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::to_string(p.roi.size()) + " unknowns"), std::string::npos) << e.what();
  }
  // Nothing to solve is exact, whatever the threshold.
  EXPECT_EQ(system.solve<CGAL::Sequential_tag>(Matrix_n3::Zero(r.rows(), 3), Matrix_n3::Zero(t.rows(), 3)).norm(), 0.0);
  settings.accepted_residual = 0;
  EXPECT_THROW(settings.validate(), Invalid_input);
}

#ifdef CGAL_EXT_USE_CHOLMOD
namespace {
/// CHOLMOD allocates through SuiteSparse_config: while one of these lives, its allocations come out of a
/// budget of bytes, and fail as a real shortage would once the budget is spent.
class Cholmod_allocation_budget
{
public:
  explicit Cholmod_allocation_budget(std::size_t bytes) : m_saved(SuiteSparse_config)
  {
    remaining = bytes;
    taken = 0;
    SuiteSparse_config.malloc_func = [](std::size_t size) { return take(size) ? std::malloc(size) : nullptr; };
    SuiteSparse_config.calloc_func = [](std::size_t n, std::size_t size) { return take(n * size) ? std::calloc(n, size) : nullptr; };
    SuiteSparse_config.realloc_func = [](void* p, std::size_t size) { return take(size) ? std::realloc(p, size) : nullptr; };
  }
  ~Cholmod_allocation_budget() { SuiteSparse_config = m_saved; }

  static inline std::size_t remaining = 0, taken = 0;

private:
  static bool take(std::size_t bytes)
  {
    if(bytes > remaining) return false;
    remaining -= bytes;
    taken += bytes;
    return true;
  }

  SuiteSparse_config_struct m_saved;
};

} // namespace

TEST(DetailLeastSquares, CholmodRunningOutOfMemoryIsANumericalFailureNamingTheStep)
{
  const Small_problem p;
  const Sparse_row_matrix A = detail_operator_rows<CGAL::Sequential_tag>(p.K, Detail_filter{Detail_order::quadric, 0.8, 1.6}, p.roi);
  const Matrix_n3 r = random_block(A.rows(), 1), t = random_block(Eigen::Index(p.anchors.size()), 2);
  auto factor = [&](Detail_least_squares& system) {
    system.factor<CGAL::Sequential_tag>(A, p.anchors, p.roi_positions, Least_squares_settings{});
  };
  // What the analysis and factorisation take from CHOLMOD's allocator (the same on every run).
  std::size_t factor_bytes = 0;
  Matrix_n3 expected;
  {
    const Cholmod_allocation_budget unlimited(std::size_t(1) << 40);
    Detail_least_squares system;
    factor(system);
    factor_bytes = Cholmod_allocation_budget::taken;
    expected = system.solve<CGAL::Sequential_tag>(r, t);
  }
  ASSERT_GT(factor_bytes, 0u);
  // Budgets that run out during the analysis or the factorisation.
  for(double fraction : {0.0, 0.05, 0.3, 0.6, 0.9, 0.99}) {
    const Cholmod_allocation_budget budget(std::size_t(fraction * double(factor_bytes)));
    Detail_least_squares system;
    const std::string message = thrown_message<Numerical_failure>([&] { factor(system); });
    EXPECT_NE(message.find("out of memory while"), std::string::npos) << fraction << ": " << message;
    EXPECT_NE(message.find(std::to_string(p.roi.size()) + " unknowns"), std::string::npos) << message;
    EXPECT_THROW(system.solve<CGAL::Sequential_tag>(r, t), Invalid_input); // no half-made factor is used
  }
  // Exactly enough to factor: the solve's own allocation fails, and says so.
  {
    const Cholmod_allocation_budget budget(factor_bytes);
    Detail_least_squares system;
    factor(system);
    const std::string message = thrown_message<Numerical_failure>([&] { system.solve<CGAL::Sequential_tag>(r, t); });
    EXPECT_NE(message.find("out of memory while solving"), std::string::npos) << message;
  }
  // Memory again: the same system solves as before.
  Detail_least_squares system;
  factor(system);
  EXPECT_EQ((system.solve<CGAL::Sequential_tag>(r, t) - expected).norm(), 0.0);
}
#endif

#ifdef CGAL_EXT_SCOPED_RUNTIME_SETTINGS
// The factorisation serialises CHOLMOD's OpenMP regions (which compete with OpenBLAS's threads for the cores)
// for the calling thread only, and restores what that thread had.
TEST(DetailLeastSquares, FactorisationSerialisesTheOpenMPRegionsOfItsOwnThreadOnly)
{
  using Get = int (*)();
  const auto max_active_levels = reinterpret_cast<Get>(dlsym(RTLD_DEFAULT, "omp_get_max_active_levels"));
  if(!max_active_levels) GTEST_SKIP() << "CHOLMOD brought no OpenMP runtime";
  const int before = max_active_levels();
  ASSERT_GT(before, 0);
  {
    const Serial_openmp_regions serial;
    EXPECT_EQ(max_active_levels(), 0);
    int elsewhere = -1;
    std::thread([&] { elsewhere = max_active_levels(); }).join();
    EXPECT_EQ(elsewhere, before);
  }
  EXPECT_EQ(max_active_levels(), before);
}

// The solves run OpenBLAS on the calling thread (its threads would spin for the cores of the caller's next
// parallel loop) and give OpenBLAS its thread count back.
TEST(DetailLeastSquares, SolvesRunBlasOnTheCallingThreadAndRestoreItsThreadCount)
{
  const auto threads = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  const auto set_threads = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if(!threads || !set_threads) GTEST_SKIP() << "CHOLMOD's BLAS is not OpenBLAS";
  const int before = threads();
  set_threads(2);
  if(threads() != 2) GTEST_SKIP() << "this OpenBLAS is built for one thread";
  {
    const Serial_blas serial;
    EXPECT_EQ(threads(), 1);
  }
  EXPECT_EQ(threads(), 2);
  set_threads(before);
}
#endif
