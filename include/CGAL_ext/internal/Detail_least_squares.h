// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_DETAIL_LEAST_SQUARES_H
#define CGAL_EXT_INTERNAL_DETAIL_LEAST_SQUARES_H

#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/Least_squares_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/Sparse_products.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/nested_dissection.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/SparseCholesky>
#ifdef CGAL_EXT_USE_CHOLMOD
#include <Eigen/CholmodSupport>
#if __has_include(<dlfcn.h>) && __has_include(<sys/resource.h>) && __has_include(<unistd.h>)
#include <dlfcn.h>
#include <sys/resource.h>
#include <unistd.h>
#define CGAL_EXT_SCOPED_RUNTIME_SETTINGS
#endif
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// The rows of `f(K)` of the points `roi` (indices into K, increasing) restricted to the columns of those
/// points, renumbered 0..|roi|-1. The other columns multiply points that stay fixed; with displacements as
/// unknowns they contribute nothing. Built by Horner's scheme, `f(K) = K^(d-1) (c_low I + c_high K)`, as a
/// product of restricted sparse factors: K's powers are never formed for the whole cloud.
template <typename ConcurrencyTag>
Sparse_row_matrix detail_operator_rows(const Sparse_row_matrix& K, const Detail_filter& filter,
                                       const std::vector<int>& roi)
{
  const Detail_filter::Coefficients c = filter.coefficients();
  const int degree = filter.degree();
  // f(K) = K^(degree - 1) (low I + high K) for the three orders (the cubic has no linear term).
  const double low = degree == 1 ? 0.0 : degree == 2 ? c.c1 : c.c2;
  const double high = degree == 1 ? c.c1 : degree == 2 ? c.c2 : c.c3;

  std::vector<int> local_of(std::size_t(K.cols()), -1);
  for(std::size_t r = 0; r < roi.size(); ++r) local_of[std::size_t(roi[r])] = int(r);

  // Rows roi of (low I + high K); its columns are renumbered now when it is the last factor.
  const bool last = degree == 1;
  Sparse_row_matrix B(Eigen::Index(roi.size()), last ? Eigen::Index(roi.size()) : K.cols());
  std::vector<int> counts(roi.size() + 1, 0);
  for(std::size_t r = 0; r < roi.size(); ++r) {
    int count = 0;
    for(int e = K.outerIndexPtr()[roi[r]]; e < K.outerIndexPtr()[roi[r] + 1]; ++e)
      count += !last || local_of[std::size_t(K.innerIndexPtr()[e])] >= 0;
    counts[r + 1] = counts[r] + count;
  }
  B.resizeNonZeros(counts.back());
  std::copy(counts.begin(), counts.end(), B.outerIndexPtr());
  for_range<ConcurrencyTag>(0, roi.size(), [&](std::size_t r) {
    int out = counts[r];
    for(int e = K.outerIndexPtr()[roi[r]]; e < K.outerIndexPtr()[roi[r] + 1]; ++e) {
      const int j = K.innerIndexPtr()[e];
      const int column = last ? local_of[std::size_t(j)] : j;
      if(column < 0) continue;
      B.innerIndexPtr()[out] = column;
      B.valuePtr()[out++] = high * K.valuePtr()[e] + (j == roi[r] ? low : 0.0);
    }
  });
  for(int power = 1; power < degree; ++power) {
    const bool final_factor = power == degree - 1;
    B = final_factor ? sparse_product<ConcurrencyTag>(B, K, local_of, Eigen::Index(roi.size()))
                     : sparse_product<ConcurrencyTag>(B, K);
  }
  return B;
}

#ifdef CGAL_EXT_SCOPED_RUNTIME_SETTINGS
/// An integer setting of a runtime library: its getter and setter, looked up once, not linked (null without the
/// library loaded).
struct Runtime_setting
{
  int (*get)() = nullptr;
  void (*set)(int) = nullptr;

  Runtime_setting(const char* getter, const char* setter)
    : get(reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, getter))),
      set(reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, setter)))
  {}
};

inline const Runtime_setting& openmp_max_active_levels()
{
  static const Runtime_setting setting("omp_get_max_active_levels", "omp_set_max_active_levels");
  return setting;
}

inline const Runtime_setting& openblas_threads()
{
  static const Runtime_setting setting("openblas_get_num_threads", "openblas_set_num_threads");
  return setting;
}

/// While it lives, a runtime setting holds `value`, and its old value comes back after; without the library
/// loaded this does nothing.
class Scoped_runtime_setting
{
public:
  Scoped_runtime_setting(const Runtime_setting& setting, int value)
  {
    if(!setting.get || !setting.set || (m_saved = setting.get()) == value) return;
    setting.set(value);
    m_set = setting.set;
  }
  ~Scoped_runtime_setting()
  {
    if(m_set) m_set(m_saved);
  }
  Scoped_runtime_setting(const Scoped_runtime_setting&) = delete;
  Scoped_runtime_setting& operator=(const Scoped_runtime_setting&) = delete;

private:
  void (*m_set)(int) = nullptr;
  int m_saved = 0;
};

/// While it lives, the OpenMP regions the calling thread opens run on that thread alone (the OpenMP runtime's
/// `max-active-levels` of this thread set to 0; other threads are untouched). CHOLMOD 3 runs parts of its
/// supernodal factorisation in OpenMP regions of a fixed four threads, which on a machine with few cores fight
/// OpenBLAS's threads, idle but spinning, for the cores: serial regions factor faster there
/// (doc/editing_at_scale.md, "Editing's factorisation").
struct Serial_openmp_regions : Scoped_runtime_setting
{
  Serial_openmp_regions() : Scoped_runtime_setting(openmp_max_active_levels(), 0) {}
};

/// While it lives, OpenBLAS (CHOLMOD's BLAS, when it is OpenBLAS) runs its calls on the calling thread. A solve
/// with the factor is a sequence of small triangular blocks: OpenBLAS's threads gain nothing on them, and once
/// woken they spin for the cores the caller's next parallel loop needs (doc/editing_at_scale.md, "Editing's
/// factorisation").
struct Serial_blas : Scoped_runtime_setting
{
  Serial_blas() : Scoped_runtime_setting(openblas_threads(), 1) {}
};

/// Whether `bytes` more fit under the process's address-space limit (`ulimit -v`, as batch systems set it): true
/// without one, or where the process's size cannot be read.
inline bool fits_address_space_limit(double bytes)
{
  rlimit limit;
  if(getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return true;
  std::ifstream statm("/proc/self/statm");
  double pages = 0;
  if(!(statm >> pages)) return true;
  return pages * double(sysconf(_SC_PAGESIZE)) + bytes <= double(limit.rlim_cur);
}

/// The address space OpenBLAS may still map for its work buffers: one per thread it runs, each of the size
/// Debian's OpenBLAS is built with (a build with smaller buffers is only refused sooner). OpenBLAS retries a
/// failed allocation of them forever (blas_memory_alloc), so a factorisation that reaches it under a tight
/// address-space limit would hang instead of failing (doc/editing_at_scale.md, "Editing's factorisation").
inline double blas_buffer_bytes()
{
  constexpr double debian_buffer_bytes = double(std::size_t(128) << 20);
  return openblas_threads().get ? double(openblas_threads().get()) * debian_buffer_bytes : 0.0;
}
#endif

/*
  The least-squares core of detail scaling, enhancement and editing:

      min_u  alpha ||A u - r||^2 + sum_a ||u_a - t_a||^2

  for the displacements u (|R| x 3) of the points of a region R, where A holds the ROI rows of f(K) on the ROI
  columns, r the wanted change of the details and t_a the wanted displacements of the anchors. The normal
  equations N u = b, N = alpha A^T A + S^T S, are factored once (`factor`) and solved for any number of
  right-hand sides (`solve`), x, y and z together. Solving for displacements makes "nothing changes" exact:
  r = 0 and t = 0 give u = 0 bit for bit, whatever the conditioning.

  With exact anchors (editing's handles), u_a = t_a is a hard constraint instead: the anchors' columns leave
  the unknowns (A = [A_f A_a]), and the free points solve min alpha ||A_f u_f - (r - A_a t)||^2, whose normal
  matrix alpha A_f^T A_f is factored once all the same; the anchors end exactly at their targets.

  Cholesky: N is assembled as its upper triangle by a parallel sparse product, scaled symmetrically to a unit
  diagonal (Jacobi equilibration, which narrows the spread between anchor and detail rows), factored with
  CHOLMOD's supernodal LL^T when available or Eigen's SimplicialLDLT, and each solve is followed by iterative
  refinement against the residual computed from A itself (not from the rounded N).
  Conjugate gradients: matrix-free products with A and A^T, Jacobi preconditioner, three columns in lockstep.
  Preconditioned by a simpler operator B (`factor`'s `preconditioner_rows`, the region's rows of the linear
  order for a large quadric region): the Cholesky path above factors alpha B^T B + S^T S instead of N, whose
  fill is far smaller, and conjugate gradients on N use that factor as the preconditioner.

  Nothing fails silently: CHOLMOD's status is checked after its analysis, factorisation and every solve (it
  reports running out of memory there, where Eigen's wrapper does not), an allocation that fails anywhere
  becomes a `Numerical_failure` naming the step, and a solve is accepted only when its final relative
  residual is at most `Least_squares_settings::accepted_residual` and its values are finite.
*/
class Detail_least_squares
{
  using Column_matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
  using Fallback_factor = Eigen::SimplicialLDLT<Column_matrix, Eigen::Lower, Eigen::NaturalOrdering<int>>;
#ifdef CGAL_EXT_USE_CHOLMOD
  using Main_factor = Eigen::CholmodSupernodalLLT<Column_matrix, Eigen::Lower>;
#endif

public:
  /// Diagonal shift of a normal matrix that is singular to rounding (its diagonal is scaled to 1).
  static constexpr double singular_shift = 1e-12;

  Detail_least_squares() = default;
  Detail_least_squares(const Detail_least_squares&) = delete;
  Detail_least_squares& operator=(const Detail_least_squares&) = delete;

  /// Sets up the system for the operator rows `A` (one column per point of the region, |R|; the detail
  /// operator is square, the edges of as-rigid-as-possible editing are not), the anchors (local indices,
  /// increasing), soft or, with `exact_anchors`, hard constraints, and the positions of the region's points
  /// (they give the elimination order).
  /// Throws `Numerical_failure` when the normal matrix cannot be factored.
  /// With `preconditioner_rows` (rows like `A`'s, same columns; soft anchors only), the factor is that of
  /// `alpha B^T B + S^T S` and `solve` runs conjugate gradients on N preconditioned by it.
  template <typename ConcurrencyTag>
  void factor(Sparse_row_matrix A, std::vector<int> anchors, const Matrix_n3& positions,
              const Least_squares_settings& settings, bool exact_anchors = false,
              const Sparse_row_matrix* preconditioner_rows = nullptr);

  /// Displacements of the region's points for the wanted detail change `detail_change` (|R| x 3) and anchor
  /// displacements `anchor_displacement` (one row per anchor, in the order given to `factor`).
  template <typename ConcurrencyTag>
  Matrix_n3 solve(const Matrix_n3& detail_change, const Matrix_n3& anchor_displacement);

  const Least_squares_statistics& statistics() const { return m_statistics; }
  const Sparse_row_matrix& operator_rows() const { return m_A; }

private:
  static double seconds_since(std::chrono::steady_clock::time_point t)
  {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  }

  /// The system's size, for error messages.
  std::string system_size() const
  {
    std::string size = std::to_string(m_statistics.unknowns) + " unknowns";
    if(m_statistics.normal_nonzeros > 0)
      size += ", " + std::to_string(m_statistics.normal_nonzeros) + " non-zeros in the normal matrix";
    return size;
  }

  [[noreturn]] void out_of_memory(const char* step) const
  {
    throw Numerical_failure(std::string("detail least squares: out of memory while ") + step + " (" + system_size() +
                            "); free memory, raise the process's memory limit or use a smaller region");
  }

#ifdef CGAL_EXT_USE_CHOLMOD
  /// Throws when CHOLMOD's last call failed (its status is negative: out of memory, integer overflow, ...).
  void check_cholmod(const char* step) const
  {
    const int status = m_main->cholmod().status;
    if(status >= CHOLMOD_OK) return;
    if(status == CHOLMOD_OUT_OF_MEMORY) out_of_memory(step);
    throw Numerical_failure(std::string("detail least squares: CHOLMOD failed while ") + step + " (" + system_size() +
                            "; " + (status == CHOLMOD_TOO_LARGE ? "the factor is too large for its integer type"
                                                                : "status " + std::to_string(status)) + ")");
  }
#endif

  // The steps of factor(), in order.
  /// Moves the columns of the exact `anchors` out of `A` (into `m_A_exact`); returns the free unknowns' positions.
  Matrix_n3 take_out_exact_anchors(Sparse_row_matrix& A, std::vector<int>& anchors, const Matrix_n3& positions);
  /// The diagonal of N, the conjugate gradients' Jacobi preconditioner.
  Eigen::VectorXd normal_diagonal() const;
  /// The upper triangle of N (or of the preconditioner's `alpha B^T B + S^T S`), scaled to a unit diagonal
  /// (`m_scale`).
  template <typename ConcurrencyTag>
  Sparse_row_matrix equilibrated_normal_matrix(const Sparse_row_matrix* preconditioner_rows);
  /// The lower triangle of `upper`'s symmetric matrix permuted into `order` (kept in `m_new_of`).
  Column_matrix in_elimination_order(const Sparse_row_matrix& upper, const std::vector<int>& order);
  /// Orders and factors it: CHOLMOD, else Eigen's LDL^T. Returns whether CHOLMOD chose the AMD order.
  bool factor_normal_matrix(Sparse_row_matrix upper, const Matrix_n3& positions);
#ifdef CGAL_EXT_USE_CHOLMOD
  /// CHOLMOD's supernodal LL^T of `normal` + shift; `m_main` reset when it meets a non-positive pivot.
  bool factor_with_cholmod(const Column_matrix& normal, bool amd_only);
#endif
  /// `Least_squares_statistics::method`.
  std::string factorisation_name(bool amd_order) const;

  /// The region's row of unknown `j` (they differ with exact anchors), for error messages.
  std::size_t region_row(std::size_t j) const { return m_free.empty() ? j : std::size_t(m_free[j]); }

  /// The columns of `A` where `pinned` is 0, then those where it is 1, each renumbered in increasing order.
  static std::pair<Sparse_row_matrix, Sparse_row_matrix> split_columns(const Sparse_row_matrix& A,
                                                                      const std::vector<char>& pinned)
  {
    std::vector<int> new_column(pinned.size());
    int counts[2] = {0, 0};
    for(std::size_t j = 0; j < pinned.size(); ++j) new_column[j] = counts[int(pinned[j])]++;
    Sparse_row_matrix part[2] = {Sparse_row_matrix(A.rows(), counts[0]), Sparse_row_matrix(A.rows(), counts[1])};
    std::vector<Eigen::Triplet<double, int>> entries[2];
    for(Eigen::Index i = 0; i < A.outerSize(); ++i)
      for(int e = A.outerIndexPtr()[i]; e < A.outerIndexPtr()[i + 1]; ++e) {
        const int j = A.innerIndexPtr()[e];
        entries[int(pinned[std::size_t(j)])].emplace_back(int(i), new_column[std::size_t(j)], A.valuePtr()[e]);
      }
    for(int p = 0; p < 2; ++p) part[p].setFromTriplets(entries[p].begin(), entries[p].end());
    return {std::move(part[0]), std::move(part[1])};
  }

  /// Adds a diagonal 1 where `where` says (anchors whose column of A is empty: a polynomial with a zero there).
  static Sparse_row_matrix with_unit_diagonals(const Sparse_row_matrix& upper, const std::vector<char>& where)
  {
    Sparse_row_matrix D(upper.rows(), upper.cols());
    D.reserve(Eigen::VectorXi::Ones(upper.rows()));
    for(Eigen::Index j = 0; j < upper.rows(); ++j)
      if(where[std::size_t(j)]) D.insert(j, j) = 1.0;
    D.makeCompressed();
    Sparse_row_matrix sum = upper + D;
    sum.makeCompressed();
    return sum;
  }

  /// `N X = alpha A^T A X + S^T S X`.
  template <typename ConcurrencyTag>
  Matrix_n3 apply_normal(const Matrix_n3& X) const
  {
    Matrix_n3 AX, N_X;
    multiply<ConcurrencyTag>(m_A, X, AX);
    multiply<ConcurrencyTag>(m_At, AX, N_X);
    N_X *= m_settings.detail_weight;
    for(int a : m_anchors) N_X.row(a) += X.row(a);
    return N_X;
  }

  template <typename ConcurrencyTag>
  Matrix_n3 right_hand_side(const Matrix_n3& detail_change, const Matrix_n3& anchor_displacement) const
  {
    Matrix_n3 b;
    if(m_exact.empty()) {
      multiply<ConcurrencyTag>(m_At, detail_change, b);
    } else {
      // The anchors' known displacements move to the right-hand side: A_f^T (r - A_a t).
      Matrix_n3 pinned;
      multiply<ConcurrencyTag>(m_A_exact, anchor_displacement, pinned);
      multiply<ConcurrencyTag>(m_At, Matrix_n3(detail_change - pinned), b);
    }
    b *= m_settings.detail_weight;
    for(std::size_t i = 0; i < m_anchors.size(); ++i) b.row(m_anchors[i]) += anchor_displacement.row(Eigen::Index(i));
    return b;
  }

  Matrix_n3 factor_solve(const Matrix_n3& b) const
  {
    const Eigen::MatrixXd scaled = m_new_of * (m_scale.asDiagonal() * b);
    Eigen::MatrixXd x;
#ifdef CGAL_EXT_USE_CHOLMOD
    if(m_main) {
#ifdef CGAL_EXT_SCOPED_RUNTIME_SETTINGS
      const Serial_blas serial_blas;
#endif
      x = m_main->solve(scaled);
      check_cholmod("solving with the factor");
      if(m_main->info() != Eigen::Success)
        throw Numerical_failure("detail least squares: CHOLMOD's solve failed (" + system_size() + ")");
    }
#endif
    if(m_fallback) x = m_fallback->solve(scaled);
    return m_scale.asDiagonal() * (m_new_of.transpose() * x);
  }

  template <typename ConcurrencyTag>
  void refined_cholesky_solve(const Matrix_n3& b, double b_norm, Matrix_n3& u)
  {
    u = factor_solve(b);
    double previous = b_norm;
    for(int step = 0;; ++step) {
      const Matrix_n3 residual = b - apply_normal<ConcurrencyTag>(u);
      const double norm = residual.norm();
      m_statistics.relative_residual = norm / b_norm;
      m_statistics.iterations = step;
      // Stop at rounding level, or when a step no longer halves the residual (refinement has stalled).
      if(!(norm > m_settings.refinement_tolerance * b_norm) || !(norm < 0.5 * previous) || step == 5) break;
      previous = norm;
      u += factor_solve(residual);
    }
  }

  /// Conjugate gradients on N u = b, three columns in lockstep; `precondition(r)` returns M^-1 r.
  template <typename ConcurrencyTag, typename Preconditioner>
  void conjugate_gradients(const Matrix_n3& b, double b_norm, Matrix_n3& u, const Preconditioner& precondition)
  {
    Matrix_n3 r = b, z = precondition(r), p = z;
    Eigen::RowVector3d rz = (r.array() * z.array()).colwise().sum();
    const Eigen::RowVector3d b_column = b.colwise().norm();
    const double tolerance = m_settings.tolerance;
    int iteration = 0;
    auto converged = [&] {
      const Eigen::RowVector3d r_column = r.colwise().norm();
      for(int c = 0; c < 3; ++c)
        if(r_column(c) > tolerance * b_column(c)) return false;
      return true;
    };
    while(!converged()) {
      if(iteration == m_settings.max_iterations)
        throw Numerical_failure("detail least squares: conjugate gradients did not reach the tolerance in " +
                                std::to_string(iteration) + " iterations; raise max_iterations or use Cholesky");
      const Matrix_n3 q = apply_normal<ConcurrencyTag>(p);
      const Eigen::RowVector3d pq = (p.array() * q.array()).colwise().sum();
      for(int c = 0; c < 3; ++c) {
        if(!(pq(c) > 0)) continue; // this column has converged exactly
        const double step = rz(c) / pq(c);
        u.col(c) += step * p.col(c);
        r.col(c) -= step * q.col(c);
      }
      z = precondition(r);
      const Eigen::RowVector3d rz_next = (r.array() * z.array()).colwise().sum();
      for(int c = 0; c < 3; ++c) {
        const double beta = rz(c) > 0 ? rz_next(c) / rz(c) : 0.0;
        p.col(c) = z.col(c) + beta * p.col(c);
      }
      rz = rz_next;
      ++iteration;
    }
    m_statistics.iterations = iteration;
    m_statistics.relative_residual = (b - apply_normal<ConcurrencyTag>(u)).norm() / b_norm;
  }

  bool iterative() const { return m_settings.solver == Linear_solver::conjugate_gradient || m_preconditioned; }

  Least_squares_settings m_settings;
  bool m_preconditioned = false;   // the factor is the preconditioner's, and solves iterate
  Sparse_row_matrix m_A, m_At;     // the columns of the unknowns (without exact anchors: the whole region)
  std::vector<int> m_anchors;      // soft anchors, as rows of the unknowns
  std::size_t m_region_size = 0;   // |R|
  std::vector<int> m_exact;        // exact anchors, as rows of the region (increasing)
  std::vector<int> m_free;         // the region's row of each unknown, with exact anchors
  Sparse_row_matrix m_A_exact;     // the columns of the exact anchors
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> m_new_of; // elimination order
  Eigen::VectorXd m_scale;         // Jacobi equilibration of the Cholesky path
  Eigen::VectorXd m_diagonal;      // diagonal of N for the conjugate-gradient preconditioner
#ifdef CGAL_EXT_USE_CHOLMOD
  std::unique_ptr<Main_factor> m_main;
#else
  std::unique_ptr<int> m_main;     // never set without CHOLMOD
#endif
  std::unique_ptr<Fallback_factor> m_fallback;
  bool m_factored = false;
  Least_squares_statistics m_statistics;
};

template <typename ConcurrencyTag>
void Detail_least_squares::factor(Sparse_row_matrix A, std::vector<int> anchors, const Matrix_n3& given_positions,
                                  const Least_squares_settings& settings, bool exact_anchors,
                                  const Sparse_row_matrix* preconditioner_rows)
try {
  if(given_positions.rows() != A.cols())
    throw Invalid_input("detail least squares: the operator needs one position per unknown");
  if(preconditioner_rows && (exact_anchors || preconditioner_rows->cols() != A.cols() ||
                             settings.solver != Linear_solver::cholesky))
    throw Invalid_input("detail least squares: a preconditioner needs the Cholesky solver, soft anchors and the "
                        "operator's columns");
  const auto start = std::chrono::steady_clock::now();
  m_settings = settings;
  m_region_size = std::size_t(A.cols());
  m_statistics = Least_squares_statistics();
  m_statistics.anchors = anchors.size();
  m_statistics.operator_nonzeros = std::size_t(A.nonZeros());
  m_main.reset();
  m_fallback.reset();
  m_factored = false;
  m_preconditioned = preconditioner_rows != nullptr;
  const Matrix_n3 free_positions = exact_anchors ? take_out_exact_anchors(A, anchors, given_positions) : Matrix_n3();
  m_A = std::move(A);
  m_At = m_A.transpose();
  m_anchors = std::move(anchors);
  m_statistics.unknowns = std::size_t(m_A.cols());
  if(m_A.cols() == 0) { // every point of the region is an exact anchor
    m_statistics.method = "none (every point is an exact anchor)";
    m_factored = true;
    return;
  }
  if(iterative()) m_diagonal = normal_diagonal();
  if(settings.solver == Linear_solver::conjugate_gradient) {
    m_statistics.method = "conjugate gradients (Jacobi, matrix-free)";
    m_statistics.assembly_seconds = seconds_since(start);
    m_factored = true;
    return;
  }
  Sparse_row_matrix upper = equilibrated_normal_matrix<ConcurrencyTag>(preconditioner_rows);
  m_statistics.assembly_seconds = seconds_since(start);
  const auto factor_start = std::chrono::steady_clock::now();
  const bool amd_order = factor_normal_matrix(std::move(upper), exact_anchors ? free_positions : given_positions);
  m_statistics.method = factorisation_name(amd_order);
  m_statistics.factor_seconds = seconds_since(factor_start);
  m_factored = true;
} catch(const std::bad_alloc&) {
  out_of_memory("assembling and factoring the normal matrix");
}

inline Matrix_n3 Detail_least_squares::take_out_exact_anchors(Sparse_row_matrix& A, std::vector<int>& anchors,
                                                              const Matrix_n3& positions)
{
  m_exact = std::move(anchors);
  anchors.clear();
  m_free.clear();
  std::vector<char> pinned(m_region_size, 0);
  for(int a : m_exact) pinned[std::size_t(a)] = 1;
  for(std::size_t j = 0; j < m_region_size; ++j)
    if(!pinned[j]) m_free.push_back(int(j));
  std::tie(A, m_A_exact) = split_columns(A, pinned);
  Matrix_n3 free_positions(Eigen::Index(m_free.size()), 3);
  for(std::size_t f = 0; f < m_free.size(); ++f) free_positions.row(Eigen::Index(f)) = positions.row(m_free[f]);
  return free_positions;
}

inline Eigen::VectorXd Detail_least_squares::normal_diagonal() const
{
  // alpha * the column norms of A, plus 1 on the anchors.
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(m_A.cols());
  for(Eigen::Index e = 0; e < m_A.nonZeros(); ++e)
    diagonal(m_A.innerIndexPtr()[e]) += m_settings.detail_weight * m_A.valuePtr()[e] * m_A.valuePtr()[e];
  for(int a : m_anchors) diagonal(a) += 1.0;
  for(Eigen::Index j = 0; j < diagonal.size(); ++j)
    if(!(diagonal(j) > 0))
      throw Numerical_failure("detail least squares: point " + std::to_string(region_row(std::size_t(j))) +
                              " of the region appears in no equation; the normal matrix is singular");
  return diagonal;
}

template <typename ConcurrencyTag>
Sparse_row_matrix Detail_least_squares::equilibrated_normal_matrix(const Sparse_row_matrix* preconditioner_rows)
{
  // Upper triangle of A^T A (or B^T B), row-major: read as column-major it is the lower triangle the
  // factorisations want.
  Sparse_row_matrix upper = preconditioner_rows
                              ? sparse_product<ConcurrencyTag>(Sparse_row_matrix(preconditioner_rows->transpose()),
                                                               *preconditioner_rows, {}, -1, true)
                              : sparse_product<ConcurrencyTag>(m_At, m_A, {}, -1, true);
  upper *= m_settings.detail_weight;
  const std::size_t n = std::size_t(m_A.cols());
  double* diagonal_value = upper.valuePtr();
  std::vector<char> is_anchor(n, 0), lacks_diagonal(n, 0);
  for(int a : m_anchors) is_anchor[std::size_t(a)] = 1;
  bool any_lacking = false;
  for(std::size_t j = 0; j < n; ++j) {
    // A row's first stored entry is its diagonal (the product keeps the columns >= row), present wherever
    // A has a non-zero column.
    const int first = upper.outerIndexPtr()[j];
    if(first < upper.outerIndexPtr()[j + 1] && upper.innerIndexPtr()[first] == int(j))
      diagonal_value[first] += is_anchor[j] ? 1.0 : 0.0;
    else if(is_anchor[j])
      lacks_diagonal[j] = any_lacking = true;
    else
      throw Numerical_failure("detail least squares: point " + std::to_string(region_row(j)) +
                              " of the region appears in no equation; the normal matrix is singular");
  }
  if(any_lacking) upper = with_unit_diagonals(upper, lacks_diagonal);
  // Jacobi equilibration: a unit diagonal.
  m_scale.resize(Eigen::Index(n));
  for(std::size_t j = 0; j < n; ++j) m_scale(Eigen::Index(j)) = 1.0 / std::sqrt(upper.valuePtr()[upper.outerIndexPtr()[j]]);
  for(std::size_t j = 0; j < n; ++j)
    for(int e = upper.outerIndexPtr()[j]; e < upper.outerIndexPtr()[j + 1]; ++e)
      upper.valuePtr()[e] *= m_scale(Eigen::Index(j)) * m_scale(upper.innerIndexPtr()[e]);
  m_statistics.normal_nonzeros = 2 * std::size_t(upper.nonZeros()) - n;
  return upper;
}

inline Detail_least_squares::Column_matrix Detail_least_squares::in_elimination_order(const Sparse_row_matrix& upper,
                                                                                       const std::vector<int>& order)
{
  // The lower triangle of P N P^T (`order`: the old row of each new one), which the factorisations keep as given.
  for(std::size_t i = 0; i < order.size(); ++i) m_new_of.indices()(order[i]) = int(i);
  Column_matrix twisted{upper.rows(), upper.cols()};
  twisted.template selfadjointView<Eigen::Lower>() =
    Eigen::Map<const Column_matrix>(upper.rows(), upper.cols(), upper.nonZeros(), upper.outerIndexPtr(),
                                    upper.innerIndexPtr(), upper.valuePtr())
      .template selfadjointView<Eigen::Lower>()
      .twistedBy(m_new_of);
  return twisted;
}

inline bool Detail_least_squares::factor_normal_matrix(Sparse_row_matrix upper, const Matrix_n3& positions)
{
#ifdef CGAL_EXT_USE_CHOLMOD
  // The preconditioner's matrix (the linear order's, two rings) goes to AMD alone: on nine regions of five
  // models the geometric dissection needed 1.8-3.5 times its flops (doc/detail_scaling.md, "The solver").
  const bool amd_only = m_preconditioned;
#else
  const bool amd_only = false;
#endif
  m_new_of.indices().resize(upper.rows());
  Column_matrix normal;
  if(amd_only) {
    m_new_of.setIdentity();
    normal = Eigen::Map<const Column_matrix>(upper.rows(), upper.cols(), upper.nonZeros(), upper.outerIndexPtr(),
                                             upper.innerIndexPtr(), upper.valuePtr());
  } else {
    normal = in_elimination_order(upper, geometric_nested_dissection(upper, positions));
    upper = Sparse_row_matrix();
  }
  bool amd_order = false;
#ifdef CGAL_EXT_USE_CHOLMOD
  amd_order = factor_with_cholmod(normal, amd_only);
#endif
  if(!m_main) {
    if(amd_only) normal = in_elimination_order(upper, geometric_nested_dissection(upper, positions)); // Eigen keeps the order
    m_fallback = std::make_unique<Fallback_factor>(normal);
    if(m_fallback->info() != Eigen::Success)
      throw Numerical_failure("detail least squares: the normal matrix could not be factored (singular: "
                              "some part of the region is not pinned by anchors or fixed points)");
  }
  return amd_order;
}

#ifdef CGAL_EXT_USE_CHOLMOD
inline bool Detail_least_squares::factor_with_cholmod(const Column_matrix& normal, bool amd_only)
{
  m_main = std::make_unique<Main_factor>();
  cholmod_common& common = m_main->cholmod();
  common.print = 0; // a rounding-negative pivot is handled below, not printed
  // Unless AMD alone orders it, the matrix comes in the geometric nested-dissection order (kept as given:
  // NATURAL); CHOLMOD also tries AMD and keeps the cheaper. Neither wins everywhere: the dissection needs fewer
  // flops on a compact region of a scan, AMD on an edit's sample points and on a curved region (the halves of a
  // curved region cut across its longest extent meet along a long curve). One AMD analysis costs little beside
  // such a factorisation (doc/detail_scaling.md, "The solver", measures these).
  common.nmethods = amd_only ? 1 : 2;
  common.method[0].ordering = amd_only ? CHOLMOD_AMD : CHOLMOD_NATURAL;
  common.method[1].ordering = CHOLMOD_AMD;
#ifdef CGAL_EXT_SCOPED_RUNTIME_SETTINGS
  const Serial_openmp_regions serial_openmp;
#endif
  // Eigen's compute() would go on to factorise after a failed analysis (a null factor) and reports no status.
  m_main->analyzePattern(normal);
  check_cholmod("analysing the normal matrix");
#ifdef CGAL_EXT_SCOPED_RUNTIME_SETTINGS
  // Refused before it starts where the factor (its nonzeros and a quarter more for the supernodes' padding and
  // the workspace) and OpenBLAS's buffers would not fit: past that point a shortage hangs in OpenBLAS.
  if(!fits_address_space_limit(1.25 * 8 * common.lnz + blas_buffer_bytes())) out_of_memory("factoring the normal matrix");
#endif
  const bool amd_order = amd_only || common.selected == 1;
  // N + shift I, not N (N has a unit diagonal here): with the cubic order and no anchors, the region's smoothest
  // modes are almost free and N is singular to rounding, so LL^T of N itself can meet a non-positive pivot (and
  // Eigen's simplicial LDL^T, the other way, took 452 s against 16 s on 97k unknowns). The refinement solves
  // against N: the modes N pins converge in a step or two, the free ones, which change N u by less than the
  // rounding, stay where the shifted factor puts them, and the final residual is checked as always.
  m_main->setShift(singular_shift);
  m_main->factorize(normal);
  check_cholmod("factoring the normal matrix");
  if(m_main->info() != Eigen::Success) m_main.reset();
  return amd_order;
}
#endif

inline std::string Detail_least_squares::factorisation_name(bool amd_order) const
{
  const std::string order_name = m_main && amd_order ? ", AMD order" : ", geometric nested dissection";
  if(m_preconditioned) // the factor is the preconditioner's, and nothing is refined against it
    return std::string("conjugate gradients on N, preconditioned by the ") +
           (m_main ? "CHOLMOD supernodal LL^T" : "Eigen SimplicialLDLT") +
           " of the linear order's normal matrix + 1e-12 I" + order_name +
           (m_settings.preconditioner_diagonal_weight > 0 ? ", plus Jacobi on N" : "");
  if(m_main) return "CHOLMOD supernodal LL^T of N + 1e-12 I, refined against N" + order_name;
#ifdef CGAL_EXT_USE_CHOLMOD
  return "Eigen SimplicialLDLT (CHOLMOD LL^T of N + 1e-12 I met a non-positive pivot)" + order_name;
#else
  return "Eigen SimplicialLDLT" + order_name;
#endif
}

template <typename ConcurrencyTag>
Matrix_n3 Detail_least_squares::solve(const Matrix_n3& detail_change, const Matrix_n3& anchor_displacement)
try {
  if(!m_factored) throw Invalid_input("detail least squares: solve() needs a factor() that succeeded");
  if(detail_change.rows() != m_A.rows() ||
     anchor_displacement.rows() != Eigen::Index(m_exact.empty() ? m_anchors.size() : m_exact.size()))
    throw Invalid_input("detail least squares: right-hand side sizes do not match the factored system");
  const auto start = std::chrono::steady_clock::now();
  const Matrix_n3 b = right_hand_side<ConcurrencyTag>(detail_change, anchor_displacement);
  const double b_norm = b.norm();
  Matrix_n3 u = Matrix_n3::Zero(b.rows(), 3);
  m_statistics.iterations = 0;
  m_statistics.relative_residual = 0;
  if(b_norm > 0) {
    if(m_settings.solver == Linear_solver::conjugate_gradient) {
      const Eigen::ArrayXd inverse_diagonal = m_diagonal.array().inverse();
      conjugate_gradients<ConcurrencyTag>(b, b_norm, u, [&](const Matrix_n3& r) -> Matrix_n3 {
        return (r.array().colwise() * inverse_diagonal).matrix();
      });
    } else if(m_preconditioned) {
      // B^-1 + w D^-1: the factor of the linear order B carries the smooth displacements, Jacobi on N the
      // roughest, where B's response is far above N's (Least_squares_settings::preconditioner_diagonal_weight).
      const double weight = m_settings.preconditioner_diagonal_weight;
      const Eigen::ArrayXd weighted_inverse_diagonal = weight * m_diagonal.array().inverse();
      conjugate_gradients<ConcurrencyTag>(b, b_norm, u, [&](const Matrix_n3& r) -> Matrix_n3 {
        Matrix_n3 z = factor_solve(r);
        if(weight > 0) z += (r.array().colwise() * weighted_inverse_diagonal).matrix();
        return z;
      });
    } else
      refined_cholesky_solve<ConcurrencyTag>(b, b_norm, u);
  }
  if(!m_exact.empty()) {
    Matrix_n3 whole(Eigen::Index(m_region_size), 3);
    for(std::size_t f = 0; f < m_free.size(); ++f) whole.row(m_free[f]) = u.row(Eigen::Index(f));
    for(std::size_t a = 0; a < m_exact.size(); ++a) whole.row(m_exact[a]) = anchor_displacement.row(Eigen::Index(a));
    u.swap(whole);
  }
  if(!u.allFinite())
    throw Numerical_failure("detail least squares: the solve produced non-finite values (" + system_size() + ")");
  const double accepted = std::max(m_settings.accepted_residual, iterative() ? 2 * m_settings.tolerance : 0.0);
  if(!(m_statistics.relative_residual <= accepted)) {
    std::ostringstream os;
    os << "detail least squares: the solve's relative residual " << m_statistics.relative_residual
       << " is above the accepted " << accepted << " (" << system_size() << ", " << m_statistics.method << ")";
    throw Numerical_failure(os.str());
  }
  m_statistics.solve_seconds = seconds_since(start);
  return u;
} catch(const std::bad_alloc&) {
  out_of_memory("solving");
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_DETAIL_LEAST_SQUARES_INSTANCES(EXTERN, Tag) \
  EXTERN template Sparse_row_matrix detail_operator_rows<Tag>(const Sparse_row_matrix&, const Detail_filter&, \
                                                              const std::vector<int>&); \
  EXTERN template void Detail_least_squares::factor<Tag>(Sparse_row_matrix, std::vector<int>, const Matrix_n3&, \
                                                         const Least_squares_settings&, bool, \
                                                         const Sparse_row_matrix*); \
  EXTERN template Matrix_n3 Detail_least_squares::solve<Tag>(const Matrix_n3&, const Matrix_n3&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_DETAIL_LEAST_SQUARES_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_DETAIL_LEAST_SQUARES_H
