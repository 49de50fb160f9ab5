#include "photogrammetry/sketch_session.h"

#include <sstream>

#include "core/error.h"
#include "photogrammetry/model_outputs.h"

namespace hf::photogrammetry {

SketchSession::SketchSession(const Network& network, Sketch start, const ModelOptions& options)
    : network_(network), options_(options), sketch_(std::move(start)), images_(network.shots.size()) {
  if (network_.shots.empty()) throw Error(network_.source + ": no shots to sketch on");
  check_sketch_shots(sketch_, network_, "the starting sketch");
  segments_ = segment_planes_ransac(network_.cloud.positions, options_.ransac);
  current_ = sketch_.polygons.size();
  current_id_ = "p" + std::to_string(current_);
  remodel();
}

SketchPolygon* SketchSession::current_polygon() {
  return current_ < sketch_.polygons.size() ? &sketch_.polygons[current_] : nullptr;
}

void SketchSession::remodel() { model_ = model_polygons(network_, sketch_, segments_, options_); }

void SketchSession::click(const Eigen::Vector2d& uv) {
  const Shot& shot = network_.shots[size_t(shot_)];
  if (!shot.in_image(uv)) {
    message_ = "the click lies outside " + shot.name;
    return;
  }
  if (const SketchPolygon* p = current_polygon())
    for (const SketchView& v : p->views)
      if (v.shot == shot.name) {
        message_ = current_id_ + " is sketched in " + shot.name + " already (n starts the next polygon)";
        return;
      }
  open_.push_back(uv);
  message_.clear();
}

void SketchSession::undo() {
  if (!open_.empty()) open_.pop_back();
  message_.clear();
}

bool SketchSession::close_view() {
  const SketchPolygon* p = current_polygon();
  const size_t want = p ? p->views[0].points.size() : 0;
  if (open_.size() < 3 || (want > 0 && open_.size() != want)) {
    message_ = "an outline needs " + (want > 0 ? std::to_string(want) : std::string("at least 3")) +
               " vertices (vertex k of every view is the same corner), it has " + std::to_string(open_.size());
    return false;
  }
  if (self_intersecting(open_)) {
    message_ = "the outline intersects itself";
    return false;
  }
  if (!p) {
    sketch_.polygons.push_back({current_id_, {}, ""});
    current_ = sketch_.polygons.size() - 1;
  }
  sketch_.polygons[current_].views.push_back({network_.shots[size_t(shot_)].name, open_});
  open_.clear();
  message_.clear();
  remodel();
  return true;
}

void SketchSession::same_plane() {
  SketchPolygon* p = current_polygon();
  if (!p || current_ == 0) {
    message_ = "same plane: the current polygon needs a view and a polygon before it";
    return;
  }
  p->same_plane_as = sketch_.polygons[current_ - 1].id;
  message_.clear();
  remodel();
}

void SketchSession::new_polygon() {
  open_.clear();
  current_ = sketch_.polygons.size();
  current_id_ = "p" + std::to_string(current_);
  message_.clear();
}

void SketchSession::show_shot(int shot) {
  if (shot < 0 || size_t(shot) >= network_.shots.size()) {
    message_ = "no shot " + std::to_string(shot);
    return;
  }
  shot_ = shot;
  open_.clear();
  message_.clear();
}

void SketchSession::apply(const std::string& line) {
  std::istringstream in(line);
  std::string event;
  in >> event;
  if (event == "click") {
    double u = 0, v = 0;
    std::string rest;
    if (!(in >> u >> v) || (in >> rest)) throw Error("sketch event " + quote_for_message(line) + ": expected 'click U V'");
    click({u, v});
  } else if (event == "undo" || event == "close" || event == "same_plane" || event == "new") {
    std::string rest;
    if (in >> rest) throw Error("sketch event " + quote_for_message(line) + ": expected no argument");
    if (event == "undo") undo();
    else if (event == "close") close_view();
    else if (event == "same_plane") same_plane();
    else new_polygon();
  } else if (event == "shot") {
    std::string name, rest;
    if (!(in >> name) || (in >> rest)) throw Error("sketch event " + quote_for_message(line) + ": expected 'shot NAME'");
    const int s = network_.shot_index(name);
    if (s < 0) throw Error("sketch event " + quote_for_message(line) + ": no shot named " + quote_for_message(name));
    show_shot(s);
  } else {
    throw Error("sketch event " + quote_for_message(line) +
                ": expected click U V, undo, close, same_plane, new or shot NAME");
  }
}

const ModelledPolygon* SketchSession::current() const {
  return current_ < model_.polygons.size() ? &model_.polygons[current_] : nullptr;
}

Guidance SketchSession::current_guidance() const {
  const ModelledPolygon* p = current();
  return p ? p->decision.state : Guidance::red;
}

ColorImage SketchSession::overlay() const {
  const Shot& shot = network_.shots[size_t(shot_)];
  std::optional<ColorImage>& photo = images_[size_t(shot_)];
  if (!photo) {
    if (shot.image_available) photo = load_shot_image(shot);
    else {
      photo = ColorImage(shot.width, shot.height);
      for (Rgb8& p : photo->pixels()) p = {90, 90, 90};
    }
  }
  std::vector<std::pair<Polygon2d, Rgb8>> outlines;
  for (size_t i = 0; i < sketch_.polygons.size(); ++i) {
    const Rgb8 colour = guidance_rgb(model_.polygons[i].decision.state);
    for (const SketchView& v : sketch_.polygons[i].views)
      if (v.shot == shot.name) outlines.emplace_back(v.points, colour);
    Polygon2d q;  // the placed polygon seen from this shot
    for (const auto& X : model_.polygons[i].vertices)
      if (const auto uv = shot.project(X)) q.push_back(*uv);
    if (!q.empty() && q.size() == model_.polygons[i].vertices.size()) outlines.emplace_back(q, colour);
  }
  if (open_.size() >= 2) outlines.emplace_back(open_, Rgb8{255, 255, 255});
  return draw_outlines(*photo, outlines, std::max(1, shot.width / 640));
}

}  // namespace hf::photogrammetry
