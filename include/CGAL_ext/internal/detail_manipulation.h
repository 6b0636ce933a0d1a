// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_DETAIL_MANIPULATION_H
#define CGAL_EXT_INTERNAL_DETAIL_MANIPULATION_H

// What detail scaling and enhancement share: the region of interest and its anchors in the cloud's order,
// the check that something pins every part of the region, and the solve for the region's displacements.

#include <CGAL_ext/Detail_scaling_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Detail_least_squares.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// The caller's points in spatial order, and a region of interest among them.
struct Region
{
  Spatial_point_cloud cloud;
  std::vector<int> row_of;  ///< cloud row of the caller's i-th point
  std::vector<int> roi;     ///< cloud rows of the region, increasing
  std::vector<char> in_roi; ///< per cloud row
};

/// Copies and checks the points and `k`, and places the region (`roi_indices`, or every point when null). The
/// cloud is in spatial order, or with `spatial_order` false in the caller's order, for `region_surroundings`,
/// which sorts only the points it keeps.
template <typename ConcurrencyTag, typename PointRange, typename PointMap, typename IndexRange>
Region make_region(const PointRange& points, PointMap point_map, unsigned int k, const IndexRange* roi_indices,
                   const char* who, bool spatial_order = true)
{
  Region region;
  if(spatial_order) {
    region.cloud = make_spatial_point_cloud<ConcurrencyTag>(points, point_map, who);
  } else {
    const std::vector<CGAL::Simple_cartesian<double>::Point_3> copy = copy_points(points, point_map, who);
    check_spans_a_surface(copy, who);
    region.cloud.positions.resize(Eigen::Index(copy.size()), 3);
    for(std::size_t i = 0; i < copy.size(); ++i) region.cloud.positions.row(Eigen::Index(i)) << copy[i].x(), copy[i].y(), copy[i].z();
    region.cloud.input_index.resize(copy.size());
    std::iota(region.cloud.input_index.begin(), region.cloud.input_index.end(), 0);
  }
  check_neighbor_count(k, region.cloud.size(), who);
  region.row_of = region.cloud.spatial_index();
  if(roi_indices) {
    region.roi = rows_of_indices(*roi_indices, region.row_of, who, "region-of-interest");
  } else {
    region.roi.resize(region.cloud.size());
    std::iota(region.roi.begin(), region.roi.end(), 0);
  }
  if(region.roi.empty()) throw Invalid_input(std::string(who) + ": the region of interest is empty");
  region.in_roi.assign(region.cloud.size(), 0);
  for(int r : region.roi) region.in_roi[std::size_t(r)] = 1;
  return region;
}

/// The region restricted to the cloud rows `kept`, which hold every region row, in that order. `anchors_local`
/// (indices into the region's rows) follow.
inline Region ordered_subregion(const Region& region, const std::vector<int>& kept, std::vector<int>& anchors_local)
{
  Region local;
  local.cloud.positions.resize(Eigen::Index(kept.size()), 3);
  local.cloud.input_index.resize(kept.size());
  local.row_of.assign(region.row_of.size(), -1);
  local.in_roi.assign(kept.size(), 0);
  for(std::size_t s = 0; s < kept.size(); ++s) {
    const std::size_t row = std::size_t(kept[s]);
    local.cloud.positions.row(Eigen::Index(s)) = region.cloud.positions.row(Eigen::Index(row));
    local.cloud.input_index[s] = region.cloud.input_index[row];
    local.row_of[std::size_t(local.cloud.input_index[s])] = int(s);
    if(region.in_roi[row]) {
      local.roi.push_back(int(s));
      local.in_roi[s] = 1;
    }
  }
  for(int& a : anchors_local) {
    const int row = local.row_of[std::size_t(region.cloud.input_index[std::size_t(region.roi[std::size_t(a)])])];
    a = int(std::lower_bound(local.roi.begin(), local.roi.end(), row) - local.roi.begin());
  }
  return local;
}

/// The cloud rows `rows` sorted along a Hilbert curve (the cloud's copies of them checked to span a surface).
template <typename ConcurrencyTag>
std::vector<int> spatially_sorted_rows(const Matrix_n3& positions, const std::vector<int>& rows, const char* who)
{
  std::vector<CGAL::Simple_cartesian<double>::Point_3> copy;
  copy.reserve(rows.size());
  for(int row : rows) copy.emplace_back(positions(row, 0), positions(row, 1), positions(row, 2));
  const std::vector<int> order = sort_spatially<ConcurrencyTag>(copy, who).input_index;
  std::vector<int> sorted(rows.size());
  for(std::size_t s = 0; s < rows.size(); ++s) sorted[s] = rows[std::size_t(order[s])];
  return sorted;
}

/// The region among the points near it only: those within `margin` neighbourhood radii of a region point
/// (the radius: the median distance of a region point to its k-th nearest region point), in spatial order, so
/// that a small region of a large model costs what its surroundings cost. The whole cloud, in spatial order,
/// when the surroundings would hold most of it, or too few points for `min_points`. `region` may come in any
/// order (make_region's caller order: only the points near the region get sorted); `anchors_local` follow.
template <typename ConcurrencyTag>
Region region_surroundings(const Region& region, std::size_t k, double margin, std::size_t min_points,
                           std::vector<int>& anchors_local, const char* who)
{
  const std::size_t n = region.cloud.size(), m = region.roi.size();
  auto whole_cloud = [&] {
    std::vector<int> everything(n);
    std::iota(everything.begin(), everything.end(), 0);
    return ordered_subregion(region, spatially_sorted_rows<ConcurrencyTag>(region.cloud.positions, everything, who),
                             anchors_local);
  };
  if(!(margin > 0) || m == n || m <= k) return whole_cloud();
  Matrix_n3 roi_positions(Eigen::Index(m), 3);
  for(std::size_t r = 0; r < m; ++r) roi_positions.row(Eigen::Index(r)) = region.cloud.positions.row(region.roi[r]);
  // The neighbourhood radius, from up to 2,000 of the region's points.
  const std::size_t stride = std::max<std::size_t>(1, m / 2000);
  Matrix_n3 probes(Eigen::Index((m + stride - 1) / stride), 3);
  for(Eigen::Index q = 0; q < probes.rows(); ++q) probes.row(q) = roi_positions.row(q * Eigen::Index(stride));
  const Neighbor_graph probe_neighbors = k_nearest_samples<ConcurrencyTag>(roi_positions, probes, k + 1);
  std::vector<double> radii = last_neighbor_distances(probes, roi_positions, probe_neighbors);
  std::nth_element(radii.begin(), radii.begin() + std::ptrdiff_t(radii.size() / 2), radii.end());
  const double reach = margin * radii[radii.size() / 2];
  if(!(reach > 0) || !std::isfinite(reach)) return whole_cloud();

  // Only the points in the region's bounding box grown by the reach can be that close: the others are neither
  // sorted nor searched (on a region of a tenth of a large model, most of the points). The candidates are
  // sorted first, so that the searches run in spatial order and the points kept come out in it.
  const Eigen::RowVector3d low = roi_positions.colwise().minCoeff().array() - reach;
  const Eigen::RowVector3d high = roi_positions.colwise().maxCoeff().array() + reach;
  std::vector<int> candidates;
  for(std::size_t i = 0; i < n; ++i) {
    const auto p = region.cloud.positions.row(Eigen::Index(i));
    if((p.array() >= low.array()).all() && (p.array() <= high.array()).all()) candidates.push_back(int(i));
  }
  candidates = spatially_sorted_rows<ConcurrencyTag>(region.cloud.positions, candidates, who);
  Matrix_n3 candidate_positions(Eigen::Index(candidates.size()), 3);
  std::vector<int> sorted_roi_rows;
  for(std::size_t c = 0; c < candidates.size(); ++c) {
    candidate_positions.row(Eigen::Index(c)) = region.cloud.positions.row(candidates[c]);
    if(region.in_roi[std::size_t(candidates[c])]) sorted_roi_rows.push_back(candidates[c]);
  }
  Matrix_n3 sorted_roi_positions(Eigen::Index(sorted_roi_rows.size()), 3);
  for(std::size_t r = 0; r < sorted_roi_rows.size(); ++r)
    sorted_roi_positions.row(Eigen::Index(r)) = region.cloud.positions.row(sorted_roi_rows[r]);
  const Neighbor_graph nearest = k_nearest_samples<ConcurrencyTag>(sorted_roi_positions, candidate_positions, 1);
  std::vector<int> kept;
  for(std::size_t c = 0; c < candidates.size(); ++c)
    if((candidate_positions.row(Eigen::Index(c)) - sorted_roi_positions.row(*nearest.begin(c))).squaredNorm() <= reach * reach)
      kept.push_back(candidates[c]);
  if(4 * kept.size() > 3 * n || kept.size() < min_points) return whole_cloud();
  return ordered_subregion(region, kept, anchors_local);
}

/// The anchors' positions in `roi` (local indices); throws if one is not in the region.
inline std::vector<int> local_anchor_indices(const std::vector<int>& roi, const std::vector<int>& anchor_rows,
                                             const std::vector<int>& input_index, const char* who)
{
  std::vector<int> local;
  local.reserve(anchor_rows.size());
  for(int row : anchor_rows) {
    const auto it = std::lower_bound(roi.begin(), roi.end(), row);
    if(it == roi.end() || *it != row)
      throw Invalid_input(std::string(who) + ": anchor point #" + std::to_string(input_index[std::size_t(row)]) +
                          " is not in the region of interest; anchors constrain points of the region");
    local.push_back(int(it - roi.begin()));
  }
  return local;
}

/// The region's points that have a neighbour outside it (the default anchors of a partial region).
inline std::vector<int> region_border(const Sparse_row_matrix& K, const std::vector<int>& roi, const std::vector<char>& in_roi)
{
  std::vector<int> local;
  for(std::size_t r = 0; r < roi.size(); ++r)
    for(int e = K.outerIndexPtr()[roi[r]]; e < K.outerIndexPtr()[roi[r] + 1]; ++e)
      if(!in_roi[std::size_t(K.innerIndexPtr()[e])]) { local.push_back(int(r)); break; }
  return local;
}

/// A connected part of the region (in the neighbour graph) with no anchor and no neighbour outside the region:
/// nothing pins it, it could translate freely. `first` is its first point (local index).
struct Unpinned_part
{
  int first;
  std::size_t size;
};

inline std::vector<Unpinned_part> unpinned_parts(const Sparse_row_matrix& K, const std::vector<int>& roi,
                                                 const std::vector<char>& in_roi, const std::vector<int>& anchors_local)
{
  std::vector<int> local_of(std::size_t(K.rows()), -1);
  for(std::size_t r = 0; r < roi.size(); ++r) local_of[std::size_t(roi[r])] = int(r);
  std::vector<char> pinned(roi.size(), 0), seen(roi.size(), 0);
  for(int a : anchors_local) pinned[std::size_t(a)] = 1;
  std::vector<Unpinned_part> parts;
  std::vector<int> stack;
  for(std::size_t start = 0; start < roi.size(); ++start) {
    if(seen[start]) continue;
    std::size_t size = 0;
    bool is_pinned = false;
    stack.push_back(int(start));
    seen[start] = 1;
    while(!stack.empty()) {
      const int r = stack.back();
      stack.pop_back();
      ++size;
      is_pinned = is_pinned || pinned[std::size_t(r)];
      for(int e = K.outerIndexPtr()[roi[std::size_t(r)]]; e < K.outerIndexPtr()[roi[std::size_t(r)] + 1]; ++e) {
        const int j = K.innerIndexPtr()[e];
        if(!in_roi[std::size_t(j)]) { is_pinned = true; continue; }
        const int l = local_of[std::size_t(j)];
        if(!seen[std::size_t(l)]) { seen[std::size_t(l)] = 1; stack.push_back(l); }
      }
    }
    if(!is_pinned) parts.push_back({int(start), size});
  }
  return parts;
}

/// Throws unless every connected part of the region holds an anchor or touches a point outside the region:
/// otherwise that part could translate freely and the system is singular.
inline void check_pinned(const Sparse_row_matrix& K, const std::vector<int>& roi, const std::vector<char>& in_roi,
                         const std::vector<int>& anchors_local, const std::vector<int>& input_index, const char* who)
{
  const std::vector<Unpinned_part> parts = unpinned_parts(K, roi, in_roi, anchors_local);
  if(parts.empty()) return;
  throw Invalid_input(std::string(who) + ": a part of the region of interest with " + std::to_string(parts.front().size) +
                      " points (point #" + std::to_string(input_index[std::size_t(roi[std::size_t(parts.front().first)])]) +
                      " among them) has no anchor and no neighbour outside the region, so nothing pins it and "
                      "the least-squares system is singular; give anchors in that part or shrink the region");
}

/// A region's least-squares system for a change of its details. The factor needs no right-hand side, so
/// `solve_and_write_region` computes it while the caller computes the change (enhancement's base surface).
class Region_system
{
public:
  /// Builds the operator rows of the region `roi` (cloud rows) and its anchors and factors the system.
  template <typename ConcurrencyTag>
  void factor(const Sparse_row_matrix& K, const Matrix_n3& positions, const Detail_filter& filter,
              const std::vector<int>& roi, const std::vector<int>& anchors_local, const Least_squares_settings& settings);

  /// The region's displacements for the detail change `detail_change` (rows of the whole cloud; only the
  /// region's are read) and the anchors' displacements.
  template <typename ConcurrencyTag>
  Matrix_n3 solve(const Matrix_n3& detail_change, const Matrix_n3& anchor_displacement,
                  Least_squares_statistics& statistics);

private:
  Detail_least_squares m_system;
  std::vector<int> m_roi;
  double m_operator_seconds = 0;
};

template <typename ConcurrencyTag>
void Region_system::factor(const Sparse_row_matrix& K, const Matrix_n3& positions, const Detail_filter& filter,
                           const std::vector<int>& roi, const std::vector<int>& anchors_local,
                           const Least_squares_settings& settings)
{
  const auto start = std::chrono::steady_clock::now();
  m_roi = roi;
  Sparse_row_matrix A = detail_operator_rows<ConcurrencyTag>(K, filter, roi);
  Matrix_n3 region_positions(Eigen::Index(roi.size()), 3);
  for(std::size_t r = 0; r < roi.size(); ++r) region_positions.row(Eigen::Index(r)) = positions.row(roi[r]);
  // A large quadric region: conjugate gradients preconditioned by the linear order, c1 K on the region, whose
  // response c1 k matches the quadric's c1 k + c2 k^2 at the smooth end (Least_squares_settings).
  Sparse_row_matrix B;
  const bool preconditioned = filter.order == Detail_order::quadric && settings.solver == Linear_solver::cholesky &&
                              roi.size() >= settings.preconditioned_from;
  if(preconditioned) {
    Detail_filter linear;
    linear.order = Detail_order::linear;
    linear.lambda = 1.0 / filter.coefficients().c1;
    B = detail_operator_rows<ConcurrencyTag>(K, linear, roi);
  }
  m_operator_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  m_system.factor<ConcurrencyTag>(std::move(A), anchors_local, region_positions, settings, false,
                                  preconditioned ? &B : nullptr);
}

template <typename ConcurrencyTag>
Matrix_n3 Region_system::solve(const Matrix_n3& detail_change, const Matrix_n3& anchor_displacement,
                               Least_squares_statistics& statistics)
{
  Matrix_n3 region_change(Eigen::Index(m_roi.size()), 3);
  for(std::size_t r = 0; r < m_roi.size(); ++r) region_change.row(Eigen::Index(r)) = detail_change.row(m_roi[r]);
  Matrix_n3 u = m_system.solve<ConcurrencyTag>(region_change, anchor_displacement);
  statistics = m_system.statistics();
  statistics.assembly_seconds += m_operator_seconds;
  return u;
}

/// Writes `positions + displacement` of the region's rows through the point map, in the caller's order.
template <typename PointRange, typename PointMap>
void write_region(PointRange& points, PointMap point_map, const Spatial_point_cloud& cloud, const std::vector<int>& roi,
                  const Matrix_n3& displacement)
{
  using Point = typename boost::property_traits<PointMap>::value_type;
  std::vector<int> local_of_input(std::size_t(std::distance(std::begin(points), std::end(points))), -1);
  for(std::size_t r = 0; r < roi.size(); ++r) local_of_input[std::size_t(cloud.input_index[std::size_t(roi[r])])] = int(r);
  std::size_t i = 0;
  for(auto& item : points) {
    const int r = local_of_input[i++];
    if(r < 0) continue;
    const Eigen::RowVector3d x = cloud.positions.row(roi[std::size_t(r)]) + displacement.row(r);
    put(point_map, item, Point(x(0), x(1), x(2)));
  }
}

/// The anchors of a region in local indices: the caller's (a range of indices or `point_is_constrained_map`)
/// or, without any, none, with `defaulted` set so that the caller picks its default anchors.
template <typename PointRange, typename AnchorRange, typename NamedParameters>
std::vector<int> region_anchors(const PointRange& points, const AnchorRange* anchors, const NamedParameters& np,
                                const Region& region, bool& defaulted, const char* who)
{
  using CGAL::parameters::get_parameter;
  defaulted = false;
  if(anchors)
    return local_anchor_indices(region.roi, rows_of_indices(*anchors, region.row_of, who, "anchor"), region.cloud.input_index, who);
  if constexpr(!CGAL::parameters::is_default_parameter<NamedParameters, CGAL::internal_np::point_is_constrained_t>::value)
    return local_anchor_indices(
      region.roi,
      rows_of_indices(selected_indices(points, get_parameter(np, CGAL::internal_np::point_is_constrained)), region.row_of, who, "anchor"),
      region.cloud.input_index, who);
  defaulted = true;
  return {};
}

/// The shared last steps of scaling and enhancement: check that the anchors pin the region, factor its system
/// while `detail_change()` computes the wanted change of the details (rows of the whole cloud), solve for the
/// region's displacements and write them through the point map. `result` carries the anchor choice in and out.
template <typename ConcurrencyTag, typename PointRange, typename PointMap, typename DetailChange>
Detail_manipulation_result solve_and_write_region(PointRange& points, PointMap point_map, const Sparse_row_matrix& K,
                                                  const Region& region, const std::vector<int>& anchors_local,
                                                  const DetailChange& detail_change,
                                                  const Matrix_n3& anchor_displacement,
                                                  const Detail_scaling_settings& settings, Progress& progress,
                                                  Detail_manipulation_result result, const char* who)
{
  check_pinned(K, region.roi, region.in_roi, anchors_local, region.cloud.input_index, who);
  Region_system system;
  Matrix_n3 change;
  run_concurrently<ConcurrencyTag>(
    [&] {
      system.factor<ConcurrencyTag>(K, region.cloud.positions, settings.details.filter, region.roi, anchors_local,
                                    settings.least_squares);
    },
    [&] { change = detail_change(); });
  const Matrix_n3 displacement = system.solve<ConcurrencyTag>(change, anchor_displacement, result.least_squares);
  if(!progress.report(1.0)) return {};
  write_region(points, point_map, region.cloud, region.roi, displacement);
  result.completed = true;
  result.region_size = region.roi.size();
  result.anchor_count = anchors_local.size();
  result.computed_points = region.cloud.size();
  return result;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_DETAIL_MANIPULATION_INSTANCES(EXTERN, Tag) \
  EXTERN template void Region_system::factor<Tag>(const Sparse_row_matrix&, const Matrix_n3&, const Detail_filter&, \
                                                  const std::vector<int>&, const std::vector<int>&, \
                                                  const Least_squares_settings&); \
  EXTERN template Matrix_n3 Region_system::solve<Tag>(const Matrix_n3&, const Matrix_n3&, Least_squares_statistics&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_DETAIL_MANIPULATION_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_DETAIL_MANIPULATION_H
