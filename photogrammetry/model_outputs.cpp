#include "photogrammetry/model_outputs.h"

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/image_io.h"

namespace hf::photogrammetry {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// A file-name-safe stem: [A-Za-z0-9_-], the rest '_', prefixed by the polygon's position (ids may collide after
// sanitising).
std::string safe_stem(size_t index, const std::string& id) {
  std::string s = std::to_string(index) + "_";
  for (const char c : id.substr(0, 60)) s += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return s;
}

cv::Scalar guidance_bgr(Guidance g) {
  switch (g) {
    case Guidance::green: return {40, 200, 40};
    case Guidance::yellow: return {0, 220, 240};
    case Guidance::red: return {40, 40, 230};
  }
  return {255, 255, 255};
}

cv::Mat to_bgr(const ColorImage& image) {
  cv::Mat m(image.height(), image.width(), CV_8UC3);
  for (int v = 0; v < image.height(); ++v)
    for (int u = 0; u < image.width(); ++u) {
      const Rgb8 c = image(u, v);
      m.at<cv::Vec3b>(v, u) = cv::Vec3b(c.b, c.g, c.r);
    }
  return m;
}

ColorImage from_bgr(const cv::Mat& m) {
  ColorImage out(m.cols, m.rows);
  for (int v = 0; v < m.rows; ++v)
    for (int u = 0; u < m.cols; ++u) {
      const cv::Vec3b c = m.at<cv::Vec3b>(v, u);
      out(u, v) = Rgb8{c[2], c[1], c[0]};
    }
  return out;
}

std::vector<cv::Point> cv_points(const Polygon2d& p) {
  std::vector<cv::Point> out;
  for (const auto& q : p) out.emplace_back(int(std::lround(q.x() * 16)), int(std::lround(q.y() * 16)));
  return out;
}

void polyline(cv::Mat& m, const Polygon2d& p, const cv::Scalar& colour, int thickness) {
  const std::vector<cv::Point> pts = cv_points(p);
  const cv::Point* c[] = {pts.data()};
  const int n[] = {int(pts.size())};
  cv::polylines(m, c, n, 1, true, colour, thickness, cv::LINE_AA, 4);
}

std::string obj_text(const Model& model, const std::vector<std::optional<PolygonTexture>>& textures,
                     const std::vector<std::string>& names) {
  std::ostringstream o;
  o.precision(17);
  o << "# hashfusion model: the placed polygons (polygons.json has their planes and states)\nmtllib model.mtl\n";
  size_t v_base = 1, vt_base = 1;
  for (size_t i = 0; i < model.polygons.size(); ++i) {
    const ModelledPolygon& p = model.polygons[i];
    if (p.vertices.empty()) continue;
    o << "o " << names[i] << "\n";
    for (const auto& X : p.vertices) o << "v " << X.x() << ' ' << X.y() << ' ' << X.z() << "\n";
    const bool textured = textures[i].has_value();
    if (textured) {
      for (const auto& uv : textures[i]->uv) o << "vt " << uv.x() << ' ' << uv.y() << "\n";
      o << "usemtl " << names[i] << "\n";
    }
    o << "f";
    for (size_t k = 0; k < p.vertices.size(); ++k) {
      o << ' ' << v_base + k;
      if (textured) o << '/' << vt_base + k;
    }
    o << "\n";
    v_base += p.vertices.size();
    if (textured) vt_base += p.vertices.size();
  }
  return o.str();
}

std::string mtl_text(const std::vector<std::optional<PolygonTexture>>& textures, const std::vector<std::string>& names) {
  std::ostringstream o;
  o << "# hashfusion model: one material per textured polygon\n";
  for (size_t i = 0; i < textures.size(); ++i)
    if (textures[i])
      o << "newmtl " << names[i] << "\nKa 1 1 1\nKd 1 1 1\nd 1\nillum 1\nmap_Kd textures/" << names[i] << ".png\n";
  return o.str();
}

}  // namespace

std::string format_polygons_json(const Model& model, const std::vector<std::string>& texture_names) {
  json polygons = json::array();
  for (size_t i = 0; i < model.polygons.size(); ++i) {
    const ModelledPolygon& p = model.polygons[i];
    json j;
    j["id"] = p.id;
    json vertices = json::array();
    for (const auto& X : p.vertices) vertices.push_back({X.x(), X.y(), X.z()});
    j["vertices"] = vertices;
    j["plane"] = p.plane ? json{(*p.plane)[0], (*p.plane)[1], (*p.plane)[2], (*p.plane)[3]} : json(nullptr);
    j["guidance"] = to_string(p.decision.state);
    j["method"] = p.decision.method == Placement::none ? json(nullptr) : json(to_string(p.decision.method));
    j["reprojection_error_px"] = p.reprojection_error_px;
    j["reason"] = p.decision.reason;
    j["texture"] = i < texture_names.size() && !texture_names[i].empty() ? json(texture_names[i]) : json(nullptr);
    polygons.push_back(j);
  }
  return json{{"polygons", polygons}}.dump(2) + "\n";
}

ColorImage draw_outlines(const ColorImage& photo, const std::vector<std::pair<Polygon2d, Rgb8>>& outlines,
                         int thickness_px) {
  cv::Mat m = to_bgr(photo);
  for (const auto& [q, c] : outlines)
    if (!q.empty()) polyline(m, q, {double(c.b), double(c.g), double(c.r)}, thickness_px);
  return from_bgr(m);
}

Rgb8 guidance_rgb(Guidance g) {
  const cv::Scalar c = guidance_bgr(g);
  return {std::uint8_t(c[2]), std::uint8_t(c[1]), std::uint8_t(c[0])};
}

std::string format_sketch_json(const Sketch& sketch) {
  json polygons = json::array();
  for (const SketchPolygon& p : sketch.polygons) {
    json views = json::array();
    for (const SketchView& v : p.views) {
      json points = json::array();
      for (const auto& q : v.points) points.push_back({q.x(), q.y()});
      views.push_back({{"shot", v.shot}, {"points", points}});
    }
    json j{{"id", p.id}, {"views", views}};
    if (!p.same_plane_as.empty()) j["same_plane_as"] = p.same_plane_as;
    polygons.push_back(j);
  }
  return json{{"polygons", polygons}}.dump(2) + "\n";
}

namespace {

// Section 5.2's transfer for every polygon sketched once and placed on a plane, into each other shot that sees the
// placed polygon inside its image. `image` loads (and caches) a shot's image; `lines` a shot's LSD segments.
template <class Image, class Lines>
std::vector<TransferredView> transfer_single_views(const Network& network, const Sketch& sketch, const Model& model,
                                                   const TransferOptions& options, Image image, Lines lines) {
  std::vector<TransferredView> out;
  for (size_t i = 0; i < sketch.polygons.size(); ++i) {
    const SketchPolygon& p = sketch.polygons[i];
    const ModelledPolygon& m = model.polygons[i];
    if (p.views.size() != 1 || m.vertices.empty() || !m.plane) continue;
    const size_t source = size_t(network.shot_index(p.views[0].shot));
    if (!network.shots[source].image_available) continue;
    for (size_t t = 0; t < network.shots.size(); ++t) {
      const Shot& target = network.shots[t];
      if (t == source || !target.image_available) continue;
      bool inside = true;
      for (const auto& X : m.vertices) {
        const auto uv = target.project(X);
        inside = inside && uv && target.in_image(*uv);
      }
      if (!inside) continue;
      const auto r = transfer_polygon(network.shots[source], *image(source), p.views[0].points, *m.plane, target,
                                      *image(t), lines(t), options);
      if (!r) continue;
      bool kept = true;  // a snap may push a vertex out of the image: SKETCH.json would refuse it
      for (const auto& uv : r->points) kept = kept && target.in_image(uv);
      if (kept) out.push_back({i, target.name, *r});
    }
  }
  return out;
}

}  // namespace

ModelJobResult run_model_job(const Network& network, const Sketch& input_sketch, const std::string& sketch_name,
                             const std::string& out_dir, const ModelJobOptions& o) {
  check_sketch_shots(input_sketch, network, sketch_name);
  prepare_output_folder(out_dir);
  ModelJobResult result;

  // Images: the sketched shots' (snapping, overlays) always; every available one for textures.
  std::vector<std::optional<ColorImage>> images(network.shots.size());
  const auto image = [&](size_t s) -> const ColorImage* {
    if (!images[s]) images[s] = load_shot_image(network.shots[s]);
    return &*images[s];
  };
  // A sketched shot's image is needed for snapping and its overlay: a missing one fails here, before any output.
  if (o.snap || o.overlays)
    for (const SketchPolygon& p : input_sketch.polygons)
      for (const SketchView& v : p.views) image(size_t(network.shot_index(v.shot)));
  Sketch sketch = input_sketch;
  std::map<size_t, std::vector<LineSegment2>> lines;  // per snapped or transferred-into shot, its LSD segments
  const auto shot_lines = [&](size_t s) -> const std::vector<LineSegment2>& {
    if (!lines.count(s)) lines[s] = detect_line_segments(*image(s));
    return lines[s];
  };
  if (o.snap) {
    for (SketchPolygon& p : sketch.polygons) {
      result.snaps.emplace_back();
      for (SketchView& v : p.views) {
        const size_t s = size_t(network.shot_index(v.shot));
        result.snaps.back().push_back(snap_polygon(v.points, shot_lines(s), o.snapping));
        v.points = result.snaps.back().back().points;
      }
    }
  }
  result.model = model_polygons(network, sketch, o.model);
  const Model& model = result.model;

  std::vector<std::string> names, texture_names(model.polygons.size());
  for (size_t i = 0; i < model.polygons.size(); ++i) names.push_back(safe_stem(i, model.polygons[i].id));
  std::vector<std::optional<PolygonTexture>> textures(model.polygons.size());
  if (o.textures) {
    std::vector<const ColorImage*> all(network.shots.size(), nullptr);
    bool any_placed = false;
    for (const ModelledPolygon& p : model.polygons) any_placed = any_placed || !p.vertices.empty();
    if (any_placed)
      for (size_t s = 0; s < network.shots.size(); ++s)
        if (network.shots[s].image_available) all[s] = image(s);
    for (size_t i = 0; i < model.polygons.size(); ++i) {
      const ModelledPolygon& p = model.polygons[i];
      if (p.vertices.empty() || !p.plane) continue;
      textures[i] = build_texture(p.vertices, *p.plane, network, all, o.texture);
      if (textures[i]) texture_names[i] = "textures/" + names[i] + ".png";
    }
  }
  Sketch transferred = sketch;
  if (o.transfer) {
    result.transfers = transfer_single_views(network, sketch, model, o.transferring, image, shot_lines);
    for (const TransferredView& t : result.transfers)
      transferred.polygons[t.polygon].views.push_back({t.shot, t.result.points});
  }
  const auto written = [&](const std::string& path) { result.written.push_back(path); };
  const std::string out = fs::path(out_dir).string();
  const std::string polygons_path = (fs::path(out) / "polygons.json").string();
  write_file_atomically(polygons_path, [&](std::ostream& os) { os << format_polygons_json(model, texture_names); });
  written(polygons_path);
  const std::string obj = (fs::path(out) / "model.obj").string(), mtl = (fs::path(out) / "model.mtl").string();
  write_file_atomically(obj, [&](std::ostream& os) { os << obj_text(model, textures, names); });
  written(obj);
  write_file_atomically(mtl, [&](std::ostream& os) { os << mtl_text(textures, names); });
  written(mtl);
  if (o.transfer) {
    const std::string path = (fs::path(out) / "transferred.json").string();
    write_file_atomically(path, [&](std::ostream& os) { os << format_sketch_json(transferred); });
    written(path);
  }
  for (size_t i = 0; i < textures.size(); ++i)
    if (textures[i]) {
      fs::create_directories(fs::path(out) / "textures");
      const std::string path = (fs::path(out) / texture_names[i]).string();
      write_color_png(path, textures[i]->image);
      written(path);
    }

  if (o.overlays) {
    for (size_t s = 0; s < network.shots.size(); ++s) {
      const Shot& shot = network.shots[s];
      bool sketched = false;
      for (const SketchPolygon& p : transferred.polygons)
        for (const SketchView& v : p.views) sketched = sketched || v.shot == shot.name;
      std::vector<std::pair<Polygon2d, Guidance>> projected;
      for (const ModelledPolygon& p : model.polygons) {
        Polygon2d q;
        for (const auto& X : p.vertices) {
          const auto uv = shot.project(X);
          if (!uv) break;
          q.push_back(*uv);
        }
        bool visible = q.size() == p.vertices.size() && !q.empty();
        if (visible) {
          visible = false;
          for (const auto& uv : q) visible = visible || shot.in_image(uv);
        }
        if (visible) projected.emplace_back(q, p.decision.state);
      }
      if (!sketched && projected.empty()) continue;
      if (!shot.image_available) continue;
      cv::Mat m = to_bgr(*image(s));
      const int thick = std::max(1, shot.width / 640);
      for (size_t i = 0; i < sketch.polygons.size(); ++i)
        for (size_t k = 0; k < sketch.polygons[i].views.size(); ++k) {
          if (sketch.polygons[i].views[k].shot != shot.name) continue;
          polyline(m, input_sketch.polygons[i].views[k].points, {255, 255, 255}, thick);
          if (o.snap)
            for (const EdgeSnap& e : result.snaps[i][k].edges)
              for (const int l : e.lines) {
                const LineSegment2& seg = lines[s][size_t(l)];
                cv::line(m, cv::Point(int(seg.a.x()), int(seg.a.y())), cv::Point(int(seg.b.x()), int(seg.b.y())),
                         {230, 120, 20}, thick, cv::LINE_AA);
              }
        }
      for (const TransferredView& t : result.transfers)
        if (t.shot == shot.name) polyline(m, t.result.points, {230, 40, 230}, thick);
      for (const auto& [q, g] : projected) polyline(m, q, guidance_bgr(g), 2 * thick);
      fs::create_directories(fs::path(out) / "overlays");
      const std::string path = (fs::path(out) / "overlays" / (fs::path(shot.name).stem().string() + ".png")).string();
      write_color_png(path, from_bgr(m));
      written(path);
    }
  }
  return result;
}

}  // namespace hf::photogrammetry
