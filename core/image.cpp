#include "core/image.h"

namespace hf {

IntensityImage intensity_from_color(const ColorImage& color) {
  IntensityImage out(color.width(), color.height());
  const Rgb8* src = color.data();
  float* dst = out.data();
  for (size_t i = 0; i < color.size(); ++i) {
    dst[i] = (0.299f * src[i].r + 0.587f * src[i].g + 0.114f * src[i].b) * (1.0f / 255.0f);
  }
  return out;
}

}  // namespace hf
