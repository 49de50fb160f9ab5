// `hashfusion view mesh.ply | map.hfmap | OUTDIR`: browsing results. A mesh is shown as is; a saved volume
// (fusion/volume_io.h) is meshed first (marching cubes, fusion/mesh.h); a run's output folder shows its mesh.ply
// with the trajectory.txt and the last pose's frustum, in the camera of its report.json.
// The view starts at `T_world_camera` when given, else at the folder's last trajectory pose, else framing the
// mesh's bounding box (frame_mesh). Headless with `screenshot`: renders that one view at the camera's
// size into the PNG and returns; otherwise a window (keys as viewer/view_controller.h, without the run ones) until
// closed. Throws hf::Error naming the path for anything unreadable, and when there is no display.
#pragma once

#include <optional>
#include <string>

#include "core/camera.h"
#include "core/se3.h"
#include "io/mesh.h"

namespace hf::viewer {

struct ViewFilesOptions {
  std::string screenshot;              // headless: write this PNG and return
  std::optional<PinholeCamera> camera;  // default: the folder's report.json camera, else ros
  std::optional<SE3> T_world_camera;   // default: see above
};

void view_files(const std::string& path, const ViewFilesOptions& options);

// The view of a bare mesh: looking at its bounding box's centre from outside, from the side its surfaces face (a
// scan's face the sensor), down at 25 degrees, the world's up guessed from the mesh (the axis direction the most
// triangle area faces: floors; -y, hashfusion's convention, when none stands out), from just far enough that all
// eight corners of the box project into `camera`'s image with a 5 % margin on each side, so the whole mesh is in
// view (and at least 0.1 m in front of the camera, beyond the GL near plane). Returns T_world_camera.
// Throws hf::Error for a mesh without vertices or a principal point outside the image.
SE3 frame_mesh(const TriangleMesh& mesh, const PinholeCamera& camera);

}  // namespace hf::viewer
