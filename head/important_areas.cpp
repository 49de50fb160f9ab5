#include "head/important_areas.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>
#include <unordered_map>

#include "head/mls_curvature.h"
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

// Step 3a: the face box in the head frame, in units of rho (head_frame.h, ~2.2 cm on a human head). The paper
// separates its areas by connectivity alone; on meshes whose vertex density is uneven (scans are densest on the
// face) k-ring morphology grows far into the sparse parts and joins the face to the ears and the cranium, so the
// face is bounded geometrically first: within 3 rho across, 2.5 rho above and 3 rho below the tip and 2.5 rho
// behind it.
std::vector<Area> face_box(const std::vector<Eigen::Vector3d>& ph, const VertexMask& area_mask, double rho) {
  std::vector<Area> label(ph.size(), Area::none);
  for (size_t i = 0; i < ph.size(); ++i) {
    const Eigen::Vector3d& p = ph[i];
    if (area_mask[i] && std::abs(p.x()) <= 3 * rho && p.z() <= 2.5 * rho && p.z() >= -3.0 * rho && p.y() >= -2.5 * rho)
      label[i] = Area::nose;  // placeholder: "the face area", split in step 4
  }
  return label;
}

// Vertices bucketed in a uniform grid (head-frame positions), for ball queries of radius <= the cell.
class Buckets {
 public:
  Buckets(const std::vector<Eigen::Vector3d>& p, const std::vector<int>& ids, double cell) : p_(p), cell_(cell) {
    for (int i : ids) cells_[key(cell_of(p[i]))].push_back(i);
  }
  template <class Fn>
  void ball(const Eigen::Vector3d& c, double r, Fn fn) const {
    const Eigen::Vector3i lo = cell_of(c - Eigen::Vector3d::Constant(r)), hi = cell_of(c + Eigen::Vector3d::Constant(r));
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int z = lo.z(); z <= hi.z(); ++z) {
          const auto it = cells_.find(key({x, y, z}));
          if (it == cells_.end()) continue;
          for (int i : it->second)
            if ((p_[i] - c).squaredNorm() <= r * r) fn(i);
        }
  }

 private:
  Eigen::Vector3i cell_of(const Eigen::Vector3d& p) const { return (p / cell_).array().floor().cast<int>(); }
  static std::uint64_t key(const Eigen::Vector3i& c) {
    return (static_cast<std::uint64_t>(c.x() & 0x1fffff) << 42) | (static_cast<std::uint64_t>(c.y() & 0x1fffff) << 21) |
           static_cast<std::uint64_t>(c.z() & 0x1fffff);
  }
  const std::vector<Eigen::Vector3d>& p_;
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

// Step 3b: the ears. The paper finds them as area-mask pieces already apart from the face; on real heads the
// pieces beside the head are as often a crown (Nefertiti), hair (Igea) or a temple (Max Planck: the ears lie below
// any fixed box in its frame) as an ear. What sets an ear apart is that it is a flap: the pinna is a thin sheet,
// so a vertex on it has, within r = max(0.4 rho, 2.5 edges) behind it (along -n), surface facing the other way
// (the sheet's other side); a skull, a crown or hair is locally one sheet. Per side (|x| >= 2 rho, behind the face
// y < -1.5 rho, -4 rho <= z <= 2.5 rho around the tip; border vertices excluded: an open cut is a sheet edge too),
// the thin-sheet vertices are clustered (single linkage within r) and the ear is the largest cluster that spans
// at least kEarMinSpanRho rho (an ear is ~6 cm = 2.7 rho tall) and whose centre lies where an ear can
// (ear_implausible: a TSDF fuses fins at a head's silhouette behind and above it, flaps as much as a pinna, and on
// fused heads those were the largest pieces: 24-38 voxels from the source's ear); else the side has no ear
// (covered by hair, not scanned, only a fin) and says so, naming the rejected flap. The ear area is the area mask
// and the flap within 1.5 rho of the flap's centroid, connected to the flap.
// kEarMinSpanRho: chosen on the four source heads of ../shared/data/head_meshes (the ears' flaps span 1.78-2.79
// rho, Igea's hair-covered sides hold no flap vertex at all); on heads fused at 2-4 mm voxels the TSDF thickens
// the pinna and its flaps span 0.36-0.95 rho, so fused ears are reported absent (bench/results/head.md: at 0.4
// rho one fused ear landed on another piece, 17.6 voxels off).
constexpr double kEarMinSpanRho = 1.0;

}  // namespace

// The bounds of important_areas.h's ear_implausible, in rho in the head frame; chosen on the four source heads
// (the ears that are found: libigl's centres at y -6.3 / -5.8, z -0.9 / -2.6; Max Planck's y -6.7, z -3.4;
// Nefertiti's y -3.6, z -1.8; Igea has none), reported on the fused heads (bench/results/head.md).
constexpr double kEarMaxBehindRho = 7.5;
constexpr double kEarMaxAboveRho = 0.5;

std::string ear_implausible(const Eigen::Vector3d& c) {
  std::string why;
  char buf[160];
  if (c.y() < -kEarMaxBehindRho) {
    std::snprintf(buf, sizeof buf, "%.1f rho behind the nose tip, an ear's centre lies at most %.1f (behind it is the back of the head)",
                  -c.y(), kEarMaxBehindRho);
    why = buf;
  }
  if (c.z() > kEarMaxAboveRho) {
    std::snprintf(buf, sizeof buf, "%.1f rho above the nose tip, an ear's centre lies at most %.1f (above it is the cranium)",
                  c.z(), kEarMaxAboveRho);
    why += (why.empty() ? "" : "; ") + std::string(buf);
  }
  return why;
}

namespace {

void find_ears(const std::vector<Eigen::Vector3d>& ph, const std::vector<Eigen::Vector3d>& nh,
               const MeshTopology& topology, const VertexMask& area_mask, double rho, std::vector<Area>& label,
               std::array<std::string, kAreaCount>& note, std::array<double, 2>& span_rho,
               std::array<Eigen::Vector3d, 2>& ear_centre_rho) {
  const int n = static_cast<int>(ph.size());
  const double r = std::max(0.4 * rho, 2.5);
  auto in_region = [&](int i) {
    const Eigen::Vector3d& p = ph[i];
    return !topology.is_isolated(i) && !topology.boundary_vertex[i] && std::abs(p.x()) >= 2.0 * rho &&
           p.y() < -1.5 * rho && p.z() >= -4.0 * rho && p.z() <= 2.5 * rho;
  };
  std::vector<int> region;
  for (int i = 0; i < n; ++i)
    if (in_region(i)) region.push_back(i);
  const Buckets buckets(ph, region, r);
  std::vector<int> thin;
  for (int i : region) {
    if (!(nh[i].squaredNorm() > 0.25)) continue;
    bool flap = false;
    buckets.ball(ph[i], r, [&](int j) {
      if (!flap && (ph[j] - ph[i]).dot(nh[i]) < -0.2 * r && nh[j].dot(nh[i]) < -0.3) flap = true;
    });
    if (flap) thin.push_back(i);
  }
  // Single-linkage clusters of the flap vertices (union-find over pairs within r).
  std::unordered_map<int, int> parent;
  for (int i : thin) parent[i] = i;
  const std::function<int(int)> root = [&](int i) { return parent[i] == i ? i : parent[i] = root(parent[i]); };
  const Buckets thin_buckets(ph, thin, r);
  for (int i : thin)
    thin_buckets.ball(ph[i], r, [&](int j) {
      if ((ph[i].x() > 0) == (ph[j].x() > 0)) parent[root(i)] = root(j);
    });
  std::unordered_map<int, std::vector<int>> clusters;
  for (int i : thin) clusters[root(i)].push_back(i);
  for (int side = 0; side < 2; ++side) {
    const Area ear = side == 0 ? Area::ear_right : Area::ear_left;
    // This side's pieces, largest first (ties by vertex index: the order does not depend on the hash map's).
    std::vector<const std::vector<int>*> pieces;
    for (const auto& [id, members] : clusters)
      if ((ph[members.front()].x() > 0) == (side == 0)) pieces.push_back(&members);
    std::sort(pieces.begin(), pieces.end(), [](const std::vector<int>* a, const std::vector<int>* b) {
      return a->size() != b->size() ? a->size() > b->size() : a->front() < b->front();
    });
    const std::vector<int>* best = nullptr;
    double span = 0, largest_span = 0;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    std::string rejected;  // the largest flap found where no ear can be, for the note
    for (const std::vector<int>* piece : pieces) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int i : *piece) c += ph[i];
      c /= static_cast<double>(piece->size());
      double s = 0;
      for (int i : *piece) s = std::max(s, 2.0 * (ph[i] - c).norm());
      if (piece == pieces.front()) largest_span = s;
      if (s < kEarMinSpanRho * rho) continue;
      const std::string why = ear_implausible(c / rho);
      if (!why.empty()) {
        if (rejected.empty()) {
          char buf[480];
          std::snprintf(buf, sizeof buf, "an ear-like flap spanning %.2f rho centred at x %+.2f y %+.2f z %+.2f rho was rejected: %s",
                        s / rho, c.x() / rho, c.y() / rho, c.z() / rho, why.c_str());
          rejected = buf;
        }
        continue;
      }
      best = piece;
      span = s;
      centroid = c;
      break;
    }
    span_rho[side] = (best ? span : largest_span) / rho;
    ear_centre_rho[side] = best ? Eigen::Vector3d(centroid / rho) : Eigen::Vector3d::Zero();
    if (!best) {
      char buf[640];
      if (!rejected.empty())
        std::snprintf(buf, sizeof buf, "no plausible ear on the %s side of the head (%s); its control points are absent",
                      side == 0 ? "right" : "left", rejected.c_str());
      else
        std::snprintf(buf, sizeof buf,
                      "no ear-like flap on the %s side of the head (largest thin-sheet piece spans %.2f rho, an ear "
                      "needs %.1f): hair, a missing scan, or a pinna fused too thick to be a sheet; its control points are "
                      "absent",
                      side == 0 ? "right" : "left", largest_span / rho, kEarMinSpanRho);
      note[static_cast<int>(ear)] = buf;
      continue;
    }
    VertexMask seed(n, 0);
    for (int i : *best) seed[i] = 1;
    std::vector<int> stack(best->begin(), best->end());
    for (int i : stack) label[i] = ear;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (const int* w = topology.ring_begin(v); w != topology.ring_end(v); ++w)
        if (label[*w] == Area::none && (area_mask[*w] || seed[*w]) && (ph[*w] - centroid).norm() <= 1.5 * rho &&
            (ph[*w].x() > 0) == (side == 0)) {
          label[*w] = ear;
          stack.push_back(*w);
        }
    }
  }
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
  out.k = options.k > 0 ? options.k
          : options.k_rho > 0 && frame.mean_edge_length > 0
              ? std::max(1, static_cast<int>(std::lround(options.k_rho * frame.cap_scale / frame.mean_edge_length)))
              : paper_k_for_vertex_count(n);
  std::vector<MorphologyStep> steps = {
      {MorphologyOp::close, out.k}, {MorphologyOp::open, out.k}, {MorphologyOp::close, out.k}};
  if (options.final_dilation) steps.push_back({MorphologyOp::dilate, out.k});
  out.area_mask = apply_morphology(topology, out.features, steps);
  // Step 3.
  std::vector<Eigen::Vector3d> ph(n);
  for (int i = 0; i < n; ++i) ph[i] = frame.to_head(mesh.vertices[i]);
  const double rho = frame.cap_scale * frame.scale;
  std::vector<Area> coarse = face_box(ph, out.area_mask, rho);
  {
    const std::vector<Eigen::Vector3f> normals = mls_vertex_normals(mesh, topology);
    std::vector<Eigen::Vector3d> nh(n);
    for (int i = 0; i < n; ++i) nh[i] = frame.R_head_input * normals[i].cast<double>();
    find_ears(ph, nh, topology, out.area_mask, rho, coarse, out.note, out.ear_flap_span_rho, out.ear_centre_rho);
  }
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
  const double band = 1.5;  // head units are mean edge lengths: the profile band of head_frame.h
  {
    double y_min = 0;
    for (int i = 0; i < n; ++i)
      if (std::abs(ph[i].x()) < band && ph[i].z() > 0 && ph[i].z() <= 2.5 * rho && ph[i].norm() < 3.0 * rho)
        y_min = std::min(y_min, ph[i].y());
    double z_sum = 0;
    int count = 0;
    for (int i = 0; i < n; ++i)
      if (std::abs(ph[i].x()) < band && ph[i].z() > 0 && ph[i].z() <= 2.5 * rho && ph[i].norm() < 3.0 * rho &&
          ph[i].y() <= y_min + 0.05 * rho) {
        z_sum += ph[i].z();
        ++count;
      }
    out.z_root = count > 0 ? z_sum / count : 0;
    if (options.root_fraction > 0 && count > 0) out.z_eyes_nose = options.root_fraction * out.z_root;
  }
  // Method 2's nose box: the root is the deepest profile vertex between the tip and the eyes/nose boundary.
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
  out.y_root = y_root;
  out.nose_half_width = nose_half_width;
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
  // The eyes' fallback band. Step 2's opening removes every feature narrower than ~2k rings; the paper's k by
  // vertex count assumes its models' density, and on a decimated head (Max Planck: 5272 vertices, 7 mm edges,
  // k = 5 is 3.5 cm) the eyes' features are that narrow, at any k >= 2 (bench/results/head.md). When an eye side
  // keeps less than a disc of radius rho / 2 would hold, both eyes are taken as the face box's band above the
  // eyes/nose boundary instead (the eye sockets: up to 2 rho above the tip, 2 rho to each side, beside the bridge,
  // within the face box's 2.5 rho behind the tip), and the area-specific threshold (section 4.5, MLS k_max at its
  // average over the area) finds the features inside it.
  const double disc = std::numbers::pi * 0.25 * rho * rho / (0.5 * std::sqrt(3.0));  // vertices per rho/2 disc
  const int eyes[2] = {static_cast<int>(Area::eye_right), static_cast<int>(Area::eye_left)};
  if (out.counts[eyes[0]] < disc || out.counts[eyes[1]] < disc) {
    const double z_lo = std::max(out.z_eyes_nose, 0.25 * rho), x_lo = std::max(0.5 * nose_half_width, 0.25 * rho);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d& p = ph[i];
      const bool eye_band = !topology.is_isolated(i) && p.z() > z_lo && p.z() <= 2.0 * rho &&
                            std::abs(p.x()) >= x_lo && std::abs(p.x()) <= 2.5 * rho && p.y() >= -3.5 * rho;
      if (out.label[i] == Area::eye_right || out.label[i] == Area::eye_left) out.label[i] = Area::none;
      if (eye_band && out.label[i] == Area::none) out.label[i] = p.x() > 0 ? Area::eye_right : Area::eye_left;
    }
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "eye areas from the band above the eyes/nose boundary: the morphology (k = %d) left %d / %d "
                  "vertices, under the %.0f of a rho/2 disc",
                  out.k, out.counts[eyes[0]], out.counts[eyes[1]], disc);
    out.note[eyes[0]] = out.note[eyes[1]] = buf;
    out.counts = {};
    for (int i = 0; i < n; ++i) ++out.counts[static_cast<int>(out.label[i])];
  }
  return out;
}

}  // namespace hf::head
