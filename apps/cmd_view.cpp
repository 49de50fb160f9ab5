// `hashfusion view mesh.ply | mesh.obj | map.hfmap | OUTDIR [--screenshot FILE.png] [--camera-pose POSE]`: browse a
// result in the OpenGL viewer (viewer/view_files.h), or render one view headless into a PNG (under xvfb-run without
// a screen). A bad --camera-pose is one line and exit 1 (io/trajectory_io.h parse_tum_pose).
#include <CLI/CLI.hpp>
#include <optional>

#include "apps/commands.h"
#include "core/error.h"
#include "io/trajectory_io.h"
#if HF_HAVE_VIEWER
#include "io/dataset.h"
#include "viewer/view_files.h"
#endif

namespace hf::apps {

void add_view_command(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  auto screenshot = std::make_shared<std::string>();
  auto camera = std::make_shared<std::string>();
  auto pose = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("view", "Browse a mesh, a saved map or a run's output folder in the viewer");
  auto* input = cmd->add_option("--input", *path, "a .ply or .obj mesh, map.hfmap or a `run` output folder");
  cmd->add_option("path", *path, "the same as --input (either one)")->excludes(input);
  cmd->add_option("--screenshot", *screenshot, "render one view into this PNG and exit (headless)");
  cmd->add_option("--camera", *camera, "camera preset or file for the view (default: the run's, else ros)");
  cmd->add_option("--camera-pose", *pose,
                  "the view's pose 'tx ty tz qx qy qz qw' (camera to world, metres, TUM's order; default: the run's "
                  "last pose, else framing the mesh)");
  cmd->callback([path, screenshot, camera, pose] {
    if (path->empty()) throw Error("view: --input PATH is required");
    // Checked before any file is read or a window opens, so a typo costs one line, not a GL context.
    std::optional<SE3> T_world_camera;
    if (!pose->empty()) T_world_camera = parse_tum_pose(*pose, "view: --camera-pose");
#if HF_HAVE_VIEWER
    viewer::ViewFilesOptions o;
    o.screenshot = *screenshot;
    if (!camera->empty()) o.camera = camera_from_option(*camera).camera;
    o.T_world_camera = T_world_camera;
    viewer::view_files(*path, o);
#else
    throw Error("view: the viewer is not built in (install libglfw3-dev, libglm-dev and OpenGL headers, reconfigure)");
#endif
  });
}

}  // namespace hf::apps
