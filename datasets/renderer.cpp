#include "datasets/renderer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace hf::datasets {

RenderedView render_view(const Scene& scene, const PinholeCamera& camera, const SE3& T_world_camera,
                         const Lighting& lighting) {
  const int W = camera.width, H = camera.height;
  RenderedView view{DepthImage(W, H, 0.0f), Image<float>(W, H, 0.0f), ColorImageF(W, H)};
  const Eigen::Matrix3d R = T_world_camera.rotation();
  const Eigen::Vector3d origin = T_world_camera.translation();
  const Eigen::Vector3d l = lighting.to_light_world.normalized();
  const Scene::RayOrigin ray_origin = scene.prepare(origin);
  tbb::parallel_for(0, H, [&](int v) {
    for (int u = 0; u < W; ++u) {
      const Eigen::Vector3d d_camera((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      const Eigen::Vector3d d = R * d_camera;
      const auto hit = scene.intersect(ray_origin, d);
      if (!hit) continue;
      view.depth(u, v) = float(hit->t);
      const double cos_theta = std::clamp(-hit->normal_world.dot(d) / d.norm(), 0.0, 1.0);
      view.incidence_rad(u, v) = float(std::acos(cos_theta));
      const double shade = lighting.ambient + lighting.diffuse * std::max(0.0, hit->normal_world.dot(l));
      const Eigen::Vector3d c = scene.albedo(*hit) * shade;
      view.color(u, v) = RgbF{float(c.x()), float(c.y()), float(c.z())};
    }
  });
  return view;
}

}  // namespace hf::datasets
