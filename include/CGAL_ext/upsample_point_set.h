// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_UPSAMPLE_POINT_SET_H
#define CGAL_EXT_UPSAMPLE_POINT_SET_H

#include <CGAL_ext/detect_sparse_directions.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/local_fit.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  Settings of `upsample_point_set`.
*/
struct Upsampling_settings
{
  Sparse_direction_settings detection; ///< spacing (the target spacing of the new samples) and largest hole
  unsigned int neighbors = 12;         ///< k of the principal axes and of the local surface fits, >= 6
  unsigned int relaxation_iterations = 5; ///< repulsion steps per round (10 cover 6 % better in a test, at twice the cost)
  unsigned int max_rounds = 4;         ///< detect, insert and relax at most this often (a wide hole fills in rounds)

  void validate() const
  {
    detection.validate();
    if(neighbors < 6) throw Invalid_input("upsampling: neighbors must be at least 6 (the surface fit has 6 coefficients)");
    if(max_rounds < 1) throw Invalid_input("upsampling: max_rounds must be at least 1");
  }
};

/*!
  \ingroup PkgCGALExtRef
  What `upsample_point_set` did.
*/
struct Upsampling_result
{
  bool completed = false;     ///< false when the callback cancelled (nothing was written)
  double spacing = 0;         ///< the target spacing used (local spacings: their median)
  std::size_t inserted = 0;   ///< new points written to the output
  std::size_t rounds = 0;     ///< detection rounds that inserted points
  std::size_t hole_boundary_points = 0; ///< input points on hole boundaries (first round)

  explicit operator bool() const { return completed; }
};

namespace internal {

/// A hash of grid cells of side `cell`: the points already accepted, to keep new samples apart.
class Cell_set
{
public:
  explicit Cell_set(double cell) : m_cell(cell) {}
  using Key = std::tuple<long long, long long, long long>;

  Key key(const Eigen::Vector3d& p) const
  {
    return Key((long long)std::floor(p.x() / m_cell), (long long)std::floor(p.y() / m_cell), (long long)std::floor(p.z() / m_cell));
  }
  /// Whether a point of the set lies within `radius` (at most `cell`) of `p`.
  bool near(const Eigen::Vector3d& p, double radius, const std::vector<Eigen::Vector3d>& points) const
  {
    const Key c = key(p);
    for(long long dx = -1; dx <= 1; ++dx)
      for(long long dy = -1; dy <= 1; ++dy)
        for(long long dz = -1; dz <= 1; ++dz) {
          const auto it = m_members.find(Key(std::get<0>(c) + dx, std::get<1>(c) + dy, std::get<2>(c) + dz));
          if(it == m_members.end()) continue;
          for(int m : it->second)
            if((points[std::size_t(m)] - p).norm() < radius) return true;
        }
    return false;
  }
  void insert(const Eigen::Vector3d& p, int index) { m_members[key(p)].push_back(index); }

private:
  struct Hash
  {
    std::size_t operator()(const Key& k) const
    {
      return std::size_t(std::get<0>(k) * 73856093LL ^ std::get<1>(k) * 19349663LL ^ std::get<2>(k) * 83492791LL);
    }
  };
  double m_cell;
  std::unordered_map<Key, std::vector<int>, Hash> m_members;
};

/// Projects `x` onto the surface fitted to the input samples around it, with a normal oriented like `normal`;
/// updates both. Near the samples, a degree-2 fit to the `k` nearest. Inside a hole, where the nearest sample
/// is `d` > 1.5 h away, the k nearest would lie on the hole's near side and the fit would extrapolate from there;
/// so the fit takes the nearest k / 8 samples in each of 8 directions around `x` (among the about
/// 3 pi (d / h)^2 samples of a disc of radius 2 d), which surround the hole, and a degree-3 surface through
/// them interpolates the rim: a wave's inflection across a hole is then followed, not flattened.
inline void project_onto_surface(const Matrix_n3& samples, const Position_tree& tree, std::size_t k, double h, Eigen::Vector3d& x,
                                 Eigen::Vector3d& normal)
{
  thread_local std::vector<int> near;
  near.clear();
  const Position_tree::Point query(x.x(), x.y(), x.z());
  double nearest2 = 0;
  tree.nearest(query, k, [&](int j, double d2) {
    if(near.empty()) nearest2 = d2;
    near.push_back(j);
  });
  const bool inside_hole = nearest2 > 2.25 * h * h;
  Height_fit fit(x, normal, inside_hole ? 3 : 2);
  if(inside_hole) {
    near.clear();
    const Eigen::Vector3d& u = fit.tangent_u();
    const Eigen::Vector3d& v = fit.tangent_v();
    constexpr double pi = 3.14159265358979323846;
    const std::size_t per_direction = (k + 7) / 8, candidates = k + std::size_t(std::ceil(3 * pi * nearest2 / (h * h)));
    std::size_t taken[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    tree.nearest(query, std::min<std::size_t>(candidates, std::size_t(samples.rows())), [&](int j, double) {
      const Eigen::Vector3d d = samples.row(j).transpose() - x;
      const double turn = std::atan2(d.dot(v), d.dot(u)) / (2 * pi) + 0.5; // in [0, 1]
      std::size_t& in_direction = taken[std::min(7, int(turn * 8))];
      if(in_direction < per_direction) {
        ++in_direction;
        near.push_back(j);
      }
    });
  }
  fit.fit(int(near.size()), [&](int m) { return Eigen::Vector3d(samples.row(near[std::size_t(m)]).transpose()); });
  x = fit.project(x);
  const Eigen::Vector3d n = fit.normal(x);
  normal = n.dot(normal) < 0 ? Eigen::Vector3d(-n) : n;
}

/// Whether `x` continues the surface of its 3 nearest input samples: its offset from each leans at most 30
/// degrees out of that sample's tangent plane. A projection that lands off the surface (a fit misled where the
/// surface folds, or across a thin part) fails this, and the new point is dropped rather than written there.
inline bool continues_surface(const Matrix_n3& samples, const Matrix_n3& normals, const Position_tree& tree, const Eigen::Vector3d& x)
{
  bool along = true;
  tree.nearest(Position_tree::Point(x.x(), x.y(), x.z()), 3, [&](int j, double) {
    const Eigen::Vector3d offset = x - samples.row(j).transpose();
    const double height = std::abs(offset.dot(normals.row(j).transpose()));
    along = along && 3 * height * height <= offset.squaredNorm() - height * height;
  });
  return along;
}

} // namespace internal

namespace internal {

/// Stands for "no spacing map": the spacing comes from the settings or the points themselves.
struct No_spacing_map {};

/// With a spacing map, the points whose local spacing exceeds theirs by this factor are the stretched ones.
constexpr double stretched_spacing = 1.25;

template <typename ConcurrencyTag, typename PointRange, typename IndexRange, typename SpacingMap, typename OutputIterator,
          typename NamedParameters>
Upsampling_result upsample_point_set_impl(const PointRange& points, const IndexRange* region, const SpacingMap& spacing_map,
                                          const Upsampling_settings& settings, OutputIterator output, const NamedParameters& np)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Kernel = typename NP_helper::Geom_traits;
  using namespace internal;
  constexpr const char* who = "upsample_point_set";
  settings.validate();
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  const Spatial_point_cloud cloud = make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
  const std::size_t k = settings.neighbors;
  check_neighbor_count(k, cloud.size(), who);
  if(!has_given_normals<NamedParameters>(points))
    throw Invalid_input(std::string(who) + ": the points need normals (normal_map): hole detection and the new "
                        "samples' surface come from them");
  const Matrix_n3 input_normals = gather_normals(points, NP_helper::get_normal_map(points, np), cloud, who);
  const Position_tree input_tree(cloud.positions, ConcurrencyTag());

  Upsampling_result result;
  // The spacing each input point should have: the caller's (what it had before an edit), the settings', or
  // its local spacing. New points take the one interpolated along their gap.
  std::vector<double> all_spacing;
  if constexpr(std::is_same<SpacingMap, No_spacing_map>::value) {
    all_spacing = spacings<ConcurrencyTag>(cloud.positions, input_tree, settings.detection.spacing, who);
  } else {
    all_spacing.resize(cloud.size());
    const std::vector<int> row_of = cloud.spatial_index();
    std::size_t i = 0;
    for(const auto& item : points) {
      const double h = double(get(spacing_map, item));
      if(!(h > 0) || !std::isfinite(h))
        throw Invalid_input(std::string(who) + ": the spacing of point " + std::to_string(i) + " is not a positive number");
      all_spacing[std::size_t(row_of[i++])] = h;
    }
  }
  result.spacing = median(all_spacing);
  Progress progress(callback);

  // All samples so far: the input first, then the new ones (rows n..).
  const std::size_t n = cloud.size();
  Matrix_n3 all = cloud.positions, all_normals = input_normals;
  std::vector<Eigen::Vector3d> new_points, new_normals;
  // New samples fill quarters; they empty one only by turning a point's principal axes, which is rare: after
  // the first round, only the points that were sparse and the new points are examined again.
  std::vector<int> examine, sparse;
  if(region) examine = rows_of_indices(*region, cloud.spatial_index(), who, "region");
  if constexpr(!std::is_same<SpacingMap, No_spacing_map>::value) {
    // Only what grew sparser than it was: a region point whose local spacing is now more than 25 % above the
    // given one (an edit stretched it). A part that moved rigidly, or a sampling's own irregular gaps, stay.
    const std::vector<double> now = local_spacings<ConcurrencyTag>(cloud.positions, input_tree);
    examine.erase(std::remove_if(examine.begin(), examine.end(),
                                 [&](int row) { return !(now[std::size_t(row)] > stretched_spacing * all_spacing[std::size_t(row)]); }),
                  examine.end());
  }
  // Each sample's empty radius in its spacings (see `empty_radii`): new samples take the one interpolated along
  // their gap, so a hole in a random sampling is filled to its surroundings' own standard.
  std::vector<double> all_empty_factor;
  {
    const std::vector<double> radius = empty_radii<ConcurrencyTag>(
      cloud.positions, input_normals, input_tree, k, all_spacing,
      std::is_same<SpacingMap, No_spacing_map>::value && settings.detection.spacing == 0);
    all_empty_factor.resize(n);
    for(std::size_t i = 0; i < n; ++i) all_empty_factor[i] = radius[i] / all_spacing[i];
  }
  for(std::size_t round = 0; round < settings.max_rounds; ++round) {
    std::vector<double> empty_radius(all.rows());
    for(std::size_t i = 0; i < empty_radius.size(); ++i) empty_radius[i] = all_empty_factor[i] * all_spacing[i];
    progress.stage(double(round) / settings.max_rounds, double(round + 1) / settings.max_rounds);
    if(!progress.report(0.0)) return {};
    const Position_tree tree(all, ConcurrencyTag());
    const std::vector<Hole_gap> gaps = hole_gaps<ConcurrencyTag>(all, all_normals, tree, k, all_spacing, empty_radius,
                                                                 settings.detection.max_hole_size,
                                                                 round == 0 && !region ? nullptr : &examine, sparse);
    if(round == 0) {
      std::vector<char> boundary(n, 0);
      for(const Hole_gap& g : gaps) boundary[std::size_t(g.from)] = 1;
      result.hole_boundary_points = std::size_t(std::count(boundary.begin(), boundary.end(), 1));
    }
    // Candidates along every gap at the target spacing (interpolated between the gap's ends); a candidate is
    // kept only at least half a spacing from every sample and from the candidates kept before it.
    double widest = 0;
    for(const Hole_gap& g : gaps) widest = std::max({widest, all_spacing[std::size_t(g.from)], all_spacing[std::size_t(g.across)]});
    Cell_set kept(0.5 * widest);
    std::vector<Eigen::Vector3d> round_points, round_normals;
    std::vector<double> round_spacing, round_empty_factor;
    for(const Hole_gap& g : gaps) {
      const Eigen::Vector3d a = all.row(g.from).transpose(), b = all.row(g.across).transpose();
      const Eigen::Vector3d na = all_normals.row(g.from).transpose(), nb = all_normals.row(g.across).transpose();
      const double ha = all_spacing[std::size_t(g.from)], hb = all_spacing[std::size_t(g.across)];
      const int steps = int(std::lround((b - a).norm() / (0.5 * (ha + hb))));
      for(int s = 1; s < steps; ++s) {
        const double t = double(s) / steps, h = (1 - t) * ha + t * hb;
        const Eigen::Vector3d x = a + t * (b - a);
        bool crowded = kept.near(x, 0.5 * h, round_points);
        if(!crowded)
          tree.nearest(Position_tree::Point(x.x(), x.y(), x.z()), 1, [&](int, double d2) { crowded = d2 < 0.25 * h * h; });
        if(crowded) continue;
        kept.insert(x, int(round_points.size()));
        round_points.push_back(x);
        Eigen::Vector3d normal = (1 - t) * na + t * nb;
        round_normals.push_back(normal.norm() > 0 ? Eigen::Vector3d(normal.normalized()) : na);
        round_spacing.push_back(h);
        round_empty_factor.push_back((1 - t) * all_empty_factor[std::size_t(g.from)] + t * all_empty_factor[std::size_t(g.across)]);
      }
    }
    if(round_points.empty()) break;
    ++result.rounds;

    // Relaxation (Jacobi steps, so the result does not depend on the thread count): repulsion in the tangent
    // plane from every sample closer than 1.5 spacings (the moving point's), then back onto the surface of the
    // input samples.
    // The samples of earlier rounds stay put: the round's tree serves them; only the new ones get a tree per step.
    Matrix_n3 moving(Eigen::Index(round_points.size()), 3);
    std::vector<char> settled(round_points.size(), 1);
    for(unsigned int iteration = 0; iteration <= settings.relaxation_iterations; ++iteration) {
      for(std::size_t m = 0; m < round_points.size(); ++m) moving.row(Eigen::Index(m)) = round_points[m].transpose();
      const Position_tree moving_tree(moving, ConcurrencyTag());
      std::vector<Eigen::Vector3d> moved(round_points.size()), turned(round_points.size());
      for_range<ConcurrencyTag>(0, round_points.size(), [&](std::size_t m) {
        Eigen::Vector3d x = round_points[m], normal = round_normals[m];
        const double h = round_spacing[m], radius = 1.5 * h;
        if(iteration < settings.relaxation_iterations) {
          Eigen::Vector3d push = Eigen::Vector3d::Zero();
          auto repel = [&push, &x, radius](const Matrix_n3* from) {
            return [&push, &x, radius, from](int j, double d2) {
              const double d = std::sqrt(d2);
              if(d >= radius || !(d > 0)) return;
              const double w = 1 - d / radius;
              push += w * w * (x - from->row(j).transpose()) / d;
            };
          };
          const Position_tree::Point query(x.x(), x.y(), x.z());
          tree.nearest(query, 12, repel(&all));
          moving_tree.nearest(query, std::min<std::size_t>(12, round_points.size()), repel(&moving));
          push = 0.5 * h * (push - push.dot(normal) * normal);
          if(push.norm() > 0.3 * h) push *= 0.3 * h / push.norm();
          x += push;
        }
        project_onto_surface(cloud.positions, input_tree, 2 * k, h, x, normal);
        if(iteration == settings.relaxation_iterations) {
          // A projection onto the surface should be a fixed point: projecting the result again must not move
          // it. Where the fit is unstable (a cubic across a tear, in a frame that tilts with the normal) it
          // does, and the point is dropped rather than written off the surface.
          Eigen::Vector3d again = x, again_normal = normal;
          project_onto_surface(cloud.positions, input_tree, 2 * k, h, again, again_normal);
          settled[m] = (again - x).squaredNorm() <= 0.0625 * h * h; // a quarter spacing
        }
        moved[m] = x;
        turned[m] = normal;
      });
      round_points.swap(moved);
      round_normals.swap(turned);
    }
    std::vector<char> keep(round_points.size());
    for_range<ConcurrencyTag>(0, round_points.size(), [&](std::size_t m) {
      keep[m] = settled[m] && continues_surface(cloud.positions, input_normals, input_tree, round_points[m]);
    });
    std::size_t kept_count = 0;
    for(std::size_t m = 0; m < round_points.size(); ++m)
      if(keep[m]) {
        round_points[kept_count] = round_points[m];
        round_normals[kept_count] = round_normals[m];
        round_empty_factor[kept_count] = round_empty_factor[m];
        round_spacing[kept_count++] = round_spacing[m];
      }
    round_points.resize(kept_count);
    round_normals.resize(kept_count);
    round_spacing.resize(kept_count);
    round_empty_factor.resize(kept_count);
    examine = sparse;
    for(std::size_t m = 0; m < round_points.size(); ++m) examine.push_back(int(n + new_points.size() + m));
    new_points.insert(new_points.end(), round_points.begin(), round_points.end());
    new_normals.insert(new_normals.end(), round_normals.begin(), round_normals.end());
    all_spacing.insert(all_spacing.end(), round_spacing.begin(), round_spacing.end());
    all_empty_factor.insert(all_empty_factor.end(), round_empty_factor.begin(), round_empty_factor.end());
    all.conservativeResize(Eigen::Index(n + new_points.size()), 3);
    all_normals.conservativeResize(all.rows(), 3);
    for(std::size_t m = 0; m < new_points.size(); ++m) {
      all.row(Eigen::Index(n + m)) = new_points[m].transpose();
      all_normals.row(Eigen::Index(n + m)) = new_normals[m].transpose();
    }
  }
  if(!progress.report(1.0)) return {};
  for(std::size_t m = 0; m < new_points.size(); ++m)
    *output++ = std::make_pair(typename Kernel::Point_3(new_points[m].x(), new_points[m].y(), new_points[m].z()),
                               typename Kernel::Vector_3(new_normals[m].x(), new_normals[m].y(), new_normals[m].z()));
  result.inserted = new_points.size();
  result.completed = true;
  return result;
}

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Fills the holes of an oriented point set, such as the stretched parts of an edit (Miao et al. 2007,
  Sect. 6.3, Fig. 9): hole boundaries are found by `detect_sparse_directions`; across each gap, new samples
  are placed at the target spacing on the segment to the sample that reappears beyond it, with interpolated
  normals, and kept only where no sample lies within half a spacing; then they are relaxed by repulsion
  (Pauly et al. 2002): each moves in its tangent plane away from samples closer than 1.5 spacings, and is
  projected back onto a height function fitted to the input samples: of degree 2 to the nearest ones, or, more
  than 1.5 spacings inside a hole, of degree 3 to the nearest ones in 8 directions around it (so the fit spans
  the hole's rim instead of extrapolating from its near side); a new point that a second projection would
  move by more than a quarter spacing (an unstable fit) is dropped, and so is one whose offset from one of its
  3 nearest input samples leans more than 30 degrees out of that sample's tangent plane (a fit misled where
  the surface folds). Detection, insertion and relaxation repeat until no gap is left (at most
  `settings.max_rounds` times). Open borders, with nothing within `max_hole_size` beyond them, never grow.
  Input points are not moved.

  Spacings are local: unless `settings.detection.spacing` sets one everywhere, every point is measured
  against its own local spacing (`compute_local_spacing`), so the sparser parts of an adaptively or randomly
  sampled surface are not filled, and a gap must also be twice as wide as the gaps typical around it (see
  `Sparse_direction_settings`); a new point takes the spacing of its gap's ends.

  \tparam OutputIterator accepts `std::pair<Kernel::Point_3, Kernel::Vector_3>`: each new point with its
          unit normal (the input points are not repeated, so every output point is a new one).

  \param points the points, with normals (`normal_map`, required)
  \param settings target spacing (0: each point's local spacing, see `Sparse_direction_settings`), largest hole,
         neighbours, relaxation
  \param output receives the new points
  \param np `point_map`, `normal_map`, `callback` (false cancels; nothing is then written), `geom_traits`

  An overload takes `region`, the indices of the points whose gaps may be filled (say, the points an edit
  moved): gaps are looked for from those points only, so a sampling's own gaps elsewhere stay as they are.
  Another also takes `spacing_map` (a `ReadablePropertyMap` to `double`): the spacing each point should have,
  such as its local spacing before an edit (`compute_local_spacing` on the unedited points); then gaps are
  looked for only from the region's points whose local spacing now exceeds it by more than 25 % (what the
  edit stretched), and filled at that spacing (doc/upsampling.md, "Local spacing").

  \return the spacing used, the number of new points and rounds; converts to `false` (and nothing is
          written) when the callback cancelled.
  \throws Invalid_input for an empty range, non-finite coordinates, missing, zero or non-finite normals, fewer
          points than neighbours, or invalid settings.
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename OutputIterator,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Upsampling_result upsample_point_set(const PointRange& points, const Upsampling_settings& settings, OutputIterator output,
                                     const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::upsample_point_set_impl<ConcurrencyTag>(points, static_cast<const std::vector<std::size_t>*>(nullptr),
                                                           internal::No_spacing_map(), settings, output, np);
}

/// \cond SKIP_IN_MANUAL
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename OutputIterator, typename NamedParameters = CGAL::parameters::Default_named_parameters>
Upsampling_result upsample_point_set(const PointRange& points, const IndexRange& region, const Upsampling_settings& settings,
                                     OutputIterator output, const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::upsample_point_set_impl<ConcurrencyTag>(points, &region, internal::No_spacing_map(), settings, output, np);
}

template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename SpacingMap, typename OutputIterator, typename NamedParameters = CGAL::parameters::Default_named_parameters>
Upsampling_result upsample_point_set(const PointRange& points, const IndexRange& region, const SpacingMap& spacing_map,
                                     const Upsampling_settings& settings, OutputIterator output,
                                     const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::upsample_point_set_impl<ConcurrencyTag>(points, &region, spacing_map, settings, output, np);
}
/// \endcond

} // namespace CGAL_ext

#endif // CGAL_EXT_UPSAMPLE_POINT_SET_H
