// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_SPARSE_PRODUCTS_H
#define CGAL_EXT_INTERNAL_SPARSE_PRODUCTS_H

#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/parallel.h>

#include <algorithm>
#include <numeric>
#include <vector>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/enumerable_thread_specific.h>
#endif

namespace CGAL_ext {
namespace internal {

/// Dense accumulator of one output row (Gustavson's algorithm): values scattered by column, with the list of
/// touched columns so that clearing costs only what was used.
struct Row_accumulator
{
  std::vector<double> value;
  std::vector<char> used;
  std::vector<int> touched;

  explicit Row_accumulator(std::size_t columns = 0) : value(columns, 0.0), used(columns, 0) {}

  void add(int column, double v)
  {
    if(!used[std::size_t(column)]) { used[std::size_t(column)] = 1; touched.push_back(column); }
    value[std::size_t(column)] += v;
  }
  void clear()
  {
    for(int c : touched) { used[std::size_t(c)] = 0; value[std::size_t(c)] = 0.0; }
    touched.clear();
  }
};

/// Runs `body(i, accumulator)` for every row i in [0, rows), each thread with its own accumulator.
template <typename ConcurrencyTag, typename Body>
void for_rows_with_accumulator(std::size_t rows, std::size_t columns, const Body& body)
{
#ifdef CGAL_LINKED_WITH_TBB
  if constexpr(is_parallel<ConcurrencyTag>()) {
    tbb::enumerable_thread_specific<Row_accumulator> accumulators([columns] { return Row_accumulator(columns); });
    for_range<ConcurrencyTag>(0, rows, [&](std::size_t i) { body(i, accumulators.local()); });
    return;
  }
#endif
  Row_accumulator accumulator(columns);
  for(std::size_t i = 0; i < rows; ++i) body(i, accumulator);
}

/// `C = A B` for row-major A and B, with the columns of the result renumbered on the fly: column `c` of
/// `A B` becomes column `column_map[c]` of C, or is dropped when that is negative (an empty map keeps every
/// column). With `upper_only`, row i keeps the columns >= i only (the upper triangle of a symmetric product).
/// Row-parallel, two passes (pattern, then values), each output row sorted; the result does not depend on
/// the thread count.
template <typename ConcurrencyTag>
Sparse_row_matrix sparse_product(const Sparse_row_matrix& A, const Sparse_row_matrix& B,
                                 const std::vector<int>& column_map = {}, Eigen::Index result_columns = -1,
                                 bool upper_only = false)
{
  const std::size_t rows = std::size_t(A.rows());
  const std::size_t columns = std::size_t(result_columns < 0 ? B.cols() : result_columns);
  const int* a_outer = A.outerIndexPtr();
  const int* a_inner = A.innerIndexPtr();
  const double* a_value = A.valuePtr();
  const int* b_outer = B.outerIndexPtr();
  const int* b_inner = B.innerIndexPtr();
  const double* b_value = B.valuePtr();
  const bool mapped = !column_map.empty();

  // Accumulates row i of the product; the value sum runs in the order of A's and B's storage, so it is the
  // same whichever thread computes the row.
  auto accumulate = [&](std::size_t i, Row_accumulator& acc) {
    for(int ea = a_outer[i]; ea < a_outer[i + 1]; ++ea) {
      const int j = a_inner[ea];
      const double aij = a_value[ea];
      for(int eb = b_outer[j]; eb < b_outer[j + 1]; ++eb) {
        const int c = mapped ? column_map[std::size_t(b_inner[eb])] : b_inner[eb];
        if(c < 0 || (upper_only && std::size_t(c) < i)) continue;
        acc.add(c, aij * b_value[eb]);
      }
    }
  };

  std::vector<int> counts(rows + 1, 0);
  for_rows_with_accumulator<ConcurrencyTag>(rows, columns, [&](std::size_t i, Row_accumulator& acc) {
    accumulate(i, acc);
    counts[i + 1] = int(acc.touched.size());
    acc.clear();
  });
  std::partial_sum(counts.begin(), counts.end(), counts.begin());

  Sparse_row_matrix C{Eigen::Index(rows), Eigen::Index(columns)};
  C.resizeNonZeros(counts.back());
  std::copy(counts.begin(), counts.end(), C.outerIndexPtr());
  int* c_inner = C.innerIndexPtr();
  double* c_value = C.valuePtr();
  for_rows_with_accumulator<ConcurrencyTag>(rows, columns, [&](std::size_t i, Row_accumulator& acc) {
    accumulate(i, acc);
    std::sort(acc.touched.begin(), acc.touched.end());
    int e = counts[i];
    for(int c : acc.touched) { c_inner[e] = c; c_value[e] = acc.value[std::size_t(c)]; ++e; }
    acc.clear();
  });
  return C;
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_SPARSE_PRODUCTS_H
