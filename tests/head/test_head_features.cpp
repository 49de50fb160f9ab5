// The pipeline on synthetic input and bad input: option parsers, outputs that read back, and meshes that are
// open, non-manifold, degenerate, have isolated vertices or are empty (a clear error or a documented skip, never
// NaN in an output).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "head/feature_outputs.h"
#include "head/feature_spec.h"
#include "head/head_features.h"
#include "io/ply.h"
#include "tests/common/analytic_meshes.h"

namespace hf::head {
namespace {

// An ellipsoid with a "nose": vertices within 0.35 rad of +y pushed out by a smooth bump, the back (y < 0)
// flattened so that y = 0 is no mirror plane; x = 0 is the best one (the semi-axes 0.8 / 1.2 make it unique).
TriangleMesh bumped_sphere() {
  TriangleMesh m = test::icosphere(1.0, 4);
  for (auto& v : m.vertices) {
    v.x() *= 0.8f;
    v.z() *= 1.2f;
    if (v.y() < 0) v.y() *= 0.7f;
    const double angle = std::acos(std::clamp(static_cast<double>(v.normalized().y()), -1.0, 1.0));
    if (angle < 0.35) v *= static_cast<float>(1.0 + 0.25 * std::pow(std::cos(angle / 0.35 * M_PI / 2), 2));
  }
  return m;
}

void expect_all_finite(const HeadFeatureResult& r) {
  for (const auto* v : {&r.discrete.mean, &r.discrete.gaussian, &r.discrete.k_max, &r.discrete.k_min, &r.mls.mean,
                        &r.mls.k_max, &r.laplace.magnitude, &r.evaluation_percent})
    for (float x : *v) ASSERT_TRUE(std::isfinite(x));
}

TEST(FeatureSpec, ParsesAndRejects) {
  const ThresholdRange t = parse_threshold("10, 100");
  EXPECT_FLOAT_EQ(t.a, 10);
  EXPECT_FLOAT_EQ(t.b, 100);
  EXPECT_FLOAT_EQ(parse_threshold("-50,-5").a, -50);
  for (const char* bad : {"", "10", "a,b", "10,5", "0,101", "nan,1", "1,2,3", "5 ,x"})
    EXPECT_THROW(parse_threshold(bad), Error) << bad;
  const auto steps = parse_morphology("open:5, dilate:10");
  ASSERT_EQ(steps.size(), 2u);
  EXPECT_EQ(steps[0].op, MorphologyOp::open);
  EXPECT_EQ(steps[1].k, 10);
  EXPECT_TRUE(parse_morphology("none").empty());
  for (const char* bad : {"open", "open:", "grow:3", "open:-1", "open:5,", "open:1e3", "open:100000"})
    EXPECT_THROW(parse_morphology(bad), Error) << bad;
  EXPECT_EQ(parse_evaluation("mls"), Evaluation::mls);
  EXPECT_THROW(parse_evaluation("MLS"), Error);
  EXPECT_EQ(parse_quantity("k_min"), Quantity::k_min);
  EXPECT_THROW(parse_quantity(""), Error);
}

TEST(HeadFeatures, FindsTheBumpAsTheNoseAndWritesReadableOutputs) {
  const TriangleMesh m = bumped_sphere();
  HeadFeatureOptions options;
  options.evaluation = Evaluation::laplace;
  options.morphology = {{MorphologyOp::close, 1}};
  const HeadFeatureResult r = detect_head_features(m, options);
  expect_all_finite(r);
  // The bump's apex is the vertex (0, 1.25, 0).
  EXPECT_NEAR(m.vertices[r.frame.nose_tip_vertex].y(), 1.25f, 1e-3f);
  EXPECT_NEAR(std::abs(r.frame.R_head_input.row(1).dot(Eigen::Vector3d::UnitY())), 1.0, 1e-3);

  const std::string dir = testing::TempDir() + "/hf_head_features_out";
  std::filesystem::remove_all(dir);
  write_head_feature_outputs(dir, m, r, options, {"bumped_sphere"});
  for (const char* f : {"evaluations.ply", "mean_curvature.ply", "gaussian_curvature.ply", "k1.ply", "k2.ply",
                        "laplace.ply", "features.ply", "control_points.json", "report.json", "report.md",
                        "features.png", "evaluation.png"})
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + f)) << f;
  // The evaluations PLY reads back (extra properties are skipped by the reader) with the same geometry.
  const TriangleMesh back = read_ply_mesh(dir + "/evaluations.ply");
  EXPECT_EQ(back.vertices.size(), m.vertices.size());
  EXPECT_EQ(back.triangles.size(), m.triangles.size());
  EXPECT_EQ(read_ply_mesh(dir + "/laplace.ply").colors.size(), m.vertices.size());
  std::ifstream in(dir + "/control_points.json");
  const nlohmann::json cp = nlohmann::json::parse(in);
  ASSERT_GE(cp["control_points"].size(), 1u);
  bool tip_listed = false;
  for (const auto& c : cp["control_points"])
    if (c["name"] == "nose.tip") {
      tip_listed = true;
      EXPECT_EQ(c["vertex"], r.frame.nose_tip_vertex);
    }
  EXPECT_TRUE(tip_listed);
  std::ifstream rin(dir + "/report.json");
  const nlohmann::json report = nlohmann::json::parse(rin);
  EXPECT_EQ(report["mesh"]["vertices"], m.vertices.size());
  EXPECT_EQ(report["features"]["method"], "laplace");
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "temporary left behind: " << e.path();
}

TEST(HeadFeatures, BadMeshesFailClearlyOrAreSkippedWithoutNaN) {
  TriangleMesh empty;
  EXPECT_THROW(detect_head_features(empty), Error);
  TriangleMesh one;
  one.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.triangles = {{0, 1, 2}};
  EXPECT_THROW(detect_head_features(one), Error);  // no interior vertex
  TriangleMesh bad_index = one;
  bad_index.triangles = {{0, 1, 7}};
  EXPECT_THROW(detect_head_features(bad_index), Error);

  // Open, non-manifold, degenerate and isolated elements on top of a valid head-like mesh.
  TriangleMesh m = bumped_sphere();
  m.triangles.erase(m.triangles.begin() + 100);  // a hole: open mesh
  const int n = static_cast<int>(m.vertices.size());
  m.vertices.push_back({5, 5, 5});             // isolated
  m.vertices.push_back({0.1f, 0.2f, 1.5f});    // a fin on an existing edge: non-manifold
  m.triangles.push_back({m.triangles[0][0], m.triangles[0][1], n + 1});
  m.triangles.push_back({0, 0, 1});            // degenerate (repeated index)
  m.vertices.push_back(m.vertices[2]);         // a duplicate position in a zero-area triangle
  m.triangles.push_back({2, 3, n + 2});
  const HeadFeatureResult r = detect_head_features(m);
  expect_all_finite(r);
  EXPECT_EQ(r.topology.isolated_vertex_count, 1);
  EXPECT_GE(r.topology.non_manifold_edge_count, 1);
  EXPECT_GT(r.topology.boundary_edge_count, 0);
  ASSERT_GE(r.warnings.size(), 4u);
  EXPECT_FALSE(r.discrete.valid[n]);
  EXPECT_FALSE(r.discrete.valid[m.triangles[0][0]]);
}

TEST(FeatureOutputs, DivergingColourMap) {
  EXPECT_EQ(diverging_color(0, 1), (Rgb8{255, 255, 255}));
  EXPECT_EQ(diverging_color(2, 1), (Rgb8{255, 0, 0}));
  EXPECT_EQ(diverging_color(-1, 1), (Rgb8{0, 0, 255}));
  EXPECT_EQ(diverging_color(5, 0), (Rgb8{255, 255, 255}));
}

}  // namespace
}  // namespace hf::head
