// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_SAMPLE_SYSTEM_H
#define CGAL_EXT_INTERNAL_SAMPLE_SYSTEM_H

#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/Least_squares_settings.h>
#include <CGAL_ext/internal/Detail_least_squares.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/detail_manipulation.h>
#include <CGAL_ext/internal/neighborhood_rotations.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/tangent_cotangent_weights.h>

#include <cmath>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Labels of an edit's points and sample points: fixed, in the region of interest, or a handle of group
/// `label - first_handle_label`.
enum Edit_label : int { fixed_label = 0, roi_label = 1, first_handle_label = 2 };

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

  /// Builds the graph (`k` neighbours) and Laplacian of `samples`, indexes the region and handles by `labels`,
  /// checks that every part of the region is pinned (`point_of_sample` names a point of each sample point in
  /// the messages) and factors the normal equations: of the details of `filter`, or with `rigid` of the graph's
  /// edges, weighted by `cotangent_weights` (from the sample points' `normals`) or uniformly, and with
  /// `area_scaled_smoothing` finds `smoothing_area`. A finite `handle_weight` makes the handles the paper's soft
  /// constraints, infinity exact ones.
  template <typename ConcurrencyTag>
  void setup(const Matrix_n3& samples, const Matrix_n3& normals, const std::vector<int>& labels,
             const std::vector<int>& point_of_sample, std::size_t k, const Detail_filter& filter, bool rigid,
             bool cotangent_weights, bool area_scaled_smoothing, Least_squares_settings least_squares,
             double handle_weight, const char* who)
  {
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
  }

  /// Solves for the region's displacements under these right-hand sides (per region row, per handle) and
  /// writes the region's rows of `deformed` as `samples` plus them.
  template <typename ConcurrencyTag>
  void solve(const Matrix_n3& samples, const Matrix_n3& detail_change, const Matrix_n3& anchor_displacement,
             Matrix_n3& deformed)
  {
    const Matrix_n3 u = m_solver.solve<ConcurrencyTag>(detail_change, anchor_displacement);
    for(std::size_t r = 0; r < roi.size(); ++r)
      deformed.row(roi[r]) = samples.row(roi[r]) + u.row(Eigen::Index(r));
  }

  const Least_squares_statistics& statistics() const { return m_solver.statistics(); }

private:
  Detail_least_squares m_solver;
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_SAMPLE_SYSTEM_H
