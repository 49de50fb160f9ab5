// `hashfusion head-features`: Kubásková's feature recognition on a triangulated head (head/head_features.h) and
// its outputs (head/feature_outputs.h).
#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "apps/cli_common.h"
#include "apps/commands.h"
#include "core/error.h"
#include "core/output_transaction.h"
#include "head/feature_outputs.h"
#include "head/feature_spec.h"
#include "head/head_features.h"
#include "io/mesh_file.h"

namespace hf::apps {
namespace {

struct HeadFeaturesArgs {
  std::string mesh_path, out_dir, method = "discrete", quantity = "mean", threshold, morphology;
  bool automatic = false;
  int mls_k = 3, area_k = 0, separation = 2;
  double truncate_percent = 0;
  bool no_final_dilation = false;
  bool physical_scale = false;
};

void run_head_features(const HeadFeaturesArgs& args) {
  if (args.mesh_path.empty()) throw Error("head-features: --input MESH is required");
  head::HeadFeatureOptions options;
  options.evaluation = head::parse_evaluation(args.method);
  options.quantity = head::parse_quantity(args.quantity);
  if (!args.threshold.empty()) {
    options.threshold = head::parse_threshold(args.threshold);
    options.has_threshold = true;
  }
  options.morphology = head::parse_morphology(args.morphology);
  options.automatic = args.automatic;
  options.truncate_percent = args.truncate_percent;
  options.mls.k = args.mls_k;
  options.areas.k = args.area_k;
  options.areas.separation_method = args.separation;
  options.areas.final_dilation = !args.no_final_dilation;
  if (args.physical_scale) head::use_physical_scale(options);
  const TriangleMesh mesh = read_mesh_file(args.mesh_path);
  head::HeadFeatureResult result;
  try {
    result = head::detect_head_features(mesh, options);
  } catch (const ParseError&) {
    throw;
  } catch (const Error& e) {
    throw Error(args.mesh_path + ": " + e.what());
  }
  // One transaction, as `run`'s (core/output_transaction.h): built beside --out and exchanged with it at the end,
  // so an interruption leaves the previous set or the new one. Files of the old folder this run did not write
  // are carried over (as before: a head-features folder lists no outputs to tell its own from a user's).
  OutputTransaction outputs(args.out_dir);
  head::write_head_feature_outputs(outputs.folder(), mesh, result, options, {args.mesh_path});
  outputs.commit([](const std::string&) { return false; });
  std::cout << args.mesh_path << ": " << mesh.vertices.size() << " vertices, nose tip vertex "
            << result.frame.nose_tip_vertex << ", " << result.control_points.size() << " of "
            << head::control_point_names().size() << " control points\n";
  for (const std::string& w : result.warnings) std::cout << "warning: " << w << "\n";
  std::cout << "outputs in " << args.out_dir << " (report.md)\n";
}

}  // namespace

void add_head_features_command(CLI::App& app) {
  auto args = std::make_shared<HeadFeaturesArgs>();
  CLI::App* cmd = app.add_subcommand(
      "head-features",
      "features, important areas and control points of a triangulated human head (Kubasková): curvatures, MLS, "
      "Laplace-Beltrami, thresholding, mesh morphology");
  auto* input = cmd->add_option("--input", args->mesh_path, "head mesh, .ply or .obj (any pose and unit); required");
  add_deprecated_alias(cmd, input, "--mesh", args->mesh_path);
  add_out_option(cmd, args->out_dir, "output folder (created)");
  cmd->add_option("--method", args->method, "evaluation for the features: discrete, mls or laplace")
      ->capture_default_str();
  cmd->add_option("--quantity", args->quantity, "curvature thresholded (discrete, mls): mean, gaussian, k_max, k_min")
      ->capture_default_str();
  cmd->add_option("--threshold", args->threshold,
                  "a,b: features where the evaluation lies in [a, b] percent of |w_max| (eq. 10); default: from "
                  "the evaluation's average to 100");
  cmd->add_option("--morphology", args->morphology, "operators applied to the features, e.g. open:5,dilate:10");
  cmd->add_option("--truncate", args->truncate_percent, "percent of highest evaluations truncated (section 3.1.3)");
  cmd->add_flag("--auto", args->automatic, "automatic detection (section 4.5): per-area evaluations and thresholds");
  cmd->add_option("--mls-k", args->mls_k, "MLS neighbourhood rings")->capture_default_str();
  cmd->add_option("--area-k", args->area_k, "important-area morphology k (0: 5/10/15 by vertex count)")
      ->capture_default_str();
  cmd->add_option("--separation", args->separation, "important-area separation method, 1 or 2 (section 3.3)")
      ->check(in_range(1, 2))
      ->capture_default_str();
  cmd->add_flag("--no-final-dilation", args->no_final_dilation, "skip the important areas' last dilation");
  cmd->add_flag("--physical-scale", args->physical_scale,
                "every scale a length on the head (evaluations smoothed over 0.05 rho, MLS h 0.5 rho, eyes/nose "
                "boundary from the nose root), for fused or noisy meshes; chosen end to end in "
                "bench/results/head.md");
  cmd->callback([args] { run_head_features(*args); });
}

}  // namespace hf::apps
