// Writes N points sampled uniformly on a mesh's surface, with their faces' normals, as a binary PLY: the
// large inputs of the memory measurement (benchmark/measure_edit_memory.sh).
// Usage: sample_scan MESH.off N OUT.ply
#include "bench_support.h"
#include "cli_support.h"

#include <iostream>

int main(int argc, char** argv)
{
  if(argc != 4) {
    std::cerr << "usage: sample_scan MESH.off N OUT.ply\n";
    return 2;
  }
  try {
    const std::size_t n = std::stoull(argv[2]);
    point_detail::write_file(argv[3], point_detail::ply_bytes(point_detail::sample_mesh(argv[1], n)));
  } catch(const std::exception& e) {
    std::cerr << "sample_scan: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
