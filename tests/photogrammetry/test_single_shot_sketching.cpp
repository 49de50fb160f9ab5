// Point-cloud-supported single-shot sketching and the guidance states (photogrammetry/ransac_planes.h,
// single_shot_sketching.h, guidance.h, polygon_modelling.h) on the synthetic box building, and RANSAC on the
// Sceaux cloud.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "photogrammetry/model_outputs.h"
#include "photogrammetry/polygon_modelling.h"
#include "photogrammetry/scene_readers.h"
#include "photogrammetry/sketch_session.h"
#include "tests/photogrammetry/box_building.h"

namespace hf::photogrammetry {
namespace {

using testing::BoxBuilding;
const std::string kSketchShared = HF_SHARED_DIR;
constexpr double kNoise = 0.01;  // 1 cm cloud noise

Network box_network() {
  const BoxBuilding b;
  Network n;
  n.source = "box";
  n.shots = BoxBuilding::shots();
  n.cloud = b.cloud(0.2, kNoise, 1);
  n.validate();
  return n;
}

// Index of the segment whose plane is (n, d) up to sign, within 2 degrees and 5 cm; -1 if none.
int find_plane(const std::vector<PlaneSegment>& segments, const Eigen::Vector3d& n, double d) {
  for (size_t s = 0; s < segments.size(); ++s) {
    const Eigen::Vector4d p = segments[s].plane.head<3>().dot(n) < 0 ? Eigen::Vector4d(-segments[s].plane)
                                                                     : segments[s].plane;
    if (plane_angle_deg(p, Eigen::Vector4d(n.x(), n.y(), n.z(), d)) < 2 && std::fabs(p[3] - d) < 0.05) return int(s);
  }
  return -1;
}

TEST(RansacPlanes, FindsTheBoxFacadesAndTheGround) {
  const Network n = box_network();
  RansacPlaneOptions o;
  o.distance_threshold = 3 * kNoise;
  const std::vector<PlaneSegment> segments = segment_planes_ransac(n.cloud.positions, o);
  ASSERT_GE(segments.size(), 3u);
  const int front = find_plane(segments, {0, -1, 0}, 0), right = find_plane(segments, {1, 0, 0}, -10),
            ground = find_plane(segments, {0, 0, 1}, 0);
  ASSERT_GE(front, 0);
  ASSERT_GE(right, 0);
  ASSERT_GE(ground, 0);
  // A 3-sigma band holds 99.7 % of a plane's points; the lines where planes meet go to whichever came first.
  EXPECT_GT(double(segments[size_t(front)].indices.size()), 0.95 * 1260);
  EXPECT_GT(double(segments[size_t(right)].indices.size()), 0.95 * 1200);
  // Least-squares refit: the front plane's offset within a few noise / sqrt(n).
  EXPECT_LT(std::fabs(segments[size_t(front)].plane[3]), 5 * kNoise / std::sqrt(1000.0) + 1e-3);
  // q of eq. 2 on a jittered 0.2 m grid: between half the spacing and the spacing.
  EXPECT_GT(segments[size_t(front)].mean_spacing, 0.1);
  EXPECT_LT(segments[size_t(front)].mean_spacing, 0.2);
  // Deterministic: the same cloud gives the same segments.
  const std::vector<PlaneSegment> again = segment_planes_ransac(n.cloud.positions, o);
  ASSERT_EQ(again.size(), segments.size());
  EXPECT_EQ(again[0].indices, segments[0].indices);
}

TEST(SingleShotSketching, PicksTheFrontFacadeAndPlacesItWithinTheCloudNoise) {
  const BoxBuilding b;
  const Network n = box_network();
  RansacPlaneOptions ro;
  ro.distance_threshold = 3 * kNoise;
  const std::vector<PlaneSegment> segments = segment_planes_ransac(n.cloud.positions, ro);
  const int front = find_plane(segments, {0, -1, 0}, 0);
  const Shot& shot = n.shots[1];
  const Polygon2d outline = b.project(shot, b.front_corners());
  const std::vector<SegmentFit> fits = fit_segments(shot, 1, outline, n.cloud, segments);
  const CandidateChoice choice = choose_candidate(fits);
  ASSERT_TRUE(choice.best);
  EXPECT_EQ(choice.best->segment, front);
  EXPECT_FALSE(choice.ambiguous);
  // Every front point lies inside the outline (m = n); the windows (20 % of the facade) are holes the splats do not
  // fill, so r is about 0.8.
  EXPECT_EQ(choice.best->m, choice.best->n);
  EXPECT_GT(choice.best->r, 0.7);
  EXPECT_LT(choice.best->r, 0.9);
  const auto placed = back_project_onto_plane(shot, outline, segments[size_t(front)].plane);
  ASSERT_TRUE(placed);
  for (size_t k = 0; k < 4; ++k) EXPECT_LT(((*placed)[k] - b.front_corners()[k]).norm(), 3 * kNoise);
  // The right facade's outline in the corner shot picks the right facade.
  const Polygon2d side = b.project(n.shots[3], b.right_corners());
  const CandidateChoice side_choice = choose_candidate(fit_segments(n.shots[3], 3, side, n.cloud, segments));
  ASSERT_TRUE(side_choice.best);
  EXPECT_EQ(side_choice.best->segment, find_plane(segments, {1, 0, 0}, -10));
}

TEST(Guidance, StatesFollowThePapersRules) {
  const BoxBuilding b;
  const Network n = box_network();
  ModelOptions o;
  o.ransac.distance_threshold = 3 * kNoise;
  Sketch s;
  auto view = [&](int shot, const std::vector<Eigen::Vector3d>& corners) {
    return SketchView{n.shots[size_t(shot)].name, b.project(n.shots[size_t(shot)], corners)};
  };
  // p_front: one shot, the whole front facade -> one segment fits -> green, cloud_plane.
  s.polygons.push_back({"p_front", {view(1, b.front_corners())}, ""});
  // p_window: one shot, a window: the front segment's points mostly lie outside it (h = m r / n small) -> red.
  s.polygons.push_back({"p_window", {view(1, BoxBuilding::window_corners(0))}, ""});
  // p_window_same: the same window on the plane of p_front -> green, polygon_plane.
  s.polygons.push_back({"p_window_same", {view(1, BoxBuilding::window_corners(0))}, "p_front"});
  // p_window_2: the window in two shots -> yellow, dlt; in three -> green, dlt.
  s.polygons.push_back({"p_window_2", {view(0, BoxBuilding::window_corners(1)), view(2, BoxBuilding::window_corners(1))}, ""});
  s.polygons.push_back({"p_window_3", {view(0, BoxBuilding::window_corners(2)), view(1, BoxBuilding::window_corners(2)),
                                       view(2, BoxBuilding::window_corners(2))}, ""});
  // p_sky: an outline in the sky above the building, one shot, no points -> red, nothing placed.
  s.polygons.push_back({"p_sky", {SketchView{"front.png", {{10, 5}, {100, 5}, {100, 40}, {10, 40}}}}, ""});
  check_sketch_shots(s, n, "sketch");
  const Model m = model_polygons(n, s, o);
  ASSERT_EQ(m.polygons.size(), 6u);
  const auto state = [&](size_t i) { return std::string(to_string(m.polygons[i].decision.state)); };
  const auto method = [&](size_t i) { return std::string(to_string(m.polygons[i].decision.method)); };
  EXPECT_EQ(state(0), "green");
  EXPECT_EQ(method(0), "cloud_plane");
  EXPECT_EQ(state(1), "red");
  EXPECT_TRUE(m.polygons[1].vertices.empty());
  EXPECT_FALSE(m.polygons[1].plane);
  EXPECT_EQ(state(2), "green");
  EXPECT_EQ(method(2), "polygon_plane");
  EXPECT_EQ(state(3), "yellow");
  EXPECT_EQ(method(3), "dlt");
  EXPECT_EQ(state(4), "green");
  EXPECT_EQ(method(4), "dlt");
  EXPECT_EQ(state(5), "red");
  EXPECT_TRUE(m.polygons[5].vertices.empty());
  // Placement accuracy: the window on the front segment's plane within the cloud noise; the triangulated windows
  // from exact sketches exactly (no segment is accepted for a window, so no adjustment moves them).
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_LT((m.polygons[2].vertices[k] - BoxBuilding::window_corners(0)[k]).norm(), 3 * kNoise);
    EXPECT_LT((m.polygons[3].vertices[k] - BoxBuilding::window_corners(1)[k]).norm(), 1e-9);
    EXPECT_LT((m.polygons[4].vertices[k] - BoxBuilding::window_corners(2)[k]).norm(), 1e-9);
    EXPECT_LT(m.polygons[4].reprojection_error_px[k], 1e-6);
  }
  // Planes face the first view's camera: the front facade's normal is -y.
  EXPECT_LT(m.polygons[0].plane->y(), -0.999);
  for (const ModelledPolygon& p : m.polygons)
    for (const double e : p.reprojection_error_px) EXPECT_TRUE(std::isfinite(e));
}

TEST(Guidance, DecisionTable) {
  const auto d = [](bool ref, int shots, bool dlt, bool cand, bool amb) {
    GuidanceInputs in{ref, shots, dlt, cand, amb};
    const GuidanceDecision g = decide_guidance(in);
    return std::string(to_string(g.state)) + "/" + to_string(g.method);
  };
  EXPECT_EQ(d(false, 1, false, false, false), "red/none");
  EXPECT_EQ(d(false, 2, false, false, false), "red/none");  // degenerate rays, no plane
  EXPECT_EQ(d(false, 1, false, true, true), "yellow/cloud_plane");
  EXPECT_EQ(d(false, 2, true, false, false), "yellow/dlt");
  EXPECT_EQ(d(false, 2, true, true, false), "green/cloud_plane");
  EXPECT_EQ(d(false, 3, true, true, true), "green/dlt");
  EXPECT_EQ(d(true, 1, false, false, false), "green/polygon_plane");
}

TEST(RansacPlanes, SceauxMainFacadesAreVerticalAndFaceTheCameras) {
  const std::string dir = kSketchShared + "/data/photogrammetry_sceaux_castle";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not found (../shared absent)";
  const Network n = read_network(dir);
  RansacPlaneOptions o;
  o.max_planes = 4;
  const std::vector<PlaneSegment> segments = segment_planes_ransac(n.cloud.positions, o);
  ASSERT_GE(segments.size(), 2u);
  // "Down" in the world: the mean of the cameras' image-down axes (row 1 of R); the photos are taken upright.
  Eigen::Vector3d down = Eigen::Vector3d::Zero(), view = Eigen::Vector3d::Zero();
  for (const Shot& s : n.shots) {
    down += s.R_camera_world.row(1).transpose();
    view += s.R_camera_world.row(2).transpose();
  }
  down.normalize();
  view.normalize();
  const PlaneSegment& main = segments[0];
  std::cout << "Sceaux: " << segments.size() << " segments, threshold " << 0.005 * robust_extent(n.cloud.positions)
            << "; largest " << main.indices.size() << " points, q " << main.mean_spacing << ", |n.down| "
            << std::fabs(main.plane.head<3>().dot(down)) << ", |n.view| " << std::fabs(main.plane.head<3>().dot(view))
            << "\n";
  for (size_t s = 1; s < segments.size(); ++s)
    std::cout << "  segment " << s << ": " << segments[s].indices.size() << " points, |n.down| "
              << std::fabs(segments[s].plane.head<3>().dot(down)) << "\n";
  EXPECT_GT(double(main.indices.size()), 0.15 * double(n.cloud.size()));
  EXPECT_LT(std::fabs(main.plane.head<3>().dot(down)), 0.25);  // vertical within ~15 degrees
  EXPECT_GT(std::fabs(main.plane.head<3>().dot(view)), 0.7);   // seen from the front
  // The second facade is vertical too and another plane, not a slice of the first: on Sceaux it is parallel to it
  // (0.04 degrees) and 1.13 units behind, 30 times the inlier threshold (the castle's front steps back).
  EXPECT_GT(double(segments[1].indices.size()), 0.15 * double(n.cloud.size()));
  EXPECT_LT(std::fabs(segments[1].plane.head<3>().dot(down)), 0.25);
  const double sign = segments[1].plane.head<3>().dot(main.plane.head<3>()) > 0 ? 1 : -1;
  const double offset = std::fabs(sign * segments[1].plane[3] - main.plane[3]);
  EXPECT_TRUE(plane_angle_deg(main.plane, segments[1].plane) > 10 ||
              offset > 10 * 0.005 * robust_extent(n.cloud.positions))
      << "offset " << offset;
}

}  // namespace
// Interactive sketching (photogrammetry/sketch_session.h) driven by the events the viewer's mouse and keys send: the
// guidance colour follows each click as the rules above give it, and the sketch is what SKETCH.json would hold.
TEST(SketchSession, ScriptedClicksGiveTheLiveGuidanceOfTheRules) {
  const BoxBuilding b;
  const Network n = box_network();
  ModelOptions o;
  o.ransac.distance_threshold = 3 * kNoise;
  SketchSession session(n, {}, o);
  const auto sketch_corners = [&](int shot, const std::vector<Eigen::Vector3d>& corners) {
    session.apply("shot " + n.shots[size_t(shot)].name);
    for (const Eigen::Vector2d& uv : b.project(n.shots[size_t(shot)], corners))
      session.apply("click " + std::to_string(uv.x()) + " " + std::to_string(uv.y()));
    return session.close_view();
  };
  EXPECT_EQ(session.current_guidance(), Guidance::red);  // nothing sketched
  ASSERT_TRUE(sketch_corners(1, b.front_corners()));
  EXPECT_EQ(session.current_guidance(), Guidance::green);  // one facade segment fits
  EXPECT_EQ(session.current()->decision.method, Placement::cloud_plane);

  session.apply("new");
  ASSERT_TRUE(sketch_corners(1, BoxBuilding::window_corners(0)));
  EXPECT_EQ(session.current_guidance(), Guidance::red);  // a window alone fits no segment
  session.apply("same_plane");
  EXPECT_EQ(session.current_guidance(), Guidance::green);  // on the facade's plane
  EXPECT_EQ(session.current()->decision.method, Placement::polygon_plane);

  session.apply("new");
  ASSERT_TRUE(sketch_corners(0, BoxBuilding::window_corners(1)));
  EXPECT_EQ(session.current_guidance(), Guidance::red);
  ASSERT_TRUE(sketch_corners(2, BoxBuilding::window_corners(1)));
  EXPECT_EQ(session.current_guidance(), Guidance::yellow);  // two shots
  // Refused events change nothing: a second outline in a shot already used, one vertex short, a click outside.
  session.apply("shot " + n.shots[2].name);
  session.apply("click 10 10");
  EXPECT_NE(session.message().find("already"), std::string::npos);
  session.apply("shot " + n.shots[1].name);
  session.apply("click -5 10");
  EXPECT_NE(session.message().find("outside"), std::string::npos);
  const Polygon2d w1 = b.project(n.shots[1], BoxBuilding::window_corners(1));
  for (size_t k = 0; k < 3; ++k) session.click(w1[k]);
  EXPECT_FALSE(session.close_view());
  EXPECT_NE(session.message().find("needs 4 vertices"), std::string::npos);
  session.click({1, 1});
  session.apply("undo");
  session.click(w1[3]);
  ASSERT_TRUE(session.close_view());
  EXPECT_EQ(session.current_guidance(), Guidance::green);  // three shots
  EXPECT_EQ(session.current()->decision.method, Placement::dlt);
  for (size_t k = 0; k < 4; ++k)
    EXPECT_LT((session.current()->vertices[k] - BoxBuilding::window_corners(1)[k]).norm(), 1e-4);  // clicks at 1e-6 px

  // The session's sketch models as `hashfusion model` would model its SKETCH.json.
  const Sketch& s = session.sketch();
  ASSERT_EQ(s.polygons.size(), 3u);
  EXPECT_EQ(s.polygons[1].same_plane_as, "p0");
  EXPECT_EQ(s.polygons[2].views.size(), 3u);
  const Model again = model_polygons(n, parse_sketch(format_sketch_json(s), "session.json"), o);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(again.polygons[i].decision.state, session.model().polygons[i].decision.state);
  // The overlay shows the shot with the polygons in their guidance colour.
  const ColorImage overlay = session.overlay();
  size_t green = 0;
  for (const Rgb8& p : overlay.pixels()) green += p.g > p.r + 60 && p.g > p.b + 60;  // anti-aliased green lines
  EXPECT_GT(green, 100u);
  EXPECT_THROW(session.apply("jump 3"), Error);
  EXPECT_THROW(session.apply("click 1"), Error);
}

}  // namespace hf::photogrammetry
