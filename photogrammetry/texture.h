// Textures of the modelled polygons (Kellner section 6.2, after Musialski et al.): each texel of a polygon's plane
// is coloured from the shot that sees it best, chosen per texel by angle and distance -- the score cos(theta) / dist,
// theta the angle between the plane's normal and the direction to the shot's centre, dist the distance to it --
// among the shots whose image holds the texel's projection (with a one-pixel border for bilinear sampling) and that
// see the plane's front (cos(theta) >= min_cos). The interactive repainting ("brushing") of the paper is not done.
// Occlusion is not tested (there is no depth per shot): an occluder in the best shot shows in the texture.
//
// Texture frame: axis_u along the polygon's first edge, axis_v = n x axis_u (so u, v, n is right-handed and the
// texture reads upright seen from the normal's side); texel (col, row) covers plane coordinates s = s_min + (col +
// 0.5) texel, t = t_max - (row + 0.5) texel. Texture coordinates per vertex are OBJ's: (0, 0) the bottom-left corner.
#pragma once

#include <optional>
#include <vector>

#include "core/image.h"
#include "photogrammetry/network.h"

namespace hf::photogrammetry {

struct TextureOptions {
  // World units per texel; 0: the finest footprint among the shots that see the polygon's centroid (distance /
  // focal length), then coarsened until the longer side fits max_texture_px.
  double texel_size = 0.0;
  int max_texture_px = 1024;
  double min_cos = 0.05;  // grazing views (beyond ~87 degrees) are not used
};

struct PolygonTexture {
  ColorImage image;                    // texels no shot sees are black
  Image<std::int16_t> source;          // per texel, the shot index used (-1: none)
  std::vector<Eigen::Vector2d> uv;     // per vertex, OBJ texture coordinates in [0, 1]
  double texel_size = 0.0;
  std::vector<int> shots_used;         // distinct shot indices, ascending
};

// `images[s]` is shot s's image or null (not loaded, not available). nullopt when fewer than three vertices, the
// plane's normal is not finite, or no shot sees the polygon.
std::optional<PolygonTexture> build_texture(const std::vector<Eigen::Vector3d>& vertices, const Eigen::Vector4d& plane,
                                            const Network& network, const std::vector<const ColorImage*>& images,
                                            const TextureOptions& options = {});

// Bilinear sample at pixel (u, v), inside [0, width - 1] x [0, height - 1].
Rgb8 sample_bilinear(const ColorImage& image, const Eigen::Vector2d& uv);

}  // namespace hf::photogrammetry
