// Edge snapping with LSD (photogrammetry/edge_snapping.h), textures (texture.h) and the model job's outputs
// (model_outputs.h) on the rendered synthetic box building.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "core/error.h"
#include "io/image_io.h"
#include "photogrammetry/model_outputs.h"
#include "photogrammetry/polygon_transfer.h"
#include "photogrammetry/scene_readers.h"
#include "tests/photogrammetry/box_building.h"

namespace hf::photogrammetry {
namespace {

using testing::BoxBuilding;
namespace fs = std::filesystem;

TEST(EdgeSnapping, ARoughWindowSketchSnapsToItsImageEdges) {
  const BoxBuilding b;
  const Shot shot = BoxBuilding::shots()[1];
  const ColorImage image = b.render(shot);
  const std::vector<LineSegment2> lines = detect_line_segments(image);
  ASSERT_GT(lines.size(), 20u);
  for (int w = 0; w < 6; ++w) {
    const Polygon2d truth = b.project(shot, BoxBuilding::window_corners(w));
    // A rough sketch: each corner off by 2-2.5 px in both directions (edges tilted by up to 9 degrees).
    Polygon2d rough = truth;
    const double dx[] = {2, -2.5, 2.5, -2}, dy[] = {-2.5, 2, 2.5, -2};
    for (size_t k = 0; k < 4; ++k) rough[k] += Eigen::Vector2d(dx[k], dy[k]);
    const SnapResult r = snap_polygon(rough, lines);
    ASSERT_TRUE(r.snapped) << "window " << w;
    for (size_t k = 0; k < 4; ++k) {
      EXPECT_FALSE(r.edges[k].lines.empty()) << "window " << w << " edge " << k;
      // LSD localises a sharp step edge to a fraction of a pixel; the window's edges lie on pixel boundaries of a
      // point-sampled rendering, so half a pixel each way is the rendering's own uncertainty.
      EXPECT_LT((r.points[k] - truth[k]).norm(), 1.0) << "window " << w << " corner " << k;
    }
  }
  // Far from any edge nothing snaps and the sketch comes back unchanged.
  const Polygon2d sky = {{20, 10}, {80, 10}, {80, 30}, {20, 30}};
  const SnapResult none = snap_polygon(sky, lines);
  EXPECT_FALSE(none.snapped);
  EXPECT_EQ(none.points, sky);
}

TEST(PolygonTransfer, AWindowMovesIntoTheNeighbouringShotOntoItsEdges) {
  const BoxBuilding b;
  const std::vector<Shot> shots = BoxBuilding::shots();
  const ColorImage source = b.render(shots[1]), target = b.render(shots[0]);
  const std::vector<LineSegment2> lines = detect_line_segments(target);
  for (const int w : {0, 4}) {
    const Polygon2d outline = b.project(shots[1], BoxBuilding::window_corners(w));
    // A wrong plane hypothesis: 1.5 m in front of the facade, so the plain projection lands ~10 px off.
    const auto r = transfer_polygon(shots[1], source, outline, {0, -1, 0, -1.5}, shots[0], target, lines);
    ASSERT_TRUE(r);
    const Polygon2d truth = b.project(shots[0], BoxBuilding::window_corners(w));
    double projected_error = 0;
    for (size_t k = 0; k < 4; ++k) projected_error = std::max(projected_error, (r->projected[k] - truth[k]).norm());
    EXPECT_GT(projected_error, 5.0);
    ASSERT_GE(r->anchor_edge, 0);

    // Each snapped line sits within half a pixel of the point-sampled edge across it, so a corner (two lines)
    // within sqrt(2) / 2 px, plus LSD's own sub-pixel error: 1.5 px.
    for (size_t k = 0; k < 4; ++k) EXPECT_LT((r->points[k] - truth[k]).norm(), 1.5) << "window " << w << " corner " << k;
  }
}

double psnr_front_texture(const PolygonTexture& t, const std::vector<Eigen::Vector3d>& corners) {
  // The texture frame of the front facade from corner 0 = (0,0,0) along +x: s = x, t = z (texture.h).
  double sum = 0;
  long n = 0;
  for (int r = 0; r < t.image.height(); ++r)
    for (int c = 0; c < t.image.width(); ++c) {
      const double x = (c + 0.5) * t.texel_size, z = corners[2].z() - (r + 0.5) * t.texel_size;
      if (x > 10 || z < 0) continue;
      const Rgb8 a = t.image(c, r), b = BoxBuilding::front_color(x, z);
      sum += std::pow(a.r - b.r, 2) + std::pow(a.g - b.g, 2) + std::pow(a.b - b.b, 2);
      n += 3;
    }
  return 10 * std::log10(255.0 * 255.0 / (sum / double(n)));
}

TEST(Texture, TheFrontFacadeTextureReproducesTheRenderedFacade) {
  const BoxBuilding b;
  Network n;
  n.source = "box";
  n.shots = BoxBuilding::shots();
  std::vector<ColorImage> images;
  for (const Shot& s : n.shots) images.push_back(b.render(s));
  std::vector<const ColorImage*> ptrs;
  for (const ColorImage& i : images) ptrs.push_back(&i);
  const std::vector<Eigen::Vector3d> corners = b.front_corners();
  TextureOptions o;
  o.texel_size = 0.05;
  const auto t = build_texture(corners, {0, -1, 0, 0}, n, ptrs, o);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->image.width(), 200);
  EXPECT_EQ(t->image.height(), 120);
  EXPECT_NEAR(t->uv[2].x(), 1.0, 1e-12);
  EXPECT_NEAR(t->uv[2].y(), 1.0, 1e-12);
  // The front shot sees the facade's centre best (closest, head-on); the corner shot sees it worst.
  EXPECT_EQ(t->source(100, 60), 1);
  // Bilinear resampling of point-sampled renderings at 1.5-2 texels per pixel: the error is the windows' aliased
  // edges (20 % of the facade's texels border none), bounded well below 255 / 10^(25/20) = 14 levels RMS.
  const double psnr = psnr_front_texture(*t, corners);
  EXPECT_GT(psnr, 25.0) << psnr;
  // A polygon no shot sees (behind the building) has no texture.
  EXPECT_FALSE(build_texture({{0, 8, 0}, {10, 8, 0}, {10, 8, 6}}, {0, 1, 0, -8}, n, ptrs, o));
}

TEST(ModelJob, WritesPolygonsObjTexturesAndOverlays) {
  const BoxBuilding b;
  const fs::path root = fs::temp_directory_path() / ("hf_pg_job_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "images");
  Network n;
  n.source = "box";
  n.shots = BoxBuilding::shots();
  for (Shot& s : n.shots) {
    s.image_path = (root / "images" / s.name).string();
    s.image_available = true;
    write_color_png(s.image_path, b.render(s));
  }
  n.cloud = b.cloud(0.2, 0.01, 1);
  Sketch sketch;
  sketch.polygons.push_back({"front", {{"front.png", b.project(n.shots[1], b.front_corners())}}, ""});
  sketch.polygons.push_back({"w0", {{"front.png", b.project(n.shots[1], BoxBuilding::window_corners(0))}}, "front"});
  sketch.polygons.push_back({"w1", {{"front_left.png", b.project(n.shots[0], BoxBuilding::window_corners(1))},
                                    {"front_right.png", b.project(n.shots[2], BoxBuilding::window_corners(1))}}, ""});
  sketch.polygons.push_back({"sky", {{"front.png", {{10, 5}, {100, 5}, {100, 40}, {10, 40}}}}, ""});
  ModelJobOptions o;
  o.model.ransac.distance_threshold = 0.03;
  o.texture.texel_size = 0.05;
  o.snap = true;
  const ModelJobResult r = run_model_job(n, sketch, "sketch.json", (root / "out").string(), o);
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(root / "out" / "polygons.json"));
  ASSERT_EQ(j["polygons"].size(), 4u);
  EXPECT_EQ(j["polygons"][0]["id"], "front");
  EXPECT_EQ(j["polygons"][0]["guidance"], "green");
  EXPECT_EQ(j["polygons"][0]["method"], "cloud_plane");
  EXPECT_EQ(j["polygons"][0]["vertices"].size(), 4u);
  EXPECT_EQ(j["polygons"][0]["plane"].size(), 4u);
  EXPECT_EQ(j["polygons"][1]["method"], "polygon_plane");
  EXPECT_EQ(j["polygons"][2]["guidance"], "yellow");
  EXPECT_EQ(j["polygons"][2]["method"], "dlt");
  EXPECT_EQ(j["polygons"][2]["reprojection_error_px"].size(), 4u);
  EXPECT_EQ(j["polygons"][3]["guidance"], "red");
  EXPECT_TRUE(j["polygons"][3]["method"].is_null());
  EXPECT_TRUE(j["polygons"][3]["plane"].is_null());
  EXPECT_TRUE(j["polygons"][3]["vertices"].empty());
  // Snapped to the rendered edges, the window from two shots lands within a few centimetres of its true corners
  // (a 1 px error is 4 cm at 17 m and 420 px focal length; two rays 30 degrees apart).
  for (size_t k = 0; k < 4; ++k) {
    const auto& v = j["polygons"][2]["vertices"][k];
    EXPECT_LT((Eigen::Vector3d(v[0], v[1], v[2]) - BoxBuilding::window_corners(1)[k]).norm(), 0.15);
  }
  EXPECT_TRUE(fs::exists(root / "out" / "model.obj"));
  EXPECT_TRUE(fs::exists(root / "out" / "model.mtl"));
  EXPECT_TRUE(fs::exists(root / "out" / "textures" / "0_front.png"));
  EXPECT_EQ(load_color((root / "out" / "overlays" / "front.png").string()).width(), 480);
  std::ifstream obj(root / "out" / "model.obj");
  const std::string text((std::istreambuf_iterator<char>(obj)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("usemtl 0_front"), std::string::npos);
  EXPECT_NE(text.find("f 1/1 2/2 3/3 4/4"), std::string::npos);
  for (const auto& e : fs::recursive_directory_iterator(root / "out"))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  // A missing image of a sketched shot is a clear error naming the file.
  fs::remove(n.shots[1].image_path);
  n.shots[1].image_available = false;
  try {
    run_model_job(n, sketch, "sketch.json", (root / "out2").string(), o);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("front.png: the image of shot 'front.png' is missing"), std::string::npos)
        << e.what();
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace hf::photogrammetry
