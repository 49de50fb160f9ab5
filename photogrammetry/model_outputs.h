// `hashfusion model`'s job and outputs: a network and a sketch in, a folder of results out.
//
//   polygons.json  {"polygons": [{"id", "vertices": [[X, Y, Z], ...], "plane": [a, b, c, d], "guidance":
//                  "red|yellow|green", "method": "dlt|cloud_plane|polygon_plane", "reprojection_error_px": [...],
//                  "reason": "...", "texture": "textures/NAME.png" | null}]} in the network's world frame and
//                  units; a red polygon has "vertices": [], "plane": null, "method": null, no errors.
//   model.obj + model.mtl + textures/*.png   the placed polygons, one OBJ face each, textured from the best shot
//                  per texel (photogrammetry/texture.h); polygons no shot sees are written untextured.
//   overlays/SHOT.png  per shot that a polygon is sketched in or projects into: the photo, the sketch (white), the
//                  matched image lines of snapping (blue), transferred outlines (magenta) and the reprojected 3D
//                  polygons in their guidance colour.
//   transferred.json  with `transfer` (section 5.2's multi-shot mode, photogrammetry/polygon_transfer.h): the sketch
//                  (SKETCH.json's format) with, for each polygon sketched in one shot and placed on a plane, its
//                  outline transferred into every other shot whose image is available and that sees the placed
//                  polygon wholly inside its image; run `model` on it to fix those polygons by DLT over the shots.
// Every file is written atomically (core/atomic_file.h); the folder is checked writable before any work.
// Failure modes: hf::Error naming the file for unreadable inputs (a missing image of a sketched shot included).
#pragma once

#include <string>
#include <vector>

#include "photogrammetry/edge_snapping.h"
#include "photogrammetry/polygon_modelling.h"
#include "photogrammetry/polygon_transfer.h"
#include "photogrammetry/texture.h"

namespace hf::photogrammetry {

struct ModelJobOptions {
  ModelOptions model;
  bool snap = false;  // edge snapping (section 5.2) of every sketched view before modelling
  SnapOptions snapping;
  bool textures = true;
  TextureOptions texture;
  bool overlays = true;
  bool transfer = false;  // transferred.json (see above)
  TransferOptions transferring;
};

struct TransferredView {
  size_t polygon = 0;  // index into the sketch
  std::string shot;    // the target shot's name
  TransferResult result;
};

struct ModelJobResult {
  Model model;
  std::vector<std::vector<SnapResult>> snaps;  // per polygon, per view (empty without snapping)
  std::vector<TransferredView> transfers;      // with `transfer`, in the sketch's order
  std::vector<std::string> written;            // paths, in the order written
};

// The overlays' drawing: outlines (closed polylines, anti-aliased) in their colours over a copy of the photo, and
// the colour of each guidance state (green, yellow, red).
ColorImage draw_outlines(const ColorImage& photo, const std::vector<std::pair<Polygon2d, Rgb8>>& outlines,
                         int thickness_px);
Rgb8 guidance_rgb(Guidance g);

// SKETCH.json's text for a sketch (photogrammetry/sketch.h): parse_sketch reads it back unchanged.
std::string format_sketch_json(const Sketch& sketch);

// polygons.json's text for a model.
std::string format_polygons_json(const Model& model, const std::vector<std::string>& texture_names = {});

// Snaps (when asked), models, textures and writes everything into out_dir.
ModelJobResult run_model_job(const Network& network, const Sketch& sketch, const std::string& sketch_name,
                             const std::string& out_dir, const ModelJobOptions& options = {});

}  // namespace hf::photogrammetry
