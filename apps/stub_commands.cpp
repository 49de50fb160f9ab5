// Subcommands whose cmd_NAME.cpp does not exist yet (apps/CMakeLists.txt defines HF_STUB_NAME for them).
#include <CLI/CLI.hpp>

#include "apps/commands.h"

namespace hf::apps {
#ifdef HF_STUB_generate
void add_generate_command(CLI::App& app) { app.add_subcommand("generate", "(not yet built)"); }
#endif
#ifdef HF_STUB_eval
void add_eval_command(CLI::App& app) { app.add_subcommand("eval", "(not yet built)"); }
#endif
#ifdef HF_STUB_run
void add_run_command(CLI::App& app) { app.add_subcommand("run", "(not yet built)"); }
#endif
#ifdef HF_STUB_bench
void add_bench_command(CLI::App& app) { app.add_subcommand("bench", "(not yet built)"); }
#endif
}  // namespace hf::apps
