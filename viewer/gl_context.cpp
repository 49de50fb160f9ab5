#include "viewer/gl_context.h"

#include "viewer/gl_util.h"

#include <cstdlib>
#include <mutex>

#if HF_HAVE_EGL
#include <EGL/egl.h>
#include <EGL/eglext.h>
#endif

#include "core/error.h"

namespace hf::viewer {
namespace {

std::mutex g_mutex;
int g_users = 0;  // GLFW windows
std::string g_last_error;

void on_glfw_error(int, const char* description) { g_last_error = description ? description : ""; }

#if HF_HAVE_EGL
int g_egl_users = 0;
EGLDisplay g_egl_display = EGL_NO_DISPLAY;

// A surfaceless OpenGL 3.3 core context on Mesa's surfaceless platform, or nullptr (no EGL, no such platform, no
// such context): the caller falls back to GLFW. Called with g_mutex held.
EGLContext create_surfaceless_context() {
  if (const char* off = std::getenv("HF_VIEWER_NO_EGL"); off && *off && std::string(off) != "0") return nullptr;
  if (g_egl_users == 0) {
    const char* extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!extensions || std::string(extensions).find("EGL_MESA_platform_surfaceless") == std::string::npos) return nullptr;
    const auto get_display =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_display) return nullptr;
    g_egl_display = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (g_egl_display == EGL_NO_DISPLAY || !eglInitialize(g_egl_display, &major, &minor)) return nullptr;
  }
  const EGLint config_attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext context = EGL_NO_CONTEXT;
  if (eglBindAPI(EGL_OPENGL_API) && eglChooseConfig(g_egl_display, config_attributes, &config, 1, &configs) &&
      configs > 0)
    context = eglCreateContext(g_egl_display, config, EGL_NO_CONTEXT, context_attributes);
  if (context != EGL_NO_CONTEXT && !eglMakeCurrent(g_egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(g_egl_display, context);
    context = EGL_NO_CONTEXT;
  }
  if (context == EGL_NO_CONTEXT) {
    if (g_egl_users == 0) eglTerminate(g_egl_display);
    return nullptr;
  }
  ++g_egl_users;
  return context;
}
#endif

}  // namespace

GlContext::GlContext(int width, int height, const std::string& title, bool visible) {
  std::lock_guard<std::mutex> lock(g_mutex);
#if HF_HAVE_EGL
  if (!visible) {
    egl_context_ = create_surfaceless_context();
    if (egl_context_) return;
  }
#endif
  if (g_users == 0) {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit())
      throw Error("no display for the viewer (DISPLAY unset? run under xvfb-run, or build with libegl-dev for headless "
                  "use): " + g_last_error);
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
#if HF_HAVE_EGL
  if (egl_context_) {
    eglMakeCurrent(g_egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(g_egl_display, static_cast<EGLContext>(egl_context_));
    if (--g_egl_users == 0) eglTerminate(g_egl_display);
    return;
  }
#endif
  glfwDestroyWindow(static_cast<GLFWwindow*>(window_));
  if (--g_users == 0) glfwTerminate();
}

std::string GlContext::renderer() const {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return r ? r : "unknown";
}

}  // namespace hf::viewer
