// Morphological operators on vertex sets of a mesh, by k-neighbourhoods N^k (Kubásková section 3.2, after Rössl,
// Kobbelt and Seidel):
//   dilate^k(F) = {v_j | exists v_i in F : v_j in N_i^k}      erode^k(F) = {v_j | N_j^k subset of F}
//   open^k = dilate^k o erode^k                               close^k = erode^k o dilate^k
// Graph distance is symmetric, so dilate^k is one breadth-first pass from F to depth k (mesh/k_ring.h) and
// erode^k(F) = complement(dilate^k(complement(F))): O(V + E) for any k. A vertex near the boundary has a smaller
// N^k (only vertices that exist), so erosion does not eat in from an open mesh's border.
//
// A sequence of operators ("open:5,dilate:10") is parsed by parse_morphology() (head/feature_spec.h).
#pragma once

#include <string>
#include <vector>

#include "head/thresholding.h"
#include "mesh/topology.h"

namespace hf::head {

VertexMask dilate(const MeshTopology& topology, const VertexMask& set, int k);
VertexMask erode(const MeshTopology& topology, const VertexMask& set, int k);
VertexMask open(const MeshTopology& topology, const VertexMask& set, int k);
VertexMask close(const MeshTopology& topology, const VertexMask& set, int k);

enum class MorphologyOp { dilate, erode, open, close };
struct MorphologyStep {
  MorphologyOp op = MorphologyOp::dilate;
  int k = 1;
};
const char* morphology_op_name(MorphologyOp op);
VertexMask apply_morphology(const MeshTopology& topology, const VertexMask& set,
                            const std::vector<MorphologyStep>& steps);

}  // namespace hf::head
