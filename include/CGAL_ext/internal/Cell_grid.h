// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_CELL_GRID_H
#define CGAL_EXT_INTERNAL_CELL_GRID_H

#include <CGAL_ext/internal/Point_arrays.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// The rows of a position array binned into cubic cells of one size, each cell's coordinates side by side, and
/// the points of a block of cells around a cell gathered for a query (doc/editing_at_scale.md, "The k-nearest
/// graph on a grid"). Cells are numbered in the order the rows first enter them.
class Cell_grid
{
public:
  /// The points of a block of cells, side by side, and the block's box.
  struct Block
  {
    std::vector<double> x, y, z;
    std::vector<int> rows;
    double low[3], high[3];

    std::size_t size() const { return rows.size(); }
  };

  /// `cell_size` > 0; larger when the positions' extent would need more than 2^21 cells along an axis.
  Cell_grid(const Matrix_n3& positions, double cell_size)
  {
    const std::size_t n = std::size_t(positions.rows());
    m_origin = positions.colwise().minCoeff();
    const double extent = (positions.colwise().maxCoeff() - m_origin).maxCoeff();
    m_size = std::max(cell_size, extent / double(max_cells_per_axis - 4));
    m_inverse = 1 / m_size;
    // Consecutive rows mostly share a cell (they are in spatial order): the changes bound the cells.
    std::vector<std::uint64_t> key(n);
    std::size_t changes = 1;
    for(std::size_t i = 0; i < n; ++i) {
      key[i] = key_of(
        cell_coordinates(positions(Eigen::Index(i), 0), positions(Eigen::Index(i), 1), positions(Eigen::Index(i), 2)));
      changes += i > 0 && key[i] != key[i - 1];
    }
    std::size_t capacity = 16;
    m_slot_shift = 60;
    while(capacity < 2 * changes) capacity <<= 1, --m_slot_shift;
    m_slot_key.assign(capacity, empty_key);
    m_slot_cell.assign(capacity, -1);
    std::vector<int> cell_of(n);
    std::vector<int> count;
    for(std::size_t i = 0; i < n; ++i) {
      if(i > 0 && key[i] == key[i - 1]) {
        cell_of[i] = cell_of[i - 1];
      } else {
        const std::size_t s = probe(key[i]);
        if(m_slot_key[s] == empty_key) {
          m_slot_key[s] = key[i];
          m_slot_cell[s] = int(m_cell_key.size());
          m_cell_key.push_back(key[i]);
          count.push_back(0);
        }
        cell_of[i] = m_slot_cell[s];
      }
      ++count[std::size_t(cell_of[i])];
    }
    m_first.assign(m_cell_key.size() + 1, 0);
    for(std::size_t c = 0; c < m_cell_key.size(); ++c) m_first[c + 1] = m_first[c] + count[c];
    m_x.resize(n), m_y.resize(n), m_z.resize(n), m_rows.resize(n), m_cell_of_row = std::move(cell_of);
    std::vector<int> fill(m_first.begin(), m_first.end() - 1);
    for(std::size_t i = 0; i < n; ++i) {
      const std::size_t at = std::size_t(fill[std::size_t(m_cell_of_row[i])]++);
      m_x[at] = positions(Eigen::Index(i), 0), m_y[at] = positions(Eigen::Index(i), 1);
      m_z[at] = positions(Eigen::Index(i), 2), m_rows[at] = int(i);
    }
    // Within this of a block's face a point may have been binned across it, or the face placed, by rounding.
    m_margin = 4e-9 * m_size + 1e-14 * std::max(m_origin.cwiseAbs().maxCoeff(), std::abs(m_origin.maxCoeff() + extent));
  }

  std::size_t cell_count() const { return m_cell_key.size(); }
  std::size_t cell_of_row(std::size_t row) const { return std::size_t(m_cell_of_row[row]); }
  /// The rows of a cell and their coordinates lie at [first(c), first(c + 1)) of `rows()`, `x()`, `y()`, `z()`.
  int first(std::size_t cell) const { return m_first[cell]; }
  const std::vector<int>& rows() const { return m_rows; }
  const double* x() const { return m_x.data(); }
  const double* y() const { return m_y.data(); }
  const double* z() const { return m_z.data(); }
  /// How far inside a block's faces a ball must stay to be certain that it holds no point outside the block.
  double margin() const { return m_margin; }

  /// The points of the cells within `reach` cells of `cell` along each axis, and that block's box; false (and
  /// nothing gathered) when they are more than `most`.
  bool gather(std::size_t cell, int reach, std::size_t most, Block& block) const
  {
    block.x.clear(), block.y.clear(), block.z.clear(), block.rows.clear();
    const std::uint64_t key = m_cell_key[cell];
    const std::int64_t centre[3] = {std::int64_t(key & axis_mask), std::int64_t((key >> axis_bits) & axis_mask),
                                    std::int64_t(key >> (2 * axis_bits))};
    thread_local std::vector<int> cells;
    cells.clear();
    std::size_t total = 0;
    std::int64_t c[3];
    for(c[2] = centre[2] - reach; c[2] <= centre[2] + reach; ++c[2])
      for(c[1] = centre[1] - reach; c[1] <= centre[1] + reach; ++c[1])
        for(c[0] = centre[0] - reach; c[0] <= centre[0] + reach; ++c[0]) {
          if(c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] > axis_mask || c[1] > axis_mask || c[2] > axis_mask) continue;
          const int other = find(key_of(c));
          if(other < 0) continue;
          cells.push_back(other);
          total += std::size_t(m_first[std::size_t(other) + 1] - m_first[std::size_t(other)]);
        }
    if(total > most) return false;
    for(const int other : cells) {
      const auto b = m_first[std::size_t(other)], e = m_first[std::size_t(other) + 1];
      block.x.insert(block.x.end(), m_x.begin() + b, m_x.begin() + e);
      block.y.insert(block.y.end(), m_y.begin() + b, m_y.begin() + e);
      block.z.insert(block.z.end(), m_z.begin() + b, m_z.begin() + e);
      block.rows.insert(block.rows.end(), m_rows.begin() + b, m_rows.begin() + e);
    }
    for(int a = 0; a < 3; ++a) {
      block.low[a] = m_origin(a) + double(centre[a] - reach) * m_size;
      block.high[a] = m_origin(a) + double(centre[a] + reach + 1) * m_size;
    }
    return true;
  }

private:
  static constexpr int axis_bits = 21;
  static constexpr std::int64_t axis_mask = (std::int64_t(1) << axis_bits) - 1;
  static constexpr std::int64_t max_cells_per_axis = axis_mask;
  static constexpr std::uint64_t empty_key = ~std::uint64_t(0);

  std::array<std::int64_t, 3> cell_coordinates(double x, double y, double z) const
  {
    const double p[3] = {x, y, z};
    std::array<std::int64_t, 3> c;
    for(int a = 0; a < 3; ++a)
      c[std::size_t(a)] = std::clamp(std::int64_t((p[a] - m_origin(a)) * m_inverse), std::int64_t(0), axis_mask);
    return c;
  }
  static std::uint64_t key_of(const std::array<std::int64_t, 3>& c) { return key_of(c.data()); }
  static std::uint64_t key_of(const std::int64_t* c)
  {
    return std::uint64_t(c[0]) | (std::uint64_t(c[1]) << axis_bits) | (std::uint64_t(c[2]) << (2 * axis_bits));
  }
  // The slot that holds `key`, or the empty one where it would go: from its Fibonacci hash (the product's top
  // bits, which every bit of the key reaches) on.
  std::size_t probe(std::uint64_t key) const
  {
    std::size_t s = std::size_t((key * 0x9E3779B97F4A7C15ull) >> m_slot_shift);
    while(m_slot_key[s] != key && m_slot_key[s] != empty_key) s = (s + 1) & (m_slot_key.size() - 1);
    return s;
  }
  int find(std::uint64_t key) const { return m_slot_cell[probe(key)]; } // -1 in an empty slot

  Eigen::RowVector3d m_origin;
  double m_size = 0, m_inverse = 0, m_margin = 0;
  int m_slot_shift = 60; // 64 less the bits of the table's size
  std::vector<std::uint64_t> m_slot_key, m_cell_key;
  std::vector<int> m_slot_cell, m_first, m_cell_of_row, m_rows;
  std::vector<double> m_x, m_y, m_z;
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_CELL_GRID_H
