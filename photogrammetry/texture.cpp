#include "photogrammetry/texture.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace hf::photogrammetry {

Rgb8 sample_bilinear(const ColorImage& image, const Eigen::Vector2d& uv) {
  const double u = std::clamp(uv.x(), 0.0, image.width() - 1.0), v = std::clamp(uv.y(), 0.0, image.height() - 1.0);
  const int u0 = std::min(int(u), image.width() - 2 < 0 ? 0 : image.width() - 2);
  const int v0 = std::min(int(v), image.height() - 2 < 0 ? 0 : image.height() - 2);
  const int u1 = std::min(u0 + 1, image.width() - 1), v1 = std::min(v0 + 1, image.height() - 1);
  const double a = u - u0, b = v - v0;
  const auto mix = [&](auto channel) {
    const double top = (1 - a) * channel(image(u0, v0)) + a * channel(image(u1, v0));
    const double bottom = (1 - a) * channel(image(u0, v1)) + a * channel(image(u1, v1));
    return std::uint8_t(std::clamp(std::lround((1 - b) * top + b * bottom), 0L, 255L));
  };
  return {mix([](Rgb8 c) { return double(c.r); }), mix([](Rgb8 c) { return double(c.g); }),
          mix([](Rgb8 c) { return double(c.b); })};
}

namespace {

// Best shot for world point X on a plane with unit normal n: highest cos / dist, or -1.
int best_shot(const Eigen::Vector3d& X, const Eigen::Vector3d& n, const Network& network,
              const std::vector<const ColorImage*>& images, double min_cos, Eigen::Vector2d* uv_out) {
  int best = -1;
  double best_score = 0;
  for (size_t s = 0; s < network.shots.size(); ++s) {
    if (!images[s]) continue;
    const Shot& shot = network.shots[s];
    const Eigen::Vector3d to_camera = shot.C_world - X;
    const double dist = to_camera.norm();
    if (!(dist > 0)) continue;
    const double c = n.dot(to_camera) / dist;
    if (c < min_cos) continue;
    const auto uv = shot.project(X);
    if (!uv || uv->x() < 0 || uv->y() < 0 || uv->x() > shot.width - 1.0 || uv->y() > shot.height - 1.0) continue;
    const double score = c / dist;
    if (score > best_score) {
      best_score = score;
      best = int(s);
      *uv_out = *uv;
    }
  }
  return best;
}

}  // namespace

std::optional<PolygonTexture> build_texture(const std::vector<Eigen::Vector3d>& vertices, const Eigen::Vector4d& plane,
                                            const Network& network, const std::vector<const ColorImage*>& images,
                                            const TextureOptions& o) {
  if (vertices.size() < 3 || !plane.allFinite() || !(plane.head<3>().norm() > 0)) return std::nullopt;
  const Eigen::Vector3d n = plane.head<3>().normalized();
  Eigen::Vector3d u = vertices[1] - vertices[0];
  u -= n.dot(u) * n;
  if (!(u.norm() > 0)) return std::nullopt;
  u.normalize();
  const Eigen::Vector3d v = n.cross(u);
  const Eigen::Vector3d origin = vertices[0];
  double s_min = INFINITY, s_max = -INFINITY, t_min = INFINITY, t_max = -INFINITY;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& X : vertices) {
    const double s = u.dot(X - origin), t = v.dot(X - origin);
    s_min = std::min(s_min, s), s_max = std::max(s_max, s), t_min = std::min(t_min, t), t_max = std::max(t_max, t);
    centroid += X;
  }
  centroid /= double(vertices.size());
  const double width = s_max - s_min, height = t_max - t_min;
  if (!(width > 0) || !(height > 0) || !std::isfinite(width + height)) return std::nullopt;

  double texel = o.texel_size;
  if (!(texel > 0)) {
    texel = INFINITY;
    for (size_t s = 0; s < network.shots.size(); ++s) {
      if (!images[s]) continue;
      const double z = network.shots[s].to_camera(centroid).z();
      if (z > 0) texel = std::min(texel, z / network.shots[s].focal_px());
    }
    if (!std::isfinite(texel)) return std::nullopt;
  }
  texel = std::max(texel, std::max(width, height) / std::max(1, o.max_texture_px));
  const int cols = std::max(1, int(std::ceil(width / texel))), rows = std::max(1, int(std::ceil(height / texel)));

  PolygonTexture tex;
  tex.texel_size = texel;
  tex.image = ColorImage(cols, rows);
  tex.source = Image<std::int16_t>(cols, rows, -1);
  std::set<int> used;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector3d X = origin + (s_min + (c + 0.5) * texel) * u + (t_max - (r + 0.5) * texel) * v;
      Eigen::Vector2d uv;
      const int s = best_shot(X, n, network, images, o.min_cos, &uv);
      if (s < 0) continue;
      tex.image(c, r) = sample_bilinear(*images[size_t(s)], uv);
      tex.source(c, r) = std::int16_t(std::min(s, 32767));
      used.insert(s);
    }
  if (used.empty()) return std::nullopt;
  tex.shots_used.assign(used.begin(), used.end());
  const double W = cols * texel, H = rows * texel;
  for (const auto& X : vertices)
    tex.uv.emplace_back((u.dot(X - origin) - s_min) / W, (v.dot(X - origin) - (t_max - H)) / H);
  return tex;
}

}  // namespace hf::photogrammetry
