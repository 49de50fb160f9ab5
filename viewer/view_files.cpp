#include "viewer/view_files.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
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

}  // namespace

namespace {

// The world's up and the side to look from, guessed from the mesh itself: meshes come in y-down frames (hashfusion's
// first-camera world, Open3D's) and z-up ones (TUM's motion-capture world, the synthetic scenes).
// - Up: of the six axis directions, the one the largest area of triangles faces (normals within 25 degrees):
//   floors and table tops face up, ceilings are rarely scanned. -y (hashfusion's convention) when no direction
//   gathers 10 % of the area.
// - Looking along: a scan's surfaces face the sensor that saw them, so the area-weighted mean normal, flattened to
//   the horizontal, points to where the cameras stood; the view looks back against it, down at 25 degrees. A closed
//   mesh (mean normal under 10 % of the area) is seen along +z, or +y when z is up.
// Returns the camera's axes in the world as the columns of R (x right, y down, z forward).
Eigen::Matrix3d view_axes(const TriangleMesh& mesh) {
  std::array<double, 6> facing{};  // +x, -x, +y, -y, +z, -z
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double area = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[size_t(t[0])].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[size_t(t[1])].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[size_t(t[2])].cast<double>();
    const Eigen::Vector3d n2 = (b - a).cross(c - a);  // twice the area along the normal
    const double a2 = n2.norm();
    if (!(a2 > 0.0)) continue;
    mean += n2;
    area += a2;
    for (int k = 0; k < 3; ++k) {
      const double cosine = n2[k] / a2;
      if (cosine > std::cos(25.0 * M_PI / 180.0)) facing[size_t(2 * k)] += a2;
      if (-cosine > std::cos(25.0 * M_PI / 180.0)) facing[size_t(2 * k + 1)] += a2;
    }
  }
  const size_t best = size_t(std::max_element(facing.begin(), facing.end()) - facing.begin());
  Eigen::Vector3d up(0.0, -1.0, 0.0);
  if (area > 0.0 && facing[best] >= 0.1 * area) {
    up = Eigen::Vector3d::Zero();
    up[int(best / 2)] = best % 2 == 0 ? 1.0 : -1.0;
  }
  Eigen::Vector3d horizontal = Eigen::Vector3d::Zero();
  if (area > 0.0 && mean.norm() >= 0.1 * area) horizontal = -(mean - mean.dot(up) * up);
  if (!(horizontal.norm() >= 0.05 * area) || horizontal.norm() == 0.0)
    horizontal = std::abs(up.z()) > 0.5 ? Eigen::Vector3d(0, 1, 0) : Eigen::Vector3d(0, 0, 1);
  horizontal.normalize();
  const double tilt = 25.0 * M_PI / 180.0;
  const Eigen::Vector3d z = std::cos(tilt) * horizontal - std::sin(tilt) * up;
  const Eigen::Vector3d y = (-up - (-up).dot(z) * z).normalized();  // image down: the world's down, in view
  Eigen::Matrix3d R;
  R << y.cross(z), y, z;
  return R;
}

}  // namespace

SE3 frame_mesh(const TriangleMesh& mesh, const PinholeCamera& camera) {
  if (mesh.vertices.empty()) throw Error("frame_mesh: the mesh has no vertices");
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& v : mesh.vertices) {
    lo = lo.cwiseMin(v.cast<double>());
    hi = hi.cwiseMax(v.cast<double>());
  }
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  const Eigen::Matrix3d R = view_axes(mesh);
  const Eigen::Vector3d z = R.col(2);
  // The camera stands at centre - d z. A corner q (camera axes, relative to the centre) projects to
  // u = fx q.x / (q.z + d) + cx; it stays inside [margin, width - 1 - margin] when d >= fx |q.x| / room - q.z,
  // room the pixels from cx to the side q.x points to. The same along y; d is the largest such bound over the
  // eight corners (and keeps every corner 0.1 m in front of the camera, beyond the GL renderer's 0.05 m near plane:
  // a mesh of a few centimetres is then shown smaller than the margins allow).
  const double margin_x = 0.05 * camera.width, margin_y = 0.05 * camera.height;
  const double right = camera.width - 1 - margin_x - camera.cx, left = camera.cx - margin_x;
  const double down = camera.height - 1 - margin_y - camera.cy, up = camera.cy - margin_y;
  if (!(right > 0 && left > 0 && down > 0 && up > 0))
    throw Error("frame_mesh: the principal point lies outside the camera's image, " + camera.describe());
  double d = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
    const Eigen::Vector3d q = R.transpose() * (corner - centre);
    d = std::max(d, camera.fx * std::abs(q.x()) / (q.x() >= 0 ? right : left) - q.z());
    d = std::max(d, camera.fy * std::abs(q.y()) / (q.y() >= 0 ? down : up) - q.z());
    d = std::max(d, 0.1 - q.z());
  }
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.block<3, 3>(0, 0) = R;
  T.block<3, 1>(0, 3) = centre - d * z;
  return SE3::from_matrix(T);
}

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
                                           : frame_mesh(mesh, cam);
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
    write_color_png(options.screenshot, renderer.render(cam, start, lines, true));
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
