#include "datasets/mesh_renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hf::datasets {

RenderedView render_mesh(const TriangleMesh& mesh, const PinholeCamera& camera, const SE3& T_world_camera,
                         const Lighting& lighting, double near_m) {
  const int W = camera.width, H = camera.height;
  RenderedView view{DepthImage(W, H, 0.0f), Image<float>(W, H, 0.0f), ColorImageF(W, H)};
  const SE3 T_camera_world = T_world_camera.inverse();
  std::vector<Eigen::Vector3d> p(mesh.vertices.size());
  for (size_t i = 0; i < p.size(); ++i) p[i] = T_camera_world * mesh.vertices[i].cast<double>();
  const Eigen::Vector3d light_camera = (T_camera_world.rotation() * lighting.to_light_world).normalized();
  Image<double> z_buffer(W, H, std::numeric_limits<double>::infinity());
  for (size_t k = 0; k < mesh.triangles.size(); ++k) {
    const Eigen::Vector3i& t = mesh.triangles[k];
    const Eigen::Vector3d &a = p[t[0]], &b = p[t[1]], &c = p[t[2]];
    if (a.z() < near_m || b.z() < near_m || c.z() < near_m) continue;
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (!(n.squaredNorm() > 0)) continue;
    // Projected corners and the pixel centres (integer coordinates) inside their bounding box.
    const auto project = [&](const Eigen::Vector3d& q) { return Eigen::Vector2d(camera.fx * q.x() / q.z() + camera.cx, camera.fy * q.y() / q.z() + camera.cy); };
    const Eigen::Vector2d pa = project(a), pb = project(b), pc = project(c);
    const int u0 = std::max(0, int(std::ceil(std::min({pa.x(), pb.x(), pc.x()})))), u1 = std::min(W - 1, int(std::floor(std::max({pa.x(), pb.x(), pc.x()}))));
    const int v0 = std::max(0, int(std::ceil(std::min({pa.y(), pb.y(), pc.y()})))), v1 = std::min(H - 1, int(std::floor(std::max({pa.y(), pb.y(), pc.y()}))));
    if (u0 > u1 || v0 > v1) continue;
    const auto edge = [](const Eigen::Vector2d& from, const Eigen::Vector2d& to, double u, double v) {
      return (to.x() - from.x()) * (v - from.y()) - (to.y() - from.y()) * (u - from.x());
    };
    const double area = edge(pa, pb, pc.x(), pc.y());
    if (area == 0) continue;
    // Colour of the triangle: mean vertex colour (or grey) times the shade on its camera-facing normal.
    const Eigen::Vector3d n_unit = n.normalized();
    Eigen::Vector3d albedo(0.8, 0.8, 0.8);
    if (mesh.has_colors()) {
      albedo.setZero();
      for (int j = 0; j < 3; ++j) albedo += Eigen::Vector3d(mesh.colors[t[j]].r, mesh.colors[t[j]].g, mesh.colors[t[j]].b) / (3 * 255.0);
    }
    for (int v = v0; v <= v1; ++v)
      for (int u = u0; u <= u1; ++u) {
        const double e0 = edge(pb, pc, u, v), e1 = edge(pc, pa, u, v), e2 = edge(pa, pb, u, v);
        const bool inside = area > 0 ? (e0 >= 0 && e1 >= 0 && e2 >= 0) : (e0 <= 0 && e1 <= 0 && e2 <= 0);
        if (!inside) continue;
        const Eigen::Vector3d d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
        const double nd = n.dot(d);
        if (nd == 0) continue;
        const double depth = n.dot(a) / nd;  // the ray's t, which is its depth z since d.z() = 1
        if (!(depth > 0) || depth >= z_buffer(u, v)) continue;
        z_buffer(u, v) = depth;
        const Eigen::Vector3d facing = nd < 0 ? n_unit : Eigen::Vector3d(-n_unit);
        const double cos_theta = std::clamp(-facing.dot(d) / d.norm(), 0.0, 1.0);
        view.depth(u, v) = float(depth);
        view.incidence_rad(u, v) = float(std::acos(cos_theta));
        const Eigen::Vector3d col = albedo * (lighting.ambient + lighting.diffuse * std::max(0.0, facing.dot(light_camera)));
        view.color(u, v) = RgbF{float(col.x()), float(col.y()), float(col.z())};
      }
  }
  return view;
}

}  // namespace hf::datasets
