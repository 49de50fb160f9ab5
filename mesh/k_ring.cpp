#include "mesh/k_ring.h"

#include <algorithm>

namespace hf {

KRing::KRing(const MeshTopology& topology)
    : topology_(topology), stamp_(topology.vertex_count, 0), depth_(topology.vertex_count, 0) {}

int KRing::collect(int i, int k, std::vector<int>& out) {
  out.clear();
  if (++current_ == 0) {  // the stamp wrapped: forget every earlier visit
    std::fill(stamp_.begin(), stamp_.end(), 0);
    current_ = 1;
  }
  out.push_back(i);
  stamp_[i] = current_;
  depth_[i] = 0;
  // `out` doubles as the breadth-first queue: entries before `head` are expanded.
  for (size_t head = 0; head < out.size(); ++head) {
    const int v = out[head];
    if (depth_[v] >= k) continue;
    for (const int* n = topology_.ring_begin(v); n != topology_.ring_end(v); ++n) {
      if (stamp_[*n] == current_) continue;
      stamp_[*n] = current_;
      depth_[*n] = depth_[v] + 1;
      out.push_back(*n);
    }
  }
  return static_cast<int>(out.size());
}

std::vector<int> multi_source_distance(const MeshTopology& topology, const std::vector<std::uint8_t>& in_set,
                                       int max_k) {
  const int n = topology.vertex_count;
  std::vector<int> dist(n, max_k + 1);
  std::vector<int> queue;
  queue.reserve(n);
  for (int i = 0; i < n && i < static_cast<int>(in_set.size()); ++i)
    if (in_set[i]) {
      dist[i] = 0;
      queue.push_back(i);
    }
  for (size_t head = 0; head < queue.size(); ++head) {
    const int v = queue[head];
    if (dist[v] >= max_k) continue;
    for (const int* nb = topology.ring_begin(v); nb != topology.ring_end(v); ++nb)
      if (dist[*nb] > dist[v] + 1) {
        dist[*nb] = dist[v] + 1;
        queue.push_back(*nb);
      }
  }
  return dist;
}

}  // namespace hf
