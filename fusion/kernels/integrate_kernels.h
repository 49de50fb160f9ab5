// Per-voxel TSDF integration maths, shared by the C++ loop (fusion/integrate.cpp) and an OpenCL kernel
// (core/kernels/cl_compat.h subset: no templates, no references).
//
// Projective TSDF (KinectFusion, InfiniTAM): a voxel centre p in the camera frame projects to the nearest pixel u
// with measured depth d(u); its observed signed distance is eta = d(u) - p.z (positive in front of the surface).
// Voxels with eta < -mu lie behind the surface, hidden from the camera: they are not updated. Otherwise the
// truncated, normalised observation is tsdf = min(1, eta / mu) (or, point-to-plane, the same with eta scaled to
// the distance from the surface's tangent plane, see hf_integrate_voxel_at) and the voxel takes the weighted
// running average of equations 57-58 of the registration report (shared/seeds 004, section 2.2):
//   D_{t+1} = (W_t D_t + w_{t+1} d_{t+1}) / (W_t + w_{t+1}),   W_{t+1} = min(W_t + w_{t+1}, W_max),
// where the cap W_max (not in eq. 58) keeps the model able to follow slow changes. Colour is averaged with the
// same weights, only for observations inside the truncation band (|eta| < mu), where the voxel is near the surface
// the colour pixel shows; free-space observations (tsdf = 1) carve the SDF but leave colour alone.
// Deintegration (hf_tsdf_downdate) takes a frame's observation back out of that average (fusion/deintegrate.h).
#ifndef HF_FUSION_KERNELS_INTEGRATE_KERNELS_H
#define HF_FUSION_KERNELS_INTEGRATE_KERNELS_H

#include "core/kernels/cl_compat.h"
#include "fusion/kernels/voxel.h"

// Equations 57-58 on one voxel with a normalised observation tsdf in [-1, 1] of weight w > 0. colour_valid = 0
// leaves the colour as it is. Quantisation: the stored SDF is rounded to 1/32767 of mu and the weight to 1/16,
// so the result differs from the float update by at most half a step each time.
HF_INLINE hf_voxel hf_tsdf_update(hf_voxel v, float tsdf, float w, float max_weight, int colour_valid, float r,
                                  float g, float b) {
  float W = hf_voxel_weight(v);
  float D = hf_voxel_sdf(v);
  float W_new = W + w;
  float inv = 1.0f / W_new;
  hf_voxel out = v;
  out.sdf = hf_quantise_sdf((D * W + tsdf * w) * inv);
  if (colour_valid) {
    // A voxel's first colour sample is taken as it is (its colour weight is 0 even if carving gave it weight).
    float Wc = (v.flags & HF_VOXEL_FLAG_COLOUR) ? W : 0.0f;
    float inv_c = 1.0f / (Wc + w);
    float rr = ((float)v.r * Wc + r * w) * inv_c + 0.5f;
    float gg = ((float)v.g * Wc + g * w) * inv_c + 0.5f;
    float bb = ((float)v.b * Wc + b * w) * inv_c + 0.5f;
    out.r = (hf_uint8)(rr > 255.0f ? 255.0f : rr);
    out.g = (hf_uint8)(gg > 255.0f ? 255.0f : gg);
    out.b = (hf_uint8)(bb > 255.0f ? 255.0f : bb);
    out.flags = (hf_uint8)(v.flags | HF_VOXEL_FLAG_COLOUR);
  }
  out.weight = hf_quantise_weight(W_new > max_weight ? max_weight : W_new);
  return out;
}

// Where the voxel centre (x, y, z) (camera frame, metres) projects: the row-major index of the nearest pixel, or
// -1 when it lies behind the camera or outside the image. Branch-free, so a loop over a block row vectorises.
HF_INLINE int hf_voxel_pixel(float x, float y, float z, hf_intrinsics K) {
  float inv_z = 1.0f / z;
  float px = K.fx * x * inv_z + K.cx + 0.5f;  // + 0.5 and floor: nearest pixel centre
  float py = K.fy * y * inv_z + K.cy + 0.5f;
  int inside = (z > 0.0f) & (px >= 0.0f) & (py >= 0.0f) & (px < (float)K.width) & (py < (float)K.height);
  return inside ? (int)py * K.width + (int)px : -1;
}

// The factor that turns a depth difference along pixel (u, v)'s viewing ray into the distance to the tangent plane
// of the surface the pixel sees (depth image in metres, row-major, K.width x K.height, 0 = none): |cos theta| times
// |(x/z, y/z, 1)|, theta the angle between the pixel's viewing ray and the surface normal there (1 for a
// fronto-parallel plane anywhere in the image; below 1 when the surface is seen obliquely). The normal is the cross
// product of the differences of the back-projected depth (eq. 3) along u and along v. A neighbour counts when its
// depth is valid and within max_jump_m of the pixel's; each direction takes the central difference when both
// neighbours count and the one-sided difference when only one does. The one-sided case matters: silhouette pixels,
// where the viewing ray grazes the surface, are exactly the ones whose projective distance is most wrong
// (fused-sphere normals measured 3.2x worse when they fell back to it). Returns 0 ("unknown": the caller falls back
// to the projective distance) on the image border, when the pixel has no valid depth, or when neither neighbour
// counts in one of the directions. Noise-free depth of a plane gives its exact factor; elsewhere the error is that
// of the finite differences (curvature over 1-2 pixels, sensor noise).
//
// hf_point_to_plane_factor_at is the arithmetic on values: the pixel's depth d, its neighbours' (left, right, up,
// down), the pixel's normalised ray (a, b) = ((u - cx) / fx, (v - cy) / fy) and 1 / fx, 1 / fy, without branches
// (the choices are selects; gcc 12 still does not vectorise the row loop: ~5.8 ms of one core per 640 x 480 frame).
// hf_point_to_plane_factor adds the border test and the loads; the two give the same bits.
HF_INLINE float hf_point_to_plane_factor_at(float d, float dl, float dr, float du, float dd, float a, float b,
                                            float inv_fx, float inv_fy, float max_jump_m) {
  // A neighbour counts when its depth is positive and within max_jump_m of the pixel's (NaN and inf fail).
  int l = (dl > 0.0f) & (hf_fabs(dl - d) <= max_jump_m);
  int r = (dr > 0.0f) & (hf_fabs(dr - d) <= max_jump_m);
  int t = (du > 0.0f) & (hf_fabs(du - d) <= max_jump_m);
  int o = (dd > 0.0f) & (hf_fabs(dd - d) <= max_jump_m);
  // The two ends of each difference: the neighbours where both count (central), else the pixel and the one that
  // does (one-sided). Back-projection is d (a, b, 1) (eq. 3); the neighbours' rays differ by 1 / fx or 1 / fy.
  float h0 = l ? dl : d, h1 = r ? dr : d;
  float a0 = l ? a - inv_fx : a, a1 = r ? a + inv_fx : a;
  float v0 = t ? du : d, v1 = o ? dd : d;
  float b0 = t ? b - inv_fy : b, b1 = o ? b + inv_fy : b;
  float ux = h1 * a1 - h0 * a0, uy = b * (h1 - h0), uz = h1 - h0;
  float vx = a * (v1 - v0), vy = v1 * b1 - v0 * b0, vz = v1 - v0;
  float nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  float nn = nx * nx + ny * ny + nz * nz;
  int ok = (d > 0.0f) & (l | r) & (t | o) & (nn > 0.0f);
  // |n . p| / (|n| d) = |n^ . (a, b, 1)|: cos theta times the length of the ray per unit depth, because eta is a
  // difference of depths (z), not of distances along the ray.
  float f = hf_fabs(nx * a + ny * b + nz) / hf_sqrt(ok ? nn : 1.0f);
  return ok ? f : 0.0f;
}

HF_INLINE float hf_point_to_plane_factor(HF_GLOBAL const float* depth, int u, int v, hf_intrinsics K,
                                         float max_jump_m) {
  if (u < 1 || v < 1 || u >= K.width - 1 || v >= K.height - 1) return 0.0f;
  int idx = v * K.width + u;
  float inv_fx = 1.0f / K.fx, inv_fy = 1.0f / K.fy;
  return hf_point_to_plane_factor_at(depth[idx], depth[idx - 1], depth[idx + 1], depth[idx - K.width],
                                     depth[idx + K.width], ((float)u - K.cx) * inv_fx, ((float)v - K.cy) * inv_fy,
                                     inv_fx, inv_fy, max_jump_m);
}

// What one frame observes at a voxel once the voxel's pixel is known (integrate's and deintegrate's shared
// selection): z is the voxel centre's depth in the camera frame, idx the pixel from hf_voxel_pixel (>= 0).
// incidence is 0 (projective TSDF) or the per-pixel map of hf_point_to_plane_factor; with it, the observed signed
// distance is the point-to-plane distance eta * factor (Bylow et al. 2013), or eta where the map holds 0 (unknown).
// Which voxels a frame updates and which get colour is still decided by the projective eta (the frame allocated
// [d - mu, d + mu] along its rays; a voxel more than mu behind the measured surface along the ray is hidden), so the
// truncation and the free space that is never allocated are unchanged; only the value changes (still truncated to
// [-1, 1] of mu). Returns 1 and fills *obs when the frame observes the voxel, 0 when it does not.
typedef struct {
  float tsdf;        // normalised truncated signed distance, [-1, 1]
  int colour_valid;  // 1 when the observation carries colour (rgb given and inside the band, eta < mu)
  float r, g, b;     // the colour pixel, 0 .. 255, when colour_valid
} hf_tsdf_observation;

// Depth-dependent truncation (IntegrateParams::truncation_depth_ref_m): the band of an observation at measured depth
// d is mu_d = mu * s(d) with s(d) = min(1, max(min_fraction, (d / ref)^2)), the Kinect's axial noise growing as d^2
// (Nguyen et al. 2012): near pixels, whose noise is a few millimetres, carve and average over a narrower band, so
// a near surface is not smeared over the whole mu. Values stay normalised by the volume's mu (what the raycast and
// the sdf tracker multiply by), so an observation's value lies in [-s, s]: a truncated value of s(d) still means
// "at least mu_d away", and trilinear samples mix views of different bands in the same unit. ref <= 0: s = 1.
HF_INLINE float hf_truncation_scale(float ref, float min_fraction, float d) {
  if (!(ref > 0.0f) || !(d > 0.0f)) return 1.0f;
  const float q = d / ref;
  const float s = q * q;
  return s >= 1.0f ? 1.0f : (s < min_fraction ? min_fraction : s);
}

// Observation weight by depth (IntegrateParams::weight_depth_ref_m): an observation at measured depth d counts
// w min(1, (ref / d)^2), floored at 1/8 (the weight is stored in 1/16 steps, so a far observation still moves it),
// the inverse of the axial noise's standard deviation beyond ref. ref <= 0: 1.
HF_INLINE float hf_weight_scale(float ref, float d) {
  if (!(ref > 0.0f) || !(d > 0.0f)) return 1.0f;
  const float q = ref / d;
  const float s = q * q;
  return s >= 1.0f ? 1.0f : (s < 0.125f ? 0.125f : s);
}

// hf_observe_voxel_at with a per-pixel truncation: mu_scale is 0 (every pixel's band is mu) or a map of
// hf_truncation_scale per pixel. Where the map holds s, the band is mu_d = s mu: a voxel more than mu_d behind the
// measurement is hidden, the value is clamped to [-mu_d, mu_d] and divided by mu (so it lies in [-s, s]), and
// colour comes only from inside the band. With mu_scale = 0 it is hf_observe_voxel_at, the same bits.
HF_INLINE int hf_observe_voxel_mu(float z, int idx, HF_GLOBAL const float* depth, HF_GLOBAL const float* incidence,
                                  HF_GLOBAL const float* mu_scale, HF_GLOBAL const hf_uint8* rgb, float mu,
                                  hf_tsdf_observation* obs) {
  float d = depth[idx];
  if (!(d > 0.0f) || !hf_isfinite(d)) return 0;
  float s = 1.0f;
  float band = mu;
  if (mu_scale != 0) {
    s = mu_scale[idx];
    band = mu * s;
  }
  float eta = d - z;
  if (eta < -band) return 0;
  float sdf = eta;
  if (incidence != 0) {
    float c = incidence[idx];
    if (c > 0.0f) sdf = eta * c;
  }
  // The factor reaches |(x/z, y/z, 1)| > 1 for off-axis rays meeting a surface head-on: clamp at -1 as well.
  obs->tsdf = sdf >= band ? s : (sdf <= -band ? -s : sdf / mu);
  obs->colour_valid = 0;
  obs->r = 0.0f;
  obs->g = 0.0f;
  obs->b = 0.0f;
  if (rgb != 0 && eta < band) {
    obs->colour_valid = 1;
    obs->r = (float)rgb[3 * idx];
    obs->g = (float)rgb[3 * idx + 1];
    obs->b = (float)rgb[3 * idx + 2];
  }
  return 1;
}

HF_INLINE int hf_observe_voxel_at(float z, int idx, HF_GLOBAL const float* depth, HF_GLOBAL const float* incidence,
                                  HF_GLOBAL const hf_uint8* rgb, float mu, hf_tsdf_observation* obs) {
  return hf_observe_voxel_mu(z, idx, depth, incidence, 0, rgb, mu, obs);
}

// The per-voxel step of integrate: the observation (hf_observe_voxel_at) averaged in by eqs. 57-58 with weight w.
// Returns 1 when the voxel was updated, 0 when it was not observed.
HF_INLINE int hf_integrate_voxel_at(HF_GLOBAL hf_voxel* voxel, float z, int idx, HF_GLOBAL const float* depth,
                                    HF_GLOBAL const float* incidence, HF_GLOBAL const hf_uint8* rgb, float mu,
                                    float max_weight, float w) {
  hf_tsdf_observation obs;
  if (!hf_observe_voxel_at(z, idx, depth, incidence, rgb, mu, &obs)) return 0;
  *voxel = hf_tsdf_update(*voxel, obs.tsdf, w, max_weight, obs.colour_valid, obs.r, obs.g, obs.b);
  return 1;
}

// The same with a per-pixel truncation map (hf_observe_voxel_mu) and a per-pixel factor of the observation weight
// w_scale (hf_weight_scale); both 0: hf_integrate_voxel_at, the same bits.
HF_INLINE int hf_integrate_voxel_mu(HF_GLOBAL hf_voxel* voxel, float z, int idx, HF_GLOBAL const float* depth,
                                    HF_GLOBAL const float* incidence, HF_GLOBAL const float* mu_scale,
                                    HF_GLOBAL const float* w_scale, HF_GLOBAL const hf_uint8* rgb, float mu,
                                    float max_weight, float w) {
  hf_tsdf_observation obs;
  if (!hf_observe_voxel_mu(z, idx, depth, incidence, mu_scale, rgb, mu, &obs)) return 0;
  if (w_scale != 0) w *= w_scale[idx];
  *voxel = hf_tsdf_update(*voxel, obs.tsdf, w, max_weight, obs.colour_valid, obs.r, obs.g, obs.b);
  return 1;
}

// Deintegration (BundleFusion, Dai et al. 2017): the running average of eqs. 57-58 inverted, taking an observation
// (tsdf, w, colour) that hf_tsdf_update added back out of the voxel v it is now part of:
//   W_t = W_{t+1} - w,   D_t = (W_{t+1} D_{t+1} - w d_{t+1}) / W_t,   colour likewise (when the observation had
// colour and the voxel holds some), and a voxel left with W_t <= 0 (as quantised) is reset to unobserved (all
// zero). An unobserved voxel (weight 0: nothing of the frame is left in it) is returned as it is.
// Exactness:
// - while the update did not reach the cap (W_t + w <= W_max), this is its inverse up to the quantisation: the
//   stored D_{t+1} is within half an sdf step of the exact average, so D_t is within (W_{t+1} / W_t) / 2 + 1/2
//   steps of the voxel's earlier value (at most 1.5 steps for w <= W_t, e.g. every observation of weight 1 but the
//   first); the weight is exact when W_t and w are multiples of 1/16;
// - once the cap clipped the update (W_{t+1} = W_max < W_t + w), W_t is unknown; this takes the stored weight as
//   if it were exact, which inverts the update that reached the cap (W_t = W_max - w), so
//   hf_tsdf_update(hf_tsdf_downdate(v)) = v up to the quantisation (unless that inverse leaves [-1, 1] and is
//   clamped), and a voxel at the cap whose previous value D_t was itself at the cap comes back as
//   D_t + w^2 (D_t - d) / (W_max^2 - w^2) (|.| <= 2 w^2 / (W_max^2 - w^2), 1.2e-4 of mu for W_max = 128 and w = 1)
//   with weight W_max - w instead of W_max (also where the update left it unchanged, e.g. saturated free space);
// - colour: integrate gives the first colour sample of a voxel the full weight and later ones the SDF weight W_t,
//   and the voxel does not store which frame gave its first colour. Taking the frame's colour out of a voxel whose
//   first colour it was leaves the colour (c W_{t+1} - c_obs w) / W_t clamped to [0, 255] (c_obs itself when only
//   carving observations came after it) rather than "no colour"; otherwise the colour is the inverse, within
//   (W_{t+1} / W_t) / 2 + 1/2 of a unit.
HF_INLINE hf_voxel hf_tsdf_downdate(hf_voxel v, float tsdf, float w, int colour_valid, float r, float g, float b) {
  if (v.weight == 0) return v;
  float W = hf_voxel_weight(v);
  float W_old = W - w;
  hf_uint16 weight_old = hf_quantise_weight(W_old);
  hf_voxel out = v;
  if (weight_old == 0) {
    out.sdf = 0;
    out.weight = 0;
    out.r = 0;
    out.g = 0;
    out.b = 0;
    out.flags = 0;
    return out;
  }
  float inv = 1.0f / W_old;
  out.sdf = hf_quantise_sdf((hf_voxel_sdf(v) * W - tsdf * w) * inv);
  if (colour_valid && (v.flags & HF_VOXEL_FLAG_COLOUR)) {
    float rr = ((float)v.r * W - r * w) * inv + 0.5f;
    float gg = ((float)v.g * W - g * w) * inv + 0.5f;
    float bb = ((float)v.b * W - b * w) * inv + 0.5f;
    out.r = (hf_uint8)(rr > 255.0f ? 255.0f : (rr < 0.0f ? 0.0f : rr));
    out.g = (hf_uint8)(gg > 255.0f ? 255.0f : (gg < 0.0f ? 0.0f : gg));
    out.b = (hf_uint8)(bb > 255.0f ? 255.0f : (bb < 0.0f ? 0.0f : bb));
  }
  out.weight = weight_old;
  return out;
}

// The per-voxel step of deintegrate: the same observation as hf_integrate_voxel_at taken back out
// (hf_tsdf_downdate). Returns 1 when the frame observes the voxel and the voxel held weight, else 0.
HF_INLINE int hf_deintegrate_voxel_at(HF_GLOBAL hf_voxel* voxel, float z, int idx, HF_GLOBAL const float* depth,
                                      HF_GLOBAL const float* incidence, HF_GLOBAL const hf_uint8* rgb, float mu,
                                      float w) {
  hf_tsdf_observation obs;
  if (voxel->weight == 0 || !hf_observe_voxel_at(z, idx, depth, incidence, rgb, mu, &obs)) return 0;
  *voxel = hf_tsdf_downdate(*voxel, obs.tsdf, w, obs.colour_valid, obs.r, obs.g, obs.b);
  return 1;
}

// The same with the per-pixel maps of hf_integrate_voxel_mu (both 0: hf_deintegrate_voxel_at).
HF_INLINE int hf_deintegrate_voxel_mu(HF_GLOBAL hf_voxel* voxel, float z, int idx, HF_GLOBAL const float* depth,
                                      HF_GLOBAL const float* incidence, HF_GLOBAL const float* mu_scale,
                                      HF_GLOBAL const float* w_scale, HF_GLOBAL const hf_uint8* rgb, float mu,
                                      float w) {
  hf_tsdf_observation obs;
  if (voxel->weight == 0 || !hf_observe_voxel_mu(z, idx, depth, incidence, mu_scale, rgb, mu, &obs)) return 0;
  if (w_scale != 0) w *= w_scale[idx];
  *voxel = hf_tsdf_downdate(*voxel, obs.tsdf, w, obs.colour_valid, obs.r, obs.g, obs.b);
  return 1;
}

// The whole per-voxel step: p_cam is the voxel centre in the camera frame (metres), depth a width x height
// row-major image in metres (0 = no measurement), incidence 0 or its hf_point_to_plane_factor map (see
// hf_integrate_voxel_at), rgb the matching colour image as 3 bytes per pixel (or 0 for none). mu = truncation
// distance in metres. Returns 1 when the voxel was updated, 0 when it was not observed.
HF_INLINE int hf_integrate_voxel(HF_GLOBAL hf_voxel* voxel, hf_float4 p_cam, HF_GLOBAL const float* depth,
                                 HF_GLOBAL const float* incidence, HF_GLOBAL const hf_uint8* rgb, hf_intrinsics K,
                                 float mu, float max_weight, float w) {
  int idx = hf_voxel_pixel(p_cam.x, p_cam.y, p_cam.z, K);
  if (idx < 0) return 0;
  return hf_integrate_voxel_at(voxel, p_cam.z, idx, depth, incidence, rgb, mu, max_weight, w);
}

// hf_integrate_voxel inverted (hf_deintegrate_voxel_at): the same arguments but the cap, which the inverse does not
// need. Returns 1 when the voxel held an observation of the frame that was taken out, 0 otherwise.
HF_INLINE int hf_deintegrate_voxel(HF_GLOBAL hf_voxel* voxel, hf_float4 p_cam, HF_GLOBAL const float* depth,
                                   HF_GLOBAL const float* incidence, HF_GLOBAL const hf_uint8* rgb, hf_intrinsics K,
                                   float mu, float w) {
  int idx = hf_voxel_pixel(p_cam.x, p_cam.y, p_cam.z, K);
  if (idx < 0) return 0;
  return hf_deintegrate_voxel_at(voxel, p_cam.z, idx, depth, incidence, rgb, mu, w);
}

#endif
