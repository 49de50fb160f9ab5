// Temporary: subcommands not yet written. Each owner replaces its stub with apps/cmd_NAME.cpp.
#include <CLI/CLI.hpp>

#include "apps/commands.h"

namespace hf::apps {
void add_generate_command(CLI::App& app) { app.add_subcommand("generate", "(not yet built)"); }
void add_eval_command(CLI::App& app) { app.add_subcommand("eval", "(not yet built)"); }
void add_run_command(CLI::App& app) { app.add_subcommand("run", "(not yet built)"); }
}  // namespace hf::apps
