// hashfusion: real-time RGB-D SLAM and 3D reconstruction. `hashfusion --help` lists the subcommands.
// Exit status: 0 done, 1 bad input or arguments (one line on stderr naming the file or the option), 2 internal
// error, 130 / 143 / 129 interrupted by SIGINT / SIGTERM / SIGHUP after writing every output for the work done
// (apps/interrupt.h). CLI11's own codes (104 .. 109 for argument errors) never reach the shell: a script tells
// "bad arguments" from "bad input" by the message, not the code, as with every other tool's exit 1.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "apps/build_info.h"
#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/invocation.h"
#include "core/error.h"
#include "core/memory_policy.h"

namespace {

// "run" when the error came from `hashfusion run ...`: the deepest subcommand parsed so far.
std::string parsed_subcommand(const CLI::App& app) {
  std::string name;
  for (const CLI::App* sub : app.get_subcommands()) name = sub->get_name();
  return name;
}

// One line: CLI11's messages can hold newlines (e.g. a list of unexpected arguments).
std::string one_line(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  hf::keep_freed_memory_for_reuse();  // first, before any thread or buffer exists (core/memory_policy.h)
  hf::apps::record_invocation(argc, argv);
  CLI::App app{"hashfusion: voxel-hashed RGB-D SLAM and 3D reconstruction"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("hashfusion ") + hf::apps::build_version() + " (commit " +
                                        hf::apps::build_commit() + ")");
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
  hf::apps::add_config_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::string sub = parsed_subcommand(app);
    std::cerr << "hashfusion" << (sub.empty() ? "" : " " + sub) << ": " << one_line(e.what()) << " (see hashfusion"
              << (sub.empty() ? "" : " " + sub) << " --help)\n";
    return 1;
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
