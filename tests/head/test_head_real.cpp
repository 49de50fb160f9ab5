// The whole method on the real heads of ../shared/data/head_meshes (skipped when absent): the nose tip and the
// paired control points are mirror-symmetric about the found plane, lie in the expected order (eyes above the nose
// tip above the lips), and are the same vertices after a random rigid motion and uniform scale of the input.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>

#include "head/head_features.h"
#include "mesh/topology.h"
#include "io/obj.h"
#include "io/ply.h"

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

// Control points on the two heads where every area is found (bench/results/head.md: on the decimated Max Planck
// bust the eyes are not separated, on Igea a scan crack beside the mouth and the hair make lips and ears
// asymmetric).
class RealHead : public ::testing::TestWithParam<const char*> {};


TEST_P(RealHead, SymmetricOrderedAndStableUnderSimilarity) {
  if (!std::filesystem::exists(kDir + GetParam())) GTEST_SKIP() << kDir << GetParam() << " not found (../shared absent)";
  const TriangleMesh mesh = load(GetParam());
  HeadFeatureOptions options;
  options.automatic = true;
  const HeadFeatureResult r = detect_head_features(mesh, options);
  const auto points = by_name(r);
  ASSERT_TRUE(points.count("nose.tip"));
  auto head = [&](const std::string& n) { return r.frame.to_head(points.at(n).position); };  // mean edge lengths

  // Symmetry: a point and its mirror partner have opposite x and equal y, z. The features are thresholded
  // vertex sets, so the tolerance is in mesh resolution: rho (the tip's scale, ~2 cm) on each axis, in edges.
  const double rho_edges = r.frame.cap_scale * r.frame.scale;
  int pairs = 0;
  for (const auto& [name, c] : points) {
    const std::string other = mirrored(name);
    if (other.empty() || !points.count(other) || name.find("right") == std::string::npos) continue;
    if (name.find("ear") != std::string::npos) continue;  // ears: see the report; not held to symmetry here
    const Eigen::Vector3d a = head(name), b = head(other);
    std::printf("%-28s x %+7.1f/%+7.1f  y %+7.1f/%+7.1f  z %+7.1f/%+7.1f (edges)\n", name.c_str(), a.x(), b.x(), a.y(),
                b.y(), a.z(), b.z());
    EXPECT_NEAR(a.x(), -b.x(), rho_edges) << name;
    EXPECT_NEAR(a.y(), b.y(), rho_edges) << name;
    EXPECT_NEAR(a.z(), b.z(), rho_edges) << name;
    EXPECT_GT(a.x(), 0) << name << " lies on the subject's right (+x)";
    ++pairs;
  }
  EXPECT_GE(pairs, 6);
  // Profile points lie on the plane.
  for (const char* n : {"nose.tip", "nose.root", "nose.subnasale"})
    if (points.count(n)) {
      EXPECT_LT(std::abs(head(n).x()), 2.0) << n;
    }
  // Order: eyes above the nose tip above the lips' corners.
  for (const char* n : {"eye_right.corner_inner", "eye_left.corner_inner", "eye_right.corner_outer", "eye_left.corner_outer"}) {
    ASSERT_TRUE(points.count(n)) << n;
    EXPECT_GT(head(n).z(), 0.0) << n;
  }
  for (const char* n : {"lips.corner_right", "lips.corner_left"}) {
    ASSERT_TRUE(points.count(n)) << n;
    EXPECT_LT(head(n).z(), 0.0) << n;
  }
  // The nose tip is the foremost point of the face (within the nose's own curvature scale).
  EXPECT_NEAR(head("nose.tip").y(), 0.0, 1e-6);

  // Stability: a random rotation, translation and scale of the input finds the same points.
  const TriangleMesh moved = moved_copy(mesh, r.frame.mean_edge_length, 11);
  const HeadFeatureResult rm = detect_head_features(moved, options);
  EXPECT_TRUE(same_point(mesh, rm.frame.nose_tip_vertex, r.frame.nose_tip_vertex, r.frame.mean_edge_length));
  const auto moved_points = by_name(rm);
  int same = 0, exact = 0;
  for (const auto& [name, c] : points) {
    if (!moved_points.count(name)) continue;
    exact += moved_points.at(name).vertex == c.vertex;
    same += same_point(mesh, moved_points.at(name).vertex, c.vertex, r.frame.mean_edge_length);
  }
  std::printf("%d of %zu control points on the same vertex after the motion, %d within one edge\n", exact,
              points.size(), same);
  // Every stage is pose-invariant (the frame's sectors, k-rings, thresholds at averages); only float rounding of
  // the moved positions can flip a tie. Measured: 51 of 52 exactly on libigl, 52 of 52 on Nefertiti.
  EXPECT_GE(exact, static_cast<int>(points.size()) - 2);
  EXPECT_GE(same, static_cast<int>(points.size()) - 2);
}

INSTANTIATE_TEST_SUITE_P(HeadMeshes, RealHead, ::testing::Values("libigl_face_head.obj", "nefertiti.obj"),
                         [](const auto& info) {
                           std::string n = info.param;
                           return n.substr(0, n.find('.'));
                         });

}  // namespace
}  // namespace hf::head
