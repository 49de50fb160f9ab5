// The whole method on the real heads of ../shared/data/head_meshes (skipped when absent): the nose tip and the
// paired control points are mirror-symmetric about the found plane, lie in the expected order (eyes above the nose
// tip above the lips), and are the same vertices after a random rigid motion and uniform scale of the input.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <map>
#include <ostream>
#include <string>
#include <vector>
#include <random>

#include "head/head_features.h"
#include "mesh/topology.h"
#include "io/obj.h"
#include "io/ply.h"
#include "tests/common/sanitizer.h"

namespace hf::head {
namespace {

const std::string kDir = std::string(HF_SHARED_DIR) + "/data/head_meshes/";

TriangleMesh load(const std::string& name) {
  const std::string path = kDir + name;
  return name.ends_with(".ply") ? read_ply_mesh(path) : read_obj(path);
}

std::map<std::string, ControlPoint> by_name(const HeadFeatureResult& r) {
  std::map<std::string, ControlPoint> m;
  for (const ControlPoint& c : r.control_points) m[c.name] = c;
  return m;
}

// The mirror partner's name: right <-> left.
std::string mirrored(std::string name) {
  for (auto [a, b] : {std::pair{"right", "left"}, std::pair{"left", "right"}}) {
    const size_t at = name.find(a);
    if (at != std::string::npos) return name.replace(at, std::string(a).size(), b);
  }
  return "";
}

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  return Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
}

// The input moved by a random rotation, a translation of ~300 mean edge lengths and a uniform scale of 2.5.
TriangleMesh moved_copy(const TriangleMesh& mesh, double edge, unsigned seed) {
  std::mt19937 rng(seed);
  const Eigen::Matrix3d R = random_rotation(rng);
  std::uniform_real_distribution<double> u(-1, 1);
  const Eigen::Vector3d t = 300.0 * edge * Eigen::Vector3d(u(rng), u(rng), u(rng));
  TriangleMesh moved = mesh;
  for (auto& v : moved.vertices) v = (2.5 * (R * v.cast<double>()) + t).cast<float>();
  return moved;
}

// Vertices at most one mean edge length apart (in the input) count as the same point: Igea's strips hold
// coincident and near-coincident vertices, so "the same vertex" is judged by position.
bool same_point(const TriangleMesh& mesh, int a, int b, double edge) {
  return a == b || (mesh.vertices[a] - mesh.vertices[b]).norm() <= edge;
}

class HeadFrameOnRealHeads : public ::testing::TestWithParam<const char*> {};

TEST_P(HeadFrameOnRealHeads, TipOnThePlaneAndStableUnderSimilarity) {
  if (!std::filesystem::exists(kDir + GetParam())) GTEST_SKIP() << kDir << GetParam() << " not found (../shared absent)";
  const TriangleMesh mesh = load(GetParam());
  const MeshTopology topology = build_topology(mesh);
  const HeadFrame f = find_head_frame(mesh, topology);
  // Trimmed RMS mirror residual: measured 0.7 (Max Planck) .. 4.3 (Igea) mean edge lengths.
  EXPECT_LT(f.symmetry_rms_edges, 6.0);
  EXPECT_TRUE((f.R_head_input * f.R_head_input.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-9));
  EXPECT_NEAR(f.R_head_input.determinant(), 1.0, 1e-9);
  EXPECT_NEAR(f.to_head(mesh.vertices[f.nose_tip_vertex]).norm(), 0.0, 1e-6);
  const TriangleMesh moved = moved_copy(mesh, f.mean_edge_length, 5);
  const HeadFrame g = find_head_frame(moved, build_topology(moved));
  EXPECT_TRUE(same_point(mesh, g.nose_tip_vertex, f.nose_tip_vertex, f.mean_edge_length))
      << g.nose_tip_vertex << " vs " << f.nose_tip_vertex << ": "
      << (mesh.vertices[g.nose_tip_vertex] - mesh.vertices[f.nose_tip_vertex]).norm() / f.mean_edge_length
      << " edges apart; cap scores " << g.cap_score_edges << " vs " << f.cap_score_edges;
  EXPECT_NEAR(g.scale * 2.5, f.scale, 1e-3 * f.scale);  // lengths in edges do not change with the scale
}

INSTANTIATE_TEST_SUITE_P(HeadMeshes, HeadFrameOnRealHeads,
                         ::testing::Values("max_planck_decimated.obj", "libigl_face_head.obj", "nefertiti.obj",
                                           "igea_tristrips.ply"),
                         [](const auto& info) {
                           std::string n = info.param;
                           return n.substr(0, n.find('.'));
                         });

// Control points on every head. What each head has, and what it is held to:
//   every head: the nose, eyes and lips are found; the nose tip, root and subnasale lie on the plane; eyes above
//     the tip above the lip corners; the same vertices after a random rigid motion and uniform scale;
//   ears: found on libigl, Max Planck and Nefertiti (a flap, important_areas.h); absent on Igea, whose ears are
//     under hair: no ear area, no ear control point, and the reason in the areas' note and in the warnings;
//   symmetry: a point and its mirror partner have opposite x and equal y, z within rho (the tip's scale, ~2 cm:
//     features are thresholded vertex sets whose borders move by whole rings, and rho spans 3 (Max Planck) to 15
//     (Igea) rings) on each axis, except the pairs bench/results/head.md measures as asymmetric, held to 1.6 rho:
//     Max Planck's eyes and lips (1.1 and 1.5 rho: 5272 vertices, 3 edges per rho, the eyes from the fallback
//     band) and Igea's eyes and lips (1.3 and 1.0 rho: a scan crack beside the mouth, the left eye's features
//     reach the side of the nose).
struct HeadCase {
  const char* file;
  bool ears;
  std::vector<std::string> loose;  // areas (name before the '.') held to 1.6 rho instead of rho
  bool physical = false;  // head_features.h's use_physical_scale() (chosen on a fused head, reported here)
};

void PrintTo(const HeadCase& c, std::ostream* os) { *os << c.file; }

class RealHead : public ::testing::TestWithParam<HeadCase> {};

std::string area_of(const std::string& name) {
  std::string a = name.substr(0, name.find('.'));
  for (const char* side : {"_right", "_left"})
    if (a.ends_with(side)) a = a.substr(0, a.size() - std::string(side).size());
  return a;
}

TEST_P(RealHead, SymmetricOrderedAndStableUnderSimilarity) {
  const HeadCase& hc = GetParam();
  if (!std::filesystem::exists(kDir + hc.file)) GTEST_SKIP() << kDir << hc.file << " not found (../shared absent)";
  if (hc.physical) HF_RELEASE_ONLY_ACCURACY("HeadMeshes/RealHead.* (the same detection at the paper's scales)");
  const TriangleMesh mesh = load(hc.file);
  HeadFeatureOptions options;
  options.automatic = true;
  if (hc.physical) use_physical_scale(options);
  const HeadFeatureResult r = detect_head_features(mesh, options);
  const auto points = by_name(r);
  ASSERT_TRUE(points.count("nose.tip"));
  auto head = [&](const std::string& n) { return r.frame.to_head(points.at(n).position); };  // mean edge lengths

  // What is found, and the documented absence.
  for (Area a : {Area::eye_right, Area::eye_left, Area::nose, Area::lips})
    EXPECT_GT(r.areas.counts[static_cast<int>(a)], 0) << area_name(a);
  for (Area a : {Area::ear_right, Area::ear_left}) {
    const int i = static_cast<int>(a);
    if (hc.ears) {
      EXPECT_GT(r.areas.counts[i], 0) << area_name(a);
      EXPECT_TRUE(r.areas.note[i].empty()) << r.areas.note[i];
    } else {
      EXPECT_EQ(r.areas.counts[i], 0) << area_name(a) << " should be absent (hair)";
      EXPECT_NE(r.areas.note[i].find("no ear-like flap"), std::string::npos) << r.areas.note[i];
      const std::string name = area_name(a);
      bool warned = false;
      for (const std::string& w : r.warnings) warned |= w.find(name) != std::string::npos && w.find("flap") != std::string::npos;
      EXPECT_TRUE(warned) << "no warning names the absent " << name;
    }
  }
  size_t expected = 0;
  for (const std::string& n : control_point_names()) expected += hc.ears || n.find("ear") == std::string::npos;
  int ear_points = 0;
  for (const auto& [name, c] : points) ear_points += name.starts_with("ear");
  EXPECT_EQ(ear_points, hc.ears ? 10 : 0);
  EXPECT_EQ(points.size(), expected);

  // Symmetry.
  const double rho_edges = r.frame.cap_scale * r.frame.scale;
  int pairs = 0;
  for (const auto& [name, c] : points) {
    const std::string other = mirrored(name);
    if (other.empty() || !points.count(other) || name.find("right") == std::string::npos) continue;
    const bool loose = std::find(hc.loose.begin(), hc.loose.end(), area_of(name)) != hc.loose.end();
    const double tol = (loose ? 1.6 : 1.0) * rho_edges;
    const Eigen::Vector3d a = head(name), b = head(other);
    std::printf("%-24s x %+7.1f/%+7.1f  y %+7.1f/%+7.1f  z %+7.1f/%+7.1f (edges; tolerance %.1f)\n", name.c_str(), a.x(),
                b.x(), a.y(), b.y(), a.z(), b.z(), tol);
    EXPECT_NEAR(a.x(), -b.x(), tol) << name;
    EXPECT_NEAR(a.y(), b.y(), tol) << name;
    EXPECT_NEAR(a.z(), b.z(), tol) << name;
    EXPECT_GT(a.x(), 0) << name << " lies on the subject's right (+x)";
    ++pairs;
  }
  EXPECT_EQ(pairs, hc.ears ? 18 : 13);  // 10 eye pairs, the lip corners, 2 nose pairs, 5 ear pairs
  // Profile points lie on the plane (within the profile band of 1.5 edges and one more edge of rounding).
  for (const char* n : {"nose.tip", "nose.root", "nose.subnasale"})
    if (points.count(n)) {
      EXPECT_LT(std::abs(head(n).x()), 2.5) << n;
    }
  // Order: eyes above the nose tip above the lips' corners; ears behind the face.
  for (const char* n : {"eye_right.corner_inner", "eye_left.corner_inner", "eye_right.corner_outer", "eye_left.corner_outer"}) {
    ASSERT_TRUE(points.count(n)) << n;
    EXPECT_GT(head(n).z(), 0.0) << n;
  }
  for (const char* n : {"lips.corner_right", "lips.corner_left"}) {
    ASSERT_TRUE(points.count(n)) << n;
    EXPECT_LT(head(n).z(), 0.0) << n;
  }
  for (const auto& [name, c] : points)
    if (name.starts_with("ear")) {
      EXPECT_LT(head(name).y(), head("eye_right.corner_outer").y()) << name << " lies behind the eyes";
    }
  EXPECT_NEAR(head("nose.tip").y(), 0.0, 1e-6);

  // Stability: a random rotation, translation and scale of the input finds the same points.
  const TriangleMesh moved = moved_copy(mesh, r.frame.mean_edge_length, 11);
  const HeadFeatureResult rm = detect_head_features(moved, options);
  EXPECT_TRUE(same_point(mesh, rm.frame.nose_tip_vertex, r.frame.nose_tip_vertex, r.frame.mean_edge_length));
  EXPECT_EQ(rm.areas.counts, r.areas.counts);
  const auto moved_points = by_name(rm);
  EXPECT_EQ(moved_points.size(), points.size());
  int same = 0, exact = 0;
  for (const auto& [name, c] : points) {
    if (!moved_points.count(name)) continue;
    exact += moved_points.at(name).vertex == c.vertex;
    same += same_point(mesh, moved_points.at(name).vertex, c.vertex, r.frame.mean_edge_length);
  }
  std::printf("%d of %zu control points on the same vertex after the motion, %d within one edge\n", exact,
              points.size(), same);
  // Every stage is pose-invariant (the frame's sectors, k-rings, thresholds at averages, the flap test's
  // distances); only float rounding of the moved positions can flip a tie.
  EXPECT_GE(exact, static_cast<int>(points.size()) - 2);
  EXPECT_GE(same, static_cast<int>(points.size()) - 2);
}

INSTANTIATE_TEST_SUITE_P(HeadMeshes, RealHead,
                         ::testing::Values(HeadCase{"libigl_face_head.obj", true, {}},
                                           HeadCase{"nefertiti.obj", true, {}},
                                           HeadCase{"max_planck_decimated.obj", true, {"eye", "lips"}},
                                           HeadCase{"igea_tristrips.ply", false, {"eye", "lips"}}),
                         [](const auto& info) {
                           std::string n = info.param.file;
                           return n.substr(0, n.find('.'));
                         });
// The same checks with the physical scales of the end-to-end test (chosen on libigl's head fused at 3 mm; libigl's
// source is the one the choice saw). Max Planck is left out: decimated to 7 mm edges (3 per rho), its right lip
// corner moves to 1.8 rho from its mirror (held to 1.6) and an ear point to 1.2 rho (held to 1), measured in
// bench/results/head.md; the paper's scales hold it above.
INSTANTIATE_TEST_SUITE_P(HeadMeshesPhysicalScale, RealHead,
                         ::testing::Values(HeadCase{"libigl_face_head.obj", true, {}, true},
                                           HeadCase{"nefertiti.obj", true, {}, true},
                                           HeadCase{"igea_tristrips.ply", false, {"eye", "lips"}, true}),
                         [](const auto& info) {
                           std::string n = info.param.file;
                           return n.substr(0, n.find('.'));
                         });

}  // namespace
}  // namespace hf::head
