// An OpenGL 3.3 core context: a GLFW window the user sees, or, for rendering offscreen (the headless --screenshot
// mode), an EGL context without any surface (Mesa's surfaceless platform, EGL_MESA_platform_surfaceless: no X
// server, no GPU needed; llvmpipe renders into the framebuffer objects MeshRenderer draws to) where the build has
// EGL (HF_HAVE_EGL) and the driver offers it, else a hidden GLFW window (under Xvfb with Mesa on a machine without
// a screen).
//
// Construction makes the context current on the calling thread; every GL call of the viewer then happens on that
// thread. GLFW and the EGL display are initialised once per process (reference counted). Throws hf::Error with one
// line when there is no display and no EGL ("no display for the viewer (DISPLAY unset?): ..."), or the driver has
// no OpenGL 3.3 core profile. HF_VIEWER_NO_EGL=1 in the environment skips the EGL path (to test the GLFW one).
// This header does not include GL, GLFW or EGL: code below slam/ never sees them.
#pragma once

#include <memory>
#include <string>

namespace hf::viewer {

class GlContext {
 public:
  GlContext(int width, int height, const std::string& title, bool visible);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  void* window() const { return window_; }  // the GLFWwindow*; nullptr for an EGL context
  bool egl() const { return egl_context_ != nullptr; }
  std::string renderer() const;             // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"

 private:
  void* window_ = nullptr;
  void* egl_context_ = nullptr;  // EGLContext
};

}  // namespace hf::viewer
