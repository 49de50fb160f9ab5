// `hashfusion devices`: what each live back-end (OpenNI2, V4L2, libcamera) sees now, with the modes of each
// device, or that it sees none / is not built in. Exit 0 whatever is connected (listing is not a failure).
#include <CLI/CLI.hpp>

#include <iostream>

#include "apps/commands.h"
#include "io/live_input.h"

namespace hf::apps {

void add_devices_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("devices", "List the live capture devices of each back-end and their modes");
  cmd->callback([] {
    for (const DeviceListing& l : list_devices()) {
      std::cout << l.backend << ":";
      if (!l.available) {
        std::cout << " " << l.note << "\n";
        continue;
      }
      if (l.devices.empty()) std::cout << " " << (l.note.empty() ? "none connected" : l.note);
      std::cout << "\n";
      for (const std::string& d : l.devices) std::cout << "  " << d << "\n";
    }
  });
}

}  // namespace hf::apps
