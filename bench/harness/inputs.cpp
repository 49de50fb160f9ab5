#include "bench/harness/inputs.h"

#include <algorithm>
#include <filesystem>
#include <set>

#include "core/error.h"
#include "datasets/presets.h"
#include "datasets/synthetic_source.h"
#include "io/dataset.h"

namespace hf::bench {
namespace fs = std::filesystem;
namespace {

struct Finder {
  int max_depth;
  std::vector<std::string> found;  // dataset folders
  std::vector<std::string> notes;

  bool is_dataset(const fs::path& dir) const { return detect_dataset_format(dir.string()) != DatasetFormat::unknown; }

  // Datasets at or below `dir`; notes the top-most subfolders without any.
  int search(const fs::path& dir, int depth) {
    if (is_dataset(dir)) {
      found.push_back(dir.string());
      return 1;
    }
    if (depth >= max_depth) return 0;
    std::vector<fs::path> children;
    std::error_code ec;
    for (fs::directory_iterator it(dir, fs::directory_options::skip_permission_denied, ec), end; !ec && it != end;
         it.increment(ec)) {
      std::error_code type_ec;
      const std::string name = it->path().filename().string();
      if (!name.empty() && name[0] == '.') continue;  // hidden folders (.git, caches)
      if (it->is_directory(type_ec)) children.push_back(it->path());
    }
    std::sort(children.begin(), children.end());
    int total = 0;
    std::vector<fs::path> empty;
    for (const fs::path& child : children) {
      const int n = search(child, depth + 1);
      total += n;
      if (n == 0) empty.push_back(child);
    }
    if (total > 0) {
      for (const fs::path& e : empty) notes.push_back("skipping " + e.string() + ": not a TUM or 7-Scenes dataset");
    }
    return total;
  }
};

std::string canonical_or_same(const std::string& path) {
  std::error_code ec;
  const fs::path c = fs::weakly_canonical(path, ec);
  return ec ? path : c.string();
}

}  // namespace

DiscoveredInputs discover_inputs(const std::vector<std::string>& paths, int max_depth) {
  DiscoveredInputs out;
  std::set<std::string> seen;  // canonical dataset paths and synthetic specs
  auto add = [&](const std::string& spec, bool synthetic, const std::string& key) {
    if (!seen.insert(key).second) return;
    out.inputs.push_back({spec, synthetic ? spec : fs::path(spec).filename().string(), synthetic});
  };

  for (const std::string& path : paths) {
    if (datasets::is_synthetic_input(path)) {
      const std::string preset = path.substr(std::string(datasets::kSyntheticPrefix).size());
      if (preset == "all") {
        for (const std::string& name : datasets::preset_names()) {
          const std::string spec = datasets::kSyntheticPrefix + name;
          add(spec, true, spec);
        }
      } else {
        datasets::make_preset(preset);  // throws for an unknown preset, listing the known ones
        add(path, true, path);
      }
      continue;
    }
    std::string trimmed = path;
    while (trimmed.size() > 1 && trimmed.back() == '/') trimmed.pop_back();
    std::error_code ec;
    if (!fs::exists(trimmed, ec)) throw Error(path + ": no such file or folder");
    if (!fs::is_directory(trimmed, ec)) {
      throw Error(path + ": not a folder (expected a TUM or 7-Scenes dataset folder, or a folder containing them)");
    }
    Finder finder{max_depth, {}, {}};
    if (finder.search(trimmed, 0) == 0) {
      throw Error(path + ": no TUM RGB-D or 7-Scenes dataset in this folder or below it");
    }
    for (const std::string& dir : finder.found) add(dir, false, canonical_or_same(dir));
    std::sort(finder.notes.begin(), finder.notes.end());
    out.notes.insert(out.notes.end(), finder.notes.begin(), finder.notes.end());
  }

  // Unique labels: a folder name that occurs twice gets its parent's name in front ("a/seq-01", "b/seq-01").
  std::vector<int> same(out.inputs.size(), 0);
  for (size_t i = 0; i < out.inputs.size(); ++i) {
    for (const BenchInput& o : out.inputs) same[i] += !o.synthetic && o.label == out.inputs[i].label ? 1 : 0;
  }
  for (size_t i = 0; i < out.inputs.size(); ++i) {
    BenchInput& in = out.inputs[i];
    if (in.synthetic || same[i] < 2) continue;
    const fs::path p(in.spec);
    in.label = p.parent_path().filename().string() + "/" + p.filename().string();
  }
  for (size_t i = 0; i < out.inputs.size(); ++i) {  // still equal (deep twins): number them
    int k = 1;
    for (size_t j = i + 1; j < out.inputs.size(); ++j) {
      if (out.inputs[j].label == out.inputs[i].label) out.inputs[j].label += " #" + std::to_string(++k);
    }
  }
  return out;
}

}  // namespace hf::bench
