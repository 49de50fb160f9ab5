// k-neighbourhoods on a mesh graph: N_i^k is every vertex within k edges of vertex i (i itself included, k = 0
// gives {i}), the neighbourhood the morphological operators and the MLS fit of Kubásková's paper range over.
//
// KRing keeps its scratch (a visit stamp per vertex) between queries so a query costs O(|N_i^k|), not O(V);
// one KRing per thread. multi_source_distance() is the breadth-first search from a set, the single pass that
// dilation and erosion by k-neighbourhoods reduce to.
#pragma once

#include <cstdint>
#include <vector>

#include "mesh/topology.h"

namespace hf {

class KRing {
 public:
  explicit KRing(const MeshTopology& topology);
  // Fills `out` with N_i^k in breadth-first order (i first, then the 1-ring, ...). Returns out.size().
  int collect(int i, int k, std::vector<int>& out);

 private:
  const MeshTopology& topology_;
  std::vector<std::uint32_t> stamp_;
  std::vector<int> depth_;
  std::uint32_t current_ = 0;
};

// Graph distance (edges) from the nearest vertex with in_set[v] != 0, stopped at max_k: entries are 0..max_k,
// or max_k + 1 for everything farther (or unreachable). Size topology.vertex_count; in_set must be that long.
std::vector<int> multi_source_distance(const MeshTopology& topology, const std::vector<std::uint8_t>& in_set,
                                       int max_k);

}  // namespace hf
