// Images: a dense, row-major, owning 2-D array of plain pixels.
//
// Depth is in metres as float with 0 meaning "no measurement" (never NaN/inf: loaders reject those).
// Colour is RGB8 (R first, unlike OpenCV's BGR). Intensity is float in [0, 1].
// Vertex and normal maps hold hf_float4 with w = 1 valid, w = 0 invalid (see core/kernels/cl_compat.h).
#pragma once

#include <cstdint>
#include <vector>

#include "core/kernels/cl_compat.h"

namespace hf {

struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb8&) const = default;
};

template <class T>
class Image {
 public:
  Image() = default;
  Image(int width, int height, T fill = T{}) : width_(width), height_(height), data_(size_t(width) * height, fill) {}

  int width() const { return width_; }
  int height() const { return height_; }
  size_t size() const { return data_.size(); }
  bool empty() const { return data_.empty(); }

  T& operator()(int x, int y) { return data_[size_t(y) * width_ + x]; }
  const T& operator()(int x, int y) const { return data_[size_t(y) * width_ + x]; }
  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  std::vector<T>& pixels() { return data_; }
  const std::vector<T>& pixels() const { return data_; }

 private:
  int width_ = 0, height_ = 0;
  std::vector<T> data_;
};

using DepthImage = Image<float>;
using ColorImage = Image<Rgb8>;
using IntensityImage = Image<float>;
using VertexMap = Image<hf_float4>;
using NormalMap = Image<hf_float4>;

// ITU-R BT.601 luma, the weights DVO and Open3D use, scaled to [0, 1].
IntensityImage intensity_from_color(const ColorImage& color);

}  // namespace hf
