// Writes N points sampled uniformly on a mesh's surface, with their faces' normals (or none: a raw scan), as a
// binary PLY: the large inputs of benchmark/measure_edit_memory.sh and benchmark/measure_raw_scan.sh.
// Usage: sample_scan MESH.off N OUT.ply [--without-normals]
#include "bench_support.h"
#include "program_basics.h"

#include <iostream>

namespace sample_scan {

int run(int argc, char** argv)
{
  const bool without_normals = argc == 5 && std::string(argv[4]) == "--without-normals";
  if(argc != 4 && !without_normals) {
    std::cerr << "usage: sample_scan MESH.off N OUT.ply [--without-normals]\n";
    return 2;
  }
  try {
    const std::size_t n = std::stoull(argv[2]);
    point_detail::Point_cloud cloud = point_detail::sample_mesh(argv[1], n);
    if(without_normals) cloud.normals.clear();
    point_detail::write_file(argv[3], point_detail::ply_bytes(cloud));
  } catch(const std::exception& e) {
    std::cerr << "sample_scan: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

} // namespace sample_scan

// The project links every benchmark from one library (benchmark/CMakeLists.txt); alone, this file is a program.
#ifndef CGAL_EXT_BENCHMARK_LIBRARY
int main(int argc, char** argv) { return sample_scan::run(argc, argv); }
#endif
