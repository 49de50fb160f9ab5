// One function per `hashfusion` subcommand; each adds its CLI11 subcommand and the callback that runs it.
// A callback reports failure by throwing hf::Error; main() prints it as one line and exits 1.
#pragma once

namespace CLI {
class App;
}

namespace hf::apps {

void add_generate_command(CLI::App& app);  // apps/cmd_generate.cpp
void add_eval_command(CLI::App& app);      // apps/cmd_eval.cpp
void add_run_command(CLI::App& app);       // apps/cmd_run.cpp
void add_bench_command(CLI::App& app);     // apps/cmd_bench.cpp
void add_lidar_command(CLI::App& app);     // apps/cmd_lidar.cpp
void add_head_features_command(CLI::App& app);  // apps/cmd_head_features.cpp
void add_devices_command(CLI::App& app);   // apps/cmd_devices.cpp
void add_record_command(CLI::App& app);    // apps/cmd_record.cpp
void add_view_command(CLI::App& app);      // apps/cmd_view.cpp
void add_model_command(CLI::App& app);     // apps/cmd_model.cpp
void add_config_command(CLI::App& app);    // apps/cmd_config.cpp

}  // namespace hf::apps
