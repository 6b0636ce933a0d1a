// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// The Botsch-Sorkine cactus edit, ours against CGAL's mesh ARAP (Surface_mesh_deformation): for the editing
// benchmark and the convergence test (test/test_cactus_arap.cpp). Compiled once, in the benchmark library, so
// that the test does not compile CGAL's deformation again.
#ifndef CGAL_EXT_BENCHMARK_CACTUS_COMPARISON_H
#define CGAL_EXT_BENCHMARK_CACTUS_COMPARISON_H

#include <CGAL_ext/Detail_preserving_deformation_settings.h>

#include <filesystem>
#include <memory>

namespace bench_editing {

struct Cactus;

/// CGAL's two mesh ARAP energies (`CGAL::SRE_ARAP`, `CGAL::ORIGINAL_ARAP`).
enum class Cgal_arap
{
  sre,
  original
};

/// The cactus (620 vertices) with its .sel region and .def motion, scaled to a fraction of that motion.
class Cactus_comparison
{
public:
  /// Reads DATA/meshes/cactus.off, DATA/deformation/cactus.sel and .def; throws std::runtime_error when one is
  /// missing (scripts/fetch_data.sh fetches them).
  explicit Cactus_comparison(const std::filesystem::path& data);
  ~Cactus_comparison();

  /// The handle's rotation angle at `fraction` of the .def motion, in degrees.
  double degrees(double fraction) const;
  /// The edit's settings as the benchmark runs it (every point its own sample point).
  CGAL_ext::Detail_preserving_deformation_settings settings() const;
  /// The Hausdorff distance, over the bounding-box diagonal, from our edit with `settings` at `fraction` of the
  /// motion (one drag) to CGAL's `kind` after `iterations` (CGAL's result computed once per argument set).
  double distance_to_cgal(double fraction, const CGAL_ext::Detail_preserving_deformation_settings& settings,
                          Cgal_arap kind, unsigned iterations) const;

private:
  std::unique_ptr<Cactus> m_cactus;
};

} // namespace bench_editing

#endif // CGAL_EXT_BENCHMARK_CACTUS_COMPARISON_H
