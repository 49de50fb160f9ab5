#include "viewer/view_files.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/bounded_read.h"
#include "core/error.h"
#include "fusion/mesh.h"
#include "fusion/volume_io.h"
#include "io/image_io.h"
#include "io/mesh_file.h"
#include "io/ply.h"
#include "io/trajectory_io.h"
#include "viewer/gl_context.h"
#include "viewer/gl_util.h"
#include "viewer/mesh_renderer.h"
#include "viewer/view_controller.h"

namespace hf::viewer {
namespace {

namespace fs = std::filesystem;

// report.json's "camera": an object {fx, fy, cx, cy, width, height} (issue 36 on), or the string
// "fx=525 fy=525 cx=319.5 cy=239.5 640x480" (PinholeCamera::describe) that earlier runs wrote.
std::optional<PinholeCamera> camera_from_report(const std::string& dir) {
  const fs::path report = fs::path(dir) / "report.json";
  std::error_code ec;
  if (!fs::is_regular_file(report, ec)) return std::nullopt;
  try {
    const nlohmann::json j = nlohmann::json::parse(read_regular_file(report.string(), "run report", 1 << 26));
    if (j.at("camera").is_object()) return PinholeCamera::parse(j["camera"].dump(), report.string());
    PinholeCamera c;
    if (std::sscanf(j.at("camera").get<std::string>().c_str(), "fx=%lf fy=%lf cx=%lf cy=%lf %dx%d", &c.fx, &c.fy,
                    &c.cx, &c.cy, &c.width, &c.height) == 6)
      return c;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

SE3 look_at_mesh(const TriangleMesh& mesh) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo;
  for (const auto& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Eigen::Vector3d centre = (0.5f * (lo + hi)).cast<double>();
  const double radius = std::max(0.05, 0.5 * double((hi - lo).norm()));
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.block<3, 1>(0, 3) = centre - Eigen::Vector3d(0, 0, 1.5 * radius / std::tan(0.5));
  return SE3::from_matrix(T);
}

}  // namespace

void view_files(const std::string& path, const ViewFilesOptions& options) {
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw Error(path + ": not found (expected a .ply or .obj mesh, map.hfmap or a run's output folder)");
  TriangleMesh mesh;
  Trajectory trajectory;
  std::optional<PinholeCamera> camera = options.camera;
  if (fs::is_directory(path, ec)) {
    const fs::path m = fs::path(path) / "mesh.ply";
    if (!fs::is_regular_file(m, ec)) throw Error(path + ": a folder without mesh.ply (not a run's output folder)");
    mesh = read_ply_mesh(m.string());
    if (fs::is_regular_file(fs::path(path) / "trajectory.txt", ec))
      trajectory = read_tum_trajectory((fs::path(path) / "trajectory.txt").string());
    if (!camera) camera = camera_from_report(path);
  } else if (fs::path(path).extension() == ".ply" || fs::path(path).extension() == ".obj") {
    mesh = read_mesh_file(path);
  } else {
    const fusion::Volume volume = fusion::load_volume(path);
    mesh = fusion::extract_mesh(volume.grid, volume.store);
  }
  if (mesh.triangles.empty()) throw Error(path + ": the mesh has no triangles");
  const PinholeCamera cam = camera ? *camera : PinholeCamera::preset("ros");
  const SE3 start = options.T_world_camera ? *options.T_world_camera
                    : !trajectory.empty()  ? trajectory.back().T_world_camera
                                           : look_at_mesh(mesh);
  std::vector<Polyline> lines;
  if (!trajectory.empty()) {
    Polyline t;
    t.color = {60, 220, 60};
    for (const auto& p : trajectory) t.points_world.push_back(p.T_world_camera.translation().cast<float>());
    lines.push_back(t);
    lines.push_back(camera_frustum(cam, trajectory.back().T_world_camera, 0.2, {240, 220, 40}));
  }
  const bool headless = !options.screenshot.empty();
  GlContext context(cam.width, cam.height, "hashfusion view " + path, !headless);
  MeshRenderer renderer;
  renderer.set_mesh(mesh);
  if (headless) {
    write_color_png(options.screenshot, renderer.render(cam, start, lines, false));
    return;
  }
  auto* window = static_cast<GLFWwindow*>(context.window());
  ViewController controller;
  controller.reset(start);
  glfwSetWindowUserPointer(window, &controller);
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int) {
    if (action != GLFW_PRESS) return;
    auto* c = static_cast<ViewController*>(glfwGetWindowUserPointer(w));
    if (key == GLFW_KEY_R) c->key(Key::reset_view);
    if (key == GLFW_KEY_Q || key == GLFW_KEY_ESCAPE) c->key(Key::quit);
  });
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) {
    static_cast<ViewController*>(glfwGetWindowUserPointer(w))->scroll(dy);
  });
  OrbitInput orbit(window);
  while (!glfwWindowShouldClose(window) && !controller.quit_flag()->load()) {
    glfwWaitEventsTimeout(1.0 / 30.0);
    orbit.poll(controller);
    if (controller.follow()) controller.reset(start);
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.08f, 0.08f, 0.1f, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    PinholeCamera view = cam;
    view.width = fw;
    view.height = fh;
    renderer.draw(view, controller.T_world_view(), lines, true);
    glfwSwapBuffers(window);
  }
}

}  // namespace hf::viewer
