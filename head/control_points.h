// Control points on the detected features (Kubásková section 3.4), each a mesh vertex. Directions are those of
// the head frame (head_frame.h: x towards the subject's right, y towards the nose, z up); the placement of the
// points the paper leaves to its figures (and to the thesis [1], not among the seeds) is ours, stated here:
//   eye (each side, 10): the corners (extreme x of the eye's features); at 20, 40, 60, 80 % of the way from one
//     corner to the other, the upper (max z) and lower (min z) feature vertex;
//   lips (14): the corners (extreme x); at 25, 50, 75 % from the left corner: the upper border (max z of the
//     features), the middle of the upper lip (the area vertex halfway in z between the upper border and the mouth
//     line, the deepest -- min y -- area vertex between the borders), the middle of the lower lip likewise, and
//     the lower border (min z): 3 x 4 = 12 besides the corners;
//   ear (each side, 5): v1, v2 the extreme z; v3, v4 the vertex with minimal y a quarter of the way from v1 (and
//     from v2) towards the other; v5 the area vertex nearest the area's centroid;
//   nose (8): tip (the head frame's), root (deepest profile vertex between the tip and the eyes/nose boundary),
//     the profile vertex halfway between them, the alae (extreme x of the nose's features), the subnasale
//     (deepest profile vertex between the tip and the nose/lips boundary) and each nostril (the nose feature
//     below the tip nearest the midpoint of that side's ala and the subnasale).
// Eyes and lips use the largest connected piece of their features (stray vertices would set the extremes); the
// lips the largest piece that reaches within 0.25 rho of the symmetry plane (the mouth straddles it; a speckle
// patch on a fused head's cheek outgrew the lips once, bench/results/head.md), the largest piece when none does.
// "Within a band": candidates within max(1.5, 5 % of the corner distance) mean edge lengths of the target x (or
// z), widened up to 8x when empty. A point whose area (or features) is empty is not reported; the caller lists it
// as missing.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "head/head_frame.h"
#include "head/important_areas.h"
#include "head/thresholding.h"
#include "io/mesh.h"

namespace hf::head {

struct ControlPoint {
  std::string name;  // e.g. "eye_right.corner_outer", "lips.upper_50", "nose.tip"
  int vertex = -1;
  Eigen::Vector3f position;  // input frame (the mesh's own)
};

std::vector<ControlPoint> find_control_points(const TriangleMesh& mesh, const MeshTopology& topology,
                                              const HeadFrame& frame, const ImportantAreas& areas,
                                              const VertexMask& features);

// The names find_control_points can report, in its order (10 + 10 + 14 + 5 + 5 + 8 = 52).
std::vector<std::string> control_point_names();

}  // namespace hf::head
