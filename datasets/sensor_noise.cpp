#include "datasets/sensor_noise.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"

namespace hf::datasets {
namespace {

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Random streams, so depth, colour and holes never share numbers.
constexpr std::uint64_t kStreamDepth = 1, kStreamColour = 2, kStreamHoles = 3;

double theta_term(double theta) {
  const double t = std::clamp(theta, 0.0, std::numbers::pi / 2 - 1e-3);
  return t / (std::numbers::pi / 2 - t);
}

std::uint32_t hash2(std::int32_t x, std::int32_t y, std::uint64_t seed) {
  std::uint64_t h = splitmix64(seed ^ (std::uint64_t(std::uint32_t(x)) << 32 | std::uint32_t(y)));
  return std::uint32_t(h >> 32);
}

double value_noise2(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = std::int32_t(fx), iy = std::int32_t(fy);
  auto s = [](double t) { return t * t * (3.0 - 2.0 * t); };
  const double ux = s(x - fx), uy = s(y - fy);
  auto v = [&](int dx, int dy) { return double(hash2(ix + dx, iy + dy, seed) >> 8) * (1.0 / 16777216.0); };
  const double a = v(0, 0) + (v(1, 0) - v(0, 0)) * ux;
  const double b = v(0, 1) + (v(1, 1) - v(0, 1)) * ux;
  return a + (b - a) * uy;
}

}  // namespace

Rng::Rng(std::uint64_t seed, std::uint64_t frame, std::uint64_t stream, std::uint64_t row)
    : engine_(splitmix64(splitmix64(splitmix64(splitmix64(seed) ^ frame) ^ stream) ^ row)) {}

double Rng::uniform() { return double(engine_() >> 11) * (1.0 / 9007199254740992.0); }

double inverse_normal_cdf(double p) {
  if (!(p > 0.0)) return -std::numeric_limits<double>::infinity();
  if (!(p < 1.0)) return std::numeric_limits<double>::infinity();
  // Acklam's rational approximation (relative error 1.15e-9) ...
  static constexpr double a[6] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                                  1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[5] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                                  6.680131188771972e+01,  -1.328068155288572e+01};
  static constexpr double c[6] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                                  -2.549671010060570e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[4] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                                  3.754408661907416e+00};
  constexpr double p_low = 0.02425;
  double x;
  if (p < p_low) {
    const double q = std::sqrt(-2.0 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  } else if (p <= 1.0 - p_low) {
    const double q = p - 0.5, r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  } else {
    const double q = std::sqrt(-2.0 * std::log1p(-p));
    x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  // ... refined by one Halley step on Phi(x) - p, which brings it to full double precision.
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
  const double u = e * std::sqrt(2.0 * std::numbers::pi) * std::exp(0.5 * x * x);
  return x - u / (1.0 + 0.5 * x * u);
}

namespace {

// Inverse-CDF table for Rng::normal(): q_k = Phi^-1((k + 0.5) / 2^16), k = 0 .. 2^16 - 1, plus q_{2^16} = q_{2^16-1}.
// Stored as float, so last-bit differences between maths libraries in building it do not reach the samples.
constexpr int kNormalTableBits = 16;
const std::vector<float>& normal_table() {
  static const std::vector<float> table = [] {
    const int n = 1 << kNormalTableBits;
    std::vector<float> t(size_t(n) + 1);
    for (int k = 0; k < n; ++k) t[size_t(k)] = float(inverse_normal_cdf((k + 0.5) / n));
    t[size_t(n)] = t[size_t(n) - 1];
    return t;
  }();
  return table;
}

// A 32-bit uniform integer to N(0, 1): the table's piecewise-linear inverse CDF (16 bits index, 16 bits fraction).
double normal_from_bits(std::uint32_t bits, const float* table) {
  const std::uint32_t k = bits >> 16;
  const double frac = double(bits & 0xFFFFu) * (1.0 / 65536.0);
  return double(table[k]) + (double(table[k + 1]) - double(table[k])) * frac;
}

}  // namespace

double Rng::normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  const float* table = normal_table().data();
  const std::uint64_t r = engine_();
  spare_ = normal_from_bits(std::uint32_t(r & 0xFFFFFFFFu), table);
  has_spare_ = true;
  return normal_from_bits(std::uint32_t(r >> 32), table);
}

NoiseOptions NoiseOptions::none() {
  NoiseOptions o;
  o.lateral = o.axial = o.quantisation = false;
  o.disparity_sigma = 0.0;
  o.min_range_m = 0.0;
  o.max_range_m = std::numeric_limits<double>::infinity();
  o.max_incidence_deg = 90.0;
  o.edge_dropout_probability = 0.0;
  o.hole_fraction = 0.0;
  o.colour_sigma = 0.0;
  return o;
}

bool NoiseOptions::depth_noise_enabled() const {
  return lateral || axial || quantisation || disparity_sigma > 0.0 || min_range_m > 0.0 ||
         std::isfinite(max_range_m) || max_incidence_deg < 90.0 || edge_dropout_probability > 0.0 ||
         hole_fraction > 0.0;
}

void NoiseOptions::validate() const {
  auto fail = [](const std::string& m) { throw Error("noise options: " + m); };
  if (!(disparity_sigma >= 0.0) || !std::isfinite(disparity_sigma)) fail("expected disparity_sigma >= 0");
  if (!(min_range_m >= 0.0)) fail("expected min_range_m >= 0");
  if (!(max_range_m > min_range_m)) fail("expected max_range_m > min_range_m");
  if (!(max_incidence_deg > 0.0 && max_incidence_deg <= 90.0)) fail("expected max_incidence_deg in (0, 90]");
  if (!(edge_dropout_probability >= 0.0 && edge_dropout_probability <= 1.0))
    fail("expected edge_dropout_probability in [0, 1]");
  if (!(edge_relative_jump > 0.0) || !std::isfinite(edge_relative_jump)) fail("expected edge_relative_jump > 0");
  if (!(hole_fraction >= 0.0 && hole_fraction <= 1.0)) fail("expected hole_fraction in [0, 1]");
  if (!(hole_blob_px > 0.0) || !std::isfinite(hole_blob_px)) fail("expected hole_blob_px > 0");
  if (!(colour_sigma >= 0.0) || !std::isfinite(colour_sigma)) fail("expected colour_sigma >= 0");
}

double axial_sigma_m(double z, double theta) {
  const double tt = theta_term(theta);
  return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4) + 0.0001 / std::sqrt(z) * tt * tt;
}

double lateral_sigma_px(double theta) { return 0.8 + 0.035 * theta_term(theta); }

double quantise_depth_m(double z) {
  if (!(z > 0.0)) return 0.0;
  const double d = std::round(kDisparityConstant / z);
  return d > 0.0 ? kDisparityConstant / d : 0.0;
}

double quantisation_step_m(double z) { return z * z / kDisparityConstant; }

Image<std::uint8_t> hole_mask(int width, int height, double fraction, double blob_px, std::uint64_t seed,
                              std::uint64_t frame) {
  Image<std::uint8_t> mask(width, height, 0);
  const size_t n = size_t(width) * height;
  const auto k = size_t(std::llround(std::clamp(fraction, 0.0, 1.0) * double(n)));
  if (k == 0 || n == 0) return mask;
  const std::uint64_t s = splitmix64(splitmix64(seed ^ kStreamHoles) ^ frame);
  const double scale = 1.0 / std::max(1.0, blob_px * width / 640.0);
  std::vector<std::pair<float, std::uint32_t>> v(n);
  tbb::parallel_for(0, height, [&](int y) {
    for (int x = 0; x < width; ++x) {
      const double f = 0.7 * value_noise2(x * scale, y * scale, s) +
                       0.3 * value_noise2(x * scale * 2.1 + 17.0, y * scale * 2.1 + 5.0, s + 1);
      const size_t i = size_t(y) * width + x;
      v[i] = {float(f), std::uint32_t(i)};
    }
  });
  // The k largest values (ties broken by index, so the mask is exactly k pixels and deterministic).
  auto greater = [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); };
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k - 1), v.end(), greater);
  for (size_t i = 0; i < k; ++i) mask.data()[v[i].second] = 1;
  return mask;
}

DepthImage apply_depth_noise(const DepthImage& clean, const Image<float>& incidence, const NoiseOptions& o,
                             std::uint64_t seed, std::uint64_t frame) {
  o.validate();
  const int W = clean.width(), H = clean.height();
  if (incidence.width() != W || incidence.height() != H)
    throw Error("apply_depth_noise: expected the incidence map to have the depth image's size");
  if (!o.depth_noise_enabled()) return clean;
  DepthImage out(W, H, 0.0f);
  const Image<std::uint8_t> holes =
      o.hole_fraction > 0.0 ? hole_mask(W, H, o.hole_fraction, o.hole_blob_px, seed, frame) : Image<std::uint8_t>();
  const double max_theta = o.max_incidence_deg * std::numbers::pi / 180.0;
  const double lateral_scale = W / 640.0;  // the model's pixels are those of a 640-wide Kinect image

  auto is_edge = [&](int x, int y) {
    const double z = clean(x, y);
    const double jump = o.edge_relative_jump * z;
    const int nx[4] = {x - 1, x + 1, x, x};
    const int ny[4] = {y, y, y - 1, y + 1};
    for (int k = 0; k < 4; ++k) {
      if (nx[k] < 0 || ny[k] < 0 || nx[k] >= W || ny[k] >= H) continue;
      const double zn = clean(nx[k], ny[k]);
      if (zn <= 0.0 || std::abs(zn - z) > jump) return true;
    }
    return false;
  };

  tbb::parallel_for(0, H, [&](int y) {
    Rng rng(seed, frame, kStreamDepth, std::uint64_t(y));
    for (int x = 0; x < W; ++x) {
      // A fixed set of draws per pixel, whatever is enabled (see the header).
      const double n_x = rng.normal(), n_y = rng.normal(), n_z = rng.normal(), n_d = rng.normal();
      const double u_edge = rng.uniform();
      int sx = x, sy = y;
      if (o.lateral && clean(x, y) > 0.0f) {
        const double sl = lateral_sigma_px(incidence(x, y)) * lateral_scale;
        sx = std::clamp(int(std::lround(x + sl * n_x)), 0, W - 1);
        sy = std::clamp(int(std::lround(y + sl * n_y)), 0, H - 1);
      }
      const double z0 = clean(sx, sy);
      if (!(z0 > 0.0)) continue;
      const double theta0 = incidence(sx, sy);
      if (z0 < o.min_range_m || z0 > o.max_range_m) continue;
      if (theta0 > max_theta) continue;
      if (o.edge_dropout_probability > 0.0 && u_edge < o.edge_dropout_probability && is_edge(sx, sy)) continue;
      if (!holes.empty() && holes(x, y)) continue;
      double z = z0;
      if (o.axial) z += axial_sigma_m(z0, theta0) * n_z;
      if (!(z > 0.0)) continue;
      if (o.quantisation || o.disparity_sigma > 0.0) {
        double d = kDisparityConstant / z + o.disparity_sigma * n_d;
        if (o.quantisation) d = std::round(d);
        if (!(d > 0.0)) continue;
        z = kDisparityConstant / d;
      }
      out(x, y) = float(z);
    }
  });
  return out;
}

ColorImage finish_colour(const ColorImageF& linear, double gain, double sigma, std::uint64_t seed,
                         std::uint64_t frame) {
  const int W = linear.width(), H = linear.height();
  ColorImage out(W, H);
  tbb::parallel_for(0, H, [&](int y) {
    Rng rng(seed, frame, kStreamColour, std::uint64_t(y));
    auto channel = [&](float c) {
      double v = 255.0 * gain * c;
      if (sigma > 0.0) v += sigma * rng.normal();
      return std::uint8_t(std::clamp(std::lround(v), 0L, 255L));
    };
    for (int x = 0; x < W; ++x) {
      const RgbF& c = linear(x, y);
      Rgb8& o = out(x, y);
      o.r = channel(c.r);
      o.g = channel(c.g);
      o.b = channel(c.b);
    }
  });
  return out;
}

}  // namespace hf::datasets
