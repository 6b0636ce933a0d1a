// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_POINT_ARRAYS_H
#define CGAL_EXT_INTERNAL_POINT_ARRAYS_H

#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>

#include <Eigen/Core>

#ifdef CGAL_EXT_CORE_DEFINITIONS
#include <CGAL/Spatial_sort_traits_adapter_3.h>
#include <CGAL/hilbert_sort.h>
#endif

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cmath>
#include <iterator>
#include <numeric>
#include <sstream>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// n x 3 array of doubles, one point or vector per row: the layout of every numerical core.
using Matrix_n3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// The caller's points copied once into a contiguous array, kept in Hilbert (spatial) order so that
/// neighbour queries and sparse products walk memory locally. `input_index[s]` is the position in the
/// caller's range of the point stored at row `s`; results are written back through it, so the
/// reordering never leaks.
struct Spatial_point_cloud
{
  Matrix_n3 positions;
  std::vector<int> input_index;

  std::size_t size() const { return input_index.size(); }

  /// The inverse permutation: the row of the caller's i-th point.
  std::vector<int> spatial_index() const
  {
    std::vector<int> row_of(size());
    for(std::size_t s = 0; s < size(); ++s) row_of[std::size_t(input_index[s])] = int(s);
    return row_of;
  }
};

inline std::string describe_point(std::size_t i, double x, double y, double z)
{
  std::ostringstream os;
  os << "point #" << i << " (" << x << ", " << y << ", " << z << ")";
  return os.str();
}

/// The cloud of the copied points `copy` (in the caller's order, validated): checked to span a surface, then
/// sorted along a Hilbert curve.
template <typename ConcurrencyTag>
Spatial_point_cloud sort_spatially(const std::vector<CGAL::Simple_cartesian<double>::Point_3>& copy, const char* who);

/// Throws when three or more points all coincide or lie on one line: they sample no surface, and every
/// tangent plane, normal and curvature of them is undefined.
inline void check_spans_a_surface(const std::vector<CGAL::Simple_cartesian<double>::Point_3>& points, const char* who)
{
  if(points.size() < 3) return; // too few for any neighbourhood; the callers' k checks name that
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for(const auto& p : points) mean += Eigen::Vector3d(p.x(), p.y(), p.z());
  mean /= double(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for(const auto& p : points) {
    const Eigen::Vector3d d = Eigen::Vector3d(p.x(), p.y(), p.z()) - mean;
    covariance += d * d.transpose();
  }
  const Eigen::Vector3d spread = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly).eigenvalues();
  if(!(spread(2) > 0))
    throw Invalid_input(std::string(who) + ": all " + std::to_string(points.size()) + " points coincide; they sample no surface");
  // Exactly collinear coordinates leave rounding noise of relative size 1e-32 in the middle eigenvalue.
  if(spread(1) <= 1e-24 * spread(2))
    throw Invalid_input(std::string(who) + ": all " + std::to_string(points.size()) +
                        " points are collinear; they sample no surface");
}

#ifdef CGAL_EXT_CORE_DEFINITIONS
/// The traits of the Hilbert sort with each axis's order made total: coordinates equal on the axis compared on the
/// next axes. Its median cuts then split the same sets of points whatever their order, so the Hilbert order is a
/// function of the positions alone but for coinciding points, which it may also part; a comparison of two of them
/// raises `coincide` (doc/design.md, "One neighbourhood rule").
struct Total_order_sort_traits : CGAL::Simple_cartesian<double>
{
  using Point_3 = CGAL::Simple_cartesian<double>::Point_3;
  template <int a, int b, int c>
  struct Less
  {
    std::atomic<bool>* coincide;
    bool operator()(const Point_3& p, const Point_3& q) const
    {
      if(p.cartesian(a) < q.cartesian(a)) return true;
      if(q.cartesian(a) < p.cartesian(a)) return false;
      if(p.cartesian(b) < q.cartesian(b)) return true;
      if(q.cartesian(b) < p.cartesian(b)) return false;
      if(p.cartesian(c) == q.cartesian(c) && &p != &q) coincide->store(true, std::memory_order_relaxed);
      return p.cartesian(c) < q.cartesian(c);
    }
  };
  using Less_x_3 = Less<0, 1, 2>;
  using Less_y_3 = Less<1, 2, 0>;
  using Less_z_3 = Less<2, 0, 1>;
  std::atomic<bool>* coincide = nullptr;
  Less_x_3 less_x_3_object() const { return {coincide}; }
  Less_y_3 less_y_3_object() const { return {coincide}; }
  Less_z_3 less_z_3_object() const { return {coincide}; }
};

template <typename ConcurrencyTag>
Spatial_point_cloud sort_spatially(const std::vector<CGAL::Simple_cartesian<double>::Point_3>& copy, const char* who)
{
  using SC_point = CGAL::Simple_cartesian<double>::Point_3;
  check_spans_a_surface(copy, who);
  const std::size_t n = copy.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t(0));
  using Traits = CGAL::Spatial_sort_traits_adapter_3<Total_order_sort_traits,
                                                     typename CGAL::Pointer_property_map<SC_point>::const_type>;
  std::atomic<bool> coincide{false};
  Total_order_sort_traits total_order;
  total_order.coincide = &coincide;
  // Median policy: balanced on uneven scans.
  CGAL::hilbert_sort<ConcurrencyTag>(order.begin(), order.end(), Traits(CGAL::make_property_map(copy), total_order),
                                     CGAL::Hilbert_sort_median_policy());
  if(coincide.load()) {
    // Coinciding points one after another, where the first of them stands: then the caller's order among them
    // moves no other row and no neighbour in a sum over rows; only a row's own diagonal, kept in its sorted place,
    // stands before or after its twin's column (doc/design.md, "One neighbourhood rule").
    std::vector<std::size_t> place(n), by_position(order);
    for(std::size_t s = 0; s < n; ++s) place[order[s]] = s;
    std::sort(by_position.begin(), by_position.end(), [&](std::size_t i, std::size_t j) {
      const SC_point &p = copy[i], &q = copy[j];
      return std::make_tuple(p.x(), p.y(), p.z(), place[i]) < std::make_tuple(q.x(), q.y(), q.z(), place[j]);
    });
    std::vector<std::size_t> run(n); // each point's run of coinciding points in by_position: its first place there
    for(std::size_t r = 0; r < n; ++r)
      run[by_position[r]] = r > 0 && copy[by_position[r]] == copy[by_position[r - 1]] ? run[by_position[r - 1]] : r;
    std::vector<std::size_t> grouped;
    grouped.reserve(n);
    for(const std::size_t i : order) {
      if(by_position[run[i]] != i) continue; // not the first of its run: placed with it
      for(std::size_t r = run[i]; r < n && run[by_position[r]] == run[i]; ++r) grouped.push_back(by_position[r]);
    }
    order.swap(grouped);
  }
  Spatial_point_cloud cloud;
  cloud.input_index.assign(order.begin(), order.end());
  cloud.positions.resize(Eigen::Index(n), 3);
  for(std::size_t s = 0; s < n; ++s) {
    const SC_point& p = copy[std::size_t(cloud.input_index[s])];
    cloud.positions.row(Eigen::Index(s)) << p.x(), p.y(), p.z();
  }
  return cloud;
}
#endif

/// Copies and validates the points of `points`, in range order. `who` names the calling algorithm in error
/// messages.
template <typename PointRange, typename PointMap>
std::vector<CGAL::Simple_cartesian<double>::Point_3> copy_points(const PointRange& points, PointMap point_map, const char* who)
{
  const std::size_t n = static_cast<std::size_t>(std::distance(points.begin(), points.end()));
  if(n == 0)
    throw Invalid_input(std::string(who) + ": the point range is empty");
  if(n >= std::size_t(INT_MAX))
    throw Invalid_input(std::string(who) + ": too many points (at most 2^31 - 2 are supported)");

  std::vector<CGAL::Simple_cartesian<double>::Point_3> copy;
  copy.reserve(n);
  std::size_t i = 0;
  for(const auto& item : points) {
    const auto& p = get(point_map, item);
    const double x = CGAL::to_double(p.x()), y = CGAL::to_double(p.y()), z = CGAL::to_double(p.z());
    if(!(std::isfinite(x) && std::isfinite(y) && std::isfinite(z)))
      throw Invalid_input(std::string(who) + ": " + describe_point(i, x, y, z) +
                          " has a non-finite coordinate; remove or repair such points first");
    copy.emplace_back(x, y, z);
    ++i;
  }
  return copy;
}

/// The cloud of the points `subset` of `copy` (increasing indices into it), sorted along a Hilbert curve; its
/// `input_index` refers to `copy`. A region's surroundings sorted alone: the whole set's order is not needed.
template <typename ConcurrencyTag>
Spatial_point_cloud sort_spatially(const std::vector<CGAL::Simple_cartesian<double>::Point_3>& copy,
                                   const std::vector<int>& subset, const char* who)
{
  std::vector<CGAL::Simple_cartesian<double>::Point_3> kept;
  kept.reserve(subset.size());
  for(const int i : subset) kept.push_back(copy[std::size_t(i)]);
  Spatial_point_cloud cloud = sort_spatially<ConcurrencyTag>(kept, who);
  for(int& i : cloud.input_index) i = subset[std::size_t(i)];
  return cloud;
}

/// Copies and validates the points of `points` (in range order) and sorts them spatially.
/// `who` names the calling algorithm in error messages.
template <typename ConcurrencyTag, typename PointRange, typename PointMap>
Spatial_point_cloud make_spatial_point_cloud(const PointRange& points, PointMap point_map, const char* who)
{
  return sort_spatially<ConcurrencyTag>(copy_points(points, point_map, who), who);
}

/// Reads the caller's normals in the cloud's order, normalised. Throws on a zero or non-finite normal.
template <typename PointRange, typename NormalMap>
Matrix_n3 gather_normals(const PointRange& points, NormalMap normal_map,
                         const Spatial_point_cloud& cloud, const char* who)
{
  // The cloud may hold a part of the points (a region's surroundings): every normal is read and checked.
  Matrix_n3 in_order(Eigen::Index(std::distance(std::begin(points), std::end(points))), 3);
  std::size_t i = 0;
  for(const auto& item : points) {
    const auto& v = get(normal_map, item);
    Eigen::RowVector3d n(CGAL::to_double(v.x()), CGAL::to_double(v.y()), CGAL::to_double(v.z()));
    const double len = n.norm();
    if(!(std::isfinite(len) && len > 0)) {
      std::ostringstream os;
      os << who << ": the normal of point #" << i << " is zero or not finite (" << n(0) << ", " << n(1) << ", "
         << n(2) << "); repair the normals or let them be estimated by passing no normal_map";
      throw Invalid_input(os.str());
    }
    in_order.row(Eigen::Index(i++)) = n / len;
  }
  Matrix_n3 sorted(Eigen::Index(cloud.size()), 3);
  for(std::size_t s = 0; s < cloud.size(); ++s)
    sorted.row(Eigen::Index(s)) = in_order.row(cloud.input_index[s]);
  return sorted;
}

/// Rows of the cloud for the caller's point indices, increasing and without repeats.
template <typename IndexRange>
std::vector<int> rows_of_indices(const IndexRange& indices, const std::vector<int>& row_of, const char* who,
                                 const char* what)
{
  std::vector<int> rows;
  for(const auto& index : indices) {
    const long long i = static_cast<long long>(index);
    if(i < 0 || i >= static_cast<long long>(row_of.size()))
      throw Invalid_input(std::string(who) + ": " + what + " index " + std::to_string(i) + " is not a point index (" +
                          std::to_string(row_of.size()) + " points)");
    rows.push_back(row_of[std::size_t(i)]);
  }
  std::sort(rows.begin(), rows.end());
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  return rows;
}

template <typename Range>
struct Point_set_3_range : std::false_type {};
template <typename P, typename V>
struct Point_set_3_range<CGAL::Point_set_3<P, V>> : std::true_type
{
  using Own_normal_map = typename CGAL::Point_set_3<P, V>::Vector_map;
};

/// Whether the caller supplied normals. CGAL 5.5 treats every `Point_set_3` as having a normal map (and its
/// `parameters()` names one) even when the set has no normal property, so for such a range it is decided at
/// run time: its own normal map counts only if the property exists.
template <typename NamedParameters, typename PointRange>
bool has_given_normals(const PointRange& points)
{
  using Named = typename CGAL::internal_np::Get_param<typename NamedParameters::base, CGAL::internal_np::normal_t>::type;
  constexpr bool named = !std::is_same<Named, CGAL::internal_np::Param_not_found>::value;
  if constexpr(Point_set_3_range<PointRange>::value) {
    if constexpr(named && !std::is_same<Named, typename Point_set_3_range<PointRange>::Own_normal_map>::value)
      return true;
    return points.has_normal_map();
  } else {
    return named;
  }
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_POINT_ARRAYS_INSTANCES(EXTERN, Tag) \
  EXTERN template Spatial_point_cloud sort_spatially<Tag>(const std::vector<CGAL::Simple_cartesian<double>::Point_3>&, \
                                                          const char*);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_POINT_ARRAYS_INSTANCES)

/// Calls `write(i, a_row, b_row)` with the rows of `a` and `b` (`row_of[i]`) for every input index `i` of `inputs`
/// (null: every one), in parallel and in increasing order: the writes go forward and the scattered reads are
/// fetched ahead.
template <typename ConcurrencyTag, typename Writer>
void for_each_row_in_input_order(const std::vector<int>& row_of, const std::vector<int>* inputs, const Matrix_n3& a,
                                 const Matrix_n3& b, const Writer& write)
{
  const std::size_t count = inputs ? inputs->size() : row_of.size();
  const auto input = [&](std::size_t k) { return inputs ? std::size_t((*inputs)[k]) : k; };
  for_range<ConcurrencyTag>(0, count, [&](std::size_t k) {
    constexpr std::size_t ahead = 16; // rows in flight: enough to hide a memory access behind the writes
#if defined(__GNUC__)
    if(k + ahead < count) {
      const Eigen::Index later = row_of[input(k + ahead)];
      __builtin_prefetch(a.row(later).data());
      __builtin_prefetch(b.row(later).data());
    }
#endif
    const std::size_t i = input(k);
    const Eigen::Index row = row_of[i];
    write(i, a.row(row).data(), b.row(row).data());
  });
}

/// Writes row `row_of[i]` of `positions` to the i-th element of `points` through `np`'s point map and, when `np`
/// names a normal map and the range has normals, that of `normals` through it.
template <typename PointRange, typename NamedParameters>
void write_points_and_normals(PointRange& points, const NamedParameters& np, const std::vector<int>& row_of,
                              const Matrix_n3& positions, const Matrix_n3& normals)
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  const auto point_map = NP_helper::get_point_map(points, np);
  using Point = typename boost::property_traits<std::remove_const_t<decltype(point_map)>>::value_type;
  constexpr bool with_normals =
    !CGAL::parameters::is_default_parameter<NamedParameters, CGAL::internal_np::normal_t>::value;
  // A Point_set_3 names a normal map even when it has no normal property: write normals only where they exist.
  const bool write_normals = with_normals && has_given_normals<NamedParameters>(points);
  std::size_t i = 0;
  for(auto& item : points) {
    const Eigen::Index row = row_of[i++];
    put(point_map, item, Point(positions(row, 0), positions(row, 1), positions(row, 2)));
    if constexpr(with_normals) {
      if(!write_normals) continue;
      const auto normal_map = NP_helper::get_normal_map(points, np);
      using Vector = typename boost::property_traits<decltype(normal_map)>::value_type;
      put(normal_map, item, Vector(normals(row, 0), normals(row, 1), normals(row, 2)));
    }
  }
}

/// The row of the caller's i-th point (`row_of`, `Spatial_point_cloud::spatial_index`), refused when out of range.
inline std::size_t checked_row(const std::vector<int>& row_of, std::size_t i, const char* who)
{
  if(i >= row_of.size())
    throw Invalid_input(std::string(who) + ": point index " + std::to_string(i) + " is out of range (" +
                        std::to_string(row_of.size()) + " points)");
  return std::size_t(row_of[i]);
}

/// Refuses a range `points` given to `call` unless it has `n` elements.
template <typename PointRange>
void check_same_size(const PointRange& points, std::size_t n, const char* call, const char* who)
{
  const std::size_t given = static_cast<std::size_t>(std::distance(points.begin(), points.end()));
  if(given != n)
    throw Invalid_input(std::string(who) + ": " + call + " was given " + std::to_string(given) + " points, but the "
                        "object holds " + std::to_string(n));
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_POINT_ARRAYS_H
