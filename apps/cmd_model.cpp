// `hashfusion model`: Kellner's guided modelling of buildings from oriented photos (photogrammetry/): a network of
// shots (OpenMVS dump, Middlebury *_par.txt or a hashfusion run folder) and SKETCH.json in, the 3D polygons, their
// guidance states, textures and per-shot overlays out (photogrammetry/model_outputs.h).
#include <CLI/CLI.hpp>
#include <sys/stat.h>

#include <filesystem>
#include <functional>
#include <iostream>
#include <sstream>
#include <memory>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_common.h"
#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"
#include "core/output_transaction.h"
#include "io/ply.h"
#include "photogrammetry/model_outputs.h"
#include "photogrammetry/scene_readers.h"
#include "photogrammetry/sketch.h"
#include "photogrammetry/sketch_session.h"
#if HF_HAVE_VIEWER
#include "viewer/sketch_window.h"
#endif

namespace hf::apps {
namespace {

struct ModelArgs {
  std::string shots, polygons, out, cloud, dataset, events;
  std::string shown_out;  // --out as given, for messages (out is the transaction's private folder)
  bool interactive = false;
  bool all_frames = false, snap = false, transfer = false, no_textures = false, no_overlays = false;
  double acceptance_h = photogrammetry::CloudFitOptions{}.acceptance_h;
  double ransac_threshold = 0.0;
  int texture_px = photogrammetry::TextureOptions{}.max_texture_px;
};

// Sketching in the session (photogrammetry/sketch_session.h): the --events script's lines, then the window with
// --interactive; the result is OUT/sketch.json (written before the model job, which checks OUT writable first).
std::string sketch_interactively(const photogrammetry::Network& network, photogrammetry::Sketch start,
                                 const ModelArgs& a, const photogrammetry::ModelJobOptions& o,
                                 photogrammetry::Sketch* out) {
  photogrammetry::SketchSession session(network, std::move(start), o.model);
  if (!a.events.empty()) {
    std::istringstream lines(read_regular_file(a.events, "sketch events"));
    std::string line;
    for (int n = 1; std::getline(lines, line); ++n) {
      if (line.empty() || line[0] == '#') continue;
      try {
        session.apply(line);
      } catch (const Error& e) {
        throw Error(a.events + ":" + std::to_string(n) + ": " + e.what());
      }
    }
  }
  if (a.interactive) {
#if HF_HAVE_VIEWER
    viewer::run_sketch_window(session);
#else
    throw Error("--interactive: the viewer is not built in (install libglfw3-dev and libglm-dev, reconfigure)");
#endif
  }
  const std::string path = (std::filesystem::path(a.out) / "sketch.json").string();
  write_file_atomically(path, [&](std::ostream& os) { os << photogrammetry::format_sketch_json(session.sketch()); });
  std::cout << "sketch: " << (std::filesystem::path(a.shown_out) / "sketch.json").string() << " ("
            << session.sketch().polygons.size() << " polygons)\n";
  *out = session.sketch();
  return path;
}

// What the model run that last wrote `out` wrote there (photogrammetry/model_outputs.h's names): all of them when
// its polygons.json is a model's, none for any other folder, so a user's files are always carried over.
std::function<bool(const std::string&)> previous_model_run_wrote(const std::string& out) {
  static const std::set<std::string> kModelOutputs = {"polygons.json", "model.obj", "model.mtl", "transferred.json",
                                                      "sketch.json",   "textures",  "overlays"};
  nlohmann::json j;
  const bool model_folder = read_previous_manifest(out + "/polygons.json", &j) && j.is_object() &&
                            j.contains("polygons") && j["polygons"].is_array();
  return [model_folder](const std::string& name) { return model_folder && kModelOutputs.count(name) > 0; };
}

void run_model(ModelArgs a) {
  if (a.shots.empty()) throw Error("model: --input NETWORK is required");
  photogrammetry::RunShotsOptions run;
  run.dataset = a.dataset;
  run.keyframes_only = !a.all_frames;
  photogrammetry::Network network = photogrammetry::read_network(a.shots, run);
  if (!a.cloud.empty()) {
    const PointCloud cloud = read_ply_point_cloud(a.cloud);
    network.cloud = {};
    for (const auto& p : cloud.positions) network.cloud.positions.push_back(p.cast<double>());
    network.cloud.colors = cloud.colors;
  }
  photogrammetry::ModelJobOptions o;
  o.model.fit.acceptance_h = a.acceptance_h;
  o.model.ransac.distance_threshold = a.ransac_threshold;
  o.snap = a.snap;
  o.transfer = a.transfer;
  o.textures = !a.no_textures;
  o.overlays = !a.no_overlays;
  o.texture.max_texture_px = a.texture_px;
  std::string sketch_name = a.polygons;
  photogrammetry::Sketch sketch;
  if (!a.polygons.empty()) sketch = photogrammetry::read_sketch(a.polygons);
  else if (!a.interactive && a.events.empty())
    throw Error("model: --polygons SKETCH.json is required (or --interactive / --events to sketch)");
  // The outputs as one transaction (core/output_transaction.h), as `run`'s: built in a private folder beside --out
  // and exchanged with it at the end, so an interruption or a failure leaves the previous set or the new one.
  OutputTransaction outputs(a.out);
  a.shown_out = a.out;
  a.out = outputs.folder();
  if (a.interactive || !a.events.empty()) {
    sketch_interactively(network, std::move(sketch), a, o, &sketch);
    sketch_name = (std::filesystem::path(a.shown_out) / "sketch.json").string();
  }
  const photogrammetry::ModelJobResult r = photogrammetry::run_model_job(network, sketch, sketch_name, a.out, o);
  outputs.commit(previous_model_run_wrote(outputs.target()));
  std::cout << network.source << ": " << network.shots.size() << " shots, " << network.cloud.size()
            << " cloud points, " << r.model.segments.size() << " planar segments\n";
  for (const auto& p : r.model.polygons)
    std::cout << "  " << p.id << ": " << to_string(p.decision.state) << " (" << to_string(p.decision.method)
              << "): " << p.decision.reason << "\n";
  for (const auto& t : r.transfers) {
    const photogrammetry::TransferResult& x = t.result;
    std::cout << "  " << sketch.polygons[t.polygon].id << " -> " << t.shot << ": transferred, "
              << (x.anchor_edge >= 0 ? "edge " + std::to_string(x.anchor_edge) + " matched (similarity " +
                                           std::to_string(x.anchor_similarity) + ")"
                                     : std::string("no edge matched (plane projection, snapped)"))
              << "\n";
  }
  if (a.transfer) std::cout << "  " << r.transfers.size() << " transferred views in transferred.json\n";
  std::cout << "outputs in " << a.shown_out << " (polygons.json, model.obj, " << r.written.size() << " files)\n";
}

}  // namespace

void add_model_command(CLI::App& app) {
  auto a = std::make_shared<ModelArgs>();
  CLI::App* cmd = app.add_subcommand(
      "model", "3D building polygons from 2D sketches on oriented photos (Kellner): multi-shot DLT, cloud planes, "
               "planes of existing polygons, guidance states, edge snapping, textures");
  auto* input = cmd->add_option("--input", a->shots,
                                "the network (required): an OpenMVS dump folder (cameras_from_scene_mvs.txt), a "
                                "Middlebury *_par.txt (or its folder), or a hashfusion run folder (report.json; "
                                "keyframes become shots)");
  add_deprecated_alias(cmd, input, "--shots", a->shots);
  cmd->add_option("--polygons", a->polygons,
                  "SKETCH.json: 2D polygons per shot (README: Photogrammetric modelling); required unless sketching "
                  "with --interactive / --events, which start from it when given");
  cmd->add_flag("--interactive", a->interactive,
                "sketch in a window: click vertices on a shot and see the guidance colour (Enter close, Backspace "
                "undo, n new polygon, p same plane as the previous, Tab next shot, q done); writes OUT/sketch.json");
  cmd->add_option("--events", a->events,
                  "sketch by a script of the window's events, one per line (click U V | undo | close | same_plane | "
                  "new | shot NAME), before the window with --interactive; writes OUT/sketch.json");
  add_out_option(cmd, a->out, "output folder (created)");
  cmd->add_option("--cloud", a->cloud, "a .ply point cloud (or mesh) replacing the network's cloud");
  cmd->add_option("--dataset", a->dataset, "a run's TUM folder when report.json's \"input\" has moved");
  cmd->add_flag("--all-frames", a->all_frames, "a run: every tracked frame is a shot, not only keyframes");
  cmd->add_flag("--snap", a->snap, "snap sketched edges to LSD line segments of the shots (section 5.2)");
  cmd->add_flag("--transfer", a->transfer,
                "transfer each polygon sketched in one shot and placed on a plane into the other shots that see it "
                "(section 5.2, edge colour histograms): transferred.json, a sketch to run model on again");
  cmd->add_option("--acceptance", a->acceptance_h, "acceptance threshold of the cloud fit h = m r / n")
      ->check(in_range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--ransac-threshold", a->ransac_threshold,
                  "RANSAC inlier distance in the network's units (0: 0.5 % of the cloud's robust extent)")
      ->check(non_negative())
      ->capture_default_str();
  cmd->add_option("--texture-px", a->texture_px, "longest texture side in texels")
      ->check(in_range(8, 16384, "texels"))
      ->capture_default_str();
  cmd->add_flag("--no-textures", a->no_textures, "skip textures (model.obj is written untextured)");
  cmd->add_flag("--no-overlays", a->no_overlays, "skip the per-shot overlay images");
  cmd->callback([a] { run_model(*a); });
}

}  // namespace hf::apps
