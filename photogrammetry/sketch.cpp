#include "photogrammetry/sketch.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <unordered_set>

#include "core/bounded_read.h"
#include "core/error.h"
#include "core/number_text.h"

namespace hf::photogrammetry {
namespace {

using json = nlohmann::json;

std::string where(const SketchPolygon& p, size_t view) {
  return "polygon " + quote_for_message(p.id) + (view == size_t(-1) ? "" : " view " + std::to_string(view + 1)) +
         ": ";
}

SketchView parse_view(const json& v, const SketchPolygon& p, size_t k, const std::string& file) {
  if (!v.is_object() || !v.contains("shot") || !v["shot"].is_string() || !v.contains("points") ||
      !v["points"].is_array())
    throw ParseError(file, 0, where(p, k) + "expected {\"shot\": NAME, \"points\": [[u, v], ...]}");
  SketchView view;
  view.shot = v["shot"].get<std::string>();
  const json& pts = v["points"];
  if (pts.size() < 3 || pts.size() > kMaxSketchVertices)
    throw ParseError(file, 0, where(p, k) + "expected 3 to " + std::to_string(kMaxSketchVertices) +
                                  " points, got " + std::to_string(pts.size()));
  for (const json& q : pts) {
    if (!q.is_array() || q.size() != 2 || !q[0].is_number() || !q[1].is_number())
      throw ParseError(file, 0, where(p, k) + "expected each point as [u, v] (two numbers)");
    const Eigen::Vector2d point(q[0].get<double>(), q[1].get<double>());
    // Checked before the self-intersection test, whose cross products overflow (1e308 read as an intersection).
    if (!(std::fabs(point.x()) <= kMaxSketchPixel && std::fabs(point.y()) <= kMaxSketchPixel))
      throw ParseError(file, 0, where(p, k) + "point " + std::to_string(view.points.size() + 1) + " (" +
                                    number_for_message(point.x()) + ", " + number_for_message(point.y()) +
                                    ") lies outside any image (beyond 1e6 px)");
    view.points.push_back(point);
  }
  if (self_intersecting(view.points))
    throw ParseError(file, 0, where(p, k) + "the outline intersects itself (or repeats a vertex)");
  return view;
}

}  // namespace

Sketch parse_sketch(const std::string& text, const std::string& file) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw ParseError(file, 0, "expected JSON, got a syntax error at byte " + std::to_string(e.byte));
  } catch (const json::exception&) {  // e.g. a number beyond double's range (out_of_range 406)
    throw ParseError(file, 0, "expected JSON, got a number out of range");
  }
  if (!j.is_object() || !j.contains("polygons") || !j["polygons"].is_array())
    throw ParseError(file, 0, "expected {\"polygons\": [...]}");
  if (j["polygons"].size() > kMaxSketchPolygons)
    throw ParseError(file, 0, "expected at most " + std::to_string(kMaxSketchPolygons) + " polygons");
  Sketch sketch;
  std::unordered_set<std::string> ids;
  for (const json& pj : j["polygons"]) {
    if (!pj.is_object() || !pj.contains("id") || !pj["id"].is_string() || !pj.contains("views") ||
        !pj["views"].is_array())
      throw ParseError(file, 0, "polygon " + std::to_string(sketch.polygons.size() + 1) +
                                    ": expected {\"id\": NAME, \"views\": [...]}");
    SketchPolygon p;
    p.id = pj["id"].get<std::string>();
    if (p.id.empty()) throw ParseError(file, 0, "polygon " + std::to_string(sketch.polygons.size() + 1) +
                                                    ": expected a non-empty id");
    if (ids.count(p.id)) throw ParseError(file, 0, where(p, -1) + "the id is used twice");
    if (pj.contains("same_plane_as") && !pj["same_plane_as"].is_null()) {
      if (!pj["same_plane_as"].is_string())
        throw ParseError(file, 0, where(p, -1) + "expected \"same_plane_as\" to be a polygon id");
      p.same_plane_as = pj["same_plane_as"].get<std::string>();
      if (!ids.count(p.same_plane_as))
        throw ParseError(file, 0, where(p, -1) + "\"same_plane_as\" " + quote_for_message(p.same_plane_as) +
                                      " names no polygon listed before this one");
    }
    if (pj["views"].empty()) throw ParseError(file, 0, where(p, -1) + "expected at least one view");
    std::unordered_set<std::string> shots;
    for (const json& v : pj["views"]) {
      SketchView view = parse_view(v, p, p.views.size(), file);
      if (!shots.insert(view.shot).second)
        throw ParseError(file, 0, where(p, p.views.size()) + "shot " + quote_for_message(view.shot) +
                                      " is sketched twice in this polygon");
      if (!p.views.empty() && view.points.size() != p.views[0].points.size())
        throw ParseError(file, 0, where(p, p.views.size()) + "expected " +
                                      std::to_string(p.views[0].points.size()) +
                                      " points (vertex k of every view is the same corner), got " +
                                      std::to_string(view.points.size()));
      p.views.push_back(std::move(view));
    }
    ids.insert(p.id);
    sketch.polygons.push_back(std::move(p));
  }
  return sketch;
}

Sketch read_sketch(const std::string& path) { return parse_sketch(read_regular_file(path, "sketch"), path); }

void check_sketch_shots(const Sketch& sketch, const Network& network, const std::string& file) {
  for (const SketchPolygon& p : sketch.polygons)
    for (size_t k = 0; k < p.views.size(); ++k) {
      const int s = network.shot_index(p.views[k].shot);
      if (s < 0)
        throw ParseError(file, 0, where(p, k) + "no shot named " + quote_for_message(p.views[k].shot) + " in " +
                                      network.source);
      for (const Eigen::Vector2d& q : p.views[k].points)
        if (!network.shots[size_t(s)].in_image(q))
          throw ParseError(file, 0, where(p, k) + "point (" + number_for_message(q.x()) + ", " +
                                        number_for_message(q.y()) +
                                        ") lies outside the " + std::to_string(network.shots[size_t(s)].width) +
                                        "x" + std::to_string(network.shots[size_t(s)].height) + " image");
    }
}

}  // namespace hf::photogrammetry
