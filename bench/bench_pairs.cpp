// Large inter-frame motion (issue 34): every pair (i, i + k), k = 1..max_k, of a real sequence registered from the
// identity, against the ground-truth relative pose. Success = within 3 cm and 2 degrees of it (and a usable
// status). Two ways of running each method, both counted:
//   pipeline  the pipeline's registration settings: pyramid from level 1 (320x240 of 640x480), its levels and
//             iterations, slam::pipeline_registration_options (combined's rgb_weight 0.4), frame to frame;
//   align     align()'s defaults: pyramid of 3 levels from full resolution, the method's default options (what
//             hashfusion.make_registration(name).align(cur, ref, camera) does).
// Variants widen the basin: "+so3" (rotation-first, registration/so3_prealign.h, iterations 10/5 on the two
// coarsest levels), "+L4" (a fourth, coarser pyramid level with 4 iterations).
//
//   build/release/bench/bench_pairs --input DIR --out FILE.json [--max-k 10] [--methods combined,icp]
//                                   [--variants base,so3,L4,so3+L4] [--modes pipeline,align] [--stride 1]
// Frames of a distorted camera (fr1 with --camera fr1) are undistorted first, as the pipeline does. Writes one
// JSON record per (method, mode, variant, i, k) and prints a summary; bench/pairs_report.py makes the tables.
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
  hf::FramePyramid pipeline_pyramid, align_pyramid, pipeline_pyramid4, align_pyramid4;
};

}  // namespace

int main(int argc, char** argv) {
  std::string input, out_path, camera;
  int max_k = 10, stride = 1;
  std::vector<std::string> methods = {"combined", "icp"}, variants = {"base", "so3", "L4", "so3+L4"},
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
    else { std::cerr << "bench_pairs: unknown option " << key << "\n"; return 1; }
  }
  if (input.empty() || out_path.empty()) {
    std::cerr << "usage: bench_pairs --input DIR --out FILE.json [--camera C] [--max-k 10] [--methods a,b] "
                 "[--variants base,so3,L4,so3+L4] [--modes pipeline,align] [--stride 1]\n";
    return 1;
  }
  try {
    hf::DatasetOptions dopt;
    dopt.camera = camera;
    auto source = hf::open_dataset(input, dopt);
    const hf::PinholeCamera cam = source->camera().pinhole();
    std::optional<hf::Undistorter> undistort;
    if (!source->camera().distortion.none()) undistort.emplace(source->camera());
    std::vector<PairsFrame> frames;
    for (hf::FrameRead r = source->next(); r.status != hf::FrameStatus::end; r = source->next()) {
      if (r.status != hf::FrameStatus::ok || !r.frame.T_world_camera_gt) continue;
      PairsFrame f;
      f.frame = std::move(r.frame);
      if (undistort) {
        f.frame.depth = undistort->depth(f.frame.depth);
        f.frame.color = undistort->color(f.frame.color);
      }
      hf::FramePyramidOptions pp;  // the pipeline's: slam::PipelineConfig{}.pyramid from its tracking level
      pp.first_level = hf::slam::PipelineConfig{}.tracking_level;
      f.pipeline_pyramid = hf::build_frame_pyramid(f.frame.depth, &f.frame.color, cam, pp);
      f.align_pyramid = hf::build_frame_pyramid(f.frame.depth, &f.frame.color, cam, {});
      pp.levels = 4;
      hf::FramePyramidOptions ap;
      ap.levels = 4;
      f.pipeline_pyramid4 = hf::build_frame_pyramid(f.frame.depth, &f.frame.color, cam, pp);
      f.align_pyramid4 = hf::build_frame_pyramid(f.frame.depth, &f.frame.color, cam, ap);
      frames.push_back(std::move(f));
    }
    std::cerr << "bench_pairs: " << frames.size() << " frames of " << input << " (" << source->camera_origin()
              << ")\n";
    nlohmann::json records = nlohmann::json::array();
    for (const std::string& method : methods)
      for (const std::string& mode : modes)
        for (const std::string& variant : variants) {
          hf::RegistrationOptions o = mode == "pipeline" ? hf::slam::pipeline_registration_options(method)
                                                         : hf::default_registration_options(method);
          const bool four = variant.find("L4") != std::string::npos;
          if (four) o.driver.iterations.push_back(4);
          if (variant.find("so3") != std::string::npos) o.driver.so3_iterations = {10, 5};
          auto reg = hf::make_registration(method, o, hf::make_backend("cpu"));
          std::vector<int> ok_per_k(size_t(max_k + 1), 0), n_per_k(size_t(max_k + 1), 0);
          double ms_total = 0.0;
          long n_total = 0;
          for (int k = 1; k <= max_k; ++k)
            for (size_t i = 0; i + size_t(k) < frames.size(); i += size_t(stride)) {
              const PairsFrame& ref = frames[i];
              const PairsFrame& cur = frames[i + size_t(k)];
              const hf::FramePyramid& cp = mode == "pipeline" ? (four ? cur.pipeline_pyramid4 : cur.pipeline_pyramid)
                                                               : (four ? cur.align_pyramid4 : cur.align_pyramid);
              const hf::FramePyramid& rp = mode == "pipeline" ? (four ? ref.pipeline_pyramid4 : ref.pipeline_pyramid)
                                                               : (four ? ref.align_pyramid4 : ref.align_pyramid);
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
