// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_HANDLE_COLLAR_H
#define CGAL_EXT_INTERNAL_HANDLE_COLLAR_H

#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/ssp_diffusion.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Exact handles and the collar about them. Exact handles put their points on the handle's transform T_g, while
/// the points next to them follow the blend of their sample points, F; where the blend differs from T_g (as rigid
/// as possible fits the sample points next to a handle turns of their own) the border would be a step, one that
/// grows, relative to the point spacing, with the sampling density. So a region point within reach r of a handle
/// also takes the step of the group's nearest handle point h, T_g(h) - F(h), weighted by w = 1 - smoothstep(d / r),
/// d its distance to h and r twice the median distance from a handle point to the farthest sample point of its
/// stencil (how far the diffusion spreads one sample point's motion): the motion is continuous up to the handle
/// (doc/editing_diffusion.md, "Exact handles without a seam"). `setup` runs once per selection, `apply` after each blend.
class Handle_collar
{
public:
  std::vector<int> handle_rows;   ///< with exact handles: the rows that follow their group's transform, increasing
  std::vector<int> handle_groups; ///< their handle groups
  std::vector<int> rows;          ///< the collar: the region's rows within reach of a handle
  /// Per collar row, the nearest handle point of each group that reaches it (an index into `handle_rows`)...
  Neighbor_graph entries;
  std::vector<double> weights;    ///< ... and the weight of that point's step
  std::vector<int> stepping_handles;       ///< the distinct handles of `entries` (indices into `handle_rows`)
  std::vector<int> stepping_handle_points; ///< their input indices
  std::vector<int> slots;                  ///< per entry, its handle's place in `stepping_handles`
  double reach = 0;                        ///< r, 0 without a collar

  /// `labels` per row; `moving_rows`: the rows a region sample point carries; `stencil` over `samples`, the
  /// diffusion's. Without `exact_handles` there is neither; without `with_collar`, no collar. `given_reach`: r
  /// as another collar measured it over all the handle points (a part of a scan's has only some), else 0.
  template <typename ConcurrencyTag>
  void setup(const Spatial_point_cloud& cloud, const std::vector<int>& labels, std::size_t groups, bool exact_handles,
             bool with_collar, const Diffusion_stencil& stencil, const Matrix_n3& samples,
             const std::vector<int>& moving_rows, double given_reach = 0)
  {
    *this = Handle_collar();
    if(exact_handles)
      for(std::size_t row = 0; row < cloud.size(); ++row)
        if(is_handle_label(labels[row])) {
          handle_rows.push_back(int(row));
          handle_groups.push_back(int(handle_group_of_label(labels[row])));
        }
    m_steps.resize(Eigen::Index(handle_rows.size()), 3);
    m_normal_steps.resize(Eigen::Index(handle_rows.size()), 3);
    if(handle_rows.empty() || !with_collar) return;
    const double r = given_reach > 0 ? given_reach : 2 * median_stencil_reach(cloud.positions, stencil, samples);
    if(!(r > 0)) return;
    reach = r;
    struct Entry { int row, handle; double weight; };
    std::vector<Entry> found;
    for(std::size_t g = 0; g < groups; ++g) {
      std::vector<int> handle; // indices into handle_rows
      Eigen::AlignedBox3d box;
      for(std::size_t h = 0; h < handle_rows.size(); ++h)
        if(handle_groups[h] == int(g)) {
          handle.push_back(int(h));
          box.extend(cloud.positions.row(handle_rows[h]).transpose());
        }
      box.min().array() -= r;
      box.max().array() += r;
      std::vector<int> near; // moving region points (not handle points) in the handle's box
      for(int row : moving_rows)
        if(labels[std::size_t(row)] == roi_label && box.contains(cloud.positions.row(row).transpose())) near.push_back(row);
      if(near.empty()) continue;
      Matrix_n3 handle_positions(Eigen::Index(handle.size()), 3), near_positions(Eigen::Index(near.size()), 3);
      for(std::size_t i = 0; i < handle.size(); ++i)
        handle_positions.row(Eigen::Index(i)) = cloud.positions.row(handle_rows[std::size_t(handle[i])]);
      for(std::size_t i = 0; i < near.size(); ++i) near_positions.row(Eigen::Index(i)) = cloud.positions.row(near[i]);
      const Neighbor_graph nearest = k_nearest_samples<ConcurrencyTag>(handle_positions, near_positions, 1);
      for(std::size_t i = 0; i < near.size(); ++i) {
        const double t = (near_positions.row(Eigen::Index(i)) - handle_positions.row(*nearest.begin(i))).norm() / r;
        if(t < 1) found.push_back({near[i], handle[std::size_t(*nearest.begin(i))], 1 - t * t * (3 - 2 * t)});
      }
    }
    std::sort(found.begin(), found.end(),
              [](const Entry& a, const Entry& b) { return a.row < b.row || (a.row == b.row && a.handle < b.handle); });
    for(std::size_t first = 0, last; first < found.size(); first = last) {
      double total = 0;
      for(last = first; last < found.size() && found[last].row == found[first].row; ++last) total += found[last].weight;
      const double scale = total > 1 ? 1 / total : 1.0; // where two groups' collars overlap
      for(std::size_t e = first; e < last; ++e) {
        entries.indices.push_back(found[e].handle);
        weights.push_back(scale * found[e].weight);
      }
      entries.offsets.push_back(int(last));
      rows.push_back(found[first].row);
    }
    stepping_handles = entries.indices;
    std::sort(stepping_handles.begin(), stepping_handles.end());
    stepping_handles.erase(std::unique(stepping_handles.begin(), stepping_handles.end()), stepping_handles.end());
    for(int h : stepping_handles) stepping_handle_points.push_back(cloud.input_index[std::size_t(handle_rows[std::size_t(h)])]);
    for(int h : entries.indices)
      slots.push_back(int(std::lower_bound(stepping_handles.begin(), stepping_handles.end(), h) - stepping_handles.begin()));
  }

  /// After the blend: puts the handle points on their group's transform (`rotations`: the transforms' rotations as
  /// matrices) and moves each collar point by its weighted handle steps; a collar point without a step keeps its
  /// blend bit for bit.
  template <typename ConcurrencyTag>
  void apply(const Matrix_n3& positions, const Matrix_n3& normals, const std::vector<Eigen::Matrix3d>& rotations,
             const std::vector<Rigid_transform>& transforms, Matrix_n3& deformed_points, Matrix_n3& deformed_normals)
  {
    for_range<ConcurrencyTag>(0, handle_rows.size(), [&](std::size_t h) {
      const Eigen::Index row = handle_rows[h], at = Eigen::Index(h);
      const std::size_t g = std::size_t(handle_groups[h]);
      Eigen::RowVector3d exact, exact_normal;
      on_transform(rotations[g], transforms[g], positions.row(row), normals.row(row), exact, exact_normal);
      m_steps.row(at) = exact - deformed_points.row(row);
      m_normal_steps.row(at) = exact_normal - deformed_normals.row(row);
      deformed_points.row(row) = exact;
      deformed_normals.row(row) = exact_normal;
    });
    for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t c) {
      const int first = entries.offsets[c];
      take_steps(entries.indices.data() + first, weights.data() + first, entries.degree(c), m_steps, m_normal_steps,
                 deformed_points.data() + 3 * rows[c], deformed_normals.data() + 3 * rows[c]);
    });
  }

  /// For apply() during a walk in input order over the other moving rows (`walk_rows`; `handles_in_order`, the
  /// handle rows in that order, `input_index` per row): copies the handle points' rest `positions` and `normals`
  /// in input order and finds where the collar points lie in the walk. Once per selection.
  void prepare_walk(const std::vector<int>& walk_rows, const std::vector<int>& handles_in_order,
                    const Matrix_n3& positions, const Matrix_n3& normals, const std::vector<int>& input_index)
  {
    Walk& walk = m_walk;
    walk = Walk();
    walk.handle_positions.resize(Eigen::Index(handles_in_order.size()), 3);
    walk.handle_normals.resize(Eigen::Index(handles_in_order.size()), 3);
    for(std::size_t h = 0; h < handles_in_order.size(); ++h) {
      const int row = handles_in_order[h];
      walk.handle_positions.row(Eigen::Index(h)) = positions.row(row);
      walk.handle_normals.row(Eigen::Index(h)) = normals.row(row);
      walk.handle_points.push_back(input_index[std::size_t(row)]);
      const auto place = std::lower_bound(handle_rows.begin(), handle_rows.end(), row); // sorted by row
      walk.handle_groups.push_back(handle_groups[std::size_t(place - handle_rows.begin())]);
    }
    for(std::size_t w = 0; w < walk_rows.size(); ++w) {
      const auto collar = std::lower_bound(rows.begin(), rows.end(), walk_rows[w]); // sorted by row
      if(collar == rows.end() || *collar != walk_rows[w]) continue;
      const std::size_t c = std::size_t(collar - rows.begin());
      walk.collar.push_back(int(w));
      for(int e = entries.offsets[c]; e < entries.offsets[c + 1]; ++e) {
        walk.collar_entries.indices.push_back(slots[std::size_t(e)]);
        walk.collar_weights.push_back(weights[std::size_t(e)]);
      }
      walk.collar_entries.offsets.push_back(int(walk.collar_entries.indices.size()));
    }
    for(int h : stepping_handles) walk.stepping_rows.push_back(handle_rows[std::size_t(h)]);
    walk.stepping_slots.resize(stepping_handles.size());
    std::iota(walk.stepping_slots.begin(), walk.stepping_slots.end(), 0);
    walk.steps.resize(Eigen::Index(stepping_handles.size()), 3);
    walk.normal_steps.resize(Eigen::Index(stepping_handles.size()), 3);
  }

  /// Per drag, before the walk: the stepping handles' steps, their blends by `stencil`, the stencil whose blends
  /// apply() steps from, with the same kernel: the steps have apply()'s bits.
  template <typename ConcurrencyTag>
  void set_walk_steps(const Diffusion_stencil& stencil, const Matrix_n3& positions, const Matrix_n3& normals,
                      const Matrix_n3& samples, const Matrix_n3& deformed_samples, Diffusion_origin origin,
                      const std::vector<Eigen::Matrix3d>& rotations, const std::vector<Rigid_transform>& transforms)
  {
    Walk& walk = m_walk;
    if(walk.stepping_rows.empty()) return;
    stencil.template move_points<ConcurrencyTag>(positions, normals, samples, deformed_samples, origin,
                                                 walk.steps.data(), walk.normal_steps.data(), &walk.stepping_rows,
                                                 &walk.stepping_slots);
    for(std::size_t c = 0; c < stepping_handles.size(); ++c) {
      const std::size_t g = std::size_t(handle_groups[std::size_t(stepping_handles[c])]);
      const Eigen::Index row = walk.stepping_rows[c], slot = Eigen::Index(c);
      Eigen::RowVector3d exact, exact_normal;
      on_transform(rotations[g], transforms[g], positions.row(row), normals.row(row), exact, exact_normal);
      walk.steps.row(slot) = exact - walk.steps.row(slot);
      walk.normal_steps.row(slot) = exact_normal - walk.normal_steps.row(slot);
    }
  }

  /// apply()'s handle points whose input indices lie in `[begin, end)`, into arrays in input order (row i: input
  /// point i, three doubles). A long run of them (a handle in scan order lies between two blended points) is
  /// shared among the threads.
  template <typename ConcurrencyTag>
  void apply_to_handle_points(std::int64_t begin, std::int64_t end, const std::vector<Eigen::Matrix3d>& rotations,
                              const std::vector<Rigid_transform>& transforms, double* out_points,
                              double* out_normals) const
  {
    using Row = Eigen::Map<Eigen::RowVector3d>;
    const Walk& walk = m_walk;
    const auto points = walk.handle_points.begin();
    const std::size_t first = std::size_t(std::lower_bound(points, walk.handle_points.end(), begin) - points);
    const std::size_t last =
      std::size_t(std::lower_bound(points + std::ptrdiff_t(first), walk.handle_points.end(), end) - points);
    const auto put = [&](std::size_t h) {
      const std::size_t g = std::size_t(walk.handle_groups[h]), i = std::size_t(walk.handle_points[h]);
      Eigen::RowVector3d exact, exact_normal;
      on_transform(rotations[g], transforms[g], walk.handle_positions.row(Eigen::Index(h)),
                   walk.handle_normals.row(Eigen::Index(h)), exact, exact_normal);
      Row(out_points + 3 * i) = exact;
      Row(out_normals + 3 * i) = exact_normal;
    };
    if(last - first > 4096)
      for_range<ConcurrencyTag>(first, last, put, 1024);
    else
      for(std::size_t h = first; h < last; ++h) put(h);
  }

  /// apply()'s collar points among the walk's rows `[begin, end)`, once they hold their blends: row
  /// `walk.destination_of(w)` of `out_points` and `out_normals` (rows of three doubles) for the walk's row w.
  template <typename Walk_rows>
  void apply_to_walk_collar(std::size_t begin, std::size_t end, const Walk_rows& rows, double* out_points,
                            double* out_normals) const
  {
    const Walk& walk = m_walk;
    const auto first = std::lower_bound(walk.collar.begin(), walk.collar.end(), int(begin)) - walk.collar.begin();
    for(std::size_t c = std::size_t(first); c < walk.collar.size() && std::size_t(walk.collar[c]) < end; ++c) {
      const int entry = walk.collar_entries.offsets[c];
      const std::size_t i = rows.destination_of(std::size_t(walk.collar[c]));
      take_steps(walk.collar_entries.indices.data() + entry, walk.collar_weights.data() + entry,
                 walk.collar_entries.degree(c), walk.steps, walk.normal_steps, out_points + 3 * i, out_normals + 3 * i);
    }
  }

  /// Calls `visit(i, slots, weights, count)` for each collar point (`input_index` per row): its `count` entries'
  /// places in `stepping_handles` and weights.
  template <typename Visitor>
  void for_each_point(const std::vector<int>& input_index, const Visitor& visit) const
  {
    for(std::size_t c = 0; c < rows.size(); ++c) {
      const int first = entries.offsets[c];
      visit(std::size_t(input_index[std::size_t(rows[c])]), slots.data() + first, weights.data() + first,
            std::size_t(entries.offsets[c + 1] - first));
    }
  }

  /// The step of the c-th of `stepping_handles` under the sample points' motions in `stencil`: its transform's
  /// position less its blended one, and the same for its normal.
  void handle_step(std::size_t c, const Diffusion_stencil& stencil, const Matrix_n3& positions, const Matrix_n3& normals,
                   const Matrix_n3& samples, const Matrix_n3& deformed_samples, Diffusion_origin origin,
                   const std::vector<Rigid_transform>& transforms, Eigen::Vector3d& step, Eigen::Vector3d& normal_step) const
  {
    const std::size_t h = std::size_t(stepping_handles.at(c)), row = std::size_t(handle_rows[h]);
    const Rigid_transform& T = transforms[std::size_t(handle_groups[h])];
    const Eigen::Matrix3d R = T.rotation.toRotationMatrix();
    Eigen::Vector3d blended, blended_normal;
    stencil.move_point(row, positions, normals, samples, deformed_samples, origin, blended, blended_normal);
    Eigen::RowVector3d exact, exact_normal;
    on_transform(R, T, positions.row(Eigen::Index(row)), normals.row(Eigen::Index(row)), exact, exact_normal);
    step = exact.transpose() - blended;
    normal_step = exact_normal.transpose() - blended_normal;
  }

private:
  // A handle point's rest `position` and `normal` on its group's transform `T` (`R`: its rotation as a matrix).
  template <typename Position, typename Normal>
  static void on_transform(const Eigen::Matrix3d& R, const Rigid_transform& T, const Position& position,
                           const Normal& normal, Eigen::RowVector3d& exact, Eigen::RowVector3d& exact_normal)
  {
    exact = (R * position.transpose() + T.translation).transpose();
    exact_normal = (R * normal.transpose()).transpose();
  }

  // Moves a collar point's blend (`point`, `normal`: three doubles each) by the weighted steps of its `count`
  // entries (rows `handles` of `steps` and `normal_steps`); without a step it keeps its blend bit for bit.
  static void take_steps(const int* handles, const double* weights, int count, const Matrix_n3& steps,
                         const Matrix_n3& normal_steps, double* point, double* normal)
  {
    Eigen::RowVector3d step = Eigen::RowVector3d::Zero(), normal_step = Eigen::RowVector3d::Zero();
    for(int e = 0; e < count; ++e) {
      step += weights[e] * steps.row(handles[e]);
      normal_step += weights[e] * normal_steps.row(handles[e]);
    }
    if(step.isZero(0) && normal_step.isZero(0)) return;
    Eigen::Map<Eigen::RowVector3d> moved(point), turned(normal);
    moved += step;
    turned = (turned + normal_step).normalized();
  }

  /// The median distance from a handle point to the farthest sample point of its stencil.
  double median_stencil_reach(const Matrix_n3& positions, const Diffusion_stencil& stencil, const Matrix_n3& samples) const
  {
    std::vector<double> reach(handle_rows.size());
    for(std::size_t h = 0; h < handle_rows.size(); ++h) {
      const std::size_t row = std::size_t(handle_rows[h]);
      reach[h] = (positions.row(Eigen::Index(row)) - samples.row(stencil.samples.end(row)[-1])).norm();
    }
    std::nth_element(reach.begin(), reach.begin() + std::ptrdiff_t(reach.size() / 2), reach.end());
    return reach[reach.size() / 2];
  }

  // The handle points in input order and where the collar points lie in a walk (prepare_walk()); the steps.
  struct Walk
  {
    Matrix_n3 handle_positions, handle_normals;     // the handle points' rest positions and normals...
    std::vector<int> handle_points, handle_groups;  // ... their input indices, increasing, and groups
    std::vector<int> collar;                        // walk positions, increasing
    Neighbor_graph collar_entries;                  // their entries as places in stepping_handles...
    std::vector<double> collar_weights;             // ... and their weights
    std::vector<int> stepping_rows, stepping_slots; // the stepping handles' rows, and 0, 1, ...
    Matrix_n3 steps, normal_steps;                  // per stepping handle, per drag
  };

  Matrix_n3 m_steps, m_normal_steps; // per handle row, its transform's position less the blend's
  Walk m_walk;
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_HANDLE_COLLAR_H
