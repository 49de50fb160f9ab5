#include "head/important_areas.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "head/morphology.h"

namespace hf::head {

const char* area_name(Area a) {
  switch (a) {
    case Area::none: return "none";
    case Area::eye_right: return "eye_right";
    case Area::eye_left: return "eye_left";
    case Area::nose: return "nose";
    case Area::lips: return "lips";
    case Area::ear_right: return "ear_right";
    case Area::ear_left: return "ear_left";
  }
  return "?";
}

int paper_k_for_vertex_count(int n) { return n <= 13000 ? 5 : (n <= 20000 ? 10 : 15); }

namespace {

// Connected components of `mask` over mesh edges; -1 outside the mask.
std::vector<int> components(const MeshTopology& topology, const VertexMask& mask, int* count) {
  std::vector<int> comp(topology.vertex_count, -1);
  std::vector<int> stack;
  int c = 0;
  for (int s = 0; s < topology.vertex_count; ++s) {
    if (!mask[s] || comp[s] >= 0) continue;
    comp[s] = c;
    stack.assign(1, s);
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (const int* n = topology.ring_begin(v); n != topology.ring_end(v); ++n)
        if (mask[*n] && comp[*n] < 0) {
          comp[*n] = c;
          stack.push_back(*n);
        }
    }
    ++c;
  }
  *count = c;
  return comp;
}

// Step 3: the face box and the ear boxes in the head frame, in units of rho (head_frame.h, ~2.2 cm on a human
// head). The paper separates its areas by connectivity alone; on meshes whose vertex density is uneven (scans are
// densest on the face) k-ring morphology grows far into the sparse parts and joins the face to the ears and the
// cranium, so the areas are bounded geometrically first: the face within 3 rho across, 2.5 rho above and
// 3 rho below the tip and 2.5 rho behind it; an ear beyond 60 % of the head's half-width at the tip's height,
// more than 2.5 rho behind the tip, within 2.5 rho of its height (the largest connected piece on each side,
// cut to 1.5 rho around its features' centroid).
std::vector<Area> classify(const std::vector<Eigen::Vector3d>& ph, const MeshTopology& topology,
                           const VertexMask& area_mask, const VertexMask& features, const HeadFrame& frame) {
  const int n = static_cast<int>(ph.size());
  const double rho = frame.cap_scale * frame.scale;
  double half_width = 0;
  for (int i = 0; i < n; ++i)
    if (std::abs(ph[i].z()) < rho && !topology.is_isolated(i)) half_width = std::max(half_width, std::abs(ph[i].x()));
  std::vector<Area> label(n, Area::none);
  VertexMask ear_mask(n, 0);
  for (int i = 0; i < n; ++i) {
    if (!area_mask[i]) continue;
    const Eigen::Vector3d& p = ph[i];
    if (std::abs(p.x()) <= 3 * rho && p.z() <= 2.5 * rho && p.z() >= -3.0 * rho && p.y() >= -2.5 * rho)
      label[i] = Area::nose;  // placeholder: "the face area", split in step 4
    else if (std::abs(p.x()) >= 0.6 * half_width && p.y() < -2.5 * rho && std::abs(p.z()) <= 2.5 * rho)
      ear_mask[i] = 1;
  }
  int count = 0;
  const std::vector<int> comp = components(topology, ear_mask, &count);
  std::vector<int> size(count, 0);
  std::vector<double> side_x(count, 0);
  for (int i = 0; i < n; ++i)
    if (comp[i] >= 0) {
      ++size[comp[i]];
      side_x[comp[i]] += ph[i].x();
    }
  int ear[2] = {-1, -1};
  for (int c = 0; c < count; ++c) {
    const int side = side_x[c] > 0 ? 0 : 1;
    if (ear[side] < 0 || size[c] > size[ear[side]]) ear[side] = c;
  }
  // The ear itself: the piece's vertices within 1.5 rho (an ear is ~6 cm tall) of its features' centroid.
  for (int side = 0; side < 2; ++side) {
    if (ear[side] < 0) continue;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    int count_f = 0;
    for (int i = 0; i < n; ++i)
      if (comp[i] == ear[side] && features[i]) {
        centroid += ph[i];
        ++count_f;
      }
    if (count_f == 0) continue;
    centroid /= count_f;
    for (int i = 0; i < n; ++i)
      if (comp[i] == ear[side] && (ph[i] - centroid).norm() <= 1.5 * rho)
        label[i] = side == 0 ? Area::ear_right : Area::ear_left;
  }
  return label;
}

}  // namespace

ImportantAreas find_important_areas(const TriangleMesh& mesh, const MeshTopology& topology,
                                    const VertexCurvatures& discrete, const HeadFrame& frame,
                                    const ImportantAreaOptions& options) {
  const int n = topology.vertex_count;
  ImportantAreas out;
  out.label.assign(n, Area::none);
  // Step 1.
  out.threshold = masked_mean(discrete.mean, discrete.valid);
  out.features = threshold(discrete.mean, discrete.valid, static_cast<float>(out.threshold),
                           std::numeric_limits<float>::max());
  // Step 2.
  out.k = options.k > 0 ? options.k : paper_k_for_vertex_count(n);
  std::vector<MorphologyStep> steps = {
      {MorphologyOp::close, out.k}, {MorphologyOp::open, out.k}, {MorphologyOp::close, out.k}};
  if (options.final_dilation) steps.push_back({MorphologyOp::dilate, out.k});
  out.area_mask = apply_morphology(topology, out.features, steps);
  // Step 3.
  std::vector<Eigen::Vector3d> ph(n);
  for (int i = 0; i < n; ++i) ph[i] = frame.to_head(mesh.vertices[i]);
  const std::vector<Area> coarse = classify(ph, topology, out.area_mask, out.features, frame);
  // Step 4 on the face area.
  // The widest point is taken among step 1's features above the tip (the outer eye corners on the paper's
  // heads): the face area itself reaches the face box's sides.
  double face_max_abs_x = -1, z_at_widest = 0, z_min = 0;
  for (int i = 0; i < n; ++i) {
    if (coarse[i] != Area::nose) continue;
    if (out.features[i] && ph[i].z() > 0 && std::abs(ph[i].x()) > face_max_abs_x) {
      face_max_abs_x = std::abs(ph[i].x());
      z_at_widest = ph[i].z();
    }
    z_min = std::min(z_min, ph[i].z());
  }
  out.z_eyes_nose = 0.5 * z_at_widest;   // halfway between the widest point and the tip (z = 0)
  out.z_nose_lips = (2.0 / 3.0) * z_min;  // two thirds of the way from the tip to the lowest point
  // Method 2's nose box: the root is the deepest profile vertex between the tip and the eyes/nose boundary.
  const double band = 1.5;  // head units are mean edge lengths: the profile band of head_frame.h
  const double rho = frame.cap_scale * frame.scale;
  double y_root = 0;
  for (int i = 0; i < n; ++i)
    if (std::abs(ph[i].x()) < band && ph[i].z() > 0 && ph[i].z() <= out.z_eyes_nose && ph[i].y() < y_root &&
        ph[i].norm() < 3.0 * rho)
      y_root = ph[i].y();
  double nose_half_width = 0;
  for (int i = 0; i < n; ++i)
    if (coarse[i] == Area::nose && ph[i].z() > out.z_nose_lips && ph[i].z() <= out.z_eyes_nose &&
        ph[i].y() >= y_root && std::abs(ph[i].x()) < 1.5 * rho)
      nose_half_width = std::max(nose_half_width, std::abs(ph[i].x()));
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = ph[i];
    if (options.separation_method == 2 && p.z() > out.z_nose_lips && p.z() <= out.z_eyes_nose && p.y() >= y_root &&
        std::abs(p.x()) <= nose_half_width && !topology.is_isolated(i)) {
      out.label[i] = Area::nose;
      continue;
    }
    if (coarse[i] == Area::nose) {
      if (p.z() > out.z_eyes_nose) {
        // The bridge between the eyes belongs to neither eye: its features would pass for inner corners.
        if (std::abs(p.x()) >= 0.5 * nose_half_width) out.label[i] = p.x() > 0 ? Area::eye_right : Area::eye_left;
      }
      else if (p.z() > out.z_nose_lips)
        out.label[i] = options.separation_method == 2 ? Area::none : Area::nose;
      else
        out.label[i] = Area::lips;
    } else {
      out.label[i] = coarse[i];
    }
  }
  for (int i = 0; i < n; ++i) ++out.counts[static_cast<int>(out.label[i])];
  return out;
}

}  // namespace hf::head
