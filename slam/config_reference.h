// The configuration reference: one row per key of the pipeline's configuration (slam/pipeline_config.h, the JSON
// of a config file and of report.json's "config"): its unit, the range the parser accepts, and what it means.
//
// One table serves three readers, so none can drift from the others:
//   - config_from_json (slam/pipeline_config.cpp) checks every number it reads against its row's range and names
//     the row's range in the error ("volume.voxel_m: expected 0.0001..10 m, got 50");
//   - `hashfusion config` prints the table with each key's default (from PipelineConfig{});
//   - docs/config.md is that output (`hashfusion config --markdown`; test app_issue36_config_doc fails when stale).
// A test holds the rows and the configuration's keys equal (every key has a row, every row a key).
//
// registration_options: the keys depend on the method. Rows cover the Gauss-Newton driver's keys (every method)
// and those of combined (the default) and its parts icp and photometric; they document, and each method's own
// validate() enforces its ranges. Keys of other methods are listed by `hashfusion config --registration NAME`
// with their defaults and the header that documents them.
#pragma once

#include <string>
#include <vector>

namespace hf::slam {

struct ConfigKey {
  const char* key;      // the JSON path: "volume.voxel_m", "tracking_level", "registration_options.max_dist_m"
  const char* unit;     // "m", "deg", "px", "ms", "MiB", "voxels", "frames", "s^-1"...; "" for counts and ratios
  double min, max;      // numbers: the accepted range (bounds included unless open); ignored for text and bools
  bool min_open, max_open;
  const char* meaning;  // one line
};

// Every row, in the order `hashfusion config` prints them (top-level keys, then section by section).
const std::vector<ConfigKey>& config_reference();

// The row of `key` ("volume.voxel_m"), or nullptr.
const ConfigKey* find_config_key(const std::string& key);

// "0.0001..10 m", "(0, 1)", ">= 0", "> 0 m" for a row's range; "" for text and bools.
std::string describe_range(const ConfigKey& row);

// Whether `value` lies in the row's range.
bool in_config_range(const ConfigKey& row, double value);

}  // namespace hf::slam
