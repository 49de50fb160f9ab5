// GL and GLFW helpers shared by the viewer's .cpp files (an internal header: it includes GL and GLFW, so only
// viewer/*.cpp may include it).
#pragma once

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GLFW/glfw3.h>

#include <vector>

#include "core/image.h"
#include "viewer/view_controller.h"

namespace hf::viewer {

// Compiles and links a vertex + fragment shader pair; throws hf::Error with the compiler's log.
GLuint link_program(const char* vertex_source, const char* fragment_source);

// RGB images drawn over the current viewport (row 0 at the top, bilinear): the windows' photo and input panels.
// Needs the current GL context for its whole life.
class ImageQuad {
 public:
  explicit ImageQuad(int textures);
  ~ImageQuad();
  ImageQuad(const ImageQuad&) = delete;
  ImageQuad& operator=(const ImageQuad&) = delete;
  void upload(int texture, const ColorImage& image);
  void draw(int texture) const;

 private:
  GLuint program_ = 0, vao_ = 0, vbo_ = 0;
  std::vector<GLuint> textures_;
};

// The mouse half of the orbit camera: a left-button drag orbits (ViewController::drag) by the cursor's motion
// since the last poll.
class OrbitInput {
 public:
  explicit OrbitInput(GLFWwindow* window) : window_(window) { glfwGetCursorPos(window, &x_, &y_); }
  void poll(ViewController& controller) {
    double x = 0, y = 0;
    glfwGetCursorPos(window_, &x, &y);
    if (glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) controller.drag(x - x_, y - y_);
    x_ = x;
    y_ = y;
  }

 private:
  GLFWwindow* window_;
  double x_ = 0, y_ = 0;
};

}  // namespace hf::viewer
