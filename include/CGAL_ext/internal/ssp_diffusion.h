// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_SSP_DIFFUSION_H
#define CGAL_EXT_INTERNAL_SSP_DIFFUSION_H

#include <CGAL_ext/Detail_preserving_deformation_settings.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/neighborhood_rotations.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <CGAL/use.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <new>
#include <string>
#include <vector>

// The diffusion's 4-wide path (Diffusion_stencil::apply): compiled where GCC or Clang can target AVX2 on
// x86-64, taken where the processor has it.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define CGAL_EXT_DIFFUSION_WIDE_VECTORS
#include <immintrin.h>
#endif

namespace CGAL_ext {
namespace internal {

/// Local frames of the simplification sample points (doc/editing_diffusion.md, "The paper's encoding and ours"), built
/// the same way before and after an edit: the third axis is the normal of a plane fitted to the sample point
/// and its frame neighbours (oriented like a given hint), the first axis the tangent part of the direction to
/// a fixed reference neighbour. Columns of a frame: e1, e2, n.
class Ssp_frames
{
public:
  /// Chooses the reference neighbour of every sample point: its nearest frame neighbour that does not lie
  /// (almost) along the normal hint.
  void setup(const Matrix_n3& positions, const Matrix_n3& normal_hints, Neighbor_graph neighbors)
  {
    m_neighbors = std::move(neighbors);
    const std::size_t n = m_neighbors.size();
    m_reference.assign(n, -1);
    for(std::size_t i = 0; i < n; ++i) {
      const Eigen::RowVector3d hint = normal_hints.row(Eigen::Index(i));
      for(const int* j = m_neighbors.begin(i); j != m_neighbors.end(i); ++j) {
        const Eigen::RowVector3d d = positions.row(*j) - positions.row(Eigen::Index(i));
        const double along = d.dot(hint) / hint.norm();
        if((d.squaredNorm() - along * along) > 1e-6 * d.squaredNorm()) { m_reference[i] = *j; break; }
      }
    }
  }

  /// The frame of sample point `i` from `positions`, its normal oriented like `hint`.
  Eigen::Matrix3d frame(const Matrix_n3& positions, std::size_t i, const Eigen::Vector3d& hint) const;

private:
  Neighbor_graph m_neighbors;
  std::vector<int> m_reference;
};

#ifdef CGAL_EXT_CORE_DEFINITIONS
// Defined where the editing class is compiled (internal/compiled_instances.h): its eigen solver is costly to compile.
inline Eigen::Matrix3d Ssp_frames::frame(const Matrix_n3& positions, std::size_t i, const Eigen::Vector3d& hint) const
{
  const Eigen::Vector3d origin = positions.row(Eigen::Index(i)).transpose();
  Eigen::Vector3d normal = hint.normalized();
  const int degree = m_neighbors.degree(i);
  if(degree >= 2) {
    Eigen::Vector3d centroid = origin;
    for(const int* j = m_neighbors.begin(i); j != m_neighbors.end(i); ++j) centroid += positions.row(*j).transpose();
    centroid /= double(degree + 1);
    Eigen::Matrix3d covariance = (origin - centroid) * (origin - centroid).transpose();
    for(const int* j = m_neighbors.begin(i); j != m_neighbors.end(i); ++j) {
      const Eigen::Vector3d d = positions.row(*j).transpose() - centroid;
      covariance += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
    // A plane needs two spread directions; a fit on collinear neighbours keeps the hint.
    if(eigen.eigenvalues()(1) > 1e-12 * eigen.eigenvalues()(2)) normal = eigen.eigenvectors().col(0);
    if(normal.dot(hint) < 0) normal = -normal;
  }
  Eigen::Vector3d e1;
  if(m_reference[i] >= 0) {
    const Eigen::Vector3d d = positions.row(m_reference[i]).transpose() - origin;
    e1 = d - d.dot(normal) * normal;
  }
  if(m_reference[i] < 0 || !(e1.squaredNorm() > 0)) {
    // No usable reference: any tangent direction, the same before and after only if the normal is.
    Eigen::Index axis;
    normal.cwiseAbs().minCoeff(&axis);
    e1 = Eigen::Vector3d::Unit(axis) - normal(axis) * normal;
  }
  e1.normalize();
  Eigen::Matrix3d F;
  F.col(0) = e1;
  F.col(1) = normal.cross(e1);
  F.col(2) = normal;
  return F;
}
#endif

/// An allocator whose blocks start on a cache line (64 bytes), for the records a drag reads by the million.
template <typename T>
struct Cache_line_allocator
{
  using value_type = T;
  Cache_line_allocator() = default;
  template <typename U>
  Cache_line_allocator(const Cache_line_allocator<U>&)
  {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(64))); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, std::align_val_t(64)); }
  template <typename U>
  bool operator==(const Cache_line_allocator<U>&) const
  {
    return true;
  }
  template <typename U>
  bool operator!=(const Cache_line_allocator<U>&) const
  {
    return false;
  }
};

/// A sample point's motion as a drag reads it, on one cache line: the displacement it gives a point `p` it carries
/// alone is `T p + offset`, with `T = A - I` (its map less the identity) rounded to floats, column-major, and
/// `offset = (s' - s) - T s` computed in doubles from that rounded `T`, so that the displacement is still
/// `(s' - s) + T (p - s)` and a point far from the origin loses nothing. The turn's rounding (2^-24 of it) is the
/// weights' own (doc/editing_at_scale.md, "A drag's memory traffic").
struct alignas(64) Motion_record
{
  double offset[3];
  float turn[9];
  float unused = 0; // read by the 4-wide path's load of the last column, never used

  Eigen::Matrix3d turn_matrix() const
  {
    Eigen::Matrix3d T;
    for(int c = 0; c < 3; ++c)
      for(int r = 0; r < 3; ++r) T(r, c) = double(turn[3 * c + r]);
    return T;
  }
  Eigen::Vector3d offset_vector() const { return Eigen::Vector3d(offset[0], offset[1], offset[2]); }
  /// Sets the record for `new_turn` (rounded to floats) and the sample point's move from `s` to `moved`.
  void set(const Eigen::Matrix3d& new_turn, const Eigen::Vector3d& s, const Eigen::Vector3d& moved)
  {
    for(int c = 0; c < 3; ++c)
      for(int r = 0; r < 3; ++r) turn[3 * c + r] = float(new_turn(r, c));
#if defined(__GNUC__)
    // The offset must use the turn as stored: GCC 12's vectoriser (-O2) took the floats' conversion back to
    // doubles for the doubles they came from. The barrier makes it read them.
    asm volatile("" : : "r"(turn) : "memory");
#endif
    const Eigen::Vector3d constant = (moved - s) - turn_matrix() * s;
    for(int r = 0; r < 3; ++r) offset[r] = constant(r);
  }
};
static_assert(sizeof(Motion_record) == 64, "a motion record fills one cache line");

constexpr std::size_t diffusion_block = 256; // points per task of Diffusion_stencil::apply
constexpr std::size_t diffusion_prefetch = 32; // how many points ahead a block asks for the rows it walks

/// Where Diffusion_stencil's blocks find the a-th point they move: `width` sample points and weights per stencil
/// row, the row `active[a]` (row a without `active`), written to row `destination[a]` (its own row without).
struct Diffusion_rows
{
  const double *points, *normals, *weights;
  const int* samples;
  std::size_t width;
  const int *active, *destination;

  std::size_t row(std::size_t a) const { return active ? std::size_t(active[a]) : a; }
  const double* point(std::size_t a) const { return points + 3 * row(a); }
  const double* normal(std::size_t a) const { return normals + 3 * row(a); }
  /// The k-th weight of the a-th point's stencil.
  double weight(std::size_t a, std::size_t k) const { return weights[width * row(a) + k]; }
  /// The k-th sample point of the a-th point's stencil (nearest first).
  std::size_t sample(std::size_t a, std::size_t k) const { return std::size_t(samples[width * row(a) + k]); }
  std::size_t destination_of(std::size_t a) const { return destination ? std::size_t(destination[a]) : row(a); }
  /// Asks the cache for the a-th point's data (a < the number of points moved).
  void prefetch(std::size_t a) const
  {
    const std::size_t i = row(a);
    for(const void* line :
        {static_cast<const void*>(points + 3 * i), static_cast<const void*>(normals + 3 * i),
         static_cast<const void*>(weights + width * i), static_cast<const void*>(samples + width * i)})
      __builtin_prefetch(line);
  }
};

/// The diffusion's per-point data in the order a drag walks it, one record per point: rest position and rest
/// normal as doubles, the destination row as a 32-bit integer, the weights as floats (multiples of 2^-24,
/// Diffusion_stencil::setup), then the sample points as 16-bit integers (32-bit ones when there are more than
/// 65,536 sample points), padded to 8 bytes (88 bytes for the default six sample points). A drag then reads one
/// stream instead of five, whose next records it asks for ahead (doc/editing_at_scale.md, "A drag's memory
/// traffic").
class Packed_diffusion_rows
{
public:
  /// Record a holds row `rows[a]` of `points`, `normals` and the stencil's `weights` and `samples` (`width`
  /// per row), to be written to row `destination_of_row[rows[a]]`.
  template <typename ConcurrencyTag>
  void pack(const std::vector<int>& rows, const std::vector<int>& destination_of_row, const Matrix_n3& points,
            const Matrix_n3& normals, const std::vector<double>& weights, const std::vector<int>& samples,
            std::size_t width)
  {
    m_width = width;
    m_short_samples = std::all_of(samples.begin(), samples.end(), [](int j) { return j <= 0xffff; });
    const std::size_t sample_bytes = m_short_samples ? sizeof(std::uint16_t) : sizeof(std::int32_t);
    const std::size_t bytes = 6 * sizeof(double) + sizeof(std::int32_t) + width * (sizeof(float) + sample_bytes);
    m_stride = (bytes + sizeof(double) - 1) / sizeof(double);
    m_records.assign(rows.size() * m_stride, 0.0);
    for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t a) {
      double* record = m_records.data() + a * m_stride;
      const std::size_t row = std::size_t(rows[a]);
      for(int c = 0; c < 3; ++c)
        record[c] = points(Eigen::Index(row), c), record[3 + c] = normals(Eigen::Index(row), c);
      char* rest = reinterpret_cast<char*>(record + 6); // by bytes: the storage holds doubles
      std::memcpy(rest, &destination_of_row[row], sizeof(std::int32_t));
      for(std::size_t k = 0; k < width; ++k) {
        const float weight = float(weights[width * row + k]); // exact: a multiple of 2^-24
        std::memcpy(rest + weights_offset + k * sizeof(float), &weight, sizeof(float));
        const int j = samples[width * row + k];
        char* sample = rest + weights_offset + width * sizeof(float) + k * sample_bytes;
        if(m_short_samples) {
          const std::uint16_t short_j = std::uint16_t(j);
          std::memcpy(sample, &short_j, sample_bytes);
        } else {
          std::memcpy(sample, &j, sample_bytes);
        }
      }
    });
  }

  std::size_t size() const { return m_stride ? m_records.size() / m_stride : 0; }
  /// The bytes of one record.
  std::size_t record_bytes() const { return m_stride * sizeof(double); }
  const double* point(std::size_t a) const { return m_records.data() + a * m_stride; }
  const double* normal(std::size_t a) const { return point(a) + 3; }
  double weight(std::size_t a, std::size_t k) const
  {
    float w; // by bytes: the storage holds doubles
    std::memcpy(&w, weights_of(a) + k * sizeof(float), sizeof(float));
    return double(w);
  }
  std::size_t sample(std::size_t a, std::size_t k) const
  {
    const char* samples = weights_of(a) + m_width * sizeof(float);
    if(m_short_samples) {
      std::uint16_t j;
      std::memcpy(&j, samples + k * sizeof(j), sizeof(j));
      return j;
    }
    std::int32_t j;
    std::memcpy(&j, samples + k * sizeof(j), sizeof(j));
    return std::size_t(j);
  }
  std::size_t destination_of(std::size_t a) const
  {
    std::int32_t row;
    std::memcpy(&row, point(a) + 6, sizeof(row));
    return std::size_t(row);
  }
  void prefetch(std::size_t a) const
  {
    const char* record = reinterpret_cast<const char*>(point(a));
    for(std::size_t byte = 0; byte < record_bytes(); byte += 64) __builtin_prefetch(record + byte);
    __builtin_prefetch(record + record_bytes() - 1); // records straddle lines
  }

private:
  static constexpr std::size_t weights_offset = sizeof(std::int32_t); // after the destination

  const char* weights_of(std::size_t a) const { return reinterpret_cast<const char*>(point(a) + 6) + weights_offset; }

  std::vector<double, Cache_line_allocator<double>> m_records;
  std::size_t m_width = 0, m_stride = 0;
  bool m_short_samples = true;
};

/// The per-point data of the diffusion, fixed at preprocessing: the `m` nearest sample points and their weights.
class Diffusion_stencil
{
public:
  Neighbor_graph samples; ///< nearest first, the same number for every point
  /// The number of sample points that carry each point.
  std::size_t width() const { return samples.size() ? std::size_t(samples.degree(0)) : 0; }
  std::vector<double> weights;

  /// Weights `(1 - d_j / d_max)^2` (Sumner, Schmid and Pauly 2007), normalised per point, with `d_max` the
  /// distance to the (m+1)-th nearest sample point: a sample point's weight falls to zero before it leaves the
  /// stencil, so the blend, and the motion, is continuous in space (doc/editing_diffusion.md, "Seamless diffusion").
  /// With `sample_of_point` (each point's own sample point, such as its cluster's), the nearest sample points
  /// are found from each sample point's neighbourhood instead of one tree query per point: the same stencil,
  /// found faster.
  template <typename ConcurrencyTag>
  void setup(const Matrix_n3& points, const Matrix_n3& sample_positions, std::size_t m,
             const std::vector<int>* sample_of_point = nullptr);

  /// Moves every point by its sample points' motions: sample point j moves from `s_j` to `s'_j` and maps
  /// offsets by `map[j]` (a rotation, or a rotation with stretch), so the offset `p - o` seen from the origin
  /// `o` becomes `A_j (p - o)` seen from `o'`; the results are blended by weight. Written as displacements,
  /// `sum_j w_j ((s'_o - s_o) + (A_j - I)(p - o))`, so sample points with `A = I` and `s' = s` contribute an
  /// exact zero and a point whose sample points all stayed keeps its position and normal bit for bit. Normals
  /// follow the blended map's cofactor matrix (`det(A) A^-T`, A itself for a rotation), so they stay normal
  /// to a stretched surface. Per point: one blend of 3x3 matrices, no allocation.
  /// Only the points listed in `active` are computed (all when it is null): the others keep whatever
  /// `out_points` / `out_normals` hold.
  template <typename ConcurrencyTag>
  void apply(const Matrix_n3& points, const Matrix_n3& normals, const Matrix_n3& sample_positions,
             const Matrix_n3& deformed_sample_positions, const std::vector<Eigen::Matrix3d>& map,
             Diffusion_origin origin, Matrix_n3& out_points, Matrix_n3& out_normals, const std::vector<int>* active = nullptr);

  /// The first half of apply(): each sample point's motion record, from its map and its move. O(sample points).
  template <typename ConcurrencyTag>
  void set_motions(const Matrix_n3& sample_positions, const Matrix_n3& deformed_sample_positions,
                   const std::vector<Eigen::Matrix3d>& map);

  /// Called after each block of moved points, `[first, last)` of the points listed (of `active`, or of all rows),
  /// while its rows are still in cache; blocks may run in parallel.
  using Block_visitor = std::function<void(std::size_t first, std::size_t last)>;

  /// The second half of apply(), with the current records: moves the points listed in `active` (all when null)
  /// and writes the a-th one's position and normal to row `destination[a]` of `out_points` and `out_normals`
  /// (rows of three doubles; its own row when `destination` is null), then calls `after_block` when given.
  template <typename ConcurrencyTag>
  void move_points(const Matrix_n3& points, const Matrix_n3& normals, const Matrix_n3& sample_positions,
                   const Matrix_n3& deformed_sample_positions, Diffusion_origin origin, double* out_points,
                   double* out_normals, const std::vector<int>* active, const std::vector<int>* destination,
                   const Block_visitor* after_block = nullptr) const;

  /// move_points() for the points of `packed`, the a-th written to its destination row; `after_block` is
  /// called with ranges of the records.
  template <typename ConcurrencyTag>
  void move_packed_points(const Packed_diffusion_rows& packed, const Matrix_n3& sample_positions,
                          const Matrix_n3& deformed_sample_positions, Diffusion_origin origin, double* out_points,
                          double* out_normals, const Block_visitor* after_block = nullptr) const;

  /// Sample point j's motion record (set by set_motions() or apply()): the point displacement `T_j p + c_j` (`T_j`
  /// its map less the identity, rounded to floats: Motion_record) as the 4x4 matrix `[T_j, c_j; 0, 1]`; a point's
  /// displacement (origin `own_sample`) is the blend of its stencil's records applied to `(p, 1)`.
  Eigen::Matrix4d motion_record(std::size_t j) const
  {
    const Motion_record& record = m_records.at(j);
    Eigen::Matrix4d out = Eigen::Matrix4d::Identity();
    out.topLeftCorner<3, 3>() = record.turn_matrix();
    out.topRightCorner<3, 1>() = record.offset_vector();
    return out;
  }
  /// The motion records set, none before the first set_motions().
  std::size_t number_of_motion_records() const { return m_records.size(); }

  /// Sets sample point j's motion record to the top three rows `records[12 j ...]` (row-major) of a record
  /// another stencil's set_motions() made (motion_record()), for `count` sample points: another process's points
  /// then move as that stencil's do (the turns, floats there, are kept exactly).
  void set_motion_records(const double* records, std::size_t count)
  {
    m_records.resize(count);
    for(std::size_t j = 0; j < count; ++j)
      for(int r = 0; r < 3; ++r) {
        for(int c = 0; c < 3; ++c) m_records[j].turn[3 * c + r] = float(records[12 * j + std::size_t(4 * r + c)]);
        m_records[j].offset[r] = records[12 * j + std::size_t(4 * r + 3)];
      }
  }

  /// Copies row `i`'s sample points and weights.
  void copy_row(std::size_t i, int* sample_points, double* out_weights) const
  {
    for(int e = samples.offsets[i], k = 0; e < samples.offsets[i + 1]; ++e, ++k) {
      sample_points[k] = samples.indices[std::size_t(e)];
      out_weights[k] = weights[std::size_t(e)];
    }
  }

  /// apply() for the one point `i` with the current records: its moved position and normal.
  void move_point(std::size_t i, const Matrix_n3& points, const Matrix_n3& normals, const Matrix_n3& sample_positions,
                  const Matrix_n3& deformed_sample_positions, Diffusion_origin origin, Eigen::Vector3d& moved_point,
                  Eigen::Vector3d& moved_normal) const
  {
    Eigen::Matrix3d turn;
    Eigen::Vector3d displacement;
    blend(rows(points, normals, nullptr, nullptr), i, sample_positions, deformed_sample_positions, origin, turn,
          displacement);
    moved_point = points.row(Eigen::Index(i)).transpose() + displacement;
    moved_normal = cofactor_times(Eigen::Matrix3d::Identity() + turn, normals.row(Eigen::Index(i)).transpose()).normalized();
  }

  /// Whether apply() may use the processor's 4-wide vectors with fused multiply-add (AVX2 and FMA, when the
  /// compiler can target them and the processor has them): a third faster; off, it computes the same up to
  /// rounding (the tests compare the two).
  bool use_wide_vectors = true;

  /// Whether this build and this processor have the 4-wide path, and the environment variable
  /// `CGAL_EXT_PORTABLE_DIFFUSION` does not ask for the portable one.
  static bool wide_vectors_available();

private:
  // Per sample point, its displacement as an affine function of the point. Blending the records of a point's
  // stencil by weight blends the maps and the offsets; the weights sum to exactly 1.
  std::vector<Motion_record, Cache_line_allocator<Motion_record>> m_records; // each on one cache line

  // This stencil's rows of `points` and `normals`, picked by `active` and written to `destination` (both optional).
  Diffusion_rows rows(const Matrix_n3& points, const Matrix_n3& normals, const std::vector<int>* active,
                      const std::vector<int>* destination) const
  {
    return {points.data(),
            normals.data(),
            weights.data(),
            samples.indices.data(),
            width(),
            active ? active->data() : nullptr,
            destination ? destination->data() : nullptr};
  }

  // The a-th point's blended turn `sum_j w_j (A_j - I)` and displacement.
  template <typename Layout>
  void blend(const Layout& layout, std::size_t a, const Matrix_n3& sample_positions,
             const Matrix_n3& deformed_sample_positions, Diffusion_origin origin, Eigen::Matrix3d& turn,
             Eigen::Vector3d& displacement) const
  {
    turn.setZero();
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    for(std::size_t k = 0, kept = width(); k < kept; ++k) {
      const double w = layout.weight(a, k);
      const Motion_record& record = m_records[layout.sample(a, k)];
      turn.noalias() += w * record.turn_matrix();
      offset.noalias() += w * record.offset_vector();
    }
    const Eigen::Vector3d p = Eigen::Map<const Eigen::Vector3d>(layout.point(a));
    if(origin == Diffusion_origin::nearest_sample) {
      // The paper's: every frame decodes p - s_0 from s'_0.
      const Eigen::Index o = Eigen::Index(layout.sample(a, 0));
      displacement = (deformed_sample_positions.row(o) - sample_positions.row(o)).transpose() +
                     turn * (p - sample_positions.row(o).transpose());
    } else {
      displacement = offset + turn * p;
    }
  }

  // Rounds a row's `count` weights (summing to 1, nearest first, so not increasing) to multiples of 2^-24 that
  // still sum to exactly 1 and do not increase: each rounded down, the quanta left over given to the first ones.
  // A float holds each exactly, so a drag reads 4 bytes a weight instead of 8 and computes the same bits as from
  // the doubles (doc/editing_at_scale.md, "A drag's memory traffic").
  static void quantize_weights(double* weights, std::size_t count)
  {
    constexpr double quanta = 16777216.0; // 2^24
    if(count == 0) return;
    double total = 0;
    for(std::size_t e = 0; e < count; ++e) total += weights[e] = std::floor(weights[e] * quanta);
    for(std::size_t e = 0; total < quanta; e = (e + 1) % count, ++total) weights[e] += 1;
    for(std::size_t e = 0; e < count; ++e) weights[e] /= quanta;
  }

  // The cofactor matrix of `M` (`det(M) M^-T`) times `n`, column by column: the cross products of the others.
  static Eigen::Vector3d cofactor_times(const Eigen::Matrix3d& M, const Eigen::Vector3d& n)
  {
    return n.x() * M.col(1).cross(M.col(2)) + n.y() * M.col(2).cross(M.col(0)) + n.z() * M.col(0).cross(M.col(1));
  }

  // Asks the cache for the data of the point `diffusion_prefetch` points after the a-th: the hardware's own
  // prefetchers left a drag waiting on memory a good part of its time.
  template <typename Layout>
  static void prefetch_ahead(const Layout& layout, std::size_t a, std::size_t count)
  {
    if(a + diffusion_prefetch < count) layout.prefetch(a + diffusion_prefetch);
  }

  // The first `count` points of `layout`, a block of them per task.
  template <typename ConcurrencyTag, typename Layout>
  void move_blocks(const Layout& layout, std::size_t count, const Matrix_n3& sample_positions,
                   const Matrix_n3& deformed_sample_positions, Diffusion_origin origin, double* out_points,
                   double* out_normals, const Block_visitor* after_block) const;

  template <typename Layout>
  void apply_block(const Layout& layout, std::size_t first, std::size_t last, std::size_t count,
                   const Matrix_n3& sample_positions, const Matrix_n3& deformed_sample_positions,
                   Diffusion_origin origin, double* out_points, double* out_normals) const;
#ifdef CGAL_EXT_DIFFUSION_WIDE_VECTORS
  template <typename Layout>
  void apply_block_wide(const Layout& layout, std::size_t first, std::size_t last, std::size_t count,
                        const Matrix_n3& sample_positions, const Matrix_n3& deformed_sample_positions,
                        Diffusion_origin origin, double* out_points, double* out_normals) const;
#endif
};

template <typename ConcurrencyTag>
void Diffusion_stencil::setup(const Matrix_n3& points, const Matrix_n3& sample_positions, std::size_t m,
                              const std::vector<int>* sample_of_point)
{
  m_records.clear(); // those of the sample points before, which may be others
  const std::size_t count = std::size_t(sample_positions.rows());
  const bool bounded = count > m; // else every sample point is in every stencil, which then never changes
  const std::size_t wanted = bounded ? m + 1 : count;
  const Neighbor_graph nearest =
    sample_of_point ? k_nearest_samples_by_owner<ConcurrencyTag>(sample_positions, points, *sample_of_point, wanted)
                    : k_nearest_samples<ConcurrencyTag>(sample_positions, points, wanted);
  const std::size_t n = nearest.size(), kept = std::min(m, count);
  samples.offsets.resize(n + 1);
  for(std::size_t i = 0; i <= n; ++i) samples.offsets[i] = int(i * kept);
  samples.indices.resize(n * kept);
  weights.resize(n * kept);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    const int* first = nearest.begin(i);
    const Eigen::RowVector3d p = points.row(Eigen::Index(i));
    // Without an (m+1)-th sample point, twice the farthest one's distance: also continuous in space.
    const double d_max = bounded ? (p - sample_positions.row(first[kept])).norm()
                                 : 2 * (p - sample_positions.row(first[kept - 1])).norm();
    double sum = 0;
    for(std::size_t e = 0; e < kept; ++e) {
      const std::size_t out = i * kept + e;
      samples.indices[out] = first[e];
      const double falloff = d_max > 0 ? 1 - (p - sample_positions.row(first[e])).norm() / d_max : 0.0;
      weights[out] = falloff * falloff;
      sum += weights[out];
    }
    // All sample points as far as the (m+1)-th (ties, coincident points): equal weights.
    for(std::size_t e = 0; e < kept; ++e) weights[i * kept + e] = sum > 0 ? weights[i * kept + e] / sum : 1.0 / double(kept);
    quantize_weights(weights.data() + i * kept, kept);
  });
}

template <typename ConcurrencyTag>
void Diffusion_stencil::apply(const Matrix_n3& points, const Matrix_n3& normals, const Matrix_n3& sample_positions,
                              const Matrix_n3& deformed_sample_positions, const std::vector<Eigen::Matrix3d>& map,
                              Diffusion_origin origin, Matrix_n3& out_points, Matrix_n3& out_normals,
                              const std::vector<int>* active)
{
  set_motions<ConcurrencyTag>(sample_positions, deformed_sample_positions, map);
  move_points<ConcurrencyTag>(points, normals, sample_positions, deformed_sample_positions, origin, out_points.data(),
                              out_normals.data(), active, nullptr);
}

template <typename ConcurrencyTag>
void Diffusion_stencil::move_points(const Matrix_n3& points, const Matrix_n3& normals,
                                    const Matrix_n3& sample_positions, const Matrix_n3& deformed_sample_positions,
                                    Diffusion_origin origin, double* out_points, double* out_normals,
                                    const std::vector<int>* active, const std::vector<int>* destination,
                                    const Block_visitor* after_block) const
{
  move_blocks<ConcurrencyTag>(rows(points, normals, active, destination), active ? active->size() : samples.size(),
                              sample_positions, deformed_sample_positions, origin, out_points, out_normals,
                              after_block);
}

template <typename ConcurrencyTag>
void Diffusion_stencil::move_packed_points(const Packed_diffusion_rows& packed, const Matrix_n3& sample_positions,
                                           const Matrix_n3& deformed_sample_positions, Diffusion_origin origin,
                                           double* out_points, double* out_normals,
                                           const Block_visitor* after_block) const
{
  move_blocks<ConcurrencyTag>(packed, packed.size(), sample_positions, deformed_sample_positions, origin, out_points,
                              out_normals, after_block);
}

template <typename ConcurrencyTag, typename Layout>
void Diffusion_stencil::move_blocks(const Layout& layout, std::size_t count, const Matrix_n3& sample_positions,
                                    const Matrix_n3& deformed_sample_positions, Diffusion_origin origin,
                                    double* out_points, double* out_normals, const Block_visitor* after_block) const
{
  // Blocks of points: first every point's position and unnormalised normal, then the block's normalisations,
  // which are independent of each other and so overlap (one point's square root and division after another
  // left the processor waiting for each in turn: a third of the time).
  const bool wide = use_wide_vectors && wide_vectors_available();
  for_range<ConcurrencyTag>(
    0, (count + diffusion_block - 1) / diffusion_block,
    [&](std::size_t b) {
      const std::size_t first = b * diffusion_block, last = std::min(count, first + diffusion_block);
#ifdef CGAL_EXT_DIFFUSION_WIDE_VECTORS
      if(wide)
        apply_block_wide(layout, first, last, count, sample_positions, deformed_sample_positions, origin, out_points,
                         out_normals);
      else
#endif
        apply_block(layout, first, last, count, sample_positions, deformed_sample_positions, origin, out_points,
                    out_normals);
      CGAL_USE(wide);
      if(after_block) (*after_block)(first, last);
    },
    8); // tasks of 8 blocks: the collar's points, which cost more, crowd into a few of them in scan order
}

template <typename ConcurrencyTag>
void Diffusion_stencil::set_motions(const Matrix_n3& sample_positions, const Matrix_n3& deformed_sample_positions,
                                    const std::vector<Eigen::Matrix3d>& map)
{
  const std::size_t count = map.size();
  m_records.resize(count);
  for_range<ConcurrencyTag>(0, count, [&](std::size_t j) {
    m_records[j].set(map[j] - Eigen::Matrix3d::Identity(), sample_positions.row(Eigen::Index(j)).transpose(),
                     deformed_sample_positions.row(Eigen::Index(j)).transpose());
  });
}

template <typename Layout>
void Diffusion_stencil::apply_block(const Layout& layout, std::size_t first, std::size_t last, std::size_t count,
                                    const Matrix_n3& sample_positions, const Matrix_n3& deformed_sample_positions,
                                    Diffusion_origin origin, double* out_points, double* out_normals) const
{
  using Row = Eigen::Map<Eigen::RowVector3d>;
  using Rest = Eigen::Map<const Eigen::RowVector3d>;
  std::size_t turned[diffusion_block];
  std::size_t turned_count = 0;
  for(std::size_t a = first; a < last; ++a) {
    prefetch_ahead(layout, a, count);
    const std::size_t o = layout.destination_of(a);
    Row out_point(out_points + 3 * o), out_normal(out_normals + 3 * o);
    const Rest point(layout.point(a)), normal(layout.normal(a));
    Eigen::Matrix3d turn;
    Eigen::Vector3d displacement;
    blend(layout, a, sample_positions, deformed_sample_positions, origin, turn, displacement);
    if(turn.isZero(0) && displacement.isZero(0)) {
      out_point = point;
      out_normal = normal;
      continue;
    }
    out_point = point + displacement.transpose();
    out_normal = cofactor_times(Eigen::Matrix3d::Identity() + turn, normal.transpose()).transpose();
    turned[turned_count++] = o;
  }
  for(std::size_t t = 0; t < turned_count; ++t) Row(out_normals + 3 * turned[t]).normalize();
}

#ifdef CGAL_EXT_DIFFUSION_WIDE_VECTORS
inline bool Diffusion_stencil::wide_vectors_available()
{
  static const bool available = [] {
    const char* portable = std::getenv("CGAL_EXT_PORTABLE_DIFFUSION");
    if(portable && *portable && std::string(portable) != "0") return false;
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return available;
}

// The cross product of the first three lanes: (u1 u2 u0) * (v2 v0 v1) - (u2 u0 u1) * (v1 v2 v0).
__attribute__((target("avx2,fma"))) inline __m256d cross_wide(__m256d u, __m256d v)
{
  const __m256d u_yzx = _mm256_permute4x64_pd(u, _MM_SHUFFLE(3, 0, 2, 1)), u_zxy = _mm256_permute4x64_pd(u, _MM_SHUFFLE(3, 1, 0, 2));
  const __m256d v_yzx = _mm256_permute4x64_pd(v, _MM_SHUFFLE(3, 0, 2, 1)), v_zxy = _mm256_permute4x64_pd(v, _MM_SHUFFLE(3, 1, 0, 2));
  return _mm256_fmsub_pd(u_yzx, v_zxy, _mm256_mul_pd(u_zxy, v_yzx));
}

// apply_block() with one 4-wide register per column of the records: a stencil of 6 sample points blends in 24
// fused multiply-adds instead of 96 multiplications and additions, and the cross products of the cofactor
// matrix are two permutations and a multiply-subtract each. A turn's column is loaded as four floats, the
// fourth the next column's first: the fourth lanes of the blended turn are never used.
template <typename Layout>
__attribute__((target("avx2,fma"))) void
Diffusion_stencil::apply_block_wide(const Layout& layout, std::size_t first, std::size_t last, std::size_t count,
                                    const Matrix_n3& sample_positions, const Matrix_n3& deformed_sample_positions,
                                    Diffusion_origin origin, double* out_points, double* out_normals) const
{
  const __m256d zero = _mm256_setzero_pd();
  std::size_t turned[diffusion_block];
  alignas(32) double normal_x[diffusion_block], normal_y[diffusion_block], normal_z[diffusion_block];
  std::size_t turned_count = 0;
  const std::size_t kept = width();
  const Motion_record* records = m_records.data();
  const __m256i first_three = _mm256_setr_epi64x(-1, -1, -1, 0);
  for(std::size_t a = first; a < last; ++a) {
    prefetch_ahead(layout, a, count);
    __m256d column[4] = {zero, zero, zero, zero};
    for(std::size_t k = 0; k < kept; ++k) {
      const __m256d w = _mm256_set1_pd(layout.weight(a, k));
      const Motion_record& record = records[layout.sample(a, k)];
      for(int c = 0; c < 3; ++c)
        column[c] = _mm256_fmadd_pd(w, _mm256_cvtps_pd(_mm_loadu_ps(record.turn + 3 * c)), column[c]);
      column[3] = _mm256_fmadd_pd(w, _mm256_maskload_pd(record.offset, first_three), column[3]);
    }
    const double* p = layout.point(a);
    __m256d displacement;
    if(origin == Diffusion_origin::nearest_sample) {
      const std::size_t o = layout.sample(a, 0);
      const double* s = sample_positions.data() + 3 * o;
      const double* moved = deformed_sample_positions.data() + 3 * o;
      displacement = _mm256_setr_pd(moved[0] - s[0], moved[1] - s[1], moved[2] - s[2], 0);
      for(int c = 0; c < 3; ++c) displacement = _mm256_fmadd_pd(_mm256_set1_pd(p[c] - s[c]), column[c], displacement);
    } else {
      displacement = column[3];
      for(int c = 0; c < 3; ++c) displacement = _mm256_fmadd_pd(_mm256_set1_pd(p[c]), column[c], displacement);
    }
    const std::size_t o = layout.destination_of(a);
    double* out_p = out_points + 3 * o;
    double* out_n = out_normals + 3 * o;
    const double* n = layout.normal(a);
    // Still: a zero map and a zero displacement (their first three lanes).
    const __m256d any = _mm256_or_pd(_mm256_or_pd(_mm256_or_pd(column[0], column[1]), column[2]), displacement);
    if((_mm256_movemask_pd(_mm256_cmp_pd(any, zero, _CMP_NEQ_UQ)) & 7) == 0) {
      for(int r = 0; r < 3; ++r) out_p[r] = p[r], out_n[r] = n[r];
      continue;
    }
    alignas(32) double moved_point[4], normal[4];
    _mm256_store_pd(moved_point, _mm256_add_pd(_mm256_setr_pd(p[0], p[1], p[2], 0), displacement));
    // The blended map's columns b_c = e_c + column_c; its cofactor matrix times n.
    const __m256d b0 = _mm256_add_pd(column[0], _mm256_setr_pd(1, 0, 0, 0));
    const __m256d b1 = _mm256_add_pd(column[1], _mm256_setr_pd(0, 1, 0, 0));
    const __m256d b2 = _mm256_add_pd(column[2], _mm256_setr_pd(0, 0, 1, 0));
    __m256d cofactor_n = _mm256_mul_pd(_mm256_set1_pd(n[0]), cross_wide(b1, b2));
    cofactor_n = _mm256_fmadd_pd(_mm256_set1_pd(n[1]), cross_wide(b2, b0), cofactor_n);
    cofactor_n = _mm256_fmadd_pd(_mm256_set1_pd(n[2]), cross_wide(b0, b1), cofactor_n);
    _mm256_store_pd(normal, cofactor_n);
    for(int r = 0; r < 3; ++r) out_p[r] = moved_point[r];
    normal_x[turned_count] = normal[0], normal_y[turned_count] = normal[1], normal_z[turned_count] = normal[2];
    turned[turned_count++] = o;
  }
  // The block's normals normalised four at a time: one 4-wide square root and three 4-wide divisions for four
  // normals, where one at a time the divisions were a ninth of the kernel.
  for(std::size_t t = turned_count; t % 4 != 0; ++t) normal_x[t] = normal_y[t] = normal_z[t] = 1; // lanes never stored
  for(std::size_t t = 0; t < turned_count; t += 4) {
    const __m256d x = _mm256_load_pd(normal_x + t), y = _mm256_load_pd(normal_y + t), z = _mm256_load_pd(normal_z + t);
    const __m256d squared = _mm256_fmadd_pd(z, z, _mm256_fmadd_pd(y, y, _mm256_mul_pd(x, x)));
    // A zero normal stays zero, as normalize() leaves it: it is divided by one.
    const __m256d length =
      _mm256_blendv_pd(_mm256_sqrt_pd(squared), _mm256_set1_pd(1.0), _mm256_cmp_pd(squared, zero, _CMP_LE_OQ));
    _mm256_store_pd(normal_x + t, _mm256_div_pd(x, length));
    _mm256_store_pd(normal_y + t, _mm256_div_pd(y, length));
    _mm256_store_pd(normal_z + t, _mm256_div_pd(z, length));
    for(std::size_t u = t; u < std::min(t + 4, turned_count); ++u) {
      double* out_n = out_normals + 3 * turned[u];
      out_n[0] = normal_x[u], out_n[1] = normal_y[u], out_n[2] = normal_z[u];
    }
  }
}
#else
inline bool Diffusion_stencil::wide_vectors_available() { return false; }
#endif

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_SSP_DIFFUSION_INSTANCES(EXTERN, Tag)                                                                  \
  EXTERN template void Diffusion_stencil::setup<Tag>(const Matrix_n3&, const Matrix_n3&, std::size_t,                  \
                                                     const std::vector<int>*);                                         \
  EXTERN template void Diffusion_stencil::set_motions<Tag>(const Matrix_n3&, const Matrix_n3&,                         \
                                                           const std::vector<Eigen::Matrix3d>&);                       \
  EXTERN template void Diffusion_stencil::apply<Tag>(                                                                  \
    const Matrix_n3&, const Matrix_n3&, const Matrix_n3&, const Matrix_n3&, const std::vector<Eigen::Matrix3d>&,       \
    Diffusion_origin, Matrix_n3&, Matrix_n3&, const std::vector<int>*);                                                \
  EXTERN template void Diffusion_stencil::move_points<Tag>(                                                            \
    const Matrix_n3&, const Matrix_n3&, const Matrix_n3&, const Matrix_n3&, Diffusion_origin, double*, double*,        \
    const std::vector<int>*, const std::vector<int>*, const Block_visitor*) const;                                     \
  EXTERN template void Diffusion_stencil::move_packed_points<Tag>(const Packed_diffusion_rows&, const Matrix_n3&,      \
                                                                  const Matrix_n3&, Diffusion_origin, double*,         \
                                                                  double*, const Block_visitor*) const;
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_SSP_DIFFUSION_INSTANCES)

/// The rows that a drag can move: those with a region sample point in their stencil and, with `exact_handles`, the
/// handle points (`point_labels` per row, `sample_labels` per sample point). Points carried by fixed sample points
/// only never move: each drag skips them.
inline std::vector<int> moving_rows(const Diffusion_stencil& stencil, const std::vector<int>& sample_labels,
                                    const std::vector<int>& point_labels, bool exact_handles)
{
  std::vector<int> rows;
  for(std::size_t row = 0; row < stencil.samples.size(); ++row) {
    bool moving = exact_handles && is_handle_label(point_labels[row]);
    for(const int* s = stencil.samples.begin(row); s != stencil.samples.end(row) && !moving; ++s)
      moving = sample_labels[std::size_t(*s)] != fixed_label;
    if(moving) rows.push_back(int(row));
  }
  return rows;
}

/// The linear part of each region sample point's motion, by which it carries its points (`Sample_turn`): the
/// best rotation or linear map of its neighbourhood's edges, or its deformed frame against its original one. A
/// sample point whose neighbourhood did not move (and, with frames, that was not turned) keeps the identity
/// exactly, so unchanged parts stay bit for bit; fixed sample points keep theirs (doc/editing_diffusion.md, "Sample point
/// turns"). `setup` runs once per selection, `update` once per drag.
class Sample_turns
{
public:
  std::vector<Eigen::Matrix3d> maps; ///< per sample point (a rotation unless `Sample_turn::affine`)

  template <typename ConcurrencyTag>
  void setup(Sample_turn kind, const Matrix_n3& samples, const Matrix_n3& normals, const Neighbor_graph& graph,
             const std::vector<int>& roi)
  {
    m_kind = kind;
    m_priors.clear();
    if(kind == Sample_turn::affine) {
      m_priors.resize(roi.size());
      for_range<ConcurrencyTag>(0, roi.size(), [&](std::size_t r) {
        m_priors[r] = Linear_map_prior(samples, graph, std::size_t(roi[r]));
      });
    }
    if(kind == Sample_turn::frames) { // the fitted turns need no frames
      m_frame_builder.setup(samples, normals, graph);
      m_frames.resize(std::size_t(samples.rows()));
      for_range<ConcurrencyTag>(0, m_frames.size(), [&](std::size_t s) {
        m_frames[s] = m_frame_builder.frame(samples, s, normals.row(Eigen::Index(s)).transpose());
      });
    }
    maps.assign(std::size_t(samples.rows()), Eigen::Matrix3d::Identity());
  }

  void reset() { std::fill(maps.begin(), maps.end(), Eigen::Matrix3d::Identity()); }

  /// The maps of the region's sample points `roi` for their `deformed` positions. A handle sample point of an exact
  /// handle (`exact_handles`, `labels` per sample point) turns by its group's rotation in `group_rotations`. With
  /// `fitted_rotations`, `detail_rotations` are the rotations the as-rigid-as-possible step fitted to these very
  /// positions: they are taken as they are; else they are the details' rotations, the frames' normal hints.
  template <typename ConcurrencyTag>
  void update(const Matrix_n3& samples, const Matrix_n3& normals, const Matrix_n3& deformed, const Neighbor_graph& graph,
              const std::vector<int>& roi, const std::vector<int>& labels, bool exact_handles,
              const std::vector<Eigen::Matrix3d>& group_rotations, const std::vector<Eigen::Matrix3d>& detail_rotations,
              bool fitted_rotations)
  {
    for_range<ConcurrencyTag>(0, roi.size(), [&](std::size_t r) {
      const std::size_t s = std::size_t(roi[r]);
      if(exact_handles && is_handle_label(labels[s])) { // moved rigidly by its group, exactly
        maps[s] = group_rotations[handle_group_of_label(labels[s])];
        return;
      }
      if(m_kind != Sample_turn::frames) {
        const bool affine = m_kind == Sample_turn::affine;
        double covariance[9]; // of the edges: the rotation's fit and the linear map's
        const bool moved = (affine || !fitted_rotations) && edge_covariance(samples, deformed, graph, s, nullptr, covariance);
        // The fitted rotation is the identity exactly where the neighbourhood did not move: keep it so.
        const Eigen::Matrix3d fitted =
          fitted_rotations ? detail_rotations[s]
          : moved          ? best_rotation(Eigen::Matrix3d(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(covariance)))
                           : Eigen::Matrix3d::Identity();
        maps[s] = affine && !fitted.isIdentity(0) ? m_priors[r].fitted_linear_map(covariance, fitted) : fitted;
        return;
      }
      bool moved = !detail_rotations[s].isIdentity(0) || deformed.row(Eigen::Index(s)) != samples.row(Eigen::Index(s));
      for(const int* j = graph.begin(s); j != graph.end(s) && !moved; ++j) moved = deformed.row(*j) != samples.row(*j);
      if(!moved) {
        maps[s].setIdentity();
        return;
      }
      const Eigen::Vector3d hint = detail_rotations[s] * normals.row(Eigen::Index(s)).transpose();
      maps[s] = m_frame_builder.frame(deformed, s, hint) * m_frames[s].transpose();
    });
  }

private:
  Sample_turn m_kind = Sample_turn::fitted;
  std::vector<Linear_map_prior> m_priors; // affine: per region sample point
  Ssp_frames m_frame_builder;             // frames: the rest frames and how to build the deformed ones
  std::vector<Eigen::Matrix3d> m_frames;
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_SSP_DIFFUSION_H
