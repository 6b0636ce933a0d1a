// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_SPARSE_PRODUCTS_H
#define CGAL_EXT_INTERNAL_SPARSE_PRODUCTS_H

#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/compiled_instances.h>
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

/// Runs `body(chunk, accumulator)` for every chunk in [0, chunks), each thread with its own accumulator.
template <typename ConcurrencyTag, typename Body>
void for_chunks_with_accumulator(std::size_t chunks, std::size_t columns, const Body& body)
{
#ifdef CGAL_LINKED_WITH_TBB
  if constexpr(is_parallel<ConcurrencyTag>()) {
    tbb::enumerable_thread_specific<Row_accumulator> accumulators([columns] { return Row_accumulator(columns); });
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) { body(c, accumulators.local()); });
    return;
  }
#endif
  Row_accumulator accumulator(columns);
  for(std::size_t c = 0; c < chunks; ++c) body(c, accumulator);
}

/// `C = A B` for row-major A and B, with the columns of the result renumbered on the fly: column `c` of
/// `A B` becomes column `column_map[c]` of C, or is dropped when that is negative (an empty map keeps every
/// column). With `upper_only`, row i keeps the columns >= i only (the upper triangle of a symmetric product).
/// Rows are computed in parallel chunks (Gustavson's algorithm, rows sorted) and concatenated; each value is
/// summed in the order of A's and B's storage, so the result does not depend on the thread count.
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

  const std::size_t chunk_rows = 64;
  const std::size_t chunks = (rows + chunk_rows - 1) / chunk_rows;
  std::vector<std::vector<int>> chunk_columns(chunks);
  std::vector<std::vector<double>> chunk_values(chunks);
  std::vector<int> counts(rows + 1, 0);
  for_chunks_with_accumulator<ConcurrencyTag>(chunks, columns, [&](std::size_t chunk, Row_accumulator& acc) {
    std::vector<int>& out_columns = chunk_columns[chunk];
    std::vector<double>& out_values = chunk_values[chunk];
    for(std::size_t i = chunk * chunk_rows; i < std::min(rows, (chunk + 1) * chunk_rows); ++i) {
      for(int ea = a_outer[i]; ea < a_outer[i + 1]; ++ea) {
        const int j = a_inner[ea];
        const double aij = a_value[ea];
        for(int eb = b_outer[j]; eb < b_outer[j + 1]; ++eb) {
          const int c = mapped ? column_map[std::size_t(b_inner[eb])] : b_inner[eb];
          if(c < 0 || (upper_only && std::size_t(c) < i)) continue;
          acc.add(c, aij * b_value[eb]);
        }
      }
      std::sort(acc.touched.begin(), acc.touched.end());
      for(int c : acc.touched) {
        out_columns.push_back(c);
        out_values.push_back(acc.value[std::size_t(c)]);
      }
      counts[i + 1] = int(acc.touched.size());
      acc.clear();
    }
  });
  std::partial_sum(counts.begin(), counts.end(), counts.begin());

  Sparse_row_matrix C{Eigen::Index(rows), Eigen::Index(columns)};
  C.resizeNonZeros(counts.back());
  std::copy(counts.begin(), counts.end(), C.outerIndexPtr());
  for_range<ConcurrencyTag>(0, chunks, [&](std::size_t chunk) {
    const int begin = counts[chunk * chunk_rows];
    std::copy(chunk_columns[chunk].begin(), chunk_columns[chunk].end(), C.innerIndexPtr() + begin);
    std::copy(chunk_values[chunk].begin(), chunk_values[chunk].end(), C.valuePtr() + begin);
  });
  return C;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_SPARSE_PRODUCTS_INSTANCES(EXTERN, Tag) \
  EXTERN template Sparse_row_matrix sparse_product<Tag>(const Sparse_row_matrix&, const Sparse_row_matrix&, \
                                                        const std::vector<int>&, Eigen::Index, bool);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_SPARSE_PRODUCTS_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_SPARSE_PRODUCTS_H
