// Readers of photogrammetric networks (photogrammetry/network.h) from the three sources the issue names.
//
// OpenMVS text dump (../shared/data/photogrammetry_sceaux_castle, derived from scene.mvs):
//   cameras_from_scene_mvs.txt, one line per image:
//     image_name width height fx fy cx cy  R00 .. R22  Cx Cy Cz  tx ty tz  present
//   (R world -> camera, C the centre, t = -R C checked against R and C within 1e-6 of |C|, present 0/1); the image is
//   image_name relative to the file's folder. sparse_points_with_views.txt, one line per point:
//     X Y Z R G B n_views view_1 .. view_n   (view = 0-based line order of the cameras file)
// Middlebury *_par.txt: the first data line is the number of rows, then per image
//     name k11 k12 k13 k21 k22 k23 k31 k32 k33 r11 .. r33 t1 t2 t3   (P = K [R | t], so C = -R^T t)
//   The file has no image size: width x height come from the options (640 x 480, the size of every Middlebury MVS
//   image, README.txt); load_shot_image() checks it against the image.
// hashfusion run output (`hashfusion run --out DIR`): report.json ("input": the TUM folder, "camera": the pinhole
//   the run used, "per_frame": which frames were keyframes), trajectory.txt (T_world_camera per frame) and mesh.ply
//   (its vertices and colours become the cloud, with unknown visibility). Each keyframe (or every frame) is a shot:
//   its colour image from the dataset's rgb.txt, x_cam = R (X - C) with R = R_world_camera^T, C = t_world_camera.
//
// Limits: at most kMaxShots shots and kMaxCloudPoints points; a point lists at most one view per shot.
// Failure modes: hf::ParseError "FILE:LINE: expected ..." for malformed text (values quoted, printable, short);
// hf::Error naming the file for missing files and inconsistent content (Network::validate()).
#pragma once

#include <cstddef>
#include <string>

#include "core/camera.h"
#include "photogrammetry/network.h"

namespace hf::photogrammetry {

inline constexpr size_t kMaxShots = 100000;
inline constexpr size_t kMaxCloudPoints = 50'000'000;

// cameras_from_scene_mvs.txt: shots with image_path = image_root / image_name and image_available = present && the
// file exists. name_for_errors replaces the path in messages.
std::vector<Shot> parse_openmvs_cameras(const std::string& text, const std::string& name_for_errors,
                                        const std::string& image_root);
// sparse_points_with_views.txt for a network of `shot_count` shots.
Cloud parse_openmvs_points(const std::string& text, const std::string& name_for_errors, size_t shot_count);
// A folder holding cameras_from_scene_mvs.txt (and sparse_points_with_views.txt, optional), or the cameras file.
Network read_openmvs_text(const std::string& path);

struct MiddleburyOptions {
  int width = 640, height = 480;  // Middlebury MVS images (README.txt)
};
std::vector<Shot> parse_middlebury_par(const std::string& text, const std::string& name_for_errors,
                                       const std::string& image_root, const MiddleburyOptions& options = {});
// A *_par.txt file, or a folder holding exactly one.
Network read_middlebury(const std::string& path, const MiddleburyOptions& options = {});

struct RunShotsOptions {
  std::string dataset;          // the TUM folder of the run; empty: report.json's "input"
  bool keyframes_only = true;   // false: every tracked frame is a shot
};
// What a run's report.json says about its shots.
struct RunReport {
  std::string input;                     // "input"
  PinholeCamera camera;                  // "camera" ("fx=.. fy=.. cx=.. cy=.. WxH", PinholeCamera::describe())
  std::vector<double> keyframe_stamps_s;  // "per_frame" entries with "keyframe": true, their "timestamp_s"
  std::vector<double> tracked_stamps_s;   // "per_frame" entries whose "state" is not "lost"
};
RunReport parse_run_report(const std::string& text, const std::string& name_for_errors);
Network read_run_network(const std::string& run_dir, const RunShotsOptions& options = {});

// Any of the above by what `path` holds: a run folder (report.json), an OpenMVS dump, an OpenMVS scene.mvs
// (photogrammetry/scene_mvs.h; a folder with scene.mvs and no dump too), a Middlebury *_par.txt.
// Throws hf::Error naming `path` when it is none of them.
Network read_network(const std::string& path, const RunShotsOptions& run_options = {});

}  // namespace hf::photogrammetry
