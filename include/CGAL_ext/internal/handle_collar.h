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
  std::vector<int> handle_rows;   ///< with exact handles: the rows that follow their group's transform exactly
  std::vector<int> handle_groups; ///< their handle groups
  std::vector<int> rows;          ///< the collar: the region's rows within reach of a handle
  /// Per collar row, the nearest handle point of each group that reaches it (an index into `handle_rows`)...
  Neighbor_graph entries;
  std::vector<double> weights;    ///< ... and the weight of that point's step
  std::vector<int> stepping_handles;       ///< the distinct handles of `entries` (indices into `handle_rows`)
  std::vector<int> stepping_handle_points; ///< their input indices
  std::vector<int> slots;                  ///< per entry, its handle's place in `stepping_handles`

  /// `labels` per row; `moving_rows`: the rows a region sample point carries; `stencil` over `samples`, the
  /// diffusion's. Without `exact_handles` there is neither; without `with_collar`, no collar.
  template <typename ConcurrencyTag>
  void setup(const Spatial_point_cloud& cloud, const std::vector<int>& labels, std::size_t groups, bool exact_handles,
             bool with_collar, const Diffusion_stencil& stencil, const Matrix_n3& samples,
             const std::vector<int>& moving_rows)
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
    const double r = 2 * median_stencil_reach(cloud.positions, stencil, samples);
    if(!(r > 0)) return;
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
    apply_to<ConcurrencyTag>(positions, normals, rotations, transforms, deformed_points.data(), deformed_normals.data(),
                             nullptr);
  }

  /// apply() on blends held elsewhere: row r's in row `destination_of_row[r]` of `out_points` and `out_normals`
  /// (rows of three doubles).
  template <typename ConcurrencyTag>
  void apply_to(const Matrix_n3& positions, const Matrix_n3& normals, const std::vector<Eigen::Matrix3d>& rotations,
                const std::vector<Rigid_transform>& transforms, double* out_points, double* out_normals,
                const std::vector<int>* destination_of_row)
  {
    using Row = Eigen::Map<Eigen::RowVector3d>;
    auto out = [&](double* base, Eigen::Index row) {
      return Row(base + 3 * (destination_of_row ? (*destination_of_row)[std::size_t(row)] : row));
    };
    for_range<ConcurrencyTag>(0, handle_rows.size(), [&](std::size_t h) {
      const Eigen::Index row = handle_rows[h];
      const std::size_t g = std::size_t(handle_groups[h]);
      const Eigen::RowVector3d exact = (rotations[g] * positions.row(row).transpose() + transforms[g].translation).transpose();
      const Eigen::RowVector3d exact_normal = (rotations[g] * normals.row(row).transpose()).transpose();
      Row point = out(out_points, row), normal = out(out_normals, row);
      m_steps.row(Eigen::Index(h)) = exact - point;
      m_normal_steps.row(Eigen::Index(h)) = exact_normal - normal;
      point = exact;
      normal = exact_normal;
    });
    for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t c) {
      const Eigen::Index row = rows[c];
      Eigen::RowVector3d step = Eigen::RowVector3d::Zero(), normal_step = Eigen::RowVector3d::Zero();
      for(int e = entries.offsets[c]; e < entries.offsets[c + 1]; ++e) {
        const double weight = weights[std::size_t(e)];
        step += weight * m_steps.row(entries.indices[std::size_t(e)]);
        normal_step += weight * m_normal_steps.row(entries.indices[std::size_t(e)]);
      }
      if(step.isZero(0) && normal_step.isZero(0)) return; // no step to take: bit for bit
      Row point = out(out_points, row), normal = out(out_normals, row);
      point += step;
      normal = (normal + normal_step).normalized();
    });
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
    step = R * positions.row(Eigen::Index(row)).transpose() + T.translation - blended;
    normal_step = R * normals.row(Eigen::Index(row)).transpose() - blended_normal;
  }

private:
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

  Matrix_n3 m_steps, m_normal_steps; // per handle row, its transform's position less the blend's
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_HANDLE_COLLAR_H
