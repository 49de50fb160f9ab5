// Bounds io/las.h's LasReader enforces on a LAS header, beside the format's own rules: a scale of 1e300 or a box
// at 1e308 is finite, yet makes every coordinate, grid size and message absurd.
#pragma once

namespace hf {

// Scale factors (|scale|, units of the CRS per integer step): real surveys use 1e-7 (degrees) .. 0.01 (metres).
inline constexpr double kLasMinScale = 1e-9, kLasMaxScale = 10.0;
// Offsets and bounding-box coordinates (|value|): 1e10 is beyond any projected or geocentric coordinate. Every
// position a file can encode (2^31 steps of the largest scale from the largest offset) lies within
// kLasMaxCoordinate, so a box written from decoded points always reads back.
inline constexpr double kLasMaxOffset = 1e10, kLasMaxCoordinate = 1e11;

}  // namespace hf
