// The parts of harness.h that do not need the SLAM pipeline.
#include <algorithm>
#include <sstream>

#include "bench/harness/harness.h"
#include "core/error.h"
#include "registration/registration.h"

namespace hf::bench {
namespace {

std::vector<std::string> split_list(const std::string& spec) {
  std::vector<std::string> out;
  std::stringstream ss(spec);
  for (std::string item; std::getline(ss, item, ',');) {
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (!item.empty() && std::find(out.begin(), out.end(), item) == out.end()) out.push_back(item);
  }
  return out;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (size_t k = 0; k < names.size(); ++k) s += (k ? ", " : "") + names[k];
  return s;
}

}  // namespace

std::vector<std::string> resolve_registrations(const std::string& spec) {
  const std::vector<std::string> known = registration_names();
  if (spec == "all") return known;
  const std::vector<std::string> list = split_list(spec);
  if (list.empty()) throw Error("--registration: expected 'all' or a comma-separated list of " + joined(known));
  for (const std::string& name : list) {
    if (name != "groundtruth" && std::find(known.begin(), known.end(), name) == known.end()) {
      throw Error("--registration: unknown method '" + name + "' (known: " + joined(known) + ", groundtruth)");
    }
  }
  return list;
}

std::vector<std::string> resolve_loop_closure_modes(const std::string& spec) {
  const std::vector<std::string> known = {"off", "on", "global"};
  if (spec == "all") return known;
  const std::vector<std::string> list = split_list(spec);
  if (list.empty()) throw Error("--loop-closure: expected 'all' or a comma-separated list of " + joined(known));
  for (const std::string& m : list)
    if (std::find(known.begin(), known.end(), m) == known.end())
      throw Error("--loop-closure: unknown mode '" + m + "' (known: " + joined(known) + ", or all)");
  return list;
}

std::string loop_closure_label(const std::string& method, const std::string& mode) {
  if (mode == "off") return method + " -loops";
  if (mode == "global") return method + " +global";
  return method;
}

std::vector<std::string> resolve_peers(const std::string& spec) {
  const std::vector<std::string> known = peer_names();
  if (spec == "none" || spec.empty()) return {};
  if (spec == "all") return known;
  const std::vector<std::string> list = split_list(spec);
  for (const std::string& name : list) {
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      throw Error("--peers: unknown peer '" + name + "' (known: " + (known.empty() ? "none, built without PCL" : joined(known)) +
                  "; or 'none')");
    }
  }
  return list;
}

std::string build_source_dir() {
#ifdef HF_BENCH_SOURCE_DIR
  return HF_BENCH_SOURCE_DIR;
#else
  return "";
#endif
}

std::string file_safe(const std::string& label) {
  std::string s = label;
  for (char& ch : s) {
    const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '-' ||
                    ch == '_' || ch == '.';
    if (!ok) ch = '_';
  }
  return s.empty() ? "_" : s;
}

}  // namespace hf::bench
