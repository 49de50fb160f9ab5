// Fuzz target: the volume loader must turn any byte string into a Volume or an hf::ParseError, never a crash,
// a sanitizer report or an allocation driven by an unchecked size field.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/error.h"
#include "fusion/volume_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto volume = hf::fusion::parse_volume(
        std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.hfvol");
    (void)volume.grid.block_count();
  } catch (const hf::ParseError&) {
  }
  return 0;
}
