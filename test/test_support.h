// Shared helpers of the test suites.
#ifndef CGAL_EXT_TEST_SUPPORT_H
#define CGAL_EXT_TEST_SUPPORT_H

#include <CGAL_ext/Detail_filter.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <string>
#include <vector>

// Built with AddressSanitizer: GCC says so with __SANITIZE_ADDRESS__, clang 14 through __has_feature.
#if defined(__SANITIZE_ADDRESS__)
#define TEST_WITH_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TEST_WITH_ADDRESS_SANITIZER 1
#endif
#endif
#ifndef TEST_WITH_ADDRESS_SANITIZER
#define TEST_WITH_ADDRESS_SANITIZER 0
#endif

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;

const CGAL_ext::Detail_order all_orders[] = {CGAL_ext::Detail_order::linear, CGAL_ext::Detail_order::quadric,
                                             CGAL_ext::Detail_order::cubic};

/// The message of the `Exception` that `f` throws ("" and a test failure if it throws nothing or another type).
template <typename Exception>
std::string thrown_message(const std::function<void()>& f)
{
  try {
    f();
  } catch(const Exception& e) {
    return e.what();
  } catch(const std::exception& e) {
    ADD_FAILURE() << "threw another exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << "threw nothing";
  return "";
}

/// 0, 1, ..., v.size() - 1: the keys of index-keyed property maps over v (`CGAL::make_property_map(v)`).
template <typename T>
std::vector<std::size_t> index_range_of(const std::vector<T>& v)
{
  std::vector<std::size_t> keys(v.size());
  std::iota(keys.begin(), keys.end(), std::size_t(0));
  return keys;
}

/// Index of the cube face (0..5: axis * 2 + positive side) a normal points to.
inline int face_of(const Vector& n)
{
  int axis = 0;
  for(int a = 1; a < 3; ++a)
    if(std::abs(n[a]) > std::abs(n[axis])) axis = a;
  return 2 * axis + (n[axis] > 0 ? 1 : 0);
}

inline double pearson(const std::vector<double>& a, const std::vector<double>& b)
{
  const double n = double(a.size());
  const double ma = std::accumulate(a.begin(), a.end(), 0.0) / n, mb = std::accumulate(b.begin(), b.end(), 0.0) / n;
  double sab = 0, saa = 0, sbb = 0;
  for(std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

/// The largest distance between corresponding points of two equally long ranges.
inline double max_distance(const std::vector<Point>& a, const std::vector<Point>& b)
{
  double d = 0;
  for(std::size_t i = 0; i < a.size(); ++i) d = std::max(d, std::sqrt(CGAL::squared_distance(a[i], b[i])));
  return d;
}

#endif
