#include "slam/appearance.h"

#include <algorithm>
#include <functional>
#include <map>

#include "core/error.h"
#include "slam/appearance/eigenspaces.h"
#include "slam/appearance/ferns.h"
#include "slam/appearance/thumbnail.h"

namespace hf::slam {
namespace {

const std::map<std::string, std::function<std::unique_ptr<AppearanceIndex>()>>& registry() {
  static const std::map<std::string, std::function<std::unique_ptr<AppearanceIndex>()>> r = {
      {"eigenspaces", [] { return std::make_unique<EigenspacesIndex>(); }},
      {"ferns", [] { return std::make_unique<FernsIndex>(); }},
      {"thumbnail", [] { return std::make_unique<ThumbnailIndex>(); }},
  };
  return r;
}

}  // namespace

std::vector<AppearanceMatch> best_matches(std::vector<AppearanceMatch> candidates, size_t k) {
  k = std::min(k, candidates.size());
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const AppearanceMatch& a, const AppearanceMatch& b) { return a.distance < b.distance; });
  candidates.resize(k);
  return candidates;
}

std::unique_ptr<AppearanceIndex> make_appearance_index(const std::string& name) {
  const auto it = registry().find(name);
  if (it == registry().end()) {
    std::string known;
    for (const std::string& n : appearance_index_names()) known += (known.empty() ? "" : ", ") + n;
    throw Error("unknown appearance index '" + name + "' (known: " + known + ")");
  }
  return it->second();
}

std::vector<std::string> appearance_index_names() {
  std::vector<std::string> names;
  for (const auto& [name, make] : registry()) names.push_back(name);
  return names;
}

// bench/results/appearance.md (build/release/bench/appearance_eval), mean over the untouched report cases:
// ferns p@1 0.729 / p@5 0.669 / 3613 B per keyframe; thumbnail 0.729 / 0.652 / 2400 B; eigenspaces 0.722 / 0.652 /
// 1758 B (+2400 B rebuild store). Ferns tie on p@1 and lead p@5, the rule the results file states.
std::string default_appearance_index_name() { return "ferns"; }

}  // namespace hf::slam
