// `hashfusion record --input LIVE --out DIR [--frames N | --seconds S]`: a live input (io/live_input.h) recorded as
// a TUM RGB-D folder (io/tum_recorder.h) that `hashfusion run --input DIR` replays exactly. Ctrl-C / SIGTERM stop
// the recording and still write the folder for the frames so far (exit 130 / 143, apps/interrupt.h); an unplugged
// device ends it the same way with exit 0 and a line saying so.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>

#include "apps/cli_common.h"
#include "apps/commands.h"
#include "apps/interrupt.h"
#include "core/error.h"
#include "core/progress.h"
#include "io/live_input.h"
#include "io/tum_recorder.h"

namespace hf::apps {
namespace {

struct RecordOptions {
  std::string input, out, camera, live_mode = "640x480@30";
  long frames = 0;
  double seconds = 0.0;
};

void record(const RecordOptions& o) {
  if (!is_live_input(o.input))
    throw Error(o.input + ": not a live input (openni2://[URI], FILE.oni, v4l2:///dev/videoN, libcamera://[ID])");
  const LiveInputOptions options = live_input_options(o.live_mode, o.camera);
  check_new_record_folder(o.out);  // before the device starts, not after
  InterruptGuard guard;
  std::unique_ptr<FrameSource> source = open_live_input(o.input, options);
  std::cerr << "input: " << source->name() << "\ncamera: " << source->camera().describe() << " ("
            << source->camera_origin() << ")\n";
  if (o.frames == 0 && o.seconds == 0.0 && source->size() == kUnknownFrameCount)
    std::cerr << "recording until Ctrl-C (give --frames N or --seconds S to stop on its own)\n";
  Progress progress("record", o.frames);
  RecordLimits limits;
  limits.frames = o.frames;
  limits.seconds = o.seconds;
  limits.stop = guard.flag();
  limits.progress = [&](long n) { progress.update(n); };
  RecordResult r;
  try {
    r = record_tum_folder(*source, o.out, limits);
  } catch (const Error&) {
    progress.finish();
    guard.exit_if_interrupted("nothing recorded");
    throw;
  }
  progress.finish();
  std::cout << "recorded " << r.frames << " frames into " << std::filesystem::absolute(o.out).string() << "\n";
  if (r.skipped) std::cout << "skipped " << r.skipped << " frames (unreadable or without an increasing time stamp)\n";
  if (r.capture)
    std::cout << "capture: " << r.capture->captured << " frames at " << r.capture->input_fps << " fps, written "
              << r.capture->delivered << ", dropped " << r.capture->dropped << "\n";
  if (!r.input_ended.empty()) std::cerr << "input ended: " << r.input_ended << "\n";
  guard.exit_if_interrupted("recorded " + std::to_string(r.frames) + " frames into " + o.out);
}

}  // namespace

void add_record_command(CLI::App& app) {
  auto opts = std::make_shared<RecordOptions>();
  CLI::App* cmd = app.add_subcommand("record", "Record a live input as a TUM RGB-D folder that `run` replays");
  cmd->add_option("--input", opts->input,
                  "openni2://[URI], FILE.oni, v4l2:///dev/videoN[+/dev/videoM], libcamera://[ID]")
      ->required();
  add_out_option(cmd, opts->out, "the folder to create (must not exist)");
  auto* frames = cmd->add_option("--frames", opts->frames, "stop after N frames")->check(positive());
  cmd->add_option("--seconds", opts->seconds, "stop after S seconds")->check(positive())->excludes(frames);
  cmd->add_option("--camera", opts->camera, "camera preset or file (default: the device's, else ros)");
  cmd->add_option("--live-mode", opts->live_mode, "WIDTHxHEIGHT@FPS to ask the device for")->capture_default_str();
  cmd->callback([opts] { record(*opts); });
}

}  // namespace hf::apps
