// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_EDIT_SELECTION_H
#define CGAL_EXT_INTERNAL_EDIT_SELECTION_H

// What an edit's user selects and moves: each point's label and each handle group's rigid transform.

#include <CGAL_ext/exceptions.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Labels of an edit's points and sample points: fixed, in the region of interest, or a handle of group
/// `label - first_handle_label`.
enum Edit_label : int { fixed_label = 0, roi_label = 1, first_handle_label = 2 };

inline bool is_handle_label(int label) { return label >= first_handle_label; }
inline std::size_t handle_group_of_label(int label) { return std::size_t(label - first_handle_label); }

/// A rigid transform `p -> rotation p + translation`.
struct Rigid_transform
{
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d operator()(const Eigen::Vector3d& p) const { return rotation * p + translation; }
};

/// The transform `p -> R p + t` of handle `group`, refused unless finite and `R` a rotation (orthonormal within
/// 1e-6, determinant +1).
inline Rigid_transform checked_rigid_transform(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, std::size_t group,
                                               const char* who)
{
  if(!R.allFinite() || !t.allFinite())
    throw Invalid_input(std::string(who) + ": the transform of handle group " + std::to_string(group) + " is not finite");
  const double error = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
  if(!(error < 1e-6) || !(R.determinant() > 0)) {
    std::ostringstream os;
    os << who << ": the matrix of handle group " << group << " is not a rotation (|R^T R - I| = " << error
       << ", det R = " << R.determinant() << "); give a rigid transform without scaling, shear or mirroring";
    throw Invalid_input(os.str());
  }
  return Rigid_transform{Eigen::Quaterniond(R).normalized(), t};
}

/// As above with the rotation as a quaternion, refused unless its norm is within 1e-6 of 1.
inline Rigid_transform checked_rigid_transform(const Eigen::Quaterniond& q, const Eigen::Vector3d& t, std::size_t group,
                                               const char* who)
{
  if(!q.coeffs().allFinite() || !t.allFinite())
    throw Invalid_input(std::string(who) + ": the transform of handle group " + std::to_string(group) + " is not finite");
  if(!(std::abs(q.norm() - 1) < 1e-6)) {
    std::ostringstream os;
    os << who << ": the quaternion of handle group " << group << " has norm " << q.norm()
       << "; a rotation needs a unit quaternion (normalise it)";
    throw Invalid_input(os.str());
  }
  return Rigid_transform{q.normalized(), t};
}

/// An edit's selection: each point's label (rows of the edit's point cloud) and each handle group's transform.
class Edit_selection
{
public:
  std::vector<int> labels;                 ///< per row: an `Edit_label`
  std::vector<Rigid_transform> transforms; ///< per handle group

  /// `n` fixed points and no handle group.
  void clear(std::size_t n)
  {
    labels.assign(n, fixed_label);
    m_in_roi.assign(n, 0);
    transforms.clear();
  }

  void insert_roi(std::size_t row)
  {
    m_in_roi[row] = 1;
    if(labels[row] == fixed_label) labels[row] = roi_label;
  }

  std::size_t create_group()
  {
    transforms.push_back(Rigid_transform());
    return transforms.size() - 1;
  }

  std::size_t checked_group(std::size_t group, const char* who) const
  {
    if(group >= transforms.size())
      throw Invalid_input(std::string(who) + ": there is no handle group " + std::to_string(group) + " (" +
                          std::to_string(transforms.size()) + " groups; create_handle_group() adds one)");
    return group;
  }

  /// Makes `row` (input index `i`) a handle of `group`; refused when it is one of another group.
  void insert_handle(std::size_t group, std::size_t row, std::size_t i, const char* who)
  {
    checked_group(group, who);
    const int label = first_handle_label + int(group);
    if(is_handle_label(labels[row]) && labels[row] != label)
      throw Invalid_input(std::string(who) + ": point #" + std::to_string(i) + " is a handle of group " +
                          std::to_string(handle_group_of_label(labels[row])) + " and cannot also be one of group " +
                          std::to_string(group) + " (handle groups must not overlap)");
    labels[row] = label;
  }

  /// Refuses an empty region, no handle group, a group without a point and a handle outside the region
  /// (`input_index` per row, for the messages).
  void check(const std::vector<int>& input_index, const char* who) const
  {
    if(std::find(m_in_roi.begin(), m_in_roi.end(), 1) == m_in_roi.end())
      throw Invalid_input(std::string(who) + ": the region of interest is empty; insert_roi_points() selects the "
                          "deformable part");
    if(transforms.empty())
      throw Invalid_input(std::string(who) + ": there is no handle group; create_handle_group() and "
                          "insert_handle_points() select what the user moves");
    std::vector<std::size_t> count(transforms.size(), 0);
    for(std::size_t row = 0; row < labels.size(); ++row) {
      if(!is_handle_label(labels[row])) continue;
      ++count[handle_group_of_label(labels[row])];
      if(!m_in_roi[row])
        throw Invalid_input(std::string(who) + ": handle point #" + std::to_string(input_index[row]) +
                            " is not in the region of interest; handles are deformable points (insert it into the "
                            "region too)");
    }
    for(std::size_t g = 0; g < count.size(); ++g)
      if(count[g] == 0) throw Invalid_input(std::string(who) + ": handle group " + std::to_string(g) + " has no point");
  }

private:
  std::vector<char> m_in_roi; // per row: inserted into the region (handles must be too)
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_EDIT_SELECTION_H
