// Per-pixel image maths shared by the C++ loops (core/pyramid.cpp, core/filters.cpp, core/normals.cpp) and the
// OpenCL kernels. Written in the subset of core/kernels/cl_compat.h: each function computes ONE output pixel
// from a row-major input image given as a pointer plus width/height, so a C++ loop over rows and an OpenCL
// NDRange over pixels produce bit-compatible results (up to the device's exp/sqrt accuracy).
//
// Conventions:
// - Depth is metres, a pixel is valid when it is finite and > 0; invalid outputs are written as 0 (never NaN).
// - Vertex/normal maps are hf_float4 with w = 1 valid, w = 0 invalid.
// - Pyramid geometry: pixel (x, y) of level l+1 covers pixels {2x, 2x+1} x {2y, 2y+1} of level l, i.e. its
//   centre is at (2x + 0.5, 2y + 0.5) in level-l pixels. This is the convention of hf::PinholeCamera::scaled()
//   (c_{l+1} = (c_l + 0.5) / 2 - 0.5), so back-projecting a level-(l+1) pixel with the scaled camera hits the
//   same ray as the level-l point it was averaged around.
#ifndef HF_CORE_KERNELS_IMAGE_KERNELS_H
#define HF_CORE_KERNELS_IMAGE_KERNELS_H

#include "core/kernels/cl_compat.h"

HF_INLINE int hf_clampi(int v, int lo, int hi) { return v < lo ? lo : (v > hi ? hi : v); }
HF_INLINE int hf_mini(int a, int b) { return a < b ? a : b; }
HF_INLINE int hf_maxi(int a, int b) { return a > b ? a : b; }

// A depth sample is a measurement when it is finite and positive (0 = "no measurement"; NaN, inf and negative
// values from foreign loaders are treated the same way).
HF_INLINE int hf_depth_is_valid(float d) { return hf_isfinite(d) && d > 0.0f; }

// The Kinect's axial depth noise at normal incidence, sigma_z(z) = 0.0012 + 0.0019 (z - 0.4)^2 metres (Nguyen, Izadi
// and Lovell 2012), the one noise model tolerances on measured depth derive from (the raycast's depth-hint
// bracket, the pipeline's depth-consistency test). datasets/sensor_noise.h simulates the full model, with its
// incidence-angle term.
HF_INLINE float hf_kinect_axial_sigma_m(float z) {
  float e = z - 0.4f;
  return 0.0012f + 0.0019f * e * e;
}

// Weights of the 6-tap binomial [1 5 10 10 5 1] / 32 at offsets -2..3 from 2x. It is the 5-tap binomial
// [1 4 6 4 1] / 16 blur followed by the 2x2 block average that the pyramid geometry above asks for
// ([1 4 6 4 1] * [1 1] = [1 5 10 10 5 1]), so the decimated sample sits at 2x + 0.5, not at 2x as in
// OpenCV's pyrDown. It is symmetric about 2x + 0.5, so linear ramps are reproduced exactly.
HF_INLINE float hf_pyramid_tap_weight(int i) {
  return (i == 0 || i == 5) ? (1.0f / 32.0f) : ((i == 1 || i == 4) ? (5.0f / 32.0f) : (10.0f / 32.0f));
}

// Gaussian pyramid, one output pixel (x, y) of the half-size image: the 6x6 separable binomial above over
// source pixels 2x-2..2x+3, 2y-2..2y+3 with indices clamped to the image (border replication).
HF_INLINE float hf_pyrdown_gaussian_pixel(const HF_GLOBAL float* src, int src_width, int src_height, int x, int y) {
  float sum = 0.0f;
  for (int j = 0; j < 6; ++j) {
    const int sy = hf_clampi(2 * y - 2 + j, 0, src_height - 1);
    float row = 0.0f;
    for (int i = 0; i < 6; ++i) {
      const int sx = hf_clampi(2 * x - 2 + i, 0, src_width - 1);
      row += hf_pyramid_tap_weight(i) * src[sy * src_width + sx];
    }
    sum += hf_pyramid_tap_weight(j) * row;
  }
  return sum;
}

// Depth-aware pyramid (KinectFusion, section 3.2: "averaging only depth values within 3 sigma_r of the central
// pixel"), one output pixel. With the 2x2-block geometry there is no single central pixel, so the reference
// ("centre") depth is the mean of those valid depths of the block {2x,2x+1} x {2y,2y+1} that lie within
// max_diff_m of the block's lower median: a block needs at least one valid pixel, one outlier among four cannot
// become the reference, and a block split 2:2 by an edge takes the nearer surface. The output is the binomial-weighted mean (weights as in the Gaussian pyramid)
// of the valid samples of the 6x6 window whose depth is within max_diff_m (= 3 sigma_r) of the reference, so
// foreground and background are never averaged together. Returns 0 when the whole block is invalid.
HF_INLINE float hf_pyrdown_depth_pixel(const HF_GLOBAL float* src, int src_width, int src_height, int x, int y,
                                       float max_diff_m) {
  float b0 = 0.0f, b1 = 0.0f, b2 = 0.0f, b3 = 0.0f;
  int n = 0;
  for (int dy = 0; dy < 2; ++dy) {
    for (int dx = 0; dx < 2; ++dx) {
      const int sx = hf_clampi(2 * x + dx, 0, src_width - 1);
      const int sy = hf_clampi(2 * y + dy, 0, src_height - 1);
      const float d = src[sy * src_width + sx];
      if (!hf_depth_is_valid(d)) continue;
      // Insertion into the sorted prefix b0 <= b1 <= b2 <= b3 (no arrays of variable index: cheap on GPUs).
      if (n == 0) {
        b0 = d;
      } else if (n == 1) {
        if (d < b0) { b1 = b0; b0 = d; } else { b1 = d; }
      } else if (n == 2) {
        if (d < b0) { b2 = b1; b1 = b0; b0 = d; } else if (d < b1) { b2 = b1; b1 = d; } else { b2 = d; }
      } else {
        if (d < b0) { b3 = b2; b2 = b1; b1 = b0; b0 = d; }
        else if (d < b1) { b3 = b2; b2 = b1; b1 = d; }
        else if (d < b2) { b3 = b2; b2 = d; }
        else { b3 = d; }
      }
      ++n;
    }
  }
  if (n == 0) return 0.0f;
  // Lower median (index (n - 1) / 2 of the sorted valid depths) picks the surface; the reference is then the
  // mean of the block samples on that surface, i.e. the depth at the block centre (2x + 0.5, 2y + 0.5). A
  // reference at a corner pixel would make the 3 sigma_r acceptance window asymmetric on steep surfaces and bias
  // the coarse levels by a sizeable fraction of the depth step between pixels.
  const float median = (n <= 2) ? b0 : b1;
  float ref_sum = 0.0f;
  int ref_n = 0;
  if (hf_fabs(b0 - median) <= max_diff_m) { ref_sum += b0; ++ref_n; }
  if (n > 1 && hf_fabs(b1 - median) <= max_diff_m) { ref_sum += b1; ++ref_n; }
  if (n > 2 && hf_fabs(b2 - median) <= max_diff_m) { ref_sum += b2; ++ref_n; }
  if (n > 3 && hf_fabs(b3 - median) <= max_diff_m) { ref_sum += b3; ++ref_n; }
  const float ref = ref_sum / (float)ref_n;  // ref_n >= 1: the median itself
  float sum = 0.0f, wsum = 0.0f;
  for (int j = 0; j < 6; ++j) {
    const int sy = hf_clampi(2 * y - 2 + j, 0, src_height - 1);
    for (int i = 0; i < 6; ++i) {
      const int sx = hf_clampi(2 * x - 2 + i, 0, src_width - 1);
      const float d = src[sy * src_width + sx];
      if (!hf_depth_is_valid(d) || hf_fabs(d - ref) > max_diff_m) continue;
      const float w = hf_pyramid_tap_weight(i) * hf_pyramid_tap_weight(j);
      sum += w * d;
      wsum += w;
    }
  }
  if (!(wsum > 0.0f)) return median;  // unreachable in exact arithmetic: the median is within range of ref
  return sum / wsum;
}

// Bilateral depth filter (KinectFusion eq. 2): D(u) = 1/W sum_q N_s(|u - q|) N_r(|R(u) - R(q)|) R(q) over the
// (2 radius + 1)^2 window clipped to the image, N_s(t) = exp(-t^2 / (2 sigma_s^2)), N_r likewise with sigma_r.
// Invalid centres stay invalid (0) and invalid neighbours carry no weight. The caller passes
// inv_two_sigma_s2 = 1 / (2 sigma_s^2) [1/px^2] and inv_two_sigma_r2 = 1 / (2 sigma_r^2) [1/m^2].
HF_INLINE float hf_bilateral_depth_pixel(const HF_GLOBAL float* src, int width, int height, int x, int y,
                                         int radius_px, float inv_two_sigma_s2, float inv_two_sigma_r2) {
  const float d0 = src[y * width + x];
  if (!hf_depth_is_valid(d0)) return 0.0f;
  const int x0 = hf_maxi(x - radius_px, 0), x1 = hf_mini(x + radius_px, width - 1);
  const int y0 = hf_maxi(y - radius_px, 0), y1 = hf_mini(y + radius_px, height - 1);
  float sum = 0.0f, wsum = 0.0f;
  for (int yy = y0; yy <= y1; ++yy) {
    const float dy = (float)(yy - y);
    for (int xx = x0; xx <= x1; ++xx) {
      const float d = src[yy * width + xx];
      if (!hf_depth_is_valid(d)) continue;
      const float dx = (float)(xx - x);
      const float dd = d - d0;
      // One exp per tap: N_s * N_r = exp(-(spatial + range)).
      const float w = hf_exp(-(dx * dx + dy * dy) * inv_two_sigma_s2 - dd * dd * inv_two_sigma_r2);
      sum += w * d;
      wsum += w;
    }
  }
  return sum / wsum;  // wsum >= 1: the centre tap has weight exp(0)
}

// A model vertex's depth for the model pyramid (build_model_pyramid): z where the vertex is valid, finite and in
// front of the camera, else 0 (no measurement).
HF_INLINE float hf_model_depth_pixel(hf_float4 v) { return (v.w != 0.0f && hf_depth_is_valid(v.z)) ? v.z : 0.0f; }

// Vertex map (KinectFusion eq. 3 / report eq. 3): the camera-frame point of pixel (x, y), or invalid.
HF_INLINE hf_float4 hf_vertex_pixel(const HF_GLOBAL float* depth, hf_intrinsics K, int x, int y) {
  const float d = depth[y * K.width + x];
  if (!hf_depth_is_valid(d)) return hf_invalid4();
  return hf_backproject(K, (float)x, (float)y, d);
}

// Whether neighbour vertex n can be used for a tangent at centre c: valid and not across a depth
// discontinuity, i.e. |n.z - c.z| <= max_depth_jump_ratio * c.z.
HF_INLINE int hf_normal_neighbour_usable(hf_float4 c, hf_float4 n, float max_depth_jump_ratio) {
  return hf_is_valid4(n) && hf_fabs(n.z - c.z) <= max_depth_jump_ratio * c.z;
}

// Tangent along one image axis from the left/previous (a) and right/next (b) neighbours of c: the central
// difference b - a when both are usable, else the one-sided difference, else w = 0 (undefined).
HF_INLINE hf_float4 hf_normal_tangent(hf_float4 c, hf_float4 a, hf_float4 b, float max_depth_jump_ratio) {
  const int use_a = hf_normal_neighbour_usable(c, a, max_depth_jump_ratio);
  const int use_b = hf_normal_neighbour_usable(c, b, max_depth_jump_ratio);
  hf_float4 t;
  if (use_a && use_b) {
    t = hf_sub3(b, a);
  } else if (use_b) {
    t = hf_sub3(b, c);
  } else if (use_a) {
    t = hf_sub3(c, a);
  } else {
    return hf_invalid4();
  }
  t.w = 1.0f;
  return t;
}

// Normal map pixel: the unit normal of the surface through vertex (x, y) from the cross product of the
// horizontal and vertical tangents (central differences, one-sided next to holes and depth discontinuities),
// oriented towards the camera (n . v < 0). Invalid (w = 0) when the vertex is invalid, when either axis has no
// usable neighbour, or when the tangents are (numerically) parallel.
HF_INLINE hf_float4 hf_normal_pixel(const HF_GLOBAL hf_float4* vmap, int width, int height, int x, int y,
                                    float max_depth_jump_ratio) {
  const hf_float4 c = vmap[y * width + x];
  if (!hf_is_valid4(c)) return hf_invalid4();
  const hf_float4 l = x > 0 ? vmap[y * width + x - 1] : hf_invalid4();
  const hf_float4 r = x < width - 1 ? vmap[y * width + x + 1] : hf_invalid4();
  const hf_float4 u = y > 0 ? vmap[(y - 1) * width + x] : hf_invalid4();
  const hf_float4 d = y < height - 1 ? vmap[(y + 1) * width + x] : hf_invalid4();
  const hf_float4 tx = hf_normal_tangent(c, l, r, max_depth_jump_ratio);
  const hf_float4 ty = hf_normal_tangent(c, u, d, max_depth_jump_ratio);
  if (!hf_is_valid4(tx) || !hf_is_valid4(ty)) return hf_invalid4();
  hf_float4 n = hf_cross3(tx, ty);
  const float len = hf_norm3(n);
  // |tx x ty| = |tx| |ty| sin(angle): reject near-parallel tangents (and zero-length ones).
  if (!(len > 1e-6f * hf_norm3(tx) * hf_norm3(ty))) return hf_invalid4();
  n = hf_scale3(n, (hf_dot3(n, c) > 0.0f ? -1.0f : 1.0f) / len);
  n.w = 1.0f;
  return n;
}

// Image gradient in intensity units per pixel: a Sobel operator normalised by 1/8, i.e. a [1 2 1]/4 smoothing
// across the axis and a central difference (I(x+1) - I(x-1)) / 2 along it. At the image border the difference
// becomes one-sided with its true span and the smoothing clamps, so the gradient of any linear ramp
// a x + b y + c is exactly (a, b) everywhere. A 1-pixel-wide axis has gradient 0.
HF_INLINE void hf_gradient_pixel(const HF_GLOBAL float* img, int width, int height, int x, int y, float* gx,
                                 float* gy) {
  const int xl = hf_maxi(x - 1, 0), xr = hf_mini(x + 1, width - 1);
  const int yu = hf_maxi(y - 1, 0), yd = hf_mini(y + 1, height - 1);
  const float sl = 0.25f * (img[yu * width + xl] + 2.0f * img[y * width + xl] + img[yd * width + xl]);
  const float sr = 0.25f * (img[yu * width + xr] + 2.0f * img[y * width + xr] + img[yd * width + xr]);
  const float su = 0.25f * (img[yu * width + xl] + 2.0f * img[yu * width + x] + img[yu * width + xr]);
  const float sd = 0.25f * (img[yd * width + xl] + 2.0f * img[yd * width + x] + img[yd * width + xr]);
  *gx = xr > xl ? (sr - sl) / (float)(xr - xl) : 0.0f;
  *gy = yd > yu ? (sd - su) / (float)(yd - yu) : 0.0f;
}

// Bilinear interpolation of a float image at (x, y) (pixel centres at integers). Returns 0 when (x, y) lies
// outside [0, width-1] x [0, height-1] or is NaN; when require_valid_depth is non-zero, also returns 0 when a
// tap with non-zero weight is not a valid depth (so holes never bleed into the result). On success writes
// *value and returns 1.
HF_INLINE int hf_sample_bilinear(const HF_GLOBAL float* img, int width, int height, float x, float y,
                                 int require_valid_depth, float* value) {
  if (!(x >= 0.0f && y >= 0.0f && x <= (float)(width - 1) && y <= (float)(height - 1))) return 0;
  const int x0 = hf_clampi((int)hf_floor(x), 0, hf_maxi(width - 2, 0));
  const int y0 = hf_clampi((int)hf_floor(y), 0, hf_maxi(height - 2, 0));
  const int x1 = hf_mini(x0 + 1, width - 1), y1 = hf_mini(y0 + 1, height - 1);
  const float ax = x - (float)x0, ay = y - (float)y0;
  const float w00 = (1.0f - ax) * (1.0f - ay), w10 = ax * (1.0f - ay);
  const float w01 = (1.0f - ax) * ay, w11 = ax * ay;
  const float v00 = img[y0 * width + x0], v10 = img[y0 * width + x1];
  const float v01 = img[y1 * width + x0], v11 = img[y1 * width + x1];
  if (require_valid_depth) {
    if ((w00 > 0.0f && !hf_depth_is_valid(v00)) || (w10 > 0.0f && !hf_depth_is_valid(v10)) ||
        (w01 > 0.0f && !hf_depth_is_valid(v01)) || (w11 > 0.0f && !hf_depth_is_valid(v11))) {
      return 0;
    }
  }
  // Zero-weight taps are skipped so an invalid (possibly NaN) neighbour cannot poison the sum.
  float v = 0.0f;
  if (w00 > 0.0f) v += w00 * v00;
  if (w10 > 0.0f) v += w10 * v10;
  if (w01 > 0.0f) v += w01 * v01;
  if (w11 > 0.0f) v += w11 * v11;
  *value = v;
  return 1;
}

#endif
