// What `hashfusion bench --input PATH...` runs on: each PATH is
//   synthetic:PRESET   one synthetic preset (datasets/presets.h),
//   synthetic:all      every preset, hard cases included, in preset_names() order,
//   a dataset folder   TUM RGB-D or 7-Scenes (io/dataset.h detect_dataset_format),
//   any other folder   searched recursively for dataset folders (sorted by path; a dataset's own subfolders are
//                      not searched). Each top-most subfolder that neither is nor contains a dataset is reported
//                      in `notes` ("skipping ...: not a TUM or 7-Scenes dataset"); a folder without any dataset
//                      is an error.
// The same dataset reached twice (e.g. a folder and its parent both given) is run once.
#pragma once

#include <string>
#include <vector>

namespace hf::bench {

struct BenchInput {
  std::string spec;   // what to open: "synthetic:PRESET" or the dataset folder's path
  std::string label;  // the short name tables show: "synthetic:wall", "rgbd_dataset_freiburg1_rpy" (made unique)
  bool synthetic = false;
};

struct DiscoveredInputs {
  std::vector<BenchInput> inputs;
  std::vector<std::string> notes;  // one line per skipped folder
};

// Throws hf::Error for an unknown preset ("unknown synthetic preset 'x' (known: ...)"), a path that does not
// exist, a path that is neither a dataset nor a folder, or a folder with no dataset anywhere below it. Folders
// deeper than `max_depth` below a given PATH are not searched.
DiscoveredInputs discover_inputs(const std::vector<std::string>& paths, int max_depth = 8);

}  // namespace hf::bench
