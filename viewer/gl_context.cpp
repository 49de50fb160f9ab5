#include "viewer/gl_context.h"

#include "viewer/gl_util.h"

#include <mutex>

#include "core/error.h"

namespace hf::viewer {
namespace {

std::mutex g_mutex;
int g_users = 0;
std::string g_last_error;

void on_glfw_error(int, const char* description) { g_last_error = description ? description : ""; }

}  // namespace

GlContext::GlContext(int width, int height, const std::string& title, bool visible) {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_users == 0) {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit())
      throw Error("no display for the viewer (DISPLAY unset? run under xvfb-run for headless use): " + g_last_error);
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
  GLFWwindow* w = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!w) {
    if (g_users == 0) glfwTerminate();
    throw Error("viewer: no OpenGL 3.3 core context (" + g_last_error + ")");
  }
  ++g_users;
  window_ = w;
  glfwMakeContextCurrent(w);
  glfwSwapInterval(visible ? 1 : 0);
}

GlContext::~GlContext() {
  std::lock_guard<std::mutex> lock(g_mutex);
  glfwDestroyWindow(static_cast<GLFWwindow*>(window_));
  if (--g_users == 0) glfwTerminate();
}

std::string GlContext::renderer() const {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return r ? r : "unknown";
}

}  // namespace hf::viewer
