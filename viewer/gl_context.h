// An OpenGL 3.3 core context through GLFW: a window the user sees, or a hidden one for rendering offscreen (the
// headless --screenshot mode; under Xvfb with Mesa on a machine without a screen).
//
// Construction initialises GLFW (once per process, reference counted) and makes the context current on the calling
// thread; every GL call of the viewer then happens on that thread. Throws hf::Error with one line when there is no
// display ("no display for the viewer (DISPLAY unset?): ..."), or the driver has no OpenGL 3.3 core profile.
// This header does not include GL or GLFW: code below slam/ never sees them.
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

  void* window() const { return window_; }  // the GLFWwindow*
  std::string renderer() const;             // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"

 private:
  void* window_ = nullptr;
};

}  // namespace hf::viewer
