// The network readers (photogrammetry/scene_readers.h) and SKETCH.json (photogrammetry/sketch.h): good files read
// exactly, malformed ones fail with one line naming file and line; the two shared data sets read as documented.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/error.h"
#include "io/image_io.h"
#include "io/ply.h"
#include "io/trajectory_io.h"
#include "photogrammetry/model_outputs.h"
#include "photogrammetry/scene_mvs.h"
#include "photogrammetry/scene_readers.h"
#include "photogrammetry/sketch.h"
#include "tests/photogrammetry/synthetic_shots.h"

namespace hf::photogrammetry {
namespace {

const std::string kReadersShared = HF_SHARED_DIR;

template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(OpenMvsText, ParsesCamerasAndChecksTheRedundantTranslation) {
  const std::string text =
      "# comment\n"
      "images/a.jpg 640 480 500 510 319.5 239.5  1 0 0 0 1 0 0 0 1  0 0 -5  0 0 5  1\n";
  const std::vector<Shot> shots = parse_openmvs_cameras(text, "cams.txt", "/root");
  ASSERT_EQ(shots.size(), 1u);
  EXPECT_EQ(shots[0].name, "a.jpg");
  EXPECT_EQ(shots[0].image_path, "/root/images/a.jpg");
  EXPECT_FALSE(shots[0].image_available);
  EXPECT_EQ(shots[0].K(1, 1), 510);
  EXPECT_EQ(shots[0].C_world, Eigen::Vector3d(0, 0, -5));
  // The origin lies 5 in front of this camera, on the principal point.
  const auto uv = shots[0].project(Eigen::Vector3d::Zero());
  ASSERT_TRUE(uv);
  EXPECT_NEAR((*uv - Eigen::Vector2d(319.5, 239.5)).norm(), 0, 1e-12);
  EXPECT_EQ(error_of([] {
              parse_openmvs_cameras("a.jpg 640 480 500 500 1 1  1 0 0 0 1 0 0 0 1  0 0 -5  0 0 4  1\n", "c.txt", ".");
            }),
            "c.txt:1: expected t = -R C (the camera's translation and centre disagree)");
  EXPECT_EQ(error_of([] { parse_openmvs_cameras("a.jpg 640 x\n", "c.txt", "."); }),
            "c.txt:1: expected 23 fields 'image width height fx fy cx cy R00..R22 Cx Cy Cz tx ty tz present', got 3");
  EXPECT_EQ(error_of([] {
              parse_openmvs_cameras("\na.jpg 640 480 nan 500 1 1  1 0 0 0 1 0 0 0 1  0 0 -5  0 0 5  1\n", "c.txt", ".");
            }),
            "c.txt:2: expected a finite number (fx), got 'nan'");
}

TEST(OpenMvsText, ParsesPointsWithVisibility) {
  const Cloud c = parse_openmvs_points("1 2 3 10 20 30 2 0 2\n-1 0 0.5 0 0 0 0\n", "p.txt", 3);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[0], Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(c.colors[0], (Rgb8{10, 20, 30}));
  EXPECT_EQ(c.views[0], (std::vector<int>{0, 2}));
  EXPECT_TRUE(c.visible_in(0, 2));
  EXPECT_FALSE(c.visible_in(0, 1));
  EXPECT_TRUE(c.visible_in(1, 1));  // no visibility listed: every shot
  EXPECT_EQ(error_of([] { parse_openmvs_points("1 2 3 10 20 30 2 0 3\n", "p.txt", 3); }),
            "p.txt:1: expected an integer in [0, 2] (view index), got '3'");
  EXPECT_EQ(error_of([] { parse_openmvs_points("1 2 3 10 20 30 2 1 1\n", "p.txt", 3); }),
            "p.txt:1: expected each view once, got view 1 twice");
  EXPECT_EQ(error_of([] { parse_openmvs_points("1 2 3 10 20 300 0\n", "p.txt", 3); }),
            "p.txt:1: expected an integer in [0, 255] (blue), got '300'");
}

TEST(Middlebury, ParsesProjectionAndCentre) {
  const std::string text =
      "1\nx.png 1520.4 0 302.32 0 1525.9 246.87 0 0 1 0 1 0 -1 0 0 0 0 1 0.01 -0.02 0.5\n";
  const std::vector<Shot> shots = parse_middlebury_par(text, "par.txt", "/d");
  ASSERT_EQ(shots.size(), 1u);
  // P = K [R | t]: the camera's own P equals that.
  Matrix34d Rt;
  Rt << 0, 1, 0, 0.01, -1, 0, 0, -0.02, 0, 0, 1, 0.5;
  Eigen::Matrix3d K;
  K << 1520.4, 0, 302.32, 0, 1525.9, 246.87, 0, 0, 1;
  EXPECT_LT((shots[0].P() - K * Rt).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(shots[0].width, 640);
  EXPECT_EQ(error_of([] { parse_middlebury_par("2\nx.png 1 0 0 0 1 0 0 0 1 1 0 0 0 1 0 0 0 1 0 0 1\n", "p.txt", "."); }),
            "p.txt:2: expected 2 images (the first line), got 1");
  EXPECT_EQ(error_of([] { parse_middlebury_par("", "p.txt", "."); }),
            "p.txt: expected the number of images on the first line, got no data");
}

TEST(Network, ValidateRejectsANonRotation) {
  Network n;
  n.source = "net";
  n.shots.push_back(testing::look_at("a.png", {0, -5, 0}, {0, 0, 0}));
  n.validate();
  n.shots[0].R_camera_world(0, 0) *= 1.01;
  EXPECT_EQ(error_of([&] { n.validate(); }),
            "net: shot 'a.png': expected a rotation R (R R^T = I within 1e-6, det R = +1)");
  n.shots[0] = testing::look_at("a.png", {0, -5, 0}, {0, 0, 0});
  n.shots.push_back(n.shots[0]);
  EXPECT_EQ(error_of([&] { n.validate(); }), "net: shot 'a.png': the name is used by two shots");
}

TEST(RunReport, ParsesCameraAndKeyframes) {
  const RunReport r = parse_run_report(
      R"({"input": "d", "camera": "fx=517.3 fy=516.5 cx=318.6 cy=255.3 640x480",
          "per_frame": [{"timestamp_s": 1.25, "state": "tracked", "keyframe": true},
                        {"timestamp_s": 1.5, "state": "lost", "keyframe": false},
                        {"timestamp_s": 1.75, "state": "tracked", "keyframe": false}]})",
      "report.json");
  EXPECT_EQ(r.input, "d");
  EXPECT_EQ(r.camera.fx, 517.3);
  EXPECT_EQ(r.camera.cy, 255.3);
  EXPECT_EQ(r.camera.height, 480);
  EXPECT_EQ(r.keyframe_stamps_s, std::vector<double>{1.25});
  EXPECT_EQ(r.tracked_stamps_s, (std::vector<double>{1.25, 1.75}));
  EXPECT_EQ(error_of([] { parse_run_report(R"({"input": "d", "camera": "525"})", "r.json"); }),
            "r.json: expected \"camera\": \"fx=.. fy=.. cx=.. cy=.. WxH\", got '525'");
  EXPECT_EQ(error_of([] { parse_run_report("{", "r.json"); }),
            "r.json: expected a run's report.json (JSON), got a syntax error at byte 2");
}

// Issue 36: report.json's "camera" is an object; a report of either form reads as the same camera.
TEST(RunReport, ReadsTheStructuredCamera) {
  const RunReport r = parse_run_report(
      R"({"input": "d", "camera": {"fx": 517.3, "fy": 516.5, "cx": 318.6, "cy": 255.3, "width": 640, "height": 480},
          "per_frame": [{"timestamp_s": 1.25, "state": "tracked", "keyframe": true}]})",
      "report.json");
  EXPECT_EQ(r.camera.fx, 517.3);
  EXPECT_EQ(r.camera.fy, 516.5);
  EXPECT_EQ(r.camera.cx, 318.6);
  EXPECT_EQ(r.camera.cy, 255.3);
  EXPECT_EQ(r.camera.width, 640);
  EXPECT_EQ(r.camera.height, 480);
  // a camera object outside the bounds a camera file is held to is refused naming the report
  const std::string error = error_of([] {
    parse_run_report(R"({"input": "d", "camera": {"fx": -1, "fy": 516.5, "cx": 318.6, "cy": 255.3, "width": 640,
                        "height": 480}, "per_frame": []})",
                     "r.json");
  });
  EXPECT_NE(error.find("r.json"), std::string::npos) << error;
  EXPECT_NE(error.find("fx within"), std::string::npos) << error;
}

TEST(RunNetwork, KeyframesBecomeShotsWithTheTrackedPosesAndTheMeshIsTheCloud) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / ("hf_pg_run_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "data" / "rgb");
  fs::create_directories(root / "run");
  std::ofstream(root / "data" / "rgb.txt") << "# colour\n1.000000 rgb/1.000000.png\n1.500000 rgb/1.500000.png\n";
  std::ofstream(root / "data" / "depth.txt") << "1.000000 depth/1.png\n1.500000 depth/2.png\n";
  write_color_png((root / "data" / "rgb" / "1.500000.png").string(), ColorImage(8, 6, Rgb8{1, 2, 3}));
  const SE3 T(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())), Eigen::Vector3d(1, 2, 3));
  write_tum_trajectory((root / "run" / "trajectory.txt").string(), {{1.0, SE3()}, {1.5, T}});
  std::ofstream(root / "run" / "report.json")
      << R"({"input": ")" << (root / "data").string() << R"(", "camera": "fx=10 fy=11 cx=3.5 cy=2.5 8x6",
             "per_frame": [{"timestamp_s": 1.0, "state": "tracked", "keyframe": false},
                           {"timestamp_s": 1.5, "state": "tracked", "keyframe": true}]})";
  PointCloud mesh_vertices;
  mesh_vertices.positions = {{0, 0, 5}, {1, 0, 5}};
  write_ply((root / "run" / "mesh.ply").string(), mesh_vertices);
  const Network n = read_network((root / "run").string());
  ASSERT_EQ(n.shots.size(), 1u);
  const Shot& s = n.shots[0];
  EXPECT_EQ(s.name, "1.500000.png");
  EXPECT_TRUE(s.image_available);
  EXPECT_EQ(load_shot_image(s).width(), 8);
  EXPECT_EQ(s.K(1, 1), 11);
  // x_cam = R (X - C) is T_world_camera^-1.
  const Eigen::Vector3d X(0.5, -1, 7);
  EXPECT_LT((s.to_camera(X) - T.inverse() * X).norm(), 1e-12);
  EXPECT_EQ(n.cloud.size(), 2u);
  RunShotsOptions every;
  every.keyframes_only = false;
  const Network all = read_run_network((root / "run").string(), every);
  ASSERT_EQ(all.shots.size(), 2u);
  EXPECT_FALSE(all.shots[0].image_available);  // 1.000000.png was never written
  fs::remove_all(root);
}

TEST(Sketch, ParsesAndChecksStructure) {
  const Sketch s = parse_sketch(
      R"({"polygons": [{"id": "p0", "views": [{"shot": "a.png", "points": [[0, 0], [10, 0], [10, 10]]},
                                               {"shot": "b.png", "points": [[1, 0], [11, 0], [11, 10]]}]},
                       {"id": "p1", "views": [{"shot": "a.png", "points": [[2, 2], [4, 2], [4, 4]]}],
                        "same_plane_as": "p0"}]})",
      "s.json");
  ASSERT_EQ(s.polygons.size(), 2u);
  EXPECT_EQ(s.polygons[0].views[1].points[2], Eigen::Vector2d(11, 10));
  EXPECT_EQ(s.polygons[1].same_plane_as, "p0");
  // What `model --transfer` writes (transferred.json) reads back as the same sketch.
  const Sketch again = parse_sketch(format_sketch_json(s), "t.json");
  ASSERT_EQ(again.polygons.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(again.polygons[i].id, s.polygons[i].id);
    EXPECT_EQ(again.polygons[i].same_plane_as, s.polygons[i].same_plane_as);
    ASSERT_EQ(again.polygons[i].views.size(), s.polygons[i].views.size());
    for (size_t k = 0; k < s.polygons[i].views.size(); ++k) {
      EXPECT_EQ(again.polygons[i].views[k].shot, s.polygons[i].views[k].shot);
      EXPECT_EQ(again.polygons[i].views[k].points, s.polygons[i].views[k].points);
    }
  }
  const auto bad = [](const std::string& t) { return error_of([&] { parse_sketch(t, "s.json"); }); };
  EXPECT_EQ(bad(R"({"polygons": [{"id": "p", "views": [{"shot": "a", "points": [[0,0],[10,10],[10,0],[0,10]]}]}]})"),
            "s.json: polygon 'p' view 1: the outline intersects itself (or repeats a vertex)");
  EXPECT_EQ(bad(R"({"polygons": [{"id": "p", "views": [{"shot": "a", "points": [[0,0],[1,0],[1,1]]},
                                                      {"shot": "b", "points": [[0,0],[1,0],[1,1],[0,1]]}]}]})"),
            "s.json: polygon 'p' view 2: expected 3 points (vertex k of every view is the same corner), got 4");
  EXPECT_EQ(bad(R"({"polygons": [{"id": "p", "same_plane_as": "q", "views": [{"shot": "a", "points": [[0,0],[1,0],[1,1]]}]}]})"),
            "s.json: polygon 'p': \"same_plane_as\" 'q' names no polygon listed before this one");
  EXPECT_EQ(bad(R"({"polygons": [{"id": "p", "views": [{"shot": "a", "points": [[0,0],[1,0]]}]}]})"),
            "s.json: polygon 'p' view 1: expected 3 to 1000 points, got 2");
  // Issue 35: a far point is outside every image, not a self-intersection (the cross products overflowed).
  EXPECT_EQ(bad(R"({"polygons": [{"id": "p", "views": [{"shot": "a", "points": [[0,0],[1e308,1e308],[1,0]]}]}]})"),
            "s.json: polygon 'p' view 1: point 2 (1e+308, 1e+308) lies outside any image (beyond 1e6 px)");
  Network n;
  n.source = "net";
  n.shots.push_back(testing::look_at("a.png", {0, -5, 0}, {0, 0, 0}, 500, 20, 20));
  EXPECT_EQ(error_of([&] { check_sketch_shots(s, n, "s.json"); }),
            "s.json: polygon 'p0' view 2: no shot named 'b.png' in net");
  n.shots.push_back(testing::look_at("b.png", {1, -5, 0}, {0, 0, 0}, 500, 11, 11));
  EXPECT_EQ(error_of([&] { check_sketch_shots(s, n, "s.json"); }),
            "s.json: polygon 'p0' view 2: point (11, 0) lies outside the 11x11 image");
}

TEST(SharedData, SceauxReadsTenPresentShotsAndTheSparseCloud) {
  const std::string dir = kReadersShared + "/data/photogrammetry_sceaux_castle";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not found (../shared absent)";
  const Network n = read_network(dir);
  ASSERT_EQ(n.shots.size(), 11u);
  int present = 0;
  for (const Shot& s : n.shots) present += s.image_available;
  EXPECT_EQ(present, 10);  // 00010.jpg is absent (PROVENANCE.md)
  EXPECT_FALSE(n.shots[10].image_available);
  EXPECT_EQ(n.shots[0].name, "00000.jpg");
  EXPECT_EQ(n.shots[0].width, 2832);
  EXPECT_EQ(n.cloud.size(), 12683u);
  // PROVENANCE.md: 45,378 of 45,518 point-view pairs project in front of the camera and inside the image.
  size_t pairs = 0, inside = 0;
  for (size_t i = 0; i < n.cloud.size(); ++i)
    for (const int v : n.cloud.views[i]) {
      ++pairs;
      const auto uv = n.shots[size_t(v)].project(n.cloud.positions[i]);
      inside += uv && n.shots[size_t(v)].in_image(*uv);
    }
  EXPECT_EQ(pairs, 45518u);
  EXPECT_NEAR(double(inside), 45378.0, 5.0);
}

TEST(SharedData, MiddleburyReads47CamerasOf19Images) {
  const std::string dir = kReadersShared + "/data/photogrammetry_middlebury_templeRing19";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not found (../shared absent)";
  const Network n = read_network(dir);
  ASSERT_EQ(n.shots.size(), 47u);
  int present = 0;
  for (const Shot& s : n.shots) present += s.image_available;
  EXPECT_EQ(present, 19);
  const Shot& s = n.shots[size_t(n.shot_index("templeR0013.png"))];
  EXPECT_TRUE(s.image_available);
  EXPECT_EQ(load_shot_image(s).width(), 640);
  // The object's bounding-box centre (README.txt) lies in front of every camera, inside its image.
  const Eigen::Vector3d centre = 0.5 * (Eigen::Vector3d(-0.023121, -0.038009, -0.091940) +
                                        Eigen::Vector3d(0.078626, 0.121636, -0.017395));
  for (const Shot& shot : n.shots) {
    const auto uv = shot.project(centre);
    ASSERT_TRUE(uv) << shot.name;
    EXPECT_TRUE(shot.in_image(*uv)) << shot.name;
  }
}

// scene.mvs bytes as OpenMVS's serialiser writes them (photogrammetry/scene_mvs.h).
struct MvsBytes {
  std::string b;
  template <class T>
  MvsBytes& put(T v) {
    b.append(reinterpret_cast<const char*>(&v), sizeof v);
    return *this;
  }
  MvsBytes& str(const std::string& s) {
    put(std::uint64_t(s.size()));
    b += s;
    return *this;
  }
  MvsBytes& mat(const Eigen::Matrix3d& M) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) put(M(r, c));
    return *this;
  }
  MvsBytes& vec(const Eigen::Vector3d& v) { return put(v.x()).put(v.y()).put(v.z()); }
};

Eigen::Matrix3d rotation(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

// Version 3: one platform whose camera is mounted rotated and offset, two poses; image b has no pose.
std::string small_scene(std::uint32_t width = 640, std::uint32_t version = 3) {
  MvsBytes m;
  m.b = "MVSI";
  m.put(version).put(std::uint32_t(0));
  Eigen::Matrix3d K;
  K << 500, 0, 319.5, 0, 510, 239.5, 0, 0, 1;
  m.put(std::uint64_t(1)).str("platform0").put(std::uint64_t(1)).str("cam");
  if (version >= 4) m.str("RGB");
  m.put(width).put(std::uint32_t(480)).mat(K).mat(rotation(0.05, {0, 0, 1})).vec({0.1, 0, 0});
  m.put(std::uint64_t(2)).mat(Eigen::Matrix3d::Identity()).vec({0, 0, -5});
  m.mat(rotation(0.2, {0, 1, 0})).vec({1, 0, -5});
  m.put(std::uint64_t(3));
  const auto image = [&](const std::string& name, std::uint32_t pose, std::uint32_t id) {
    m.str(name);
    if (version >= 5) m.str("");
    m.put(std::uint32_t(0)).put(std::uint32_t(0)).put(pose);
    if (version >= 3) m.put(id);
    if (version >= 7) m.put(0.f).put(0.f).put(0.f).put(std::uint64_t(0));
  };
  image("images/a.jpg", 0, 0);
  image("images/b.jpg", 0xFFFFFFFFu, 1);
  image("images/c.jpg", 1, 2);
  m.put(std::uint64_t(2));
  m.put(0.f).put(0.f).put(0.f).put(std::uint64_t(2)).put(std::uint32_t(0)).put(1.f).put(std::uint32_t(2)).put(0.5f);
  m.put(0.5f).put(-0.25f).put(1.f).put(std::uint64_t(1)).put(std::uint32_t(1)).put(0.f);
  m.put(std::uint64_t(0));                                                       // normals
  m.put(std::uint64_t(2)).put(std::uint8_t(10)).put(std::uint8_t(20)).put(std::uint8_t(30));  // B, G, R
  m.put(std::uint8_t(40)).put(std::uint8_t(50)).put(std::uint8_t(60));
  m.put(std::uint64_t(0)).put(std::uint64_t(0)).put(std::uint64_t(0));           // lines
  for (int k = 0; k < 16; ++k) m.put(k % 5 == 0 ? 1.0 : 0.0);                   // transform
  if (version >= 6)
    for (int k = 0; k < 15; ++k) m.put(0.0);
  return m.b;
}

TEST(SceneMvs, ComposesEachImagesCameraFromItsPlatformAndDropsUnposedImages) {
  for (const std::uint32_t version : {3u, 7u}) {
    const Network n = parse_scene_mvs(small_scene(640, version), "s.mvs", "/root");
    ASSERT_EQ(n.shots.size(), 2u) << "image b has no pose";
    EXPECT_EQ(n.shots[0].name, "a.jpg");
    EXPECT_EQ(n.shots[1].name, "c.jpg");
    EXPECT_EQ(n.shots[1].image_path, "/root/images/c.jpg");
    EXPECT_EQ(n.shots[0].width, 640);
    EXPECT_EQ(n.shots[0].K(1, 1), 510);
    // x_cam = R_c (R_p (X - C_p) - C_c): R = R_c R_p, C = R_p^T C_c + C_p.
    const Eigen::Matrix3d Rc = rotation(0.05, {0, 0, 1}), Rp = rotation(0.2, {0, 1, 0});
    EXPECT_LT((n.shots[1].R_camera_world - Rc * Rp).norm(), 1e-15);
    EXPECT_LT((n.shots[1].C_world - (Rp.transpose() * Eigen::Vector3d(0.1, 0, 0) + Eigen::Vector3d(1, 0, -5))).norm(),
              1e-15);
    ASSERT_EQ(n.cloud.size(), 2u);
    EXPECT_EQ(n.cloud.positions[1], Eigen::Vector3d(0.5, -0.25, 1.0));
    EXPECT_EQ(n.cloud.views[0], (std::vector<int>{0, 1}));  // images 0 and 2 are shots 0 and 1
    EXPECT_TRUE(n.cloud.views[1].empty());                   // its one view was the unposed image
    EXPECT_EQ(n.cloud.colors[0], (Rgb8{30, 20, 10}));
  }
}

TEST(SceneMvs, MalformedScenesFailWithTheByteNeverACrash) {
  const std::string good = small_scene();
  for (size_t n = 0; n < good.size(); ++n) {  // every truncation
    const std::string e = error_of([&] { parse_scene_mvs(good.substr(0, n), "s.mvs", "."); });
    EXPECT_EQ(e.rfind("s.mvs: at byte ", 0), 0u) << n << ": " << e;
  }
  EXPECT_EQ(error_of([&] { parse_scene_mvs(good + "x", "s.mvs", "."); }),
            "s.mvs: at byte " + std::to_string(good.size()) + ": expected the end of the scene, got 1 more bytes");
  EXPECT_EQ(error_of([] { parse_scene_mvs(small_scene(640, 8), "s.mvs", "."); }),
            "s.mvs: at byte 8: expected a scene version up to 7, got 8");
  EXPECT_NE(error_of([] { parse_scene_mvs(small_scene(0), "s.mvs", "."); }).find("normalised K"), std::string::npos);
  std::string huge = good;  // the platform count: far more than the bytes could hold
  const std::uint64_t count = 1ull << 40;
  std::memcpy(&huge[12], &count, 8);
  EXPECT_NE(error_of([&] { parse_scene_mvs(huge, "s.mvs", "."); }).find("expected a platform count of at most"),
            std::string::npos);
}

TEST(SharedData, SceauxSceneMvsEqualsItsTextDump) {
  const std::string dir = kReadersShared + "/data/photogrammetry_sceaux_castle";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not found (../shared absent)";
  const Network binary = read_scene_mvs(dir + "/scene.mvs");
  const Network text = read_openmvs_text(dir);
  ASSERT_EQ(binary.shots.size(), text.shots.size());
  for (size_t s = 0; s < text.shots.size(); ++s) {
    EXPECT_EQ(binary.shots[s].name, text.shots[s].name);
    EXPECT_EQ(binary.shots[s].image_available, text.shots[s].image_available) << binary.shots[s].name;
    EXPECT_EQ(binary.shots[s].width, text.shots[s].width);
    // The dump prints doubles with enough digits for 1e-9 relative.
    EXPECT_LT((binary.shots[s].K - text.shots[s].K).norm(), 1e-9 * text.shots[s].K.norm());
    EXPECT_LT((binary.shots[s].R_camera_world - text.shots[s].R_camera_world).norm(), 1e-9);
    EXPECT_LT((binary.shots[s].C_world - text.shots[s].C_world).norm(), 1e-9 * (1 + text.shots[s].C_world.norm()));
  }
  ASSERT_EQ(binary.cloud.size(), text.cloud.size());
  double worst = 0.0;
  for (size_t i = 0; i < text.cloud.size(); ++i) {
    worst = std::max(worst, (binary.cloud.positions[i] - text.cloud.positions[i]).norm() /
                                (1.0 + text.cloud.positions[i].norm()));
    ASSERT_EQ(binary.cloud.views[i], text.cloud.views[i]) << "point " << i;
    ASSERT_EQ(binary.cloud.colors[i], text.cloud.colors[i]) << "point " << i;
  }
  EXPECT_LT(worst, 1e-6);  // float coordinates printed in decimal
}

}  // namespace
}  // namespace hf::photogrammetry
