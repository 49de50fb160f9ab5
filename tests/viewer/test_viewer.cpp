// The viewer: key handling and run control without a display, and the OpenGL render of a fused sphere's mesh
// against the CPU raycast of the same TSDF from the same pose (needs a display: run under xvfb-run; skips with a
// message without one).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <thread>

#include "../common/analytic_depth.h"
#include "core/error.h"
#include "fusion/integrate.h"
#include "fusion/mesh.h"
#include "fusion/raycast.h"
#include "io/image_io.h"
#include "io/ply.h"
#include "viewer/gl_context.h"
#include "viewer/mesh_renderer.h"
#include "viewer/run_viewer.h"
#include "viewer/sketch_window.h"
#include "viewer/view_controller.h"
#include "viewer/view_files.h"

using namespace std::chrono_literals;

TEST(ViewController, PauseHoldsTheRunAndStepReleasesOneFrame) {
  hf::viewer::ViewController c;
  c.wait_for_turn();  // not paused: returns at once
  c.key(hf::viewer::Key::pause);
  EXPECT_TRUE(c.paused());
  std::atomic<int> frames{0};
  std::thread run([&] {
    for (int i = 0; i < 2; ++i) {
      c.wait_for_turn();
      ++frames;
    }
  });
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(frames.load(), 0);  // held
  c.key(hf::viewer::Key::step);
  while (frames.load() < 1) std::this_thread::sleep_for(1ms);
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(frames.load(), 1);  // exactly one frame per step
  c.key(hf::viewer::Key::pause);  // resume
  run.join();
  EXPECT_EQ(frames.load(), 2);
}

TEST(ViewController, QuitReleaseSaveAndViewKeys) {
  hf::viewer::ViewController c;
  c.key(hf::viewer::Key::pause);
  std::thread run([&] { c.wait_for_turn(); });
  c.key(hf::viewer::Key::quit);  // ends the run even while paused
  run.join();
  EXPECT_TRUE(c.quit_flag()->load());
  EXPECT_FALSE(c.take_save_request());
  c.key(hf::viewer::Key::save_mesh);
  EXPECT_TRUE(c.take_save_request());
  EXPECT_FALSE(c.take_save_request());  // once per key press
  // Orbiting stops following the camera; reset brings both back.
  c.reset(hf::SE3());
  const hf::SE3 before = c.T_world_view();
  c.drag(100, 0);
  EXPECT_FALSE(c.follow());
  EXPECT_GT((c.T_world_view().translation() - before.translation()).norm(), 0.1);
  c.key(hf::viewer::Key::reset_view);
  c.reset(hf::SE3());
  EXPECT_TRUE(c.follow());
  EXPECT_LT((c.T_world_view().translation() - before.translation()).norm(), 1e-9);
  // The view looks at the target: the point 1.5 m in front of the tracked camera projects to the view's centre.
  const Eigen::Vector3d in_view = c.T_world_view().inverse() * Eigen::Vector3d(0, 0, 1.5);
  EXPECT_NEAR(in_view.x() / in_view.z(), 0.0, 1e-9);
  EXPECT_NEAR(in_view.y() / in_view.z(), 0.0, 1e-9);
}

// The sketch window's input, without a window: keys send the session's events, a click maps to the image pixel
// under it (pixel centres at integers, drawn at `scale` from the top-left corner).
TEST(SketchWindow, KeysAndClicksMapToSessionEvents) {
  hf::photogrammetry::Network n;
  for (const char* name : {"a.png", "b.png", "c.png"}) n.shots.push_back({name, "", false, 64, 48});
  using hf::viewer::sketch_key_event;
  EXPECT_EQ(sketch_key_event(257 /* GLFW_KEY_ENTER */, 0, n, 0), "close");
  EXPECT_EQ(sketch_key_event(259 /* GLFW_KEY_BACKSPACE */, 0, n, 0), "undo");
  EXPECT_EQ(sketch_key_event(78 /* GLFW_KEY_N */, 0, n, 0), "new");
  EXPECT_EQ(sketch_key_event(80 /* GLFW_KEY_P */, 0, n, 0), "same_plane");
  EXPECT_EQ(sketch_key_event(258 /* GLFW_KEY_TAB */, 0, n, 2), "shot a.png");        // wraps round
  EXPECT_EQ(sketch_key_event(258, 1 /* GLFW_MOD_SHIFT */, n, 0), "shot c.png");     // backwards
  EXPECT_FALSE(sketch_key_event(65 /* GLFW_KEY_A */, 0, n, 0));
  // At scale 2 window pixel (0.5 .. 2.5) covers image pixel 0's footprint [-0.5, 0.5] x 2; its centre is at 1.
  EXPECT_EQ(hf::viewer::window_to_image(1.0, 1.0, 2.0), Eigen::Vector2d(0.0, 0.0));
  EXPECT_EQ(hf::viewer::window_to_image(21.0, 9.0, 2.0), Eigen::Vector2d(10.0, 4.0));
}

TEST(Viewer, ScreenshotNames) {
  EXPECT_EQ(hf::viewer::numbered_screenshot("shots/v.png", 120), "shots/v_000120.png");
}

namespace {

// A camera with its principal point at the image centre.
hf::PinholeCamera centred_camera(int width, int height, double f_px) {
  hf::PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = f_px;
  c.cx = (width - 1) / 2.0;
  c.cy = (height - 1) / 2.0;
  return c;
}

// A 0.3 m sphere fused from five views on an arc, 1 cm voxels.
hf::fusion::VoxelBlockGrid fused_sphere(const hf::PinholeCamera& camera, const Eigen::Vector3d& centre) {
  hf::fusion::VolumeParams params;
  params.voxel_m = 0.01;
  hf::fusion::VoxelBlockGrid grid(params);
  for (int k = -2; k <= 2; ++k) {
    const double a = 0.15 * k;
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.block<3, 3>(0, 0) = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.block<3, 1>(0, 3) = centre + Eigen::Vector3d(std::sin(a) * 1.0, 0, -std::cos(a) * 1.0);
    const hf::SE3 pose = hf::SE3::from_matrix(T);
    hf::fusion::integrate(grid, hf::testing::render_sphere_depth(camera, pose, centre, 0.3), hf::ColorImage(),
                          camera, pose);
  }
  return grid;
}

}  // namespace

TEST(Viewer, GlRenderOfTheMeshMatchesTheCpuRaycast) {
  std::unique_ptr<hf::viewer::GlContext> context;
  try {
    context = std::make_unique<hf::viewer::GlContext>(64, 64, "test", false);
  } catch (const hf::Error& e) {
    GTEST_SKIP() << "no display for OpenGL (run under xvfb-run): " << e.what();
  }
  const hf::PinholeCamera camera = centred_camera(160, 120, 130.0);
  const Eigen::Vector3d centre(0.1, -0.05, 1.2);
  const hf::fusion::VoxelBlockGrid grid = fused_sphere(camera, centre);
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.block<3, 3>(0, 0) = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.block<3, 1>(0, 3) = centre + Eigen::Vector3d(0.1, 0.0, -1.0);
  const hf::SE3 pose = hf::SE3::from_matrix(T);

  const hf::ColorImage cpu = hf::fusion::raycast(grid, camera, pose).shaded;
  hf::viewer::MeshRenderer renderer;
  renderer.set_mesh(hf::fusion::extract_mesh(grid));
  const hf::ColorImage gl = renderer.render(camera, pose);
  ASSERT_EQ(gl.width(), cpu.width());

  // Silhouettes: where marching cubes' linear edge crossings and the ray's refined trilinear crossing disagree on
  // whether a pixel sees the surface at all; a one-pixel band at most, so the masks overlap almost entirely.
  size_t both = 0, either = 0;
  double sq = 0.0, sq_all = 0.0;
  for (size_t i = 0; i < cpu.size(); ++i) {
    const bool a = cpu.pixels()[i].r > 0, b = gl.pixels()[i].r > 0;
    either += a || b;
    const double d = double(cpu.pixels()[i].r) - double(gl.pixels()[i].r);
    sq_all += d * d;
    if (a && b) {
      ++both;
      sq += d * d;
    }
  }
  ASSERT_GT(both, 2000u) << "the sphere should fill a good part of the image";
  const double iou = double(both) / double(either);
  // Inside, the two renderers evaluate one shading formula on two different normals: the mesh's, interpolated
  // over marching-cubes triangles, and the raycast's TSDF gradient at the refined crossing. Each deviates from the
  // true sphere's normal by about 1.7 degrees on average on a 1 cm grid (README: fused-sphere normals), RMS up to
  // 2.5; independent, their difference has an RMS up to 2 x 2.5 = 5 degrees (0.087 rad) in the worst case.
  // dI/dtheta of 0.2 + 0.7 c + 0.1 c^16 averages about 0.6 per radian over a sphere's visible cap (0.7 sin theta
  // weighted by area, plus the small specular term), so the RMS difference stays below 0.087 * 0.6 * 255 = 13.4
  // levels: PSNR >= 25.5 dB inside. (Measured: 28.7 dB with llvmpipe.) A pose or projection error shows in the IoU.
  const double psnr_inside = 10.0 * std::log10(255.0 * 255.0 / std::max(sq / double(both), 1e-9));
  const double psnr_all = 10.0 * std::log10(255.0 * 255.0 / std::max(sq_all / double(cpu.size()), 1e-9));
  EXPECT_GE(iou, 0.97) << "silhouettes disagree";
  EXPECT_GE(psnr_inside, 25.5);
  // Whole image, silhouette pixels included (a band of ~perimeter pixels each wrong by up to the full shade):
  // 2 pi r of 60 px is 4 % of 19200 pixels; at 200 levels error that caps the MSE near 1600, PSNR >= 16 dB.
  EXPECT_GE(psnr_all, 16.0);
  std::cout << "GL vs CPU raycast: IoU " << iou << ", PSNR inside " << psnr_inside << " dB, whole image " << psnr_all
            << " dB (" << context->renderer() << ")\n";
  if (const char* dir = std::getenv("HF_VIEWER_TEST_OUT")) {
    hf::write_color_png(std::string(dir) + "/gl.png", gl);
    hf::write_color_png(std::string(dir) + "/cpu.png", cpu);
  }
}

// What `run --screenshot-every` writes (and the live window's model view shows): the model raycast from the
// following free camera, with the frustum drawn over it. The raycast is the CPU one, shown texel for texel, so the
// screenshot equals fusion::raycast of the same map from the same view (model_view_options()) at every pixel no
// line covers; the lines cover at most one pixel per step of their longer image axis plus one per segment.
TEST(Viewer, ScreenshotIsTheModelRaycastWithTheFrustum) {
  const hf::PinholeCamera camera = centred_camera(320, 240, 260.0);
  const Eigen::Vector3d centre(0.1, -0.05, 1.2);
  const hf::fusion::VoxelBlockGrid grid = fused_sphere(camera, centre);
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.block<3, 1>(0, 3) = centre + Eigen::Vector3d(0.0, 0.0, -1.2);
  const hf::SE3 pose = hf::SE3::from_matrix(T);
  const std::string path = ::testing::TempDir() + "/viewer_model_view.png";
  hf::viewer::RunViewerOptions options;
  options.window = false;
  options.screenshot = path;
  options.screenshot_every = 1;
  std::unique_ptr<hf::viewer::RunViewer> viewer;
  try {
    viewer = std::make_unique<hf::viewer::RunViewer>(camera, options);
  } catch (const hf::Error& e) {
    GTEST_SKIP() << "no display or EGL for OpenGL: " << e.what();
  }
  hf::RgbdFrame frame;
  frame.depth = hf::DepthImage(camera.width, camera.height);
  frame.color = hf::ColorImage(camera.width, camera.height);
  hf::slam::FrameResult r;
  r.state = hf::slam::TrackState::tracked;
  r.pose_valid = r.integrated = true;
  r.T_world_camera = pose;
  viewer->observe(frame, r, grid);
  viewer->finish(hf::fusion::extract_mesh(grid), pose);
  const hf::ColorImage shot = hf::load_color(hf::viewer::numbered_screenshot(path, 0));

  hf::viewer::ViewController follow;
  follow.reset(pose);
  const hf::SE3 T_world_view = follow.T_world_view();
  const hf::fusion::RaycastResult cpu = hf::fusion::raycast(grid, camera, T_world_view, hf::viewer::model_view_options());
  const hf::ColorImage expected = hf::fusion::colored_shading(cpu);  // grey: the sphere was fused without colour
  ASSERT_EQ(shot.width(), expected.width());
  ASSERT_GT(cpu.hit_count, 3000) << "the sphere should fill a good part of the view";
  // The frustum's pixels: each segment's projection in the view (both ends lie in front of it).
  const hf::viewer::Polyline frustum = hf::viewer::camera_frustum(camera, pose, 0.2, {240, 220, 40});
  double line_px = 0.0;
  for (size_t i = 0; i + 1 < frustum.points_world.size(); i += 2) {
    const Eigen::Vector3d a = T_world_view.inverse() * frustum.points_world[i].cast<double>();
    const Eigen::Vector3d b = T_world_view.inverse() * frustum.points_world[i + 1].cast<double>();
    ASSERT_GT(std::min(a.z(), b.z()), 0.1);
    const Eigen::Vector2d d = camera.project(a) - camera.project(b);
    line_px += std::ceil(d.cwiseAbs().maxCoeff()) + 1.0;
  }
  size_t differ = 0, yellow = 0;
  for (size_t i = 0; i < shot.size(); ++i) {
    const hf::Rgb8 s = shot.pixels()[i], c = expected.pixels()[i];
    differ += s.r != c.r || s.g != c.g || s.b != c.b;
    yellow += s.r == 240 && s.g == 220 && s.b == 40;
  }
  EXPECT_LE(double(differ), line_px) << "pixels off the lines differ from the CPU raycast";
  EXPECT_GE(double(yellow), 0.5 * line_px) << "the frustum is not drawn";
  std::cout << "model view: " << cpu.hit_count << " surface pixels, " << differ << " differ from the CPU raycast, "
            << yellow << " frustum pixels (bound " << line_px << ")\n";
}

namespace {

// An axis-aligned box as 12 triangles, every vertex of one colour.
hf::TriangleMesh box_mesh(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, hf::Rgb8 colour) {
  hf::TriangleMesh m;
  for (int k = 0; k < 8; ++k) {
    m.vertices.emplace_back((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
    m.colors.push_back(colour);
  }
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    m.triangles.emplace_back(f[0], f[1], f[2]);
    m.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return m;
}

}  // namespace

// view of a bare mesh (no saved camera): the view looks at the bounding box's centre (it projects to the principal
// point) from outside, and every corner of the box projects inside the image, within the 5 % margin and touching
// it on some side (so the mesh is not a speck); for boxes far from the origin, flat, tall and long.
TEST(Viewer, FrameMeshKeepsTheWholeBoxInView) {
  const hf::PinholeCamera camera = hf::PinholeCamera::preset("ros");
  const std::pair<Eigen::Vector3f, Eigen::Vector3f> boxes[] = {
      {{4, -3, 7}, {6, -2, 10}},       // off the origin, behind nothing: the old view looked past it
      {{-2, 0, -2}, {2, 0.01f, 2}},    // a floor
      {{0, -5, 0}, {0.2f, 5, 0.2f}},   // a pole
      {{-50, -1, 3}, {50, 1, 4}},      // a long wall
      {{1, 1, 1}, {1.2f, 1.1f, 1.1f}},  // a small thing
  };
  for (const auto& [lo, hi] : boxes) {
    const hf::TriangleMesh mesh = box_mesh(lo, hi, {200, 200, 200});
    const hf::SE3 T = hf::viewer::frame_mesh(mesh, camera);
    const Eigen::Vector3d centre = T.inverse() * (0.5f * (lo + hi)).cast<double>();
    ASSERT_GT(centre.z(), 0.0);
    const Eigen::Vector2d c = camera.project(centre);
    EXPECT_NEAR(c.x(), camera.cx, 1e-3);  // SE3 keeps the rotation as a quaternion: rounding of 1e-7 rad
    EXPECT_NEAR(c.y(), camera.cy, 1e-3);
    double slack = 1e9;  // the least distance of a corner to the margin
    for (const Eigen::Vector3f& v : mesh.vertices) {
      const Eigen::Vector3d p = T.inverse() * v.cast<double>();
      ASSERT_GT(p.z(), 0.0) << "a corner behind the camera";
      const Eigen::Vector2d u = camera.project(p);
      const double mx = 0.05 * camera.width, my = 0.05 * camera.height;
      EXPECT_GE(u.x(), mx - 1e-3);
      EXPECT_LE(u.x(), camera.width - 1 - mx + 1e-3);
      EXPECT_GE(u.y(), my - 1e-3);
      EXPECT_LE(u.y(), camera.height - 1 - my + 1e-3);
      slack = std::min({slack, u.x() - mx, camera.width - 1 - mx - u.x(), u.y() - my, camera.height - 1 - my - u.y()});
    }
    EXPECT_LT(slack, 1.0) << "the box could be shown larger";
  }
  EXPECT_THROW(hf::viewer::frame_mesh(hf::TriangleMesh(), camera), hf::Error);
}

// Which way a bare mesh is seen: a room corner scanned from its open side (a 4 x 4 m floor and a 4 x 3 m back wall,
// both facing the scanner) shows its floor at the bottom of the picture and is seen from the open side, both in
// hashfusion's y-down world and in a z-up (TUM motion-capture) world.
TEST(Viewer, FrameMeshLooksFromTheScannedSideWithTheFloorDown) {
  const hf::PinholeCamera camera = hf::PinholeCamera::preset("ros");
  for (const bool z_up : {false, true}) {
    // y-down: floor at y = 1.5 facing -y (up), wall at z = 4 facing -z (towards the scanner at the origin).
    hf::TriangleMesh m;
    const auto quad = [&](Eigen::Vector3f a, Eigen::Vector3f b, Eigen::Vector3f c, Eigen::Vector3f d) {
      const int i = int(m.vertices.size());
      for (const Eigen::Vector3f& v : {a, b, c, d}) m.vertices.push_back(v);
      m.triangles.emplace_back(i, i + 1, i + 2);
      m.triangles.emplace_back(i, i + 2, i + 3);
    };
    quad({-2, 1.5f, 0}, {2, 1.5f, 0}, {2, 1.5f, 4}, {-2, 1.5f, 4});      // normal (b-a)x(c-a) = -y
    quad({-2, 1.5f, 4}, {2, 1.5f, 4}, {2, -1.5f, 4}, {-2, -1.5f, 4});    // normal -z
    Eigen::Matrix3f to_world = Eigen::Matrix3f::Identity();
    if (z_up) to_world << 1, 0, 0, 0, 0, 1, 0, -1, 0;  // y-down camera world -> z-up: (x, y, z) -> (x, z, -y)
    for (Eigen::Vector3f& v : m.vertices) v = to_world * v;
    const Eigen::Vector3f n_floor = to_world * Eigen::Vector3f(0, -1, 0), n_wall = to_world * Eigen::Vector3f(0, 0, -1);
    const hf::SE3 T = hf::viewer::frame_mesh(m, camera);
    const Eigen::Matrix3d R = T.rotation();  // columns: the camera's x, y (image down), z (forward) in the world
    EXPECT_GT(R.col(1).dot(-n_floor.cast<double>()), 0.8) << "the floor is not at the bottom (z_up " << z_up << ")";
    EXPECT_GT(R.col(2).dot(-n_wall.cast<double>()), 0.7) << "not seen from the scanned side (z_up " << z_up << ")";
  }
}

// `view mesh.ply --screenshot` of a coloured box far from the origin: the whole box in the picture (surface pixels,
// none on the border), in its vertex colour modulated by the shading (red-dominant); the same box with black
// vertices (no colour fused) is grey. Needs OpenGL (EGL or xvfb-run); skips with a message without.
TEST(Viewer, ScreenshotOfABareMeshFramesItInItsColours) {
  const std::string dir = ::testing::TempDir() + "/hf_view_frame";
  std::filesystem::create_directories(dir);
  hf::viewer::ViewFilesOptions options;
  options.camera = centred_camera(160, 120, 130.0);
  for (const hf::Rgb8 colour : {hf::Rgb8{220, 40, 30}, hf::Rgb8{0, 0, 0}}) {
    hf::write_ply(dir + "/box.ply", box_mesh({3, -2, 6}, {4, -1.5f, 7.5f}, colour));
    options.screenshot = dir + "/box.png";
    try {
      hf::viewer::view_files(dir + "/box.ply", options);
    } catch (const hf::Error& e) {
      GTEST_SKIP() << "no display or EGL for OpenGL: " << e.what();
    }
    const hf::ColorImage shot = hf::load_color(options.screenshot);
    ASSERT_EQ(shot.width(), 160);
    int surface = 0, border = 0, dominant = 0, grey = 0;
    for (int y = 0; y < shot.height(); ++y)
      for (int x = 0; x < shot.width(); ++x) {
        const hf::Rgb8 p = shot(x, y);
        if (p.r == 0 && p.g == 0 && p.b == 0) continue;
        ++surface;
        border += x < 2 || y < 2 || x >= shot.width() - 2 || y >= shot.height() - 2;
        dominant += p.r > 2 * p.g && p.r > 2 * p.b;
        grey += p.r == p.g && p.g == p.b;
      }
    EXPECT_GT(surface, 160 * 120 / 10) << "the box should fill a good part of the view";
    EXPECT_EQ(border, 0) << "the box reaches the image border: not all of it is in view";
    if (colour.r > 0)
      EXPECT_EQ(dominant, surface) << "a red box should render red";
    else
      EXPECT_EQ(grey, surface) << "a box without colour should render grey";
  }
  std::filesystem::remove_all(dir);
}
