// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_SSP_DIFFUSION_H
#define CGAL_EXT_INTERNAL_SSP_DIFFUSION_H

#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Local frames of the simplification sample points (doc/editing.md, "The paper's encoding and ours"), built
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
// Defined where the editing class is compiled (internal/parallel.h): its eigen solver is costly to compile.
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

/// How a point's offset is stored in the frames of its sample points (doc/editing.md, "The paper's encoding
/// and ours").
enum class Offset_origin
{
  nearest_sample, ///< the paper's: `p - s_0` (the nearest sample point) in every frame
  own_sample      ///< `p - s_j` in the frame of sample point j
};

/// The per-point data of the diffusion, fixed at preprocessing: the `m` nearest sample points and their weights.
class Diffusion_stencil
{
public:
  Neighbor_graph samples; ///< nearest first
  std::vector<double> weights;

  /// Weights `(1 - d_j / d_max)^2` (Sumner, Schmid and Pauly 2007), normalised per point, with `d_max` the
  /// distance to the (m+1)-th nearest sample point: a sample point's weight falls to zero before it leaves the
  /// stencil, so the blend, and the motion, is continuous in space (doc/editing.md, "Seamless diffusion").
  template <typename ConcurrencyTag>
  void setup(const Matrix_n3& points, const Matrix_n3& sample_positions, std::size_t m);

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
             Offset_origin origin, Matrix_n3& out_points, Matrix_n3& out_normals, const std::vector<int>* active = nullptr);

private:
  std::vector<Eigen::Matrix3d> m_turn; // per sample point, A - I
  Matrix_n3 m_constant;                // per sample point, (s' - s) - (A - I) s
};

template <typename ConcurrencyTag>
void Diffusion_stencil::setup(const Matrix_n3& points, const Matrix_n3& sample_positions, std::size_t m)
{
  const std::size_t count = std::size_t(sample_positions.rows());
  const bool bounded = count > m; // else every sample point is in every stencil, which then never changes
  const Neighbor_graph nearest = k_nearest_samples<ConcurrencyTag>(sample_positions, points, bounded ? m + 1 : count);
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
  });
}

template <typename ConcurrencyTag>
void Diffusion_stencil::apply(const Matrix_n3& points, const Matrix_n3& normals, const Matrix_n3& sample_positions,
                              const Matrix_n3& deformed_sample_positions, const std::vector<Eigen::Matrix3d>& map,
                              Offset_origin origin, Matrix_n3& out_points, Matrix_n3& out_normals,
                              const std::vector<int>* active)
{
  // Per sample point: D = A - I and, for offsets from the sample point itself, the constant part of its
  // displacement `(s' - s) - D s`, so that a point's displacement is `(sum w D) p + sum w e`.
  const std::size_t count = map.size();
  m_turn.resize(count);
  m_constant.resize(Eigen::Index(count), 3);
  for_range<ConcurrencyTag>(0, count, [&](std::size_t j) {
    m_turn[j] = map[j] - Eigen::Matrix3d::Identity();
    const Eigen::Vector3d s = sample_positions.row(Eigen::Index(j)).transpose();
    const Eigen::Vector3d moved = deformed_sample_positions.row(Eigen::Index(j)).transpose() - s;
    m_constant.row(Eigen::Index(j)) = (moved - m_turn[j] * s).transpose();
  });
  // Blocks of points: first every point's position and unnormalised normal, then the block's normalisations,
  // which are independent of each other and so overlap (one point's square root and division after another
  // left the processor waiting for each in turn: a third of the time).
  const std::size_t total = active ? active->size() : samples.size();
  constexpr std::size_t block = 256;
  for_range<ConcurrencyTag>(0, (total + block - 1) / block, [&](std::size_t b) {
    const std::size_t first = b * block, last = std::min(total, first + block);
    std::size_t turned[block];
    std::size_t turned_count = 0;
    for(std::size_t a = first; a < last; ++a) {
      const std::size_t i = active ? std::size_t((*active)[a]) : a;
      const Eigen::Vector3d p = points.row(Eigen::Index(i)).transpose();
      Eigen::Matrix3d turn = Eigen::Matrix3d::Zero();
      Eigen::Vector3d displacement = Eigen::Vector3d::Zero();
      double weight_sum = 0;
      for(int e = samples.offsets[i]; e < samples.offsets[i + 1]; ++e) {
        const std::size_t j = std::size_t(samples.indices[std::size_t(e)]);
        const double w = weights[std::size_t(e)];
        turn.noalias() += w * m_turn[j];
        displacement.noalias() += w * m_constant.row(Eigen::Index(j)).transpose();
        weight_sum += w;
      }
      if(origin == Offset_origin::nearest_sample) {
        // The paper's: every frame decodes p - s_0 from s'_0.
        const Eigen::Index o = *samples.begin(i);
        displacement = weight_sum * (deformed_sample_positions.row(o) - sample_positions.row(o)).transpose() +
                       turn * (p - sample_positions.row(o).transpose());
      } else {
        displacement.noalias() += turn * p;
      }
      if(turn.isZero(0) && displacement.isZero(0)) {
        out_points.row(Eigen::Index(i)) = points.row(Eigen::Index(i));
        out_normals.row(Eigen::Index(i)) = normals.row(Eigen::Index(i));
        continue;
      }
      // The cofactor matrix of the blended map I + turn, column by column: the cross products of the others.
      const Eigen::Matrix3d blended = Eigen::Matrix3d::Identity() + turn;
      const Eigen::Vector3d n = normals.row(Eigen::Index(i)).transpose();
      out_points.row(Eigen::Index(i)) = (p + displacement).transpose();
      out_normals.row(Eigen::Index(i)) = (n.x() * blended.col(1).cross(blended.col(2)) + n.y() * blended.col(2).cross(blended.col(0)) +
                                          n.z() * blended.col(0).cross(blended.col(1))).transpose();
      turned[turned_count++] = i;
    }
    for(std::size_t t = 0; t < turned_count; ++t) out_normals.row(Eigen::Index(turned[t])).normalize();
  });
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/parallel.h).
#define CGAL_EXT_SSP_DIFFUSION_INSTANCES(EXTERN, Tag) \
  EXTERN template void Diffusion_stencil::setup<Tag>(const Matrix_n3&, const Matrix_n3&, std::size_t); \
  EXTERN template void Diffusion_stencil::apply<Tag>(const Matrix_n3&, const Matrix_n3&, const Matrix_n3&, \
                                                     const Matrix_n3&, const std::vector<Eigen::Matrix3d>&, \
                                                     Offset_origin, Matrix_n3&, Matrix_n3&, \
                                                     const std::vector<int>*);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_SSP_DIFFUSION_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_SSP_DIFFUSION_H
