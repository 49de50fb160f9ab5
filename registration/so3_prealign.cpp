#include "registration/so3_prealign.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "core/se3.h"

namespace hf {
namespace {

// Bilinear sample of `img` at (x, y); false outside the last full 2x2 footprint.
bool so3_sample(const Image<float>& img, double x, double y, float* out) {
  if (!(x >= 0.0 && y >= 0.0 && x < img.width() - 1.0 && y < img.height() - 1.0)) return false;
  const int x0 = int(x), y0 = int(y);
  const float ax = float(x - x0), ay = float(y - y0);
  const float top = (1.0f - ax) * img(x0, y0) + ax * img(x0 + 1, y0);
  const float bottom = (1.0f - ax) * img(x0, y0 + 1) + ax * img(x0 + 1, y0 + 1);
  *out = (1.0f - ay) * top + ay * bottom;
  return true;
}

struct So3Rows {
  std::vector<double> r;
  std::vector<Eigen::Vector3d> J;
};

// The residuals and Jacobians of every current pixel at rotation R (brightness offset not yet removed).
So3Rows so3_rows(const FramePyramidLevel& cur, const FramePyramidLevel& ref, const Eigen::Matrix3d& R) {
  const PinholeCamera& c = cur.camera;
  So3Rows rows;
  rows.r.reserve(size_t(c.width) * size_t(c.height));
  rows.J.reserve(rows.r.capacity());
  for (int v = 0; v < c.height; ++v)
    for (int u = 0; u < c.width; ++u) {
      const Eigen::Vector3d q = R * Eigen::Vector3d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
      if (q.z() < 0.1) continue;
      const double iz = 1.0 / q.z();
      const double x = c.fx * q.x() * iz + c.cx, y = c.fy * q.y() * iz + c.cy;
      float iref, gx, gy;
      if (!so3_sample(ref.intensity, x, y, &iref) || !so3_sample(ref.grad_x, x, y, &gx) ||
          !so3_sample(ref.grad_y, x, y, &gy))
        continue;
      // d pi / d q (2x3) applied to the gradient: a row vector, then times -[q]x.
      const Eigen::Vector3d gq(gx * c.fx * iz, gy * c.fy * iz, -(gx * c.fx * q.x() + gy * c.fy * q.y()) * iz * iz);
      rows.J.push_back(-gq.cross(q));  // gq^T (-[q]x w) = -gq . (q x w) = w . -(gq x q)
      rows.r.push_back(double(iref) - double(cur.intensity(u, v)));
    }
  return rows;
}

double so3_median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + long(m), v.end());
  return v[m];
}

struct So3Cost {
  double offset = 0.0, sigma = 0.0, cost = 0.0;
};

double so3_huber_cost(double e, double k) { return std::abs(e) <= k ? 0.5 * e * e : k * (std::abs(e) - 0.5 * k); }

So3Cost so3_cost(const So3Rows& rows, double sigma_fixed) {
  So3Cost c;
  if (rows.r.empty()) return c;
  c.offset = so3_median(rows.r);
  std::vector<double> a(rows.r.size());
  for (size_t i = 0; i < a.size(); ++i) a[i] = std::abs(rows.r[i] - c.offset);
  c.sigma = sigma_fixed > 0.0 ? sigma_fixed : std::max(1.4826 * so3_median(a), 1e-3);
  const double k = 1.345 * c.sigma;
  for (double e : a) c.cost += so3_huber_cost(e, k);
  c.cost /= double(a.size());
  return c;
}

}  // namespace

So3PrealignResult so3_prealign(const FramePyramid& current, const FramePyramid& reference,
                               const Eigen::Matrix3d& R_initial, const std::vector<int>& iterations,
                               int levels_used) {
  So3PrealignResult out;
  out.R_ref_cur = R_initial;
  const int levels = std::min({levels_used, current.num_levels(), reference.num_levels()});
  if (levels < 1 || iterations.empty() || !current.has_intensity() || !reference.has_intensity()) return out;
  const int coarsest = levels - 1, finest = std::max(0, levels - int(iterations.size()));
  Eigen::Matrix3d R = R_initial;
  for (int l = coarsest; l >= finest; --l) {
    const FramePyramidLevel& cur = current.levels[size_t(l)];
    const FramePyramidLevel& ref = reference.levels[size_t(l)];
    if (cur.grad_x.empty() || ref.grad_x.empty() || cur.intensity.size() != ref.intensity.size()) return out;
    for (int it = 0; it < iterations[size_t(coarsest - l)]; ++it) {
      const So3Rows rows = so3_rows(cur, ref, R);
      if (rows.r.size() < 64) return out;
      const So3Cost cost = so3_cost(rows, 0.0);
      const double k = 1.345 * cost.sigma;
      Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      for (size_t i = 0; i < rows.r.size(); ++i) {
        const double e = rows.r[i] - cost.offset;
        const double w = std::abs(e) <= k ? 1.0 : k / std::abs(e);
        H.noalias() += w * rows.J[i] * rows.J[i].transpose();
        g.noalias() += w * e * rows.J[i];
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(H);
      // A rotation the image does not constrain (a blank wall) is left alone: the dense solve owns it.
      if (eig.info() != Eigen::Success || !(eig.eigenvalues()(0) > 1e-6 * eig.eigenvalues()(2))) return out;
      const Eigen::Vector3d w = -H.ldlt().solve(g);
      if (!w.allFinite()) return out;
      R = so3_exp(w) * R;
      if (w.norm() < 1e-5) break;
    }
  }
  // Accept only a rotation that explains the finest level used better than the initial one, at the initial
  // rotation's robust scale (the same yardstick for both).
  const FramePyramidLevel& cur = current.levels[size_t(finest)];
  const FramePyramidLevel& ref = reference.levels[size_t(finest)];
  const So3Rows before = so3_rows(cur, ref, R_initial), after = so3_rows(cur, ref, R);
  if (before.r.size() < 64 || after.r.size() < 64 || !R.allFinite()) return out;
  const So3Cost cb = so3_cost(before, 0.0);
  const So3Cost ca = so3_cost(after, cb.sigma);
  out.cost_before = cb.cost;
  out.cost_after = ca.cost;
  out.pixels = long(after.r.size());
  if (ca.cost < cb.cost) {
    out.R_ref_cur = R;
    out.accepted = true;
  }
  return out;
}

}  // namespace hf
