// hashfusion: real-time RGB-D SLAM and 3D reconstruction. `hashfusion --help` lists the subcommands.
// Exit status: 0 done, 1 bad input or arguments (one line on stderr naming the file), 2 internal error,
// 130 / 143 / 129 interrupted by SIGINT / SIGTERM / SIGHUP after writing every output for the work done
// (apps/interrupt.h).
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "core/error.h"

int main(int argc, char** argv) {
  CLI::App app{"hashfusion: voxel-hashed RGB-D SLAM and 3D reconstruction"};
  app.require_subcommand(1);
  hf::apps::add_run_command(app);
  hf::apps::add_generate_command(app);
  hf::apps::add_eval_command(app);
  hf::apps::add_bench_command(app);
  hf::apps::add_lidar_command(app);
  hf::apps::add_head_features_command(app);
  hf::apps::add_devices_command(app);
  hf::apps::add_record_command(app);
  hf::apps::add_view_command(app);
  hf::apps::add_model_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const hf::apps::Interrupted& e) {
    std::cerr << "hashfusion: " << e.what() << "\n";
    return e.exit_status();
  } catch (const hf::Error& e) {
    std::cerr << "hashfusion: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "hashfusion: internal error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
