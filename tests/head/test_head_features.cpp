// The pipeline on synthetic input and bad input: option parsers, outputs that read back, and meshes that are
// open, non-manifold, degenerate, have isolated vertices or are empty (a clear error or a documented skip, never
// NaN in an output).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "head/feature_outputs.h"
#include "head/feature_spec.h"
#include "head/head_features.h"
#include "head/render.h"
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

// A synthetic head for the ears: the bumped sphere with its lower half narrower (the jaw: the head frame's z is up,
// towards the wider half), and per side thin closed slabs (flattened ellipsoids, apart from the head) placed
// in the input frame, which is the head frame up to the tip's offset and scale: y towards the nose, z up.
TriangleMesh synthetic_head() {
  TriangleMesh m = bumped_sphere();
  for (auto& v : m.vertices)
    if (v.z() < 0) v.x() *= 0.85f;
  return m;
}

// Appends an ellipsoid with semi-axes `semi` centred at `centre`, icosphere level `level`; returns its first vertex.
int append_ellipsoid(TriangleMesh& m, const Eigen::Vector3d& centre, const Eigen::Vector3d& semi, int level) {
  const TriangleMesh e = test::icosphere(1.0, level);
  const int first = static_cast<int>(m.vertices.size());
  for (const auto& v : e.vertices) m.vertices.push_back((centre + semi.cwiseProduct(v.cast<double>())).cast<float>());
  for (const auto& t : e.triangles) m.triangles.push_back(t + Eigen::Vector3i::Constant(first));
  return first;
}

// A flap where no ear can be is not an ear. Each side carries a fin, a thin closed slab (0.08 thick, 0.5 x 0.4,
// 642 vertices) behind and above the head, as the TSDF fuses at a head's silhouette (on fused libigl heads:
// centred 8 .. 9.3 rho behind the tip and up to 1.9 rho above it); it is a flap of more than an ear's span, so the
// flap test alone takes it for the ear. Without an ear the side's ear is absent and the note names the rejected
// flap; with an ear-sized slab in front of and below it (0.08 thick, 0.3 x 0.44, 162 vertices: smaller than the
// fin, so not the largest flap), the ear is that slab and nothing of the fin.
TEST(HeadFeatures, AFinBehindAndAboveTheHeadIsNoEar) {
  for (bool with_ears : {false, true}) {
    SCOPED_TRACE(with_ears ? "fins and ears" : "fins only");
    TriangleMesh m = synthetic_head();
    const Eigen::Vector3d fin_semi(0.04, 0.25, 0.2), ear_semi(0.04, 0.15, 0.22);
    std::array<Eigen::Vector3d, 2> ear_centre;
    std::array<int, 2> ear_first{-1, -1};
    constexpr int kEarVertices = 162;  // icosphere level 2
    for (int side = 0; side < 2; ++side) {
      const double x = side == 0 ? 0.9 : -0.9;  // right (+x), left
      append_ellipsoid(m, {x, -0.2, 0.25}, fin_semi, 3);
      ear_centre[side] = {x, 0.35, -0.25};
      if (with_ears) ear_first[side] = append_ellipsoid(m, ear_centre[side], ear_semi, 2);
    }
    HeadFeatureOptions options;
    options.automatic = true;
    const HeadFeatureResult r = detect_head_features(m, options);
    expect_all_finite(r);
    // The premise: the head frame is the input's (tip at the bump's apex, z up), so "behind" and "above" are -y, +z.
    ASSERT_NEAR(m.vertices[r.frame.nose_tip_vertex].y(), 1.25f, 1e-3f);
    ASSERT_GT(r.frame.R_head_input(2, 2), 0.99);
    const double rho = r.frame.cap_scale * r.frame.scale;  // head units
    for (int side = 0; side < 2; ++side) {
      const Area ear = side == 0 ? Area::ear_right : Area::ear_left;
      const int a = static_cast<int>(ear);
      const std::string name = area_name(ear);
      std::vector<int> points;
      for (const ControlPoint& c : r.control_points)
        if (c.name.starts_with(name + ".")) points.push_back(c.vertex);
      if (!with_ears) {
        EXPECT_EQ(r.areas.counts[a], 0) << name;
        EXPECT_TRUE(points.empty()) << name;
        EXPECT_GE(r.areas.ear_flap_span_rho[side], 1.0) << name << ": the fin is a flap of an ear's span";
        EXPECT_NE(r.areas.note[a].find("rejected"), std::string::npos) << r.areas.note[a];
        EXPECT_NE(r.areas.note[a].find("behind the nose tip"), std::string::npos) << r.areas.note[a];
        EXPECT_NE(r.areas.note[a].find("above the nose tip"), std::string::npos) << r.areas.note[a];
        continue;
      }
      EXPECT_TRUE(r.areas.note[a].empty()) << r.areas.note[a];
      EXPECT_GT(r.areas.counts[a], 0) << name;
      for (size_t v = 0; v < r.areas.label.size(); ++v)
        if (r.areas.label[v] == ear) {
          ASSERT_GE(int(v), ear_first[side]) << name << " reaches off the ear slab";
          ASSERT_LT(int(v), ear_first[side] + kEarVertices) << name << " reaches off the ear slab";
        }
      EXPECT_EQ(points.size(), 5u) << name;
      // The flap's centroid is the slab's centre (the slab is symmetric about it): within a quarter rho.
      const Eigen::Vector3d expected = r.frame.to_head(ear_centre[side].cast<float>()) / rho;
      EXPECT_LT((r.areas.ear_centre_rho[side] - expected).norm(), 0.25) << name;
    }
  }
}

// ear_implausible on the flap centres measured on the real heads (head frame, rho; bench/results/head.md): the
// ears found on the four source heads pass; the fins the flap test found on fused libigl heads and Nefertiti's
// crown fail; a flap at an ear's depth but above the tip fails on its height alone.
TEST(ImportantAreas, EarPlausibilityOnMeasuredCentres) {
  const std::vector<Eigen::Vector3d> ears = {{3.83, -6.30, -0.89}, {-3.87, -6.29, -0.89},  // libigl
                                             {4.13, -6.58, -3.27}, {-4.14, -6.72, -3.36},  // Max Planck
                                             {2.27, -3.59, -1.79}, {-2.46, -3.41, -1.67},  // Nefertiti
                                             {3.74, -6.65, -0.86}, {-3.48, -7.37, -1.20}};  // fused at 2 mm, kept
  for (const Eigen::Vector3d& c : ears) EXPECT_EQ(ear_implausible(c), "") << c.transpose();
  const std::vector<Eigen::Vector3d> not_ears = {{-3.35, -7.99, 1.84}, {3.40, -8.73, 0.94}, {-3.03, -9.34, -0.53},
                                                 {-3.23, -8.41, 1.45}, {-2.94, -9.18, -0.56},  // fused fins
                                                 {3.39, -10.49, 0.97}, {-3.69, -10.54, 0.83}};  // Nefertiti's crown
  for (const Eigen::Vector3d& c : not_ears) EXPECT_NE(ear_implausible(c), "") << c.transpose();
  const std::string above = ear_implausible({3.8, -6.3, 1.5});
  EXPECT_NE(above.find("above the nose tip"), std::string::npos) << above;
  EXPECT_EQ(above.find("behind"), std::string::npos) << above;
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

// The legends under features.png (swatches) and evaluation.png (a colour bar): appended below the image at its
// width, every swatch colour present, wrapped so no name runs off the right edge; the bar runs from map(lo) on the
// left to map(hi) on the right.
TEST(HeadRender, LegendsShowTheirColoursWithinTheWidth) {
  const cv::Mat image(60, 300, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<LegendEntry> entries;
  for (int k = 0; k < 9; ++k)
    entries.push_back({"entry number " + std::to_string(k), Rgb8{std::uint8_t(20 * k), 90, 200}});
  const cv::Mat swatches = with_swatch_legend(image, entries);
  ASSERT_EQ(swatches.cols, 300);
  ASSERT_GT(swatches.rows, 60 + 3 * 20) << "nine entries in 300 px take several rows";
  const auto has = [](const cv::Mat& m, int y0, Rgb8 c) {
    for (int y = y0; y < m.rows; ++y)
      for (int x = 0; x < m.cols; ++x)
        if (m.at<cv::Vec3b>(y, x) == cv::Vec3b(c.b, c.g, c.r)) return true;
    return false;
  };
  for (const LegendEntry& e : entries) EXPECT_TRUE(has(swatches, 60, e.color)) << e.name;
  for (int y = 60; y < swatches.rows; ++y)
    for (int x = 296; x < 300; ++x) ASSERT_EQ(swatches.at<cv::Vec3b>(y, x), cv::Vec3b(255, 255, 255)) << x << "," << y;
  const auto map = [](double v, double, double hi) { return diverging_color(v, hi); };
  const cv::Mat bar = with_color_bar(image, -5.0, 5.0, map, "caption", "%", {{"not evaluated", Rgb8{128, 128, 128}}});
  ASSERT_EQ(bar.cols, 300);
  ASSERT_GT(bar.rows, 60);
  EXPECT_TRUE(has(bar, 60, diverging_color(-5.0, 5.0)));  // full blue
  EXPECT_TRUE(has(bar, 60, diverging_color(5.0, 5.0)));   // full red
  EXPECT_TRUE(has(bar, 60, Rgb8{128, 128, 128}));
  EXPECT_NO_THROW(with_color_bar(image, 0.0, 0.0, map, "a constant field", "%"));
}

}  // namespace
}  // namespace hf::head
