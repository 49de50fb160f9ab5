// Interactive sketching (Kellner section 5: the tool's loop of clicking vertices on a shot and seeing the guidance
// colour at once): the state behind the viewer's sketch window, without any GL, so scripts and tests drive it with
// the same events the mouse and keys send.
//
// The session holds the network, its planar segments (segmented once, photogrammetry/ransac_planes.h), the sketch
// so far (closed views only, exactly what SKETCH.json holds) and the current polygon's open outline on the shown
// shot. After every change of the sketch every polygon is modelled anew (model_polygons, photogrammetry/
// polygon_modelling.h), so current_guidance() is the state `hashfusion model` would give the same SKETCH.json.
//   click(uv)       left click on the shown shot: the next vertex of the open outline (refused outside the image, or
//                   on a shot the current polygon is already sketched in)
//   undo()          Backspace: the open outline's last vertex
//   close_view()    Enter: the outline becomes a view of the current polygon (at least 3 vertices, as many as its
//                   other views, not self-intersecting)
//   same_plane()    p: the current polygon lies on the plane of the polygon before it (same_plane_as)
//   new_polygon()   n: the next polygon ("p1", "p2", ...); the current one stays when it has a view
//   show_shot(s)    Tab: the shot shown and clicked on (the open outline is dropped)
// apply() takes one event as a text line: "click U V", "undo", "close", "same_plane", "new", "shot NAME".
// A refused event changes nothing and says why in message(); apply() throws hf::Error only for a line that is no
// event. Not thread-safe: one thread (the window's) owns a session.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "photogrammetry/polygon_modelling.h"

namespace hf::photogrammetry {

class SketchSession {
 public:
  // `start` (e.g. a SKETCH.json read before) must pass check_sketch_shots for the network.
  SketchSession(const Network& network, Sketch start = {}, const ModelOptions& options = {});

  void click(const Eigen::Vector2d& uv);
  void undo();
  bool close_view();
  void same_plane();
  void new_polygon();
  void show_shot(int shot);
  void apply(const std::string& event);

  const Network& network() const { return network_; }
  const Sketch& sketch() const { return sketch_; }
  const Model& model() const { return model_; }
  int shown_shot() const { return shot_; }
  const Polygon2d& open_outline() const { return open_; }
  // The current polygon's state (red while it has no view) and its modelled polygon (nullptr while it has none).
  Guidance current_guidance() const;
  const ModelledPolygon* current() const;
  const std::string& message() const { return message_; }
  // The shown shot's photo (grey where its image is absent) with every polygon's view there and every placed
  // polygon reprojected in its guidance colour, and the open outline in white.
  ColorImage overlay() const;

 private:
  SketchPolygon* current_polygon();
  void remodel();

  const Network& network_;
  ModelOptions options_;
  std::vector<PlaneSegment> segments_;
  Sketch sketch_;
  Model model_;
  size_t current_ = 0;  // index of the current polygon in sketch_ (== size: not started)
  std::string current_id_;
  int shot_ = 0;
  Polygon2d open_;
  std::string message_;
  mutable std::vector<std::optional<ColorImage>> images_;
};

}  // namespace hf::photogrammetry
