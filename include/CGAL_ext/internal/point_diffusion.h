// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_POINT_DIFFUSION_H
#define CGAL_EXT_INTERNAL_POINT_DIFFUSION_H

#include <CGAL_ext/Detail_preserving_deformation_settings.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/detail_relaxation.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/handle_collar.h>
#include <CGAL_ext/internal/sample_points.h>
#include <CGAL_ext/internal/ssp_diffusion.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// The editing's diffusion of the sample points' motions to every point (doc/editing_diffusion.md): the sample
/// points' turns, each point's stencil, the rows a drag can move and the exact handles' collar, set up once per
/// selection; per drag, `update_motions` (O(sample points)) then `apply` (the movable points); once a drag ends,
/// `restore_details`.
class Point_diffusion
{
public:
  Sample_turns turns;
  Diffusion_stencil stencil;
  Handle_collar collar;
  std::vector<int> moving_rows;    ///< the rows a region sample point carries, and the exact handles'
  std::vector<int> movable_points; ///< their input indices, increasing

  /// `samples` of `cloud` (`normals` per row), their neighbour `graph` and region `roi`; the edit's `selection`.
  template <typename ConcurrencyTag>
  void setup(const Spatial_point_cloud& cloud, const Edit_sample_points& samples, const Neighbor_graph& graph,
             const std::vector<int>& roi, const Edit_selection& selection,
             const Detail_preserving_deformation_settings& settings)
  {
    const bool exact_handles = std::isinf(settings.handle_weight);
    turns.template setup<ConcurrencyTag>(settings.diffusion_turn, samples.positions, samples.normals, graph, roi);
    stencil.template setup<ConcurrencyTag>(cloud.positions, samples.positions,
                                           std::min<std::size_t>(settings.diffusion_samples, samples.size()),
                                           &samples.of_row);
    stencil.use_wide_vectors = !settings.portable_diffusion;
    moving_rows = internal::moving_rows(stencil, samples.labels, selection.labels, exact_handles);
    m_movable_rows = moving_rows;
    std::sort(m_movable_rows.begin(), m_movable_rows.end(),
              [&](int a, int b) { return cloud.input_index[std::size_t(a)] < cloud.input_index[std::size_t(b)]; });
    movable_points.clear();
    for(int row : m_movable_rows) movable_points.push_back(cloud.input_index[std::size_t(row)]);
    m_in_input_order = Stencil_in_input_order();
    m_has_relaxation = false;
    collar.template setup<ConcurrencyTag>(cloud, selection.labels, selection.transforms.size(), exact_handles,
                                          settings.handle_collar, stencil, samples.positions, moving_rows);
    m_group_rotations.resize(selection.transforms.size());
  }

  /// The sample points' motions to their `deformed` positions, each turning its points by its sample turn (from
  /// `detail_rotations`, taken as they are when `fitted_rotations`); the handle groups' `transforms`. Moves no point.
  template <typename ConcurrencyTag>
  void update_motions(const Edit_sample_points& samples, const Matrix_n3& deformed, const Neighbor_graph& graph,
                      const std::vector<int>& roi, const std::vector<Rigid_transform>& transforms,
                      const std::vector<Eigen::Matrix3d>& detail_rotations, bool fitted_rotations)
  {
    for(std::size_t g = 0; g < transforms.size(); ++g) m_group_rotations[g] = transforms[g].rotation.toRotationMatrix();
    turns.template update<ConcurrencyTag>(samples.positions, samples.normals, deformed, graph, roi, samples.labels,
                                          !collar.handle_rows.empty(), m_group_rotations, detail_rotations,
                                          fitted_rotations);
    stencil.template set_motions<ConcurrencyTag>(samples.positions, deformed, turns.maps);
  }

  /// After `update_motions`: the movable rows of `deformed_points` and `deformed_normals` from their rest
  /// `points` and `normals`, then the exact handles and their collar.
  template <typename ConcurrencyTag>
  void apply(const Matrix_n3& points, const Matrix_n3& normals, const Matrix_n3& samples,
             const Matrix_n3& deformed_samples, Diffusion_origin origin, const std::vector<Rigid_transform>& transforms,
             Matrix_n3& deformed_points, Matrix_n3& deformed_normals)
  {
    stencil.template apply<ConcurrencyTag>(points, normals, samples, deformed_samples, turns.maps, origin,
                                           deformed_points, deformed_normals, &moving_rows);
    collar.template apply<ConcurrencyTag>(points, normals, m_group_rotations, transforms, deformed_points,
                                          deformed_normals);
  }

  /// `apply` into arrays in input order (row i: input point i, three doubles; `cloud` and its rest `normals`), in
  /// input order: the other movable points blended a block at a time, then the block's exact handles put on
  /// their transforms and its collar points stepped while its lines are in cache. The same results bit for bit, written where
  /// the caller keeps them instead of copied there. The first call after `setup` packs the points' rest
  /// positions, normals and stencils in input order (Packed_diffusion_rows).
  template <typename ConcurrencyTag>
  void apply_in_input_order(const Spatial_point_cloud& cloud, const Matrix_n3& normals, const Matrix_n3& samples,
                            const Matrix_n3& deformed_samples, Diffusion_origin origin,
                            const std::vector<Rigid_transform>& transforms, double* out_points, double* out_normals)
  {
    Stencil_in_input_order& ordered = m_in_input_order;
    if(!ordered.ready) copy_in_input_order<ConcurrencyTag>(cloud, normals);
    collar.template set_walk_steps<ConcurrencyTag>(stencil, cloud.positions, normals, samples, deformed_samples, origin,
                                                   m_group_rotations, transforms);
    // Each block of the walk also puts on their transforms the exact handles whose rows lie among its own, so
    // that a cache line of the caller's arrays holding both is read once, not once per pass
    // (doc/editing_at_scale.md, "A drag's memory traffic").
    const Packed_diffusion_rows& packed = ordered.packed;
    const auto handles_and_collar = [&](std::size_t first, std::size_t last) {
      const std::int64_t begin = first == 0 ? 0 : std::int64_t(packed.destination_of(first));
      const std::int64_t end =
        last == packed.size() ? std::numeric_limits<std::int64_t>::max() : std::int64_t(packed.destination_of(last));
      collar.template apply_to_handle_points<ConcurrencyTag>(begin, end, m_group_rotations, transforms, out_points,
                                                             out_normals);
      if(!collar.rows.empty()) collar.apply_to_walk_collar(first, last, packed, out_points, out_normals);
    };
    if(packed.size() == 0) handles_and_collar(0, 0);
    const Diffusion_stencil::Block_visitor after_block = handles_and_collar;
    stencil.template move_packed_points<ConcurrencyTag>(packed, samples, deformed_samples, origin, out_points,
                                                        out_normals, &after_block);
  }

  /// The bytes a drag's `apply` (`in_input_order`: `apply_in_input_order`) reads and writes for its points, as
  /// the data's layout counts them: per blended point its stencil, rest position and normal read (and its
  /// destination row, in input order) and its position and normal written; per exact handle its rest position
  /// and normal read and its new ones written; the sample points' motion records once. Neither the cache lines
  /// a store reads before it writes them nor the collar's steps are counted.
  std::size_t moved_bytes(bool in_input_order) const
  {
    const std::size_t row = 3 * sizeof(double), records = sizeof(Motion_record) * turns.maps.size();
    const std::size_t handles = collar.handle_rows.size();
    if(in_input_order && m_in_input_order.ready) {
      const Packed_diffusion_rows& packed = m_in_input_order.packed;
      return packed.size() * (packed.record_bytes() + 2 * row) + handles * 4 * row + records;
    }
    const std::size_t stencil_row = stencil.width() * (sizeof(double) + sizeof(int));
    return moving_rows.size() * (4 * row + stencil_row) + handles * 4 * row + records;
  }

  /// Puts back the fine details of the region's moved rows of `deformed` (from their rest `points`) that the
  /// blend smoothed out (Detail_relaxation), over each row's 10 nearest. The first call after `setup` sets it up.
  template <typename ConcurrencyTag>
  Detail_relaxation::Outcome restore_details(const Matrix_n3& points, const std::vector<int>& labels,
                                             const Detail_preserving_deformation_settings& settings,
                                             Matrix_n3& deformed)
  {
    const std::size_t neighbors = std::min<std::size_t>(10, std::size_t(points.rows()) - 1);
    if(neighbors == 0 || settings.detail_iterations == 0) return {};
    if(!m_has_relaxation)
      m_relaxation.template setup<ConcurrencyTag>(points, relaxed_rows(moving_rows, labels, collar.handle_rows),
                                                  neighbors);
    m_has_relaxation = true;
    return m_relaxation.template apply<ConcurrencyTag>(points, settings.detail_anchor, settings.detail_iterations,
                                                       settings.detail_tolerance, deformed);
  }

private:
  // The movable points other than exact handles, in input order for apply_in_input_order(): their rest positions,
  // normals and stencils, and their input indices.
  struct Stencil_in_input_order
  {
    bool ready = false;
    Packed_diffusion_rows packed;
  };

  template <typename ConcurrencyTag>
  void copy_in_input_order(const Spatial_point_cloud& cloud, const Matrix_n3& normals)
  {
    Stencil_in_input_order& ordered = m_in_input_order;
    std::vector<int> blended_rows, handle_rows; // an exact handle's blend would be overwritten: not blended
    for(int row : m_movable_rows)               // every handle row among them
      (std::binary_search(collar.handle_rows.begin(), collar.handle_rows.end(), row) ? handle_rows : blended_rows)
        .push_back(row);
    ordered.packed.template pack<ConcurrencyTag>(blended_rows, cloud.input_index, cloud.positions, normals,
                                                 stencil.weights, stencil.samples.indices, stencil.width());
    collar.prepare_walk(blended_rows, handle_rows, cloud.positions, normals, cloud.input_index);
    ordered.ready = true;
  }

  std::vector<Eigen::Matrix3d> m_group_rotations; // the handle groups' rotations as matrices, per drag
  std::vector<int> m_movable_rows;                // moving_rows in the order of their input indices
  Stencil_in_input_order m_in_input_order;
  Detail_relaxation m_relaxation;
  bool m_has_relaxation = false;
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_POINT_DIFFUSION_H
