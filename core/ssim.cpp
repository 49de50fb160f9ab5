#include "core/ssim.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/parallel.h"

namespace hf {

const char* to_string(SsimStatus status) {
  switch (status) {
    case SsimStatus::ok: return "ok";
    case SsimStatus::size_mismatch: return "size_mismatch";
    case SsimStatus::too_small: return "too_small";
    case SsimStatus::non_finite: return "non_finite";
  }
  return "unknown";
}

namespace {

// The 1-D factor of the window's separable Gaussian, normalised so the 2-D weights sum to 1.
std::vector<double> gaussian_taps(int window, double sigma) {
  std::vector<double> w(static_cast<size_t>(window));
  const int r = window / 2;
  double sum = 0.0;
  for (int i = 0; i < window; ++i) {
    const double d = i - r;
    w[size_t(i)] = std::exp(-d * d / (2.0 * sigma * sigma));
    sum += w[size_t(i)];
  }
  for (double& v : w) v /= sum;
  return w;
}

// The five local moments E[x], E[y], E[x^2], E[y^2], E[xy] at every 'valid' window position, filtered first
// along rows, then along columns.
struct Moments {
  int width = 0, height = 0;
  std::vector<double> mx, my, mxx, myy, mxy;
};

Moments local_moments(const Image<float>& x, const Image<float>& y, const std::vector<double>& taps) {
  const int n = int(taps.size());
  const int W = x.width(), H = x.height();
  const int ow = W - n + 1, oh = H - n + 1;
  // Row pass: (ow x H) images of the five products.
  std::vector<double> rx(size_t(ow) * H), ry(rx.size()), rxx(rx.size()), ryy(rx.size()), rxy(rx.size());
  parallel_for_rows(H, [&](int row) {
    for (int c = 0; c < ow; ++c) {
      double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
      for (int k = 0; k < n; ++k) {
        const double a = x(c + k, row), b = y(c + k, row), w = taps[size_t(k)];
        sx += w * a;
        sy += w * b;
        sxx += w * a * a;
        syy += w * b * b;
        sxy += w * a * b;
      }
      const size_t i = size_t(row) * ow + c;
      rx[i] = sx, ry[i] = sy, rxx[i] = sxx, ryy[i] = syy, rxy[i] = sxy;
    }
  });
  Moments m;
  m.width = ow;
  m.height = oh;
  const size_t N = size_t(ow) * oh;
  m.mx.resize(N), m.my.resize(N), m.mxx.resize(N), m.myy.resize(N), m.mxy.resize(N);
  parallel_for_rows(oh, [&](int row) {
    for (int c = 0; c < ow; ++c) {
      double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
      for (int k = 0; k < n; ++k) {
        const size_t i = size_t(row + k) * ow + c;
        const double w = taps[size_t(k)];
        sx += w * rx[i];
        sy += w * ry[i];
        sxx += w * rxx[i];
        syy += w * ryy[i];
        sxy += w * rxy[i];
      }
      const size_t o = size_t(row) * ow + c;
      m.mx[o] = sx, m.my[o] = sy, m.mxx[o] = sxx, m.myy[o] = syy, m.mxy[o] = sxy;
    }
  });
  return m;
}

bool all_finite(const Image<float>& img) {
  for (float v : img.pixels())
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

SsimResult ssim(const Image<float>& x, const Image<float>& y, const SsimOptions& options, Image<float>* map) {
  SsimResult result;
  if (x.width() != y.width() || x.height() != y.height()) {
    result.status = SsimStatus::size_mismatch;
    return result;
  }
  const int n = options.window_px;
  if (n < 1 || n % 2 == 0 || x.width() < n || x.height() < n) {
    result.status = SsimStatus::too_small;
    return result;
  }
  if (!all_finite(x) || !all_finite(y)) {
    result.status = SsimStatus::non_finite;
    return result;
  }
  const Moments m = local_moments(x, y, gaussian_taps(n, options.sigma_px));
  const double C1 = std::pow(options.k1 * options.dynamic_range, 2.0);
  const double C2 = std::pow(options.k2 * options.dynamic_range, 2.0);
  if (map) *map = Image<float>(m.width, m.height);
  double sum = 0.0;
  for (size_t i = 0; i < m.mx.size(); ++i) {
    const double mx = m.mx[i], my = m.my[i];
    // Variances clamp at 0: E[x^2] - E[x]^2 of a flat window can round to a tiny negative number.
    const double vx = std::max(0.0, m.mxx[i] - mx * mx), vy = std::max(0.0, m.myy[i] - my * my);
    const double cxy = m.mxy[i] - mx * my;
    const double s = (2.0 * mx * my + C1) * (2.0 * cxy + C2) / ((mx * mx + my * my + C1) * (vx + vy + C2));
    if (map) map->pixels()[i] = float(s);
    sum += s;
  }
  result.windows = long(m.mx.size());
  result.mssim = sum / double(result.windows);
  return result;
}

SsimResult ssim(const ColorImage& x, const ColorImage& y, const SsimOptions& options, Image<float>* map) {
  if (x.width() != y.width() || x.height() != y.height()) return SsimResult{SsimStatus::size_mismatch, 0.0, 0};
  return ssim(intensity_from_color(x), intensity_from_color(y), options, map);
}

}  // namespace hf
