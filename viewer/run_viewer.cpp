#include "viewer/run_viewer.h"

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/error.h"
#include "io/image_io.h"
#include "viewer/gl_context.h"
#include "viewer/gl_util.h"
#include "viewer/mesh_renderer.h"

namespace hf::viewer {

// RunViewer::Impl's member types live in a named namespace, not the anonymous one: a class of the library may
// not hold types of an anonymous namespace once this file is not the translation unit's main file, as in unity
// builds (gcc -Wsubobject-linkage).
namespace run_viewer_detail {

// A model raycast and the view it was taken from.
struct ModelView {
  PinholeCamera camera;
  SE3 T_world_view;
  ColorImage shaded;  // fusion::colored_shading
  DepthImage depth;
};

struct Shot {
  std::string path;
  size_t track = 0;  // what the trajectory held at that frame
  SE3 T_world_camera;
  ModelView model;
};

}  // namespace run_viewer_detail
using run_viewer_detail::ModelView;
using run_viewer_detail::Shot;

namespace {

constexpr int kWindowW = 1280, kWindowH = 720, kViewW = 853;  // the 3-D view takes the left two thirds

// The free camera's intrinsics for a viewport: a 60-degree-ish horizontal field of view.
PinholeCamera view_camera(int w, int h) {
  PinholeCamera c;
  c.width = w;
  c.height = h;
  c.fx = c.fy = 0.75 * w;
  c.cx = (w - 1) / 2.0;
  c.cy = (h - 1) / 2.0;
  return c;
}

ColorImage depth_as_grey(const DepthImage& d) {
  ColorImage out(d.width(), d.height());
  for (size_t i = 0; i < d.size(); ++i) {
    const float v = d.pixels()[i];
    const auto g = std::uint8_t(v > 0 ? std::clamp(255.0f - v * 50.0f, 30.0f, 255.0f) : 0.0f);  // near bright
    out.pixels()[i] = {g, g, g};
  }
  return out;
}

ModelView render_model(const fusion::VoxelBlockGrid& map, const PinholeCamera& camera, const SE3& T_world_view) {
  fusion::RaycastResult r = fusion::raycast(map, camera, T_world_view, model_view_options());
  return {camera, T_world_view, fusion::colored_shading(r), std::move(r.depth)};
}

// The window's model view size for a viewport: its aspect, at most kModelViewMaxPx on the longer side.
PinholeCamera model_view_camera(int viewport_w, int viewport_h) {
  const double s = std::min(1.0, double(kModelViewMaxPx) / std::max(viewport_w, viewport_h));
  return view_camera(std::max(1, int(viewport_w * s)), std::max(1, int(viewport_h * s)));
}

bool same_view(const PinholeCamera& a, const SE3& Ta, const PinholeCamera& b, const SE3& Tb) {
  return a.width == b.width && a.height == b.height && (Ta.matrix() - Tb.matrix()).norm() < 1e-9;
}

}  // namespace

fusion::RaycastOptions model_view_options() {
  fusion::RaycastOptions o;
  o.max_depth_m = 20.0;
  o.refine_tol_vox = 0.05;
  o.color = true;  // shaded in the fused colours (fusion::colored_shading), as render.png
  o.shade = true;
  return o;
}

std::string numbered_screenshot(const std::string& path, long index) {
  const std::filesystem::path p(path);
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%06ld", index);
  return (p.parent_path() / (p.stem().string() + buf + p.extension().string())).string();
}

struct RunViewer::Impl {
  PinholeCamera camera;
  RunViewerOptions options;
  ViewController controller;

  std::mutex mutex;
  std::condition_variable changed;
  // The snapshot (tracking thread writes, window thread reads).
  ColorImage color;
  DepthImage depth;
  std::vector<Eigen::Vector3f> track, lost_marks;
  std::optional<SE3> pose;
  // The window's model view: what it asks for (request_*), what it has (model, model_version).
  std::optional<std::pair<PinholeCamera, SE3>> request;
  std::optional<ModelView> model;
  long model_version = 0;
  bool map_changed = true;  // since the last model view
  std::chrono::steady_clock::time_point last_model{};
  double last_model_s = 0.0;  // what the last model view's raycast took
  std::string status;
  long version = 0;
  std::deque<Shot> shots;
  std::optional<TriangleMesh> final_mesh;
  SE3 final_pose;
  bool finishing = false, finished = false, started = false;
  std::string error;
  std::thread thread;

  void run();
  void serve_model_view(const fusion::VoxelBlockGrid& map);
  void render_headless(MeshRenderer& renderer);
  void render_window(GlContext& context, MeshRenderer& renderer);
  std::vector<Polyline> lines(size_t track_count, const std::optional<SE3>& current) const;
};

std::vector<Polyline> RunViewer::Impl::lines(size_t track_count, const std::optional<SE3>& current) const {
  std::vector<Polyline> l;
  Polyline t;
  t.color = {60, 220, 60};
  t.points_world.assign(track.begin(), track.begin() + long(std::min(track_count, track.size())));
  l.push_back(std::move(t));
  Polyline lost;
  lost.color = {230, 40, 40};
  lost.strip = false;
  for (const auto& p : lost_marks) {
    const float s = 0.02f;  // a 4 cm cross at each lost frame's reported pose
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::Vector3f d = Eigen::Vector3f::Zero();
      d[axis] = s;
      lost.points_world.push_back(p - d);
      lost.points_world.push_back(p + d);
    }
  }
  l.push_back(std::move(lost));
  if (current) l.push_back(camera_frustum(camera, *current, 0.2, {240, 220, 40}));
  return l;
}

void RunViewer::Impl::run() {
  try {
    GlContext context(options.window ? kWindowW : camera.width, options.window ? kWindowH : camera.height,
                      "hashfusion", options.window);
    MeshRenderer renderer;
    {
      std::lock_guard<std::mutex> lock(mutex);
      started = true;
    }
    changed.notify_all();
    if (options.window) render_window(context, renderer);
    else render_headless(renderer);
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex);
    error = e.what();
  }
  controller.release();
  std::lock_guard<std::mutex> lock(mutex);
  started = true;
  finished = true;
  changed.notify_all();
}

void RunViewer::Impl::render_headless(MeshRenderer& renderer) {
  for (;;) {
    std::unique_lock<std::mutex> lock(mutex);
    changed.wait(lock, [this] { return !shots.empty() || finishing; });
    if (!shots.empty()) {
      const Shot shot = std::move(shots.front());
      shots.pop_front();
      const std::vector<Polyline> l = lines(shot.track, shot.T_world_camera);
      lock.unlock();
      renderer.set_backdrop(shot.model.shaded, shot.model.depth);
      write_color_png(shot.path, renderer.render(shot.model.camera, shot.model.T_world_view, l, false));
      continue;
    }
    // Finishing and every shot written: the final mesh from the last pose, as render.png shows it.
    if (final_mesh && !options.screenshot.empty()) {
      const TriangleMesh mesh = *final_mesh;
      const SE3 at = final_pose;
      lock.unlock();
      renderer.set_backdrop({}, {});
      renderer.set_mesh(mesh);
      write_color_png(options.screenshot, renderer.render(camera, at, {}, true));
    }
    return;
  }
}

void RunViewer::Impl::render_window(GlContext& context, MeshRenderer& renderer) {
  auto* window = static_cast<GLFWwindow*>(context.window());
  glfwSetWindowUserPointer(window, this);
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int) {
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    auto* self = static_cast<Impl*>(glfwGetWindowUserPointer(w));
    switch (key) {
      case GLFW_KEY_SPACE: self->controller.key(Key::pause); break;
      case GLFW_KEY_N:
      case GLFW_KEY_RIGHT: self->controller.key(Key::step); break;
      case GLFW_KEY_R: self->controller.key(Key::reset_view); break;
      case GLFW_KEY_S: self->controller.key(Key::save_mesh); break;
      case GLFW_KEY_F: self->controller.key(Key::follow); break;
      case GLFW_KEY_Q:
      case GLFW_KEY_ESCAPE: self->controller.key(Key::quit); break;
      default: break;
    }
  });
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) {
    static_cast<Impl*>(glfwGetWindowUserPointer(w))->controller.scroll(dy);
  });
  ImageQuad panels(2);  // input colour, depth
  OrbitInput orbit(window);
  long seen = -1, model_seen = 0;
  bool mesh_loaded = false;
  std::vector<Polyline> l;
  std::optional<SE3> current;
  std::optional<std::pair<PinholeCamera, SE3>> shown;  // the model view on screen: its camera and pose
  while (!glfwWindowShouldClose(window) && !controller.quit_flag()->load()) {
    glfwWaitEventsTimeout(1.0 / 30.0);
    orbit.poll(controller);
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    const int vw = fw * kViewW / kWindowW;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!final_mesh && vw > 0 && fh > 0) request = {model_view_camera(vw, fh), controller.T_world_view()};
      if (model_version != model_seen && model && !mesh_loaded) {
        model_seen = model_version;
        renderer.set_backdrop(model->shaded, model->depth);
        shown = {model->camera, model->T_world_view};
      }
      if (version != seen) {
        seen = version;
        l = lines(track.size(), pose);
        current = pose;
        for (int i = 0; i < 2; ++i) {
          const ColorImage img = i == 0 ? color : depth_as_grey(depth);
          if (img.empty()) continue;
          panels.upload(i, img);
        }
        glfwSetWindowTitle(window, (status + (controller.paused() ? "  [paused]" : "")).c_str());
      }
      if (final_mesh && !mesh_loaded) {
        renderer.set_mesh(*final_mesh);
        renderer.set_backdrop({}, {});
        shown.reset();
        mesh_loaded = true;
        glfwSetWindowTitle(window, (status + "  [run finished: final mesh; close the window to exit]").c_str());
      }
    }
    if (controller.follow() && current) controller.reset(*current);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fw, fh);
    glClearColor(0.08f, 0.08f, 0.1f, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glViewport(0, 0, vw, fh);
    // The lines from the pose the model view was rendered at, so they sit on its surfaces; the view follows the
    // mouse with the next model view (at most 1 / kModelViewHz later).
    if (shown) renderer.draw(shown->first, shown->second, l, true);
    else renderer.draw(view_camera(vw, fh), controller.T_world_view(), l, true);
    for (int i = 0; i < 2; ++i) {  // colour on top, depth below, each half of the right column
      glViewport(vw, i == 0 ? fh / 2 : 0, fw - vw, fh / 2);
      panels.draw(i);
    }
    glfwSwapBuffers(window);
  }
  controller.key(Key::quit);  // a closed window ends the run (its outputs are written)
}

RunViewer::RunViewer(const PinholeCamera& camera, const RunViewerOptions& options) : impl_(std::make_unique<Impl>()) {
  impl_->camera = camera;
  impl_->options = options;
  impl_->thread = std::thread([this] { impl_->run(); });
  std::unique_lock<std::mutex> lock(impl_->mutex);
  impl_->changed.wait(lock, [this] { return impl_->started; });
  if (!impl_->error.empty()) {
    const std::string e = impl_->error;
    lock.unlock();
    impl_->thread.join();
    throw Error(e);
  }
}

RunViewer::~RunViewer() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->finishing = true;
  }
  impl_->controller.key(Key::quit);
  impl_->changed.notify_all();
  if (impl_->thread.joinable()) impl_->thread.join();
}

ViewController& RunViewer::controller() { return impl_->controller; }

void RunViewer::Impl::serve_model_view(const fusion::VoxelBlockGrid& map) {
  std::pair<PinholeCamera, SE3> want;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (!request || !options.window) return;
    const auto now = std::chrono::steady_clock::now();
    // At most kModelViewHz, and the raycasts at most kModelViewShare of the tracking thread's time.
    const double wait_s = std::max(1.0 / kModelViewHz, last_model_s / kModelViewShare);
    if (now - last_model < std::chrono::duration<double>(wait_s)) return;
    // Nothing new to show: the map is as it was and the view has not moved.
    if (!map_changed && model && same_view(model->camera, model->T_world_view, request->first, request->second))
      return;
    want = *request;
    last_model = now;
    map_changed = false;
  }
  const auto start = std::chrono::steady_clock::now();
  ModelView v = render_model(map, want.first, want.second);
  std::lock_guard<std::mutex> lock(mutex);
  last_model_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  model = std::move(v);
  ++model_version;
}

void RunViewer::observe(const RgbdFrame& frame, const slam::FrameResult& r, const fusion::VoxelBlockGrid& map) {
  Impl& m = *impl_;
  std::ostringstream status;
  status << std::fixed << std::setprecision(1) << "hashfusion  frame " << r.index << "  " << slam::to_string(r.state)
         << "  " << (r.ms.total() > 0 ? 1000.0 / r.ms.total() : 0.0) << " fps (track " << r.ms.track
         << " ms, integrate " << r.ms.integrate << " ms, raycast " << r.ms.raycast << " ms)  " << map.block_count()
         << " blocks  " << double(map.memory_bytes()) / (1 << 20) << " MiB";
  const bool shot = !m.options.window && m.options.screenshot_every > 0 && !m.options.screenshot.empty() &&
                    long(r.index) % m.options.screenshot_every == 0;
  std::optional<ModelView> shot_view;
  if (shot) {
    ViewController follow;
    follow.reset(r.T_world_camera);
    shot_view = render_model(map, m.camera, follow.T_world_view());
  }
  {
    std::lock_guard<std::mutex> lock(m.mutex);
    m.color = frame.color;
    m.depth = frame.depth;
    const Eigen::Vector3f at = r.T_world_camera.translation().cast<float>();
    if (r.pose_valid) m.track.push_back(at);
    else if (!m.track.empty()) m.lost_marks.push_back(at);
    if (r.pose_valid) m.pose = r.T_world_camera;
    m.status = status.str();
    m.map_changed = true;
    ++m.version;
    if (shot_view)
      m.shots.push_back({numbered_screenshot(m.options.screenshot, long(r.index)), m.track.size(), r.T_world_camera,
                         std::move(*shot_view)});
  }
  m.changed.notify_all();
  m.serve_model_view(map);
}

void RunViewer::hold(const fusion::VoxelBlockGrid& map) {
  while (!impl_->controller.wait_for_turn_for(std::chrono::milliseconds(int(1000.0 / kModelViewHz))))
    impl_->serve_model_view(map);
}

void RunViewer::finish(const TriangleMesh& mesh, const SE3& T_world_camera) {
  Impl& m = *impl_;
  {
    std::lock_guard<std::mutex> lock(m.mutex);
    m.final_mesh = mesh;
    m.final_pose = T_world_camera;
    m.finishing = true;
  }
  m.changed.notify_all();
  if (m.thread.joinable()) m.thread.join();
  if (!m.error.empty()) throw Error(m.error);
}

}  // namespace hf::viewer
