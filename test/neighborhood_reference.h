// The neighbourhood rule by brute force (doc/design.md, "One neighbourhood rule"): the reference the tests of
// internal/Neighbor_graph.h and the fuzz target fuzz_neighborhoods compare the kd-tree's answers with.
#ifndef CGAL_EXT_TEST_NEIGHBORHOOD_REFERENCE_H
#define CGAL_EXT_TEST_NEIGHBORHOOD_REFERENCE_H

#include <CGAL_ext/internal/Neighbor_graph.h>

#include <algorithm>
#include <vector>

/// Every other row within the distance of row i's k-th nearest other row, ranked (squared distance, row).
inline std::vector<int> brute_force_ball(const CGAL_ext::internal::Matrix_n3& points, std::size_t i, std::size_t k)
{
  using CGAL_ext::internal::Ranked_row;
  std::vector<Ranked_row> all;
  for(Eigen::Index j = 0; j < points.rows(); ++j)
    if(j != Eigen::Index(i))
      all.emplace_back(CGAL_ext::internal::squared_distance(points(Eigen::Index(i), 0), points(Eigen::Index(i), 1),
                                                            points(Eigen::Index(i), 2), points(j, 0), points(j, 1),
                                                            points(j, 2)),
                       int(j));
  std::sort(all.begin(), all.end());
  std::vector<int> ball;
  for(const Ranked_row& entry : all)
    if(entry.first <= all[k - 1].first) ball.push_back(entry.second);
  return ball;
}

#endif
