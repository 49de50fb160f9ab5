// The parts of harness.h that do not need the SLAM pipeline.
#include <algorithm>
#include <charconv>
#include <sstream>

#include "bench/harness/harness.h"
#include "bench/harness/inputs.h"
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

std::vector<PlannedRun> plan_runs(const BenchOptions& o) {
  std::vector<PlannedRun> runs;
  for (const BenchInput& input : discover_inputs(o.inputs).inputs) {
    for (const std::string& m : o.registrations)
      for (const std::string& mode : o.loop_closure_modes) runs.push_back({input.label, loop_closure_label(m, mode)});
    for (const std::string& p : o.peers) runs.push_back({input.label, p + " (peer)"});
  }
  return runs;
}

std::pair<int, int> parse_shard(const std::string& text) {
  const std::string expected = "--shard '" + text + "': expected K/N with 0 <= K < N (slice K of N, from 0)";
  const size_t slash = text.find('/');
  if (slash == std::string::npos) throw Error(expected);
  int k = -1, n = 0;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  const auto a = std::from_chars(begin, begin + slash, k);
  const auto b = std::from_chars(begin + slash + 1, end, n);
  if (a.ec != std::errc() || a.ptr != begin + slash || b.ec != std::errc() || b.ptr != end || slash == 0 ||
      k < 0 || n < 1 || k >= n)
    throw Error(expected);
  return {k, n};
}

std::pair<size_t, size_t> shard_range(size_t runs, int k, int n) {
  // 64-bit products: runs * n stays far below 2^64 for any benchmark (runs and n are counts of processes).
  return {runs * size_t(k) / size_t(n), runs * size_t(k + 1) / size_t(n)};
}

}  // namespace hf::bench
