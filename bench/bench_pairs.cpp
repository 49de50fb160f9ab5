// Large inter-frame motion (issue 34): every pair (i, i + k), k = 1..max_k, of a real sequence registered from the
// identity, against the ground-truth relative pose. Success = within 3 cm and 2 degrees of it (and a usable
// status). Two ways of running each method, both counted:
//   pipeline  the pipeline's registration settings from the identity: pyramid from level 1 (320x240 of 640x480),
//             slam::pipeline_wide_basin_options(slam::pipeline_registration_options) (combined's rgb_weight 0.4;
//             4 levels and the rotation-first step: what the pipeline runs where it has no motion prior, i.e. its
//             guess is the identity; variant "prior" = its settings where it tracks from a motion prior: 3 levels,
//             no rotation-first step);
//   align     align()'s defaults: the method's registry options (default_registration_options) on a pyramid from
//             full resolution with as many levels as their iterations list (what
//             hashfusion.make_registration(name).align(cur, ref, camera) does).
// Variants: "default" = the mode's options as they are; the others set the depth and the rotation-first step
// explicitly over them: "base" = 3 levels, no rotation-first step (both modes' settings before issue 34's
// large-motion work), "+so3" = rotation-first (registration/so3_prealign.h, iterations 10/5 on the two coarsest
// levels used), "+L4" / "+L5" = a fourth (and fifth) coarser pyramid level with 4 iterations each.
//
//   build/release/bench/bench_pairs --input DIR --out FILE.json [--max-k 10] [--methods combined,icp]
//                                   [--variants default,base,so3+L4] [--modes pipeline,align] [--stride 1]
//                                   [--camera C] [--frames-only 1]
// Frames of a distorted camera (fr1 with --camera fr1) are undistorted first, as the pipeline does. Writes one
// JSON record per (method, mode, variant, i, k) and prints a summary; bench/pairs_report.py makes the tables.
// --frames-only 1 writes the frame list alone (for bench/pairs_open3d.py) without registering anything.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/undistort.h"
#include "io/dataset.h"
#include "registration/frame_pyramid.h"
#include "registration/registration.h"
#include "registration/so3_prealign.h"
#include "slam/pipeline_config.h"

namespace {

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) if (!item.empty()) out.push_back(item);
  return out;
}

struct PairsFrame {
  hf::RgbdFrame frame;
  // Built once with the most levels any run asks for: a pyramid's levels do not depend on how many follow, and
  // the driver uses min(iterations, levels) of them.
  hf::FramePyramid pipeline_pyramid, align_pyramid;
};

// The options of `variant` over the mode's own (see the header comment).
hf::RegistrationOptions variant_options(hf::RegistrationOptions o, const std::string& variant) {
  if (variant == "default" || variant == "prior") return o;
  const int levels = variant.find("L5") != std::string::npos ? 5 : variant.find("L4") != std::string::npos ? 4 : 3;
  o.driver.iterations = {10, 5, 4};
  while (int(o.driver.iterations.size()) < levels) o.driver.iterations.push_back(4);
  o.driver.so3_iterations.clear();
  if (variant.find("so3") != std::string::npos) o.driver.so3_iterations = hf::wide_basin_so3_iterations();
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, out_path, camera;
  int max_k = 10, stride = 1;
  bool frames_only = false;
  std::vector<std::string> methods = {"combined", "icp"}, variants = {"default", "base"},
                           modes = {"pipeline", "align"};
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string key = argv[a], value = argv[a + 1];
    if (key == "--input") input = value;
    else if (key == "--out") out_path = value;
    else if (key == "--camera") camera = value;
    else if (key == "--max-k") max_k = std::stoi(value);
    else if (key == "--stride") stride = std::stoi(value);
    else if (key == "--methods") methods = split_list(value);
    else if (key == "--variants") variants = split_list(value);
    else if (key == "--modes") modes = split_list(value);
    else if (key == "--frames-only") frames_only = value != "0";
    else { std::cerr << "bench_pairs: unknown option " << key << "\n"; return 1; }
  }
  if (input.empty() || out_path.empty()) {
    std::cerr << "usage: bench_pairs --input DIR --out FILE.json [--camera C] [--max-k 10] [--methods a,b] "
                 "[--variants default,prior,base,so3,L4,so3+L4,so3+L5] [--modes pipeline,align] [--stride 1] "
                 "[--frames-only 1]\n";
    return 1;
  }
  try {
    hf::DatasetOptions dopt;
    dopt.camera = camera;
    auto source = hf::open_dataset(input, dopt);
    const hf::PinholeCamera cam = source->camera().pinhole();
    std::optional<hf::Undistorter> undistort;
    if (!source->camera().distortion.none()) undistort.emplace(source->camera());
    // The options of every run, and the levels their pyramids need.
    struct Run {
      std::string method, mode, variant;
      hf::RegistrationOptions options;
    };
    std::vector<Run> runs;
    int pipeline_levels = 0, align_levels = 0;
    if (!frames_only)
      for (const std::string& method : methods)
        for (const std::string& mode : modes)
          for (const std::string& variant : variants) {
            if (mode != "pipeline" && mode != "align") throw hf::Error("unknown mode " + mode);
            hf::RegistrationOptions mode_options = hf::default_registration_options(method);
            if (mode == "pipeline") {
              mode_options = hf::slam::pipeline_registration_options(method);
              if (variant == "default") mode_options = hf::slam::pipeline_wide_basin_options(mode_options);
            }
            hf::RegistrationOptions o = variant_options(mode_options, variant);
            int& levels = mode == "pipeline" ? pipeline_levels : align_levels;
            levels = std::max(levels, int(o.driver.iterations.size()));
            runs.push_back({method, mode, variant, std::move(o)});
          }
    std::vector<PairsFrame> frames;
    for (hf::FrameRead r = source->next(); r.status != hf::FrameStatus::end; r = source->next()) {
      if (r.status != hf::FrameStatus::ok || !r.frame.T_world_camera_gt) continue;
      PairsFrame f;
      f.frame = std::move(r.frame);
      if (undistort) {
        f.frame.depth = undistort->depth(f.frame.depth);
        f.frame.color = undistort->color(f.frame.color);
      }
      if (pipeline_levels > 0) {
        hf::FramePyramidOptions pp = hf::slam::PipelineConfig{}.pyramid;  // the pipeline's, from its tracking level
        pp.first_level = hf::slam::PipelineConfig{}.tracking_level;
        pp.levels = pipeline_levels;
        f.pipeline_pyramid = hf::build_frame_pyramid(f.frame.depth, &f.frame.color, cam, pp);
      }
      if (align_levels > 0) {
        hf::FramePyramidOptions ap;  // align()'s: the defaults from full resolution
        ap.levels = align_levels;
        f.align_pyramid = hf::build_frame_pyramid(f.frame.depth, &f.frame.color, cam, ap);
      }
      if (frames_only) f.frame.depth = {}, f.frame.color = {};
      frames.push_back(std::move(f));
    }
    std::cerr << "bench_pairs: " << frames.size() << " frames of " << input << " (" << source->camera_origin()
              << ")\n";
    nlohmann::json records = nlohmann::json::array();
    for (const Run& run : runs) {
          const std::string &method = run.method, &mode = run.mode, &variant = run.variant;
          auto reg = hf::make_registration(method, run.options, hf::make_backend("cpu"));
          std::vector<int> ok_per_k(size_t(max_k + 1), 0), n_per_k(size_t(max_k + 1), 0);
          double ms_total = 0.0;
          long n_total = 0;
          for (int k = 1; k <= max_k; ++k)
            for (size_t i = 0; i + size_t(k) < frames.size(); i += size_t(stride)) {
              const PairsFrame& ref = frames[i];
              const PairsFrame& cur = frames[i + size_t(k)];
              const hf::FramePyramid& cp = mode == "pipeline" ? cur.pipeline_pyramid : cur.align_pyramid;
              const hf::FramePyramid& rp = mode == "pipeline" ? ref.pipeline_pyramid : ref.align_pyramid;
              const auto t0 = std::chrono::steady_clock::now();
              const hf::RegistrationResult res = reg->align(cp, rp, hf::SE3());
              const double ms =
                  std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
              const hf::SE3 gt = ref.frame.T_world_camera_gt->inverse() * *cur.frame.T_world_camera_gt;
              const hf::SE3 err = gt.inverse() * res.T_ref_cur;
              const double t_err = err.translation().norm(), r_err = err.angle_rad() * 180.0 / M_PI;
              const bool ok = res.usable() && t_err < 0.03 && r_err < 2.0;
              ok_per_k[size_t(k)] += ok;
              ++n_per_k[size_t(k)];
              ms_total += ms;
              ++n_total;
              records.push_back({{"method", method}, {"mode", mode}, {"variant", variant}, {"i", i}, {"k", k},
                                 {"usable", res.usable()}, {"status", hf::to_string(res.status)},
                                 {"t_err_m", t_err}, {"r_err_deg", r_err}, {"success", ok}, {"ms", ms},
                                 {"gt_t_m", gt.translation().norm()}, {"gt_r_deg", gt.angle_rad() * 180.0 / M_PI}});
            }
          std::cerr << method << " " << mode << " " << variant << ":";
          for (int k = 1; k <= max_k; ++k)
            std::cerr << " k" << k << "="
                      << (n_per_k[size_t(k)] ? 100.0 * ok_per_k[size_t(k)] / n_per_k[size_t(k)] : 0.0) << "%";
          std::cerr << "  " << (n_total ? ms_total / double(n_total) : 0.0) << " ms/pair\n";
    }
    nlohmann::json frame_list = nlohmann::json::array();  // for a peer (bench/pairs_open3d.py) on the same pairs
    for (const PairsFrame& f : frames) {
      const Eigen::Matrix4d T = f.frame.T_world_camera_gt->matrix();
      std::vector<double> rows(T.data(), T.data() + 16);  // column-major
      frame_list.push_back(
          {{"depth", f.frame.depth_file}, {"color", f.frame.color_file}, {"T_world_camera_colmajor", rows}});
    }
    nlohmann::json doc = {{"input", input}, {"camera", source->camera_origin()}, {"frames", frames.size()},
                          {"pinhole", {cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height}},
                          {"distortion_undone", bool(undistort)}, {"max_k", max_k}, {"stride", stride},
                          {"frame_list", frame_list}, {"records", records}};
    std::ofstream(out_path) << doc.dump() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_pairs: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
