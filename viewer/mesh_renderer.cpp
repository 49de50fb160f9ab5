#include "viewer/mesh_renderer.h"

#include <algorithm>

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "core/error.h"
#include "viewer/gl_util.h"

namespace hf::viewer {
namespace {

// World -> camera (T_camera_world), then the pinhole camera as a clip transform: x_clip = 2 (fx X + (cx + 0.5) Z)
// / W - Z puts pixel centre u at NDC (2 (u + 0.5) / W - 1); y is flipped (image rows go down, GL's y up); depth is
// the usual perspective mapping of [near, far].
glm::mat4 pinhole_clip(const PinholeCamera& c, double near_m, double far_m) {
  const float W = float(c.width), H = float(c.height), n = float(near_m), f = float(far_m);
  glm::mat4 P(0.0f);  // column-major: P[col][row]
  P[0][0] = 2.0f * float(c.fx) / W;
  P[2][0] = 2.0f * (float(c.cx) + 0.5f) / W - 1.0f;
  P[1][1] = -2.0f * float(c.fy) / H;
  P[2][1] = 1.0f - 2.0f * (float(c.cy) + 0.5f) / H;
  P[2][2] = (f + n) / (f - n);
  P[3][2] = -2.0f * f * n / (f - n);
  P[2][3] = 1.0f;
  return P;
}

glm::mat4 to_glm(const Eigen::Matrix4f& m) {
  glm::mat4 g;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) g[c][r] = m(r, c);
  return g;
}

const char* kMeshVertex = R"(#version 330 core
layout(location = 0) in vec3 position_world;
layout(location = 1) in vec3 normal_world;
layout(location = 2) in vec3 color;
uniform mat4 T_camera_world;
uniform mat4 clip;
out vec3 p_camera;
out vec3 n_camera;
out vec3 v_color;
void main() {
  vec4 p = T_camera_world * vec4(position_world, 1.0);
  p_camera = p.xyz;
  n_camera = mat3(T_camera_world) * normal_world;
  v_color = color;
  gl_Position = clip * p;
}
)";

// hf_headlight_shade (fusion/kernels/raycast_kernels.h), per fragment.
const char* kMeshFragment = R"(#version 330 core
in vec3 p_camera;
in vec3 n_camera;
in vec3 v_color;
uniform int use_colors;
out vec4 frag;
void main() {
  vec3 to_camera = normalize(-p_camera);
  float c = max(dot(normalize(n_camera), to_camera), 0.0);
  float c16 = pow(c, 16.0);
  float i = min(0.2 + 0.7 * c + 0.1 * c16, 1.0);
  // A black vertex colour is no fused colour (fusion::colored_shading's rule): grey shading there.
  bool coloured = use_colors != 0 && max(v_color.r, max(v_color.g, v_color.b)) > 0.0;
  frag = vec4(coloured ? v_color * i : vec3(i), 1.0);
}
)";

const char* kLineVertex = R"(#version 330 core
layout(location = 0) in vec3 position_world;
uniform mat4 T_camera_world;
uniform mat4 clip;
void main() { gl_Position = clip * (T_camera_world * vec4(position_world, 1.0)); }
)";

// The backdrop: a quad over the viewport; each fragment takes its texel (nearest, row 0 at the top) and is put at
// that texel's depth through the same perspective mapping as pinhole_clip (z_ndc = a + b / Z).
const char* kBackdropVertex = R"(#version 330 core
layout(location = 0) in vec2 corner;
void main() { gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0); }
)";

const char* kBackdropFragment = R"(#version 330 core
uniform sampler2D image;
uniform sampler2D depth_m;
uniform vec4 viewport;
uniform vec2 depth_map;
out vec4 frag;
void main() {
  ivec2 size = textureSize(image, 0);
  vec2 t = (gl_FragCoord.xy - viewport.xy) / viewport.zw * vec2(size);
  ivec2 texel = ivec2(clamp(floor(t), vec2(0.0), vec2(size - 1)));
  texel.y = size.y - 1 - texel.y;
  float z = texelFetch(depth_m, texel, 0).r;
  if (!(z > 0.0)) discard;
  gl_FragDepth = clamp(0.5 * (depth_map.x + depth_map.y / z) + 0.5, 0.0, 1.0);
  frag = vec4(texelFetch(image, texel, 0).rgb, 1.0);
}
)";

const char* kImageVertex = R"(#version 330 core
layout(location = 0) in vec2 corner;
out vec2 uv;
void main() { uv = vec2(corner.x, 1.0 - corner.y); gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0); }
)";
const char* kImageFragment = R"(#version 330 core
in vec2 uv;
uniform sampler2D image;
out vec4 frag;
void main() { frag = vec4(texture(image, uv).rgb, 1.0); }
)";

// A vertex array of the unit square's corners as a triangle strip, attribute 0.
void unit_square(GLuint* vao, GLuint* vbo) {
  const float corners[] = {0, 0, 1, 0, 0, 1, 1, 1};
  glGenVertexArrays(1, vao);
  glGenBuffers(1, vbo);
  glBindVertexArray(*vao);
  glBindBuffer(GL_ARRAY_BUFFER, *vbo);
  glBufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindVertexArray(0);
}

const char* kLineFragment = R"(#version 330 core
uniform vec3 color;
out vec4 frag;
void main() { frag = vec4(color, 1.0); }
)";

}  // namespace

struct MeshRenderer::Gl {
  GLuint mesh_program = 0, line_program = 0, backdrop_program = 0;
  GLuint backdrop_vao = 0, backdrop_vbo = 0, backdrop_textures[2] = {0, 0};  // image, depth
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLuint line_vao = 0, line_vbo = 0;
  GLuint fbo = 0, color_rb = 0, depth_rb = 0;
  int fbo_w = 0, fbo_h = 0;
};

MeshRenderer::MeshRenderer() : gl_(std::make_unique<Gl>()) {
  gl_->mesh_program = link_program(kMeshVertex, kMeshFragment);
  gl_->line_program = link_program(kLineVertex, kLineFragment);
  gl_->backdrop_program = link_program(kBackdropVertex, kBackdropFragment);
  unit_square(&gl_->backdrop_vao, &gl_->backdrop_vbo);
  glGenTextures(2, gl_->backdrop_textures);
  for (GLuint t : gl_->backdrop_textures) {
    glBindTexture(GL_TEXTURE_2D, t);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  glGenVertexArrays(1, &gl_->vao);
  glGenBuffers(1, &gl_->vbo);
  glGenBuffers(1, &gl_->ebo);
  glGenVertexArrays(1, &gl_->line_vao);
  glGenBuffers(1, &gl_->line_vbo);
}

MeshRenderer::~MeshRenderer() {
  glDeleteProgram(gl_->mesh_program);
  glDeleteProgram(gl_->line_program);
  glDeleteProgram(gl_->backdrop_program);
  glDeleteVertexArrays(1, &gl_->backdrop_vao);
  glDeleteBuffers(1, &gl_->backdrop_vbo);
  glDeleteTextures(2, gl_->backdrop_textures);
  glDeleteVertexArrays(1, &gl_->vao);
  glDeleteBuffers(1, &gl_->vbo);
  glDeleteBuffers(1, &gl_->ebo);
  glDeleteVertexArrays(1, &gl_->line_vao);
  glDeleteBuffers(1, &gl_->line_vbo);
  if (gl_->fbo) {
    glDeleteFramebuffers(1, &gl_->fbo);
    glDeleteRenderbuffers(1, &gl_->color_rb);
    glDeleteRenderbuffers(1, &gl_->depth_rb);
  }
}

void MeshRenderer::set_mesh(const TriangleMesh& mesh) {
  // Interleaved position, normal, colour; a mesh without normals is drawn with face normals (vertices unshared).
  std::vector<float> v;
  std::vector<unsigned> idx;
  auto push = [&](const Eigen::Vector3f& p, const Eigen::Vector3f& n, const Rgb8& c) {
    v.insert(v.end(), {p.x(), p.y(), p.z(), n.x(), n.y(), n.z(), c.r / 255.0f, c.g / 255.0f, c.b / 255.0f});
  };
  const Rgb8 white{255, 255, 255};
  if (mesh.has_normals()) {
    for (size_t i = 0; i < mesh.vertices.size(); ++i)
      push(mesh.vertices[i], mesh.normals[i], mesh.has_colors() ? mesh.colors[i] : white);
    for (const auto& t : mesh.triangles) idx.insert(idx.end(), {unsigned(t[0]), unsigned(t[1]), unsigned(t[2])});
  } else {
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector3f a = mesh.vertices[size_t(t[0])], b = mesh.vertices[size_t(t[1])],
                            c = mesh.vertices[size_t(t[2])];
      const Eigen::Vector3f n = (b - a).cross(c - a).normalized();
      for (int k = 0; k < 3; ++k) {
        idx.push_back(unsigned(v.size() / 9));
        push(mesh.vertices[size_t(t[k])], n, mesh.has_colors() ? mesh.colors[size_t(t[k])] : white);
      }
    }
  }
  glBindVertexArray(gl_->vao);
  glBindBuffer(GL_ARRAY_BUFFER, gl_->vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gl_->ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(idx.size() * sizeof(unsigned)), idx.data(), GL_STATIC_DRAW);
  for (GLuint a = 0; a < 3; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 9 * sizeof(float),
                          reinterpret_cast<const void*>(size_t(a) * 3 * sizeof(float)));
  }
  glBindVertexArray(0);
  triangles_ = int(idx.size() / 3);
  mesh_lo_ = Eigen::Vector3f::Zero(), mesh_hi_ = Eigen::Vector3f::Zero();
  if (!mesh.vertices.empty()) {
    mesh_lo_ = mesh_hi_ = mesh.vertices[0];
    for (const auto& p : mesh.vertices) mesh_lo_ = mesh_lo_.cwiseMin(p), mesh_hi_ = mesh_hi_.cwiseMax(p);
  }
}

void MeshRenderer::set_backdrop(const ColorImage& image, const DepthImage& depth_m) {
  backdrop_ = !image.empty();
  if (!backdrop_) return;
  if (depth_m.width() != image.width() || depth_m.height() != image.height())
    throw Error("viewer: the backdrop's image and depth differ in size");
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glBindTexture(GL_TEXTURE_2D, gl_->backdrop_textures[0]);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, image.width(), image.height(), 0, GL_RGB, GL_UNSIGNED_BYTE, image.data());
  glBindTexture(GL_TEXTURE_2D, gl_->backdrop_textures[1]);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, depth_m.width(), depth_m.height(), 0, GL_RED, GL_FLOAT, depth_m.data());
  glBindTexture(GL_TEXTURE_2D, 0);
}

void MeshRenderer::draw(const PinholeCamera& camera, const SE3& T_world_camera, const std::vector<Polyline>& lines,
                        bool use_colors) {
  // The far plane reaches past the mesh's farthest bounding-box corner (at least 50 m), so a large mesh framed
  // whole (view_files.h frame_mesh) is not cut off; near stays 0.05 m for close-ups.
  const double near_m = 0.05;
  double far_m = 50.0;
  if (triangles_ > 0)
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d corner((k & 1) ? mesh_hi_.x() : mesh_lo_.x(), (k & 2) ? mesh_hi_.y() : mesh_lo_.y(),
                                   (k & 4) ? mesh_hi_.z() : mesh_lo_.z());
      far_m = std::max(far_m, 1.05 * (T_world_camera.inverse() * corner).z());
    }
  const glm::mat4 clip = pinhole_clip(camera, near_m, far_m);
  const glm::mat4 T_camera_world = to_glm(T_world_camera.inverse().matrixf());
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);  // back faces get the ambient term, as in the raycast
  if (backdrop_) {
    GLint vp[4] = {0, 0, 0, 0};
    glGetIntegerv(GL_VIEWPORT, vp);
    const GLuint p = gl_->backdrop_program;
    glUseProgram(p);
    glUniform1i(glGetUniformLocation(p, "image"), 0);
    glUniform1i(glGetUniformLocation(p, "depth_m"), 1);
    glUniform4f(glGetUniformLocation(p, "viewport"), float(vp[0]), float(vp[1]), float(vp[2]), float(vp[3]));
    glUniform2f(glGetUniformLocation(p, "depth_map"), float((far_m + near_m) / (far_m - near_m)),
                float(-2.0 * far_m * near_m / (far_m - near_m)));
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, gl_->backdrop_textures[1]);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, gl_->backdrop_textures[0]);
    glBindVertexArray(gl_->backdrop_vao);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  }
  if (triangles_ > 0) {
    glUseProgram(gl_->mesh_program);
    glUniformMatrix4fv(glGetUniformLocation(gl_->mesh_program, "T_camera_world"), 1, GL_FALSE,
                       glm::value_ptr(T_camera_world));
    glUniformMatrix4fv(glGetUniformLocation(gl_->mesh_program, "clip"), 1, GL_FALSE, glm::value_ptr(clip));
    glUniform1i(glGetUniformLocation(gl_->mesh_program, "use_colors"), use_colors ? 1 : 0);
    glBindVertexArray(gl_->vao);
    glDrawElements(GL_TRIANGLES, triangles_ * 3, GL_UNSIGNED_INT, nullptr);
  }
  glUseProgram(gl_->line_program);
  glUniformMatrix4fv(glGetUniformLocation(gl_->line_program, "T_camera_world"), 1, GL_FALSE,
                     glm::value_ptr(T_camera_world));
  glUniformMatrix4fv(glGetUniformLocation(gl_->line_program, "clip"), 1, GL_FALSE, glm::value_ptr(clip));
  glBindVertexArray(gl_->line_vao);
  glBindBuffer(GL_ARRAY_BUFFER, gl_->line_vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  for (const Polyline& l : lines) {
    if (l.points_world.size() < 2) continue;
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(l.points_world.size() * 3 * sizeof(float)), l.points_world.data(),
                 GL_STREAM_DRAW);
    glUniform3f(glGetUniformLocation(gl_->line_program, "color"), l.color.r / 255.0f, l.color.g / 255.0f,
                l.color.b / 255.0f);
    glDrawArrays(l.strip ? GL_LINE_STRIP : GL_LINES, 0, GLsizei(l.points_world.size()));
  }
  glBindVertexArray(0);
  glUseProgram(0);
}

ColorImage MeshRenderer::render(const PinholeCamera& camera, const SE3& T_world_camera,
                                const std::vector<Polyline>& lines, bool use_colors) {
  Gl& g = *gl_;
  if (!g.fbo || g.fbo_w != camera.width || g.fbo_h != camera.height) {
    if (g.fbo) {
      glDeleteFramebuffers(1, &g.fbo);
      glDeleteRenderbuffers(1, &g.color_rb);
      glDeleteRenderbuffers(1, &g.depth_rb);
    }
    glGenFramebuffers(1, &g.fbo);
    glGenRenderbuffers(1, &g.color_rb);
    glGenRenderbuffers(1, &g.depth_rb);
    glBindRenderbuffer(GL_RENDERBUFFER, g.color_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, camera.width, camera.height);
    glBindRenderbuffer(GL_RENDERBUFFER, g.depth_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, camera.width, camera.height);
    glBindFramebuffer(GL_FRAMEBUFFER, g.fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, g.color_rb);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, g.depth_rb);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("viewer: the offscreen framebuffer is incomplete");
    g.fbo_w = camera.width;
    g.fbo_h = camera.height;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, g.fbo);
  glViewport(0, 0, camera.width, camera.height);
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  draw(camera, T_world_camera, lines, use_colors);
  std::vector<std::uint8_t> rgba(size_t(camera.width) * camera.height * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, camera.width, camera.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (glGetError() != GL_NO_ERROR) throw Error("viewer: OpenGL reported an error while rendering");
  ColorImage out(camera.width, camera.height);
  for (int y = 0; y < camera.height; ++y) {
    const std::uint8_t* row = rgba.data() + size_t(camera.height - 1 - y) * camera.width * 4;  // GL rows go up
    for (int x = 0; x < camera.width; ++x) out(x, y) = {row[4 * x], row[4 * x + 1], row[4 * x + 2]};
  }
  return out;
}

ImageQuad::ImageQuad(int textures) : program_(link_program(kImageVertex, kImageFragment)), textures_(size_t(textures)) {
  unit_square(&vao_, &vbo_);
  glGenTextures(textures, textures_.data());
  for (GLuint t : textures_) {
    glBindTexture(GL_TEXTURE_2D, t);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  }
}

ImageQuad::~ImageQuad() {
  glDeleteTextures(GLsizei(textures_.size()), textures_.data());
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void ImageQuad::upload(int texture, const ColorImage& image) {
  glBindTexture(GL_TEXTURE_2D, textures_[size_t(texture)]);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, image.width(), image.height(), 0, GL_RGB, GL_UNSIGNED_BYTE, image.data());
}

void ImageQuad::draw(int texture) const {
  glDisable(GL_DEPTH_TEST);
  glUseProgram(program_);
  glBindVertexArray(vao_);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, textures_[size_t(texture)]);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
}

GLuint link_program(const char* vertex_source, const char* fragment_source) {
  auto compile = [](GLenum type, const char* source) {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[1024] = {};
      glGetShaderInfoLog(s, sizeof log, nullptr, log);
      throw Error(std::string("viewer: shader does not compile: ") + log);
    }
    return s;
  };
  const GLuint v = compile(GL_VERTEX_SHADER, vertex_source), f = compile(GL_FRAGMENT_SHADER, fragment_source);
  const GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) throw Error("viewer: shader program does not link");
  return p;
}

Polyline camera_frustum(const PinholeCamera& c, const SE3& T_world_camera, double depth_m, Rgb8 color) {
  const Eigen::Vector3d o = T_world_camera.translation();
  auto corner = [&](double u, double v) {
    return T_world_camera * Eigen::Vector3d((u - c.cx) / c.fx * depth_m, (v - c.cy) / c.fy * depth_m, depth_m);
  };
  const Eigen::Vector3d k[4] = {corner(-0.5, -0.5), corner(c.width - 0.5, -0.5), corner(c.width - 0.5, c.height - 0.5),
                                corner(-0.5, c.height - 0.5)};
  Polyline l;
  l.color = color;
  l.strip = false;
  for (int i = 0; i < 4; ++i) {
    l.points_world.push_back(o.cast<float>());
    l.points_world.push_back(k[i].cast<float>());
    l.points_world.push_back(k[i].cast<float>());
    l.points_world.push_back(k[(i + 1) % 4].cast<float>());
  }
  return l;
}

}  // namespace hf::viewer
