// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_SAMPLE_SYSTEM_H
#define CGAL_EXT_INTERNAL_SAMPLE_SYSTEM_H

#include <CGAL_ext/Detail_preserving_deformation_settings.h>
#include <CGAL_ext/internal/Detail_least_squares.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/detail_manipulation.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/neighborhood_rotations.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/tangent_cotangent_weights.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// The sample points of an edit as a least-squares problem (Miao et al. 2007, Sect. 6.1): their Laplacian on
/// their symmetrised kNN graph, the region's sample points (the unknowns) and its handles (the anchors), the
/// check that something pins every part of the region, the region's details and the factored normal
/// equations. `setup` runs once per selection; each drag calls `solve` with new right-hand sides.
class Sample_system
{
public:
  Neighbor_graph graph;            ///< symmetrised kNN of the sample points
  Sparse_row_matrix K;             ///< their Laplacian
  std::vector<int> roi;            ///< sample points of the region, increasing
  std::vector<int> roi_local;      ///< per sample point: its row in `roi`, or -1
  std::vector<int> anchors;        ///< rows in `roi` of the handle sample points
  std::vector<int> anchor_group;   ///< their handle groups
  std::vector<std::pair<int, int>> rigid_edges; ///< as-rigid-as-possible: the graph's edges, one equation each
  /// As-rigid-as-possible with cotangent weights: one per entry of `graph.indices` (empty: uniform).
  std::vector<double> edge_weights;
  std::vector<double> rigid_edge_scales; ///< the square roots of `rigid_edges`' weights (empty: uniform)
  /// As-rigid-as-possible: the sample points whose rotations the local step fits, the region's and the fixed
  /// ones an edge joins to it (their rotations are free in the energy, as CGAL's mesh ARAP fits the ring
  /// around its region; held at the identity, they bend the region's edge toward them).
  std::vector<int> rigid_rotation_rows;
  /// As-rigid-as-possible with the smooth-rotation term scaled by the surface's area (CGAL's SRE_ARAP): the
  /// sample points' whole area, the sum of their tangent-plane Voronoi cells; 0: scaled by edge lengths.
  double smoothing_area = 0;
  Matrix_n3 details;               ///< `f(K) s` on the region's rows

  /// Builds the graph (`settings.sample_neighbors` neighbours) and Laplacian of `samples`, indexes the region and
  /// handles by `labels`, checks that every part of the region is pinned (`point_of_sample` names a point of each
  /// sample point in the messages) and factors the normal equations: of the details of `settings.filter`, or, as
  /// rigid as possible, of the graph's edges, weighted by cotangent weights (from the sample points' `normals`) or
  /// uniformly. A finite `settings.handle_weight` makes the handles the paper's soft constraints, infinity exact
  /// ones.
  template <typename ConcurrencyTag>
  void setup(const Matrix_n3& samples, const Matrix_n3& normals, const std::vector<int>& labels,
             const std::vector<int>& point_of_sample, const Detail_preserving_deformation_settings& settings,
             const char* who)
  {
    const bool rigid = settings.rotations == Detail_rotation::as_rigid_as_possible;
    const bool cotangent_weights = settings.rigid_edge_weights == Rigid_edge_weights::cotangent;
    const bool area_scaled_smoothing = settings.rigid_rotation_smoothing > 0 &&
                                       settings.rigid_rotation_smoothing_scale == Rotation_smoothing_scale::surface_area;
    const Detail_filter& filter = settings.filter;
    Least_squares_settings least_squares = settings.least_squares;
    const double handle_weight = settings.handle_weight;
    const std::size_t k = settings.sample_neighbors;
    if(samples.rows() < 2)
      throw Invalid_input(std::string(who) + ": the points form a single sample point; lower the cluster size");
    if(k >= std::size_t(samples.rows()))
      throw Invalid_input(std::string(who) + ": sample_neighbors (" + std::to_string(k) + ") must be less than the "
                          "number of sample points (" + std::to_string(samples.rows()) + "); lower it, or make the "
                          "clusters smaller");
    const std::size_t count = std::size_t(samples.rows());
    Progress silent;
    graph = symmetrize<ConcurrencyTag>(k_nearest_neighbor_graph<ConcurrencyTag>(samples, k, silent));
    K = laplacian_matrix<ConcurrencyTag>(samples, graph, Laplacian_weights());

    roi.clear();
    roi_local.assign(count, -1);
    std::vector<char> in_region(count, 0);
    anchors.clear();
    anchor_group.clear();
    for(std::size_t s = 0; s < count; ++s) {
      if(labels[s] == fixed_label) continue;
      roi_local[s] = int(roi.size());
      in_region[s] = 1;
      if(labels[s] >= first_handle_label) {
        anchors.push_back(int(roi.size()));
        anchor_group.push_back(labels[s] - first_handle_label);
      }
      roi.push_back(int(s));
    }
    check_pinned(K, roi, in_region, anchors, point_of_sample, who);

    // Soft handles weigh w against alpha: the minimiser of alpha ||A u - r||^2 + w ||S u - t||^2 is that of
    // (alpha / w) ||A u - r||^2 + ||S u - t||^2. Exact handles leave the unknowns.
    const Matrix_n3 all_details = apply_detail_filter<ConcurrencyTag>(K, filter, samples);
    details.resize(Eigen::Index(roi.size()), 3);
    Matrix_n3 region_positions(Eigen::Index(roi.size()), 3);
    for(std::size_t r = 0; r < roi.size(); ++r) {
      details.row(Eigen::Index(r)) = all_details.row(roi[r]);
      region_positions.row(Eigen::Index(r)) = samples.row(roi[r]);
    }
    const bool exact_handles = std::isinf(handle_weight);
    if(!exact_handles) least_squares.detail_weight /= handle_weight;
    // As-rigid-as-possible editing solves for the edges of the sample points' graph instead of their details.
    edge_weights.clear();
    if(rigid && cotangent_weights) edge_weights = cotangent_edge_weights<ConcurrencyTag>(samples, normals, graph);
    smoothing_area = 0;
    if(rigid && area_scaled_smoothing)
      smoothing_area = sampled_surface_area(samples, graph, cotangent_weights ? edge_weights
                                                            : cotangent_edge_weights<ConcurrencyTag>(samples, normals, graph));
    if(rigid) {
      Sparse_row_matrix rows = rigid_edge_rows(graph, edge_weights, roi_local, roi.size(), rigid_edges, rigid_edge_scales);
      rigid_rotation_rows = roi;
      std::vector<char> listed(roi_local.size(), 0);
      for(int r : roi) listed[std::size_t(r)] = 1;
      for(const auto& [i, j] : rigid_edges)
        for(const int end : {i, j})
          if(!listed[std::size_t(end)]) {
            listed[std::size_t(end)] = 1;
            rigid_rotation_rows.push_back(end);
          }
      m_solver.factor<ConcurrencyTag>(std::move(rows), anchors, region_positions, least_squares, exact_handles);
    }
    else
      m_solver.factor<ConcurrencyTag>(detail_operator_rows<ConcurrencyTag>(K, filter, roi), anchors,
                                      region_positions, least_squares, exact_handles);
    m_anchor_displacement.resize(Eigen::Index(anchors.size()), 3);
    m_detail_change.resize(Eigen::Index(roi.size()), 3);
  }

  /// Sets the handles' targets for the next solves: each handle sample point moved by its group's transform.
  void pull_anchors(const Matrix_n3& samples, const std::vector<Rigid_transform>& transforms)
  {
    for(std::size_t a = 0; a < anchors.size(); ++a) {
      const Rigid_transform& T = transforms[std::size_t(anchor_group[a])];
      const Eigen::Vector3d s = samples.row(roi[std::size_t(anchors[a])]).transpose();
      m_anchor_displacement.row(Eigen::Index(a)) = (T.rotation * s + T.translation - s).transpose();
    }
  }

  /// Solves for the region's displacements with the right-hand side `edge_change` (per equation row) and the
  /// handles' last `pull_anchors`, and writes the region's rows of `deformed` as `samples` plus them.
  template <typename ConcurrencyTag>
  void solve(const Matrix_n3& samples, const Matrix_n3& edge_change, Matrix_n3& deformed)
  {
    const Matrix_n3 u = m_solver.solve<ConcurrencyTag>(edge_change, m_anchor_displacement);
    for(std::size_t r = 0; r < roi.size(); ++r)
      deformed.row(roi[r]) = samples.row(roi[r]) + u.row(Eigen::Index(r));
  }

  /// `solve` with each region sample point's detail turned by `rotations[s]` (per sample point).
  template <typename ConcurrencyTag>
  void solve_turned_details(const Matrix_n3& samples, const std::vector<Eigen::Matrix3d>& rotations, Matrix_n3& deformed)
  {
    for_range<ConcurrencyTag>(0, roi.size(), [&](std::size_t r) {
      const Eigen::Vector3d delta = details.row(Eigen::Index(r)).transpose();
      m_detail_change.row(Eigen::Index(r)) = (rotations[std::size_t(roi[r])] * delta - delta).transpose();
    });
    solve<ConcurrencyTag>(samples, m_detail_change, deformed);
  }

  /// The largest displacement of a region sample point over the largest of a handle sample point (`labels` per
  /// sample point; 0 when the handles did not move).
  double displacement_ratio(const Matrix_n3& samples, const Matrix_n3& deformed, const std::vector<int>& labels) const
  {
    double largest = 0, largest_handle = 0;
    for(std::size_t r = 0; r < roi.size(); ++r) {
      const double d = (deformed.row(roi[r]) - samples.row(roi[r])).norm();
      largest = std::max(largest, d);
      if(is_handle_label(labels[std::size_t(roi[r])])) largest_handle = std::max(largest_handle, d);
    }
    return largest_handle > 0 ? largest / largest_handle : 0.0;
  }

  const Least_squares_statistics& statistics() const { return m_solver.statistics(); }

private:
  Detail_least_squares m_solver;
  Matrix_n3 m_anchor_displacement, m_detail_change; // per-drag right-hand sides
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_SAMPLE_SYSTEM_H
