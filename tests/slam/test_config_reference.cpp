// The configuration reference (slam/config_reference.h) against the configuration itself: every key of
// PipelineConfig's JSON has a row and every row a key (for the default method, combined); every default lies in
// its row's range; a number outside it is refused at parse time naming the key and the range; floats are written
// as typed (shortest round trip).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <map>
#include <set>
#include <string>

#include "core/error.h"
#include "slam/config_reference.h"
#include "slam/pipeline_config.h"

namespace hf::slam {
namespace {

void config_reference_flatten(const nlohmann::json& j, const std::string& prefix,
                              std::map<std::string, nlohmann::json>* out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object()) config_reference_flatten(*it, key, out);
    else (*out)[key] = *it;
  }
}

TEST(ConfigReference, EveryKeyHasARowAndEveryRowAKey) {
  std::map<std::string, nlohmann::json> keys;
  config_reference_flatten(config_to_json(PipelineConfig{}), "", &keys);
  ASSERT_GT(keys.size(), 100u);
  for (const auto& [key, value] : keys) EXPECT_NE(find_config_key(key), nullptr) << key << " has no row";
  std::set<std::string> rows;
  for (const ConfigKey& r : config_reference()) {
    EXPECT_TRUE(rows.insert(r.key).second) << r.key << " twice";
    EXPECT_TRUE(keys.count(r.key)) << r.key << " is no key of the configuration";
    EXPECT_GT(std::string(r.meaning).size(), 8u) << r.key;
  }
}

TEST(ConfigReference, DefaultsLieInTheirRanges) {
  std::map<std::string, nlohmann::json> keys;
  config_reference_flatten(config_to_json(PipelineConfig{}), "", &keys);
  for (const auto& [key, value] : keys) {
    const ConfigKey* row = find_config_key(key);
    if (row && value.is_number()) {
      EXPECT_TRUE(in_config_range(*row, value.get<double>())) << key << " = " << value;
    }
  }
}

TEST(ConfigReference, ParserRefusesNumbersOutsideTheRowsRange) {
  auto error_of = [](const char* text) {
    try {
      parse_config(text, "c.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of(R"({"volume": {"voxel_m": 50}})"), "c.json: volume.voxel_m: expected 0.0001..10 m, got 50");
  EXPECT_EQ(error_of(R"({"tracking_level": 3})"), "c.json: tracking_level: expected 0..2, got 3");
  EXPECT_EQ(error_of(R"({"raycast": {"step_fraction": 1.0}})"),
            "c.json: raycast.step_fraction: expected (0, 1), got 1");
  EXPECT_EQ(error_of(R"({"loop_closure": {"max_angle_deg": 0}})"),
            "c.json: loop_closure.max_angle_deg: expected (0, 180] deg, got 0");
  EXPECT_EQ(error_of(R"({"keyframes": {"min_translation_m": -1}})"),
            "c.json: keyframes.min_translation_m: expected > 0 m, got -1");
  // a whole report.json: its "config" object, errors named inside it
  EXPECT_EQ(error_of(R"({"ate_online_m": 0.1, "config": {"volume": {"voxel_m": 0}}})"),
            "c.json: config: volume.voxel_m: expected 0.0001..10 m, got 0");
  EXPECT_EQ(parse_config(R"({"ate_online_m": 0.1, "config": {"volume": {"voxel_m": 0.02}}})", "r.json").volume.voxel_m,
            0.02);
}

// depth_only_registration_options: the hand-over method's own keys, over the pipeline's options of that method;
// absent from the defaults' JSON (written only when set), a key the method does not have refused, and read back
// from a report's JSON.
TEST(ConfigReference, DepthOnlyRegistrationOptionsAreTheHandOversKeys) {
  EXPECT_FALSE(config_to_json(PipelineConfig{}).contains("depth_only_registration_options"));
  const PipelineConfig c = parse_config(R"({"depth_only_registration_options": {"depth_noise_ref_m": 1.5}})", "c.json");
  ASSERT_TRUE(c.depth_only_registration_options.has_value());
  const nlohmann::json j = config_to_json(c);
  EXPECT_EQ(j["depth_only_registration_options"]["depth_noise_ref_m"].get<double>(), 1.5);
  EXPECT_EQ(j["depth_only_registration_options"]["max_abs_sdf"].dump(), "0.9");  // sdf's, the default hand-over
  const PipelineConfig back = config_from_json(j, "report.json");
  ASSERT_TRUE(back.depth_only_registration_options.has_value());
  EXPECT_EQ(config_to_json(back)["depth_only_registration_options"], j["depth_only_registration_options"]);
  EXPECT_THROW(parse_config(R"({"depth_only_registration_options": {"rgb_weight_typo": 1}})", "c.json"), Error);
  // icp as the hand-over: its keys, not sdf's
  EXPECT_THROW(parse_config(R"({"colour_check": {"depth_only_registration": "icp"},
                               "depth_only_registration_options": {"max_abs_sdf": 0.5}})", "c.json"), Error);
  EXPECT_NO_THROW(parse_config(R"({"colour_check": {"depth_only_registration": "icp"},
                                  "depth_only_registration_options": {"max_dist_m": 0.05}})", "c.json"));
}

TEST(ConfigReference, FloatsAreWrittenAsTyped) {
  const nlohmann::json j = config_to_json(PipelineConfig{});
  // float fields: 0.1f, not 0.10000000149011612; and back to the same float
  EXPECT_EQ(j["registration_options"]["max_dist_m"].dump(), "0.1");
  EXPECT_EQ(j["registration_options"]["rgb_weight"].dump(), "0.4");
  const PipelineConfig back = config_from_json(j, "j");
  EXPECT_EQ(config_to_json(back), j);
}

TEST(ConfigReference, DescribeRange) {
  EXPECT_EQ(describe_range(*find_config_key("volume.voxel_m")), "0.0001..10 m");
  EXPECT_EQ(describe_range(*find_config_key("registration")), "");
  EXPECT_EQ(describe_range(*find_config_key("stream_radius_m")), ">= 0 m");
}

}  // namespace
}  // namespace hf::slam
