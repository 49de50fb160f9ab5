#include "slam/appearance/ferns.h"

#include <cmath>
#include <random>
#include <string>

#include "core/error.h"

namespace hf::slam {
namespace {

// Uniform in [0, 1) from 53 random bits: the same numbers on every standard library (unlike
// std::uniform_real_distribution, whose algorithm is unspecified).
double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// Block average over the pixels that count (colour: all; depth: finite > 0; cells without any read 0).
template <class Image, class Value>
std::vector<float> downsample(const Image& image, int w, int h, int channels, Value value) {
  std::vector<double> sum(size_t(w) * h * channels, 0.0);
  std::vector<int> count(size_t(w) * h, 0);
  if (!image.empty()) {
    std::vector<size_t> cell_x(size_t(image.width()));
    for (int x = 0; x < image.width(); ++x) cell_x[size_t(x)] = size_t(long(x) * w / image.width());
    for (int y = 0; y < image.height(); ++y) {
      const size_t row = size_t(long(y) * h / image.height()) * size_t(w);
      for (int x = 0; x < image.width(); ++x) {
        const size_t c = row + cell_x[size_t(x)];
        if (value(image(x, y), &sum[c * channels])) ++count[c];
      }
    }
  }
  std::vector<float> out(sum.size(), 0.0f);
  for (size_t c = 0; c < count.size(); ++c)
    for (int k = 0; k < channels; ++k)
      if (count[c] > 0) out[c * channels + k] = float(sum[c * channels + k] / count[c]);
  return out;
}

}  // namespace

void FernsOptions::validate() const {
  if (ferns < 1 || ferns > 100000) throw Error("ferns: ferns must be 1..100000, got " + std::to_string(ferns));
  if (width < 1 || width > 1024 || height < 1 || height > 1024)
    throw Error("ferns: width and height must be 1..1024, got " + std::to_string(width) + "x" +
                std::to_string(height));
  if (!(std::isfinite(min_depth_m) && std::isfinite(max_depth_m) && 0.0 < min_depth_m && min_depth_m < max_depth_m))
    throw Error("ferns: need 0 < min_depth_m < max_depth_m (finite), got " + std::to_string(min_depth_m) + ", " +
                std::to_string(max_depth_m));
}

FernsIndex::FernsIndex(const FernsOptions& options) : options_(options) {
  options_.validate();
  std::mt19937_64 rng(options_.seed);
  ferns_.resize(size_t(options_.ferns));
  for (Fern& f : ferns_) {
    f.x = std::min(options_.width - 1, int(uniform01(rng) * options_.width));
    f.y = std::min(options_.height - 1, int(uniform01(rng) * options_.height));
    for (float& t : f.tau_rgb) t = float(uniform01(rng) * 255.0);
    f.tau_depth_m = float(options_.min_depth_m + uniform01(rng) * (options_.max_depth_m - options_.min_depth_m));
  }
}

FernsIndex::Code FernsIndex::encode(const ColorImage& colour, const DepthImage& depth) const {
  const int w = options_.width, h = options_.height;
  const std::vector<float> rgb = downsample(colour, w, h, 3, [](const Rgb8& p, double* s) {
    s[0] += p.r;
    s[1] += p.g;
    s[2] += p.b;
    return true;
  });
  const std::vector<float> z = downsample(depth, w, h, 1, [](float d, double* s) {
    if (!(std::isfinite(d) && d > 0.0f)) return false;
    s[0] += d;
    return true;
  });
  Code code;
  code.has_colour = !colour.empty();
  code.bits.resize(ferns_.size());
  for (size_t k = 0; k < ferns_.size(); ++k) {
    const Fern& f = ferns_[k];
    const size_t c = size_t(f.y) * w + f.x;
    std::uint8_t b = 0;
    if (code.has_colour)
      for (int ch = 0; ch < 3; ++ch) b |= std::uint8_t(rgb[c * 3 + ch] >= f.tau_rgb[ch]) << ch;
    b |= std::uint8_t(z[c] >= f.tau_depth_m) << 3;  // no depth reads 0: below every threshold
    code.bits[k] = b;
  }
  return code;
}

void FernsIndex::add(size_t id, const ColorImage& colour, const DepthImage& depth) {
  codes_.push_back(encode(colour, depth));
  ids_.push_back(id);
}

std::vector<AppearanceMatch> FernsIndex::query(const ColorImage& colour, const DepthImage& depth, size_t k) const {
  const Code q = encode(colour, depth);
  const double inv_m = 1.0 / double(ferns_.size());
  std::vector<AppearanceMatch> all(ids_.size());
  for (size_t i = 0; i < ids_.size(); ++i) {
    const Code& c = codes_[i];
    const std::uint8_t mask = (q.has_colour && c.has_colour) ? 0x0f : 0x08;
    size_t differ = 0;
    for (size_t f = 0; f < q.bits.size(); ++f) differ += ((q.bits[f] ^ c.bits[f]) & mask) != 0;
    all[i] = {ids_[i], double(differ) * inv_m};
  }
  return best_matches(std::move(all), k);
}

size_t FernsIndex::bytes_per_keyframe() const {
  const size_t table = ferns_.size() * sizeof(Fern);
  return ferns_.size() + (ids_.empty() ? table : table / ids_.size());
}

}  // namespace hf::slam
