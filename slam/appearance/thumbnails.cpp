#include "slam/appearance/thumbnails.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace hf::slam {
namespace {

// Per-cell sums of a per-pixel value over the pixels where it is valid.
struct CellAverage {
  std::vector<double> sum;
  std::vector<int> count;
  CellAverage(size_t cells) : sum(cells, 0.0), count(cells, 0) {}
};

template <class Image, class Value>
CellAverage block_average(const Image& image, const ThumbnailOptions& o, Value value) {
  CellAverage cells(size_t(o.width) * o.height);
  std::vector<size_t> cell_x(size_t(image.width()));
  for (int x = 0; x < image.width(); ++x) cell_x[size_t(x)] = size_t(long(x) * o.width / image.width());
  for (int y = 0; y < image.height(); ++y) {
    const size_t row = size_t(long(y) * o.height / image.height()) * size_t(o.width);
    for (int x = 0; x < image.width(); ++x) {
      double v = 0.0;
      if (!value(image(x, y), v)) continue;
      cells.sum[row + cell_x[size_t(x)]] += v;
      cells.count[row + cell_x[size_t(x)]] += 1;
    }
  }
  return cells;
}

// Writes the zero-mean, unit-norm (times `scale`) cell averages into out[0 .. cells); cells without samples take
// the mean. All zeros when nothing varies.
void normalise_into(const CellAverage& cells, double scale, float* out) {
  const size_t n = cells.sum.size();
  double mean = 0.0;
  size_t valid = 0;
  for (size_t c = 0; c < n; ++c) {
    if (cells.count[c] == 0) continue;
    mean += cells.sum[c] / cells.count[c];
    ++valid;
  }
  for (size_t c = 0; c < n; ++c) out[c] = 0.0f;
  if (valid == 0) return;
  mean /= double(valid);
  std::vector<double> centred(n, 0.0);
  double norm2 = 0.0;
  for (size_t c = 0; c < n; ++c) {
    if (cells.count[c] == 0) continue;
    centred[c] = cells.sum[c] / cells.count[c] - mean;
    norm2 += centred[c] * centred[c];
  }
  // Below this the part is constant up to rounding (a black frame, a flat wall at one depth): no information.
  if (!(norm2 > 1e-12 * double(valid))) return;
  const double k = scale / std::sqrt(norm2);
  for (size_t c = 0; c < n; ++c) out[c] = float(centred[c] * k);
}

}  // namespace

void ThumbnailOptions::validate() const {
  if (width < 1 || width > 256) throw Error("thumbnail width must be 1..256, got " + std::to_string(width));
  if (height < 1 || height > 256) throw Error("thumbnail height must be 1..256, got " + std::to_string(height));
  if (!std::isfinite(depth_weight) || depth_weight < 0.0)
    throw Error("thumbnail depth_weight must be finite and >= 0, got " + std::to_string(depth_weight));
}

size_t ThumbnailOptions::length() const { return size_t(width) * height * (depth_weight > 0.0 ? 2 : 1); }

std::vector<float> make_thumbnail(const ColorImage& colour, const DepthImage& depth, const ThumbnailOptions& o) {
  const size_t cells = size_t(o.width) * o.height;
  std::vector<float> out(o.length(), 0.0f);
  if (!colour.empty()) {
    const CellAverage luma = block_average(colour, o, [](const Rgb8& p, double& v) {
      v = (0.299 * p.r + 0.587 * p.g + 0.114 * p.b) / 255.0;
      return true;
    });
    normalise_into(luma, 1.0, out.data());
  }
  if (o.depth_weight > 0.0 && !depth.empty()) {
    const CellAverage d = block_average(depth, o, [](float z, double& v) {
      v = z;
      return std::isfinite(z) && z > 0.0f;
    });
    normalise_into(d, o.depth_weight, out.data() + cells);
  }
  return out;
}

double squared_distance(const float* a, const float* b, size_t n) {
  double s = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double d = double(a[i]) - double(b[i]);
    s += d * d;
  }
  return s;
}

}  // namespace hf::slam
