#include "head/control_points.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace hf::head {
namespace {

using Select = std::function<double(const Eigen::Vector3d&)>;

struct Context {
  const TriangleMesh& mesh;
  const MeshTopology& topology;
  const HeadFrame& frame;
  std::vector<Eigen::Vector3d> ph;  // head-frame positions
  std::vector<ControlPoint> out;

  void add(const std::string& name, int v) {
    if (v >= 0) out.push_back({name, v, mesh.vertices[v]});
  }
  // The vertex of `set` maximising score; -1 for an empty set.
  int best(const std::vector<int>& set, const Select& score) const {
    int arg = -1;
    double top = -std::numeric_limits<double>::infinity();
    for (int v : set) {
      const double s = score(ph[v]);
      if (s > top) {
        top = s;
        arg = v;
      }
    }
    return arg;
  }
  // Members of `set` whose coordinate `axis` lies within tol of target, the band widened until non-empty.
  std::vector<int> band(const std::vector<int>& set, int axis, double target, double tol) const {
    std::vector<int> hits;
    for (int widen = 0; widen < 4 && hits.empty(); ++widen, tol *= 2)
      for (int v : set)
        if (std::abs(ph[v][axis] - target) <= tol) hits.push_back(v);
    return hits;
  }
};

std::vector<int> members(const ImportantAreas& areas, Area a, const VertexMask* features) {
  std::vector<int> set;
  for (size_t i = 0; i < areas.label.size(); ++i)
    if (areas.label[i] == a && (!features || (*features)[i])) set.push_back(static_cast<int>(i));
  return set;
}

// The features of area a, or the whole area when it has none. With `largest_piece`, only the largest connected
// piece of the features: stray feature vertices (skin texture, scan noise) would otherwise set the extremes.
// With `eligible`, the largest piece among those holding a vertex it accepts (the lips: a piece that reaches the
// symmetry plane), else the largest piece.
std::vector<int> feature_set(const ImportantAreas& areas, Area a, const VertexMask& features,
                             const MeshTopology* largest_piece = nullptr,
                             const std::function<bool(int)>& eligible = nullptr) {
  std::vector<int> set = members(areas, a, &features);
  if (set.empty()) return members(areas, a, nullptr);
  if (!largest_piece) return set;
  std::vector<int> piece(areas.label.size(), -1), best, best_eligible, current, stack;
  for (int s : set) {
    if (piece[s] >= 0) continue;
    current.clear();
    stack.assign(1, s);
    piece[s] = s;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      current.push_back(v);
      for (const int* n = largest_piece->ring_begin(v); n != largest_piece->ring_end(v); ++n)
        if (piece[*n] < 0 && areas.label[*n] == a && features[*n]) {
          piece[*n] = s;
          stack.push_back(*n);
        }
    }
    if (current.size() > best.size()) best = current;
    if (eligible && current.size() > best_eligible.size() && std::any_of(current.begin(), current.end(), eligible))
      best_eligible = current;
  }
  return best_eligible.empty() ? best : best_eligible;
}

void eye(Context& c, const ImportantAreas& areas, const VertexMask& features, Area a) {
  const std::vector<int> set = feature_set(areas, a, features, &c.topology);
  if (set.empty()) return;
  const std::string name = area_name(a);
  const double outward = a == Area::eye_right ? 1.0 : -1.0;  // +x is the subject's right
  const int inner = c.best(set, [&](const Eigen::Vector3d& p) { return -outward * p.x(); });
  const int outer = c.best(set, [&](const Eigen::Vector3d& p) { return outward * p.x(); });
  c.add(name + ".corner_inner", inner);
  c.add(name + ".corner_outer", outer);
  const double x0 = c.ph[inner].x(), x1 = c.ph[outer].x();
  const double tol = std::max(1.5, 0.05 * std::abs(x1 - x0));
  for (int pct : {20, 40, 60, 80}) {
    const std::vector<int> b = c.band(set, 0, x0 + pct / 100.0 * (x1 - x0), tol);
    c.add(name + ".upper_" + std::to_string(pct), c.best(b, [](const Eigen::Vector3d& p) { return p.z(); }));
    c.add(name + ".lower_" + std::to_string(pct), c.best(b, [](const Eigen::Vector3d& p) { return -p.z(); }));
  }
}

void lips(Context& c, const ImportantAreas& areas, const VertexMask& features) {
  // The mouth straddles the symmetry plane: on a noisy (fused) mesh a patch of speckle on a cheek can outgrow the
  // lips' own piece, never on the plane.
  const double near_plane = 0.25 * c.frame.cap_scale * c.frame.scale;
  const std::vector<int> set = feature_set(areas, Area::lips, features, &c.topology,
                                           [&](int v) { return std::abs(c.ph[v].x()) <= near_plane; });
  const std::vector<int> area = members(areas, Area::lips, nullptr);
  if (set.empty()) return;
  const int right = c.best(set, [](const Eigen::Vector3d& p) { return p.x(); });
  const int left = c.best(set, [](const Eigen::Vector3d& p) { return -p.x(); });
  c.add("lips.corner_right", right);
  c.add("lips.corner_left", left);
  const double x0 = c.ph[left].x(), x1 = c.ph[right].x();
  const double tol = std::max(1.5, 0.05 * std::abs(x1 - x0));
  for (int pct : {25, 50, 75}) {
    const double x = x0 + pct / 100.0 * (x1 - x0);
    const std::vector<int> b = c.band(set, 0, x, tol);
    const int upper = c.best(b, [](const Eigen::Vector3d& p) { return p.z(); });
    const int lower = c.best(b, [](const Eigen::Vector3d& p) { return -p.z(); });
    if (upper < 0 || lower < 0) continue;
    std::vector<int> between;
    for (int v : c.band(area, 0, x, tol))
      if (c.ph[v].z() <= c.ph[upper].z() && c.ph[v].z() >= c.ph[lower].z()) between.push_back(v);
    const int mouth = c.best(between, [](const Eigen::Vector3d& p) { return -p.y(); });
    const std::string s = std::to_string(pct);
    c.add("lips.upper_" + s, upper);
    if (mouth >= 0) {
      const double zu = 0.5 * (c.ph[upper].z() + c.ph[mouth].z()), zl = 0.5 * (c.ph[mouth].z() + c.ph[lower].z());
      c.add("lips.upper_mid_" + s, c.best(between, [&](const Eigen::Vector3d& p) { return -std::abs(p.z() - zu); }));
      c.add("lips.lower_mid_" + s, c.best(between, [&](const Eigen::Vector3d& p) { return -std::abs(p.z() - zl); }));
    }
    c.add("lips.lower_" + s, lower);
  }
}

void ear(Context& c, const ImportantAreas& areas, const VertexMask& features, Area a) {
  const std::vector<int> set = feature_set(areas, a, features);
  const std::vector<int> area = members(areas, a, nullptr);
  if (set.empty()) return;
  const std::string name = area_name(a);
  const int top = c.best(set, [](const Eigen::Vector3d& p) { return p.z(); });
  const int bottom = c.best(set, [](const Eigen::Vector3d& p) { return -p.z(); });
  const double z1 = c.ph[top].z(), z2 = c.ph[bottom].z();
  const double tol = std::max(1.5, 0.05 * (z1 - z2));
  auto back = [](const Eigen::Vector3d& p) { return -p.y(); };
  c.add(name + ".top", top);
  c.add(name + ".bottom", bottom);
  c.add(name + ".upper_back", c.best(c.band(set, 2, z1 - 0.25 * (z1 - z2), tol), back));
  c.add(name + ".lower_back", c.best(c.band(set, 2, z2 + 0.25 * (z1 - z2), tol), back));
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int v : area) centroid += c.ph[v];
  centroid /= static_cast<double>(area.size());
  c.add(name + ".middle", c.best(area, [&](const Eigen::Vector3d& p) { return -(p - centroid).squaredNorm(); }));
}

void nose(Context& c, const ImportantAreas& areas, const VertexMask& features) {
  const int tip = c.frame.nose_tip_vertex;
  c.add("nose.tip", tip);
  const double reach = 3.0 * c.frame.cap_scale * c.frame.scale;
  std::vector<int> above, below;  // the profile (within 1.5 edges of the plane) near the tip
  for (int v = 0; v < static_cast<int>(c.ph.size()); ++v) {
    const Eigen::Vector3d& p = c.ph[v];
    if (std::abs(p.x()) > 1.5 || p.norm() > reach) continue;
    if (p.z() > 0 && p.z() <= areas.z_eyes_nose) above.push_back(v);
    if (p.z() < 0 && p.z() > areas.z_nose_lips) below.push_back(v);
  }
  auto deepest = [](const Eigen::Vector3d& p) { return -p.y(); };
  const int root = c.best(above, deepest);
  c.add("nose.root", root);
  if (root >= 0) {
    const Eigen::Vector3d mid = 0.5 * (c.ph[tip] + c.ph[root]);
    c.add("nose.bridge_mid", c.best(above, [&](const Eigen::Vector3d& p) { return -(p - mid).squaredNorm(); }));
  }
  const std::vector<int> set = feature_set(areas, Area::nose, features);
  if (set.empty()) return;
  const int ala_right = c.best(set, [](const Eigen::Vector3d& p) { return p.x(); });
  const int ala_left = c.best(set, [](const Eigen::Vector3d& p) { return -p.x(); });
  c.add("nose.ala_right", ala_right);
  c.add("nose.ala_left", ala_left);
  const int sub = c.best(below, deepest);
  c.add("nose.subnasale", sub);
  if (sub < 0) return;
  for (int side = 0; side < 2; ++side) {
    const int ala = side == 0 ? ala_right : ala_left;
    const Eigen::Vector3d target = 0.5 * (c.ph[ala] + c.ph[sub]);
    std::vector<int> candidates;
    for (int v : set)
      if (c.ph[v].z() < 0 && (side == 0 ? c.ph[v].x() > 0 : c.ph[v].x() < 0)) candidates.push_back(v);
    c.add(side == 0 ? "nose.nostril_right" : "nose.nostril_left",
          c.best(candidates, [&](const Eigen::Vector3d& p) { return -(p - target).squaredNorm(); }));
  }
}

}  // namespace

std::vector<ControlPoint> find_control_points(const TriangleMesh& mesh, const MeshTopology& topology,
                                              const HeadFrame& frame, const ImportantAreas& areas,
                                              const VertexMask& features) {
  Context c{mesh, topology, frame, {}, {}};
  c.ph.resize(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) c.ph[i] = frame.to_head(mesh.vertices[i]);
  eye(c, areas, features, Area::eye_right);
  eye(c, areas, features, Area::eye_left);
  lips(c, areas, features);
  ear(c, areas, features, Area::ear_right);
  ear(c, areas, features, Area::ear_left);
  nose(c, areas, features);
  return c.out;
}

std::vector<std::string> control_point_names() {
  std::vector<std::string> names;
  for (const char* eye : {"eye_right", "eye_left"}) {
    names.push_back(std::string(eye) + ".corner_inner");
    names.push_back(std::string(eye) + ".corner_outer");
    for (int pct : {20, 40, 60, 80}) {
      names.push_back(std::string(eye) + ".upper_" + std::to_string(pct));
      names.push_back(std::string(eye) + ".lower_" + std::to_string(pct));
    }
  }
  names.push_back("lips.corner_right");
  names.push_back("lips.corner_left");
  for (int pct : {25, 50, 75})
    for (const char* part : {"upper_", "upper_mid_", "lower_mid_", "lower_"})
      names.push_back(std::string("lips.") + part + std::to_string(pct));
  for (const char* ear : {"ear_right", "ear_left"})
    for (const char* part : {".top", ".bottom", ".upper_back", ".lower_back", ".middle"})
      names.push_back(std::string(ear) + part);
  for (const char* part : {"tip", "root", "bridge_mid", "ala_right", "ala_left", "subnasale", "nostril_right",
                           "nostril_left"})
    names.push_back(std::string("nose.") + part);
  return names;
}

}  // namespace hf::head
