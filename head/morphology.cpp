#include "head/morphology.h"

#include "mesh/k_ring.h"

namespace hf::head {

VertexMask dilate(const MeshTopology& topology, const VertexMask& set, int k) {
  if (k <= 0) return set;
  const std::vector<int> dist = multi_source_distance(topology, set, k);
  VertexMask out(set.size(), 0);
  for (size_t i = 0; i < set.size(); ++i) out[i] = dist[i] <= k;
  return out;
}

VertexMask erode(const MeshTopology& topology, const VertexMask& set, int k) {
  VertexMask complement(set.size());
  for (size_t i = 0; i < set.size(); ++i) complement[i] = !set[i];
  VertexMask out = dilate(topology, complement, k);
  for (auto& v : out) v = !v;
  return out;
}

VertexMask open(const MeshTopology& topology, const VertexMask& set, int k) {
  return dilate(topology, erode(topology, set, k), k);
}

VertexMask close(const MeshTopology& topology, const VertexMask& set, int k) {
  return erode(topology, dilate(topology, set, k), k);
}

const char* morphology_op_name(MorphologyOp op) {
  switch (op) {
    case MorphologyOp::dilate: return "dilate";
    case MorphologyOp::erode: return "erode";
    case MorphologyOp::open: return "open";
    case MorphologyOp::close: return "close";
  }
  return "?";
}

VertexMask apply_morphology(const MeshTopology& topology, const VertexMask& set,
                            const std::vector<MorphologyStep>& steps) {
  VertexMask current = set;
  for (const MorphologyStep& s : steps) {
    switch (s.op) {
      case MorphologyOp::dilate: current = dilate(topology, current, s.k); break;
      case MorphologyOp::erode: current = erode(topology, current, s.k); break;
      case MorphologyOp::open: current = open(topology, current, s.k); break;
      case MorphologyOp::close: current = close(topology, current, s.k); break;
    }
  }
  return current;
}

}  // namespace hf::head
