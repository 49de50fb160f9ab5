// Fuzz target: a pipeline configuration file (JSON) must parse into a valid PipelineConfig or throw hf::Error
// naming the file, never crash, trip a sanitizer, or narrow an out-of-range number.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "slam/pipeline.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const hf::slam::PipelineConfig c =
        hf::slam::parse_config(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
    c.validate();  // what came back must be valid
  } catch (const hf::Error&) {
  }
  return 0;
}
