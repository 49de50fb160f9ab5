// The render for people with fewer rays (fusion/sparse_render.h) on a fused noisy room at 160x120: every ray
// cast is the full render, the region of interest of a focus + context view is the full render there, fewer
// rays give a full image without holes, bad arguments throw.
#include "fusion/sparse_render.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/sample_patterns.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/integrate.h"

namespace hf::fusion {
namespace {

struct Room {
  VoxelBlockGrid grid{VolumeParams{}};
  PinholeCamera camera = PinholeCamera::preset("ros").scaled(2);
  SE3 T_world_camera;
  ColorImage full;
};

const Room& sparse_render_room() {
  static Room r = [] {
    Room sparse_render_room;
    datasets::SyntheticOptions o;
    o.preset = "room";
    o.frames = 12;
    o.camera = sparse_render_room.camera;
    const datasets::SyntheticSequence seq(o);
    for (int i = 0; i < 12; i += 3) {
      const datasets::SyntheticFrame f = seq.frame(i);
      integrate(sparse_render_room.grid, f.depth, f.color, seq.camera(), f.T_world_camera);
      sparse_render_room.T_world_camera = f.T_world_camera;
    }
    RaycastOptions opts;
    sparse_render_room.full = raycast(sparse_render_room.grid, sparse_render_room.camera, sparse_render_room.T_world_camera, opts).shaded;
    return sparse_render_room;
  }();
  return r;
}

TEST(SparseRender, EveryRayIsTheFullRender) {
  const Room& r = sparse_render_room();
  const Image<std::uint8_t> all(r.camera.width, r.camera.height, 1);
  for (Reconstruction m : {Reconstruction::push_pull, Reconstruction::mesh}) {
    const SparseRender s = render_masked(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, all, m);
    EXPECT_EQ(s.rays, long(r.camera.width) * r.camera.height);
    EXPECT_EQ(s.shaded.pixels(), r.full.pixels());
  }
  // A region of interest covering the image: the crop camera is the camera itself.
  const SparseRender f = render_focus_context(r.grid, r.camera, r.T_world_camera, RaycastOptions{},
                                              PixelRect{0, 0, r.camera.width, r.camera.height}, 1);
  EXPECT_EQ(f.shaded.pixels(), r.full.pixels());
}

TEST(SparseRender, FewerRaysGiveAWholeImage) {
  const Room& r = sparse_render_room();
  const int w = r.camera.width, h = r.camera.height;
  Image<std::uint8_t> mask(w, h);
  mask.pixels() = halton_mask(w, h, 0.3);
  const SparseRender s = render_masked(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, mask,
                                       Reconstruction::push_pull);
  EXPECT_EQ(s.rays, long(0.3 * w * h + 0.5));
  EXPECT_EQ(s.fill.status, PushPullStatus::ok);
  EXPECT_EQ(s.fill.empty_pixels, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (mask(x, y)) {
        ASSERT_EQ(s.shaded(x, y), r.full(x, y));  // cast pixels are the full render's
      }
    }
  // Focus + context: a quarter of the context rays; the region of interest is the full render up to the crop
  // camera's principal point rounding (one grey level).
  const PixelRect roi{40, 30, 120, 90};
  const SparseRender f = render_focus_context(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, roi, 1);
  EXPECT_EQ(f.rays, 80L * 60L + 80L * 60L);
  for (int y = roi.y0; y < roi.y1; ++y)
    for (int x = roi.x0; x < roi.x1; ++x) ASSERT_NEAR(f.shaded(x, y).r, r.full(x, y).r, 1) << x << "," << y;
}

TEST(SparseRender, CoNUSViewThroughASamplingMap) {
  const Room& r = sparse_render_room();
  // Rates 1 everywhere: the CoNUS image is the full render.
  const SparseRender id = render_conus(r.grid, r.camera, r.T_world_camera, RaycastOptions{},
                                       SamplingMap::identity(r.camera.width, r.camera.height, 8, 6));
  EXPECT_EQ(id.rays, long(r.camera.width) * r.camera.height);
  EXPECT_EQ(id.shaded.pixels(), r.full.pixels());
  // 20x20-pixel cells, the 2x2 centre cells (x 60..99, y 40..79) at full rate, the rest at half: a 100x80 CoNUS
  // image. The centre is sampled one ray per pixel, so it reads as the full render there.
  std::vector<float> rates(48, 0.5f);
  for (int j = 2; j < 4; ++j)
    for (int i = 3; i < 5; ++i) rates[size_t(j) * 8 + i] = 1.0f;
  const SamplingMap map = SamplingMap::from_region_rates(r.camera.width, r.camera.height, 8, 6, rates);
  const SparseRender c = render_conus(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, map);
  EXPECT_EQ(c.conus.width(), 100);
  EXPECT_EQ(c.conus.height(), 80);
  EXPECT_LE(c.rays, 100L * 80L);
  EXPECT_GT(c.rays, 100L * 80L * 9 / 10);  // distinct pixels: only snapping may merge rays
  for (int y = 41; y < 79; ++y)
    for (int x = 61; x < 99; ++x) ASSERT_NEAR(c.shaded(x, y).r, r.full(x, y).r, 1) << x << "," << y;
  EXPECT_THROW(render_conus(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, SamplingMap::identity(8, 8, 2, 2)),
               Error);
}

TEST(SparseRender, BadArgumentsThrow) {
  const Room& r = sparse_render_room();
  EXPECT_THROW(render_masked(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, Image<std::uint8_t>(4, 4, 1),
                             Reconstruction::push_pull),
               Error);
  EXPECT_THROW(render_focus_context(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, PixelRect{10, 10, 10, 20}, 1),
               Error);
  EXPECT_THROW(render_focus_context(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, PixelRect{0, 0, 200, 20}, 1),
               Error);
  EXPECT_THROW(render_focus_context(r.grid, r.camera, r.T_world_camera, RaycastOptions{}, PixelRect{0, 0, 20, 20}, 5),
               Error);
}

}  // namespace
}  // namespace hf::fusion
