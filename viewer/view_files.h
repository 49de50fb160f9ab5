// `hashfusion view mesh.ply | map.hfmap | OUTDIR`: browsing results. A mesh is shown as is; a saved volume
// (fusion/volume_io.h) is meshed first (marching cubes, fusion/mesh.h); a run's output folder shows its mesh.ply
// with the trajectory.txt and the last pose's frustum, in the camera of its report.json.
// The view starts at `T_world_camera` when given, else at the folder's last trajectory pose, else looking at the
// mesh's centre from 1.5 x its bounding radius. Headless with `screenshot`: renders that one view at the camera's
// size into the PNG and returns; otherwise a window (keys as viewer/view_controller.h, without the run ones) until
// closed. Throws hf::Error naming the path for anything unreadable, and when there is no display.
#pragma once

#include <optional>
#include <string>

#include "core/camera.h"
#include "core/se3.h"

namespace hf::viewer {

struct ViewFilesOptions {
  std::string screenshot;              // headless: write this PNG and return
  std::optional<PinholeCamera> camera;  // default: the folder's report.json camera, else ros
  std::optional<SE3> T_world_camera;   // default: see above
};

void view_files(const std::string& path, const ViewFilesOptions& options);

}  // namespace hf::viewer
