// This consumer's own "core/se3.h", named like hashfusion's on purpose: the installed hashfusion headers include
// theirs as <hashfusion/core/se3.h>, so this one is seen only by main.cpp's own include. Had an installed header
// reached this file instead, hf::SE3 would be missing and main.cpp would not compile.
#pragma once

namespace consumer {
constexpr const char* kLocalHeader = "consumer/core/se3.h";
}  // namespace consumer
