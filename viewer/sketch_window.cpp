#include "viewer/sketch_window.h"

#include <algorithm>

#include "core/error.h"
#include "photogrammetry/guidance.h"
#include "viewer/gl_context.h"
#include "viewer/gl_util.h"

namespace hf::viewer {
namespace {

namespace pg = photogrammetry;

constexpr int kMaxW = 1280, kMaxH = 800;

std::string title(const pg::SketchSession& s) {
  std::string t = "hashfusion sketch  " + s.network().shots[size_t(s.shown_shot())].name;
  const pg::ModelledPolygon* p = s.current();
  t += p ? "  " + p->id + ": " + pg::to_string(p->decision.state) + " (" + pg::to_string(p->decision.method) + ")"
         : std::string("  new polygon: red");
  t += "  [" + std::to_string(s.open_outline().size()) + " open vertices]";
  if (!s.message().empty()) t += "  " + s.message();
  return t + "  (click vertices, Enter close, Backspace undo, n new, p same plane, Tab shot, q done)";
}

}  // namespace

std::optional<std::string> sketch_key_event(int key, int mods, const pg::Network& network, int shown_shot) {
  const int n = int(network.shots.size());
  switch (key) {
    case GLFW_KEY_ENTER:
    case GLFW_KEY_KP_ENTER: return "close";
    case GLFW_KEY_BACKSPACE: return "undo";
    case GLFW_KEY_N: return "new";
    case GLFW_KEY_P: return "same_plane";
    case GLFW_KEY_TAB: {
      if (n == 0) return std::nullopt;
      const int next = (mods & GLFW_MOD_SHIFT) ? (shown_shot + n - 1) % n : (shown_shot + 1) % n;
      return "shot " + network.shots[size_t(next)].name;
    }
    default: return std::nullopt;
  }
}

Eigen::Vector2d window_to_image(double x, double y, double scale) { return {x / scale - 0.5, y / scale - 0.5}; }

void run_sketch_window(pg::SketchSession& session) {
  struct State {
    pg::SketchSession* session;
    double scale = 1.0;
    bool quit = false, changed = true;
  } state{&session};
  GlContext context(kMaxW, kMaxH, "hashfusion sketch", true);
  auto* window = static_cast<GLFWwindow*>(context.window());
  glfwSetWindowUserPointer(window, &state);
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int mods) {
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    auto* st = static_cast<State*>(glfwGetWindowUserPointer(w));
    if (key == GLFW_KEY_Q || key == GLFW_KEY_ESCAPE) st->quit = true;
    else if (const auto e = sketch_key_event(key, mods, st->session->network(), st->session->shown_shot()))
      st->session->apply(*e);
    st->changed = true;
  });
  glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int button, int action, int) {
    if (button != GLFW_MOUSE_BUTTON_LEFT || action != GLFW_PRESS) return;
    auto* st = static_cast<State*>(glfwGetWindowUserPointer(w));
    double x = 0, y = 0;
    glfwGetCursorPos(w, &x, &y);
    int ww = 0, wh = 0, fw = 0, fh = 0;
    glfwGetWindowSize(w, &ww, &wh);
    glfwGetFramebufferSize(w, &fw, &fh);
    const double to_fb = ww > 0 ? double(fw) / ww : 1.0;  // cursor positions are in screen coordinates
    st->session->click(window_to_image(x * to_fb, y * to_fb, st->scale));
    st->changed = true;
  });
  ImageQuad photo(1);
  int shown = -1, iw = 1, ih = 1;
  while (!glfwWindowShouldClose(window) && !state.quit) {
    glfwWaitEventsTimeout(1.0 / 30.0);
    if (state.changed) {
      state.changed = false;
      const ColorImage overlay = session.overlay();
      iw = overlay.width();
      ih = overlay.height();
      photo.upload(0, overlay);
      if (shown != session.shown_shot()) {  // a new shot: the window takes its aspect
        shown = session.shown_shot();
        const double s = std::min({1.0, double(kMaxW) / iw, double(kMaxH) / ih});
        glfwSetWindowSize(window, std::max(1, int(iw * s)), std::max(1, int(ih * s)));
      }
      glfwSetWindowTitle(window, title(session).c_str());
    }
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    state.scale = std::min(double(fw) / iw, double(fh) / ih);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fw, fh);
    glClearColor(0.08f, 0.08f, 0.1f, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    // The image from the top-left corner at `scale` (GL's viewport origin is bottom-left).
    const int vw = int(iw * state.scale), vh = int(ih * state.scale);
    glViewport(0, fh - vh, vw, vh);
    photo.draw(0);
    glfwSwapBuffers(window);
  }
}

}  // namespace hf::viewer
