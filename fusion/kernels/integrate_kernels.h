// Per-voxel TSDF integration maths, shared by the C++ loop (fusion/integrate.cpp) and an OpenCL kernel
// (core/kernels/cl_compat.h subset: no templates, no references).
//
// Projective TSDF (KinectFusion, InfiniTAM): a voxel centre p in the camera frame projects to the nearest pixel u
// with measured depth d(u); its observed signed distance is eta = d(u) - p.z (positive in front of the surface).
// Voxels with eta < -mu lie behind the surface, hidden from the camera: they are not updated. Otherwise the
// truncated, normalised observation is tsdf = min(1, eta / mu) and the voxel takes the weighted running average
// of equations 57-58 of the registration report (shared/seeds 004, section 2.2):
//   D_{t+1} = (W_t D_t + w_{t+1} d_{t+1}) / (W_t + w_{t+1}),   W_{t+1} = min(W_t + w_{t+1}, W_max),
// where the cap W_max (not in eq. 58) keeps the model able to follow slow changes. Colour is averaged with the
// same weights, only for observations inside the truncation band (|eta| < mu), where the voxel is near the surface
// the colour pixel shows; free-space observations (tsdf = 1) carve the SDF but leave colour alone.
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

// The per-voxel step once the voxel's pixel is known: z is the voxel centre's depth in the camera frame, idx the
// pixel from hf_voxel_pixel (>= 0). Returns 1 when the voxel was updated, 0 when it was not observed.
HF_INLINE int hf_integrate_voxel_at(HF_GLOBAL hf_voxel* voxel, float z, int idx, HF_GLOBAL const float* depth,
                                    HF_GLOBAL const hf_uint8* rgb, float mu, float max_weight, float w) {
  float d = depth[idx];
  if (!(d > 0.0f) || !hf_isfinite(d)) return 0;
  float eta = d - z;
  if (eta < -mu) return 0;
  float tsdf = eta >= mu ? 1.0f : eta / mu;
  int colour_valid = 0;
  float r = 0.0f, g = 0.0f, b = 0.0f;
  if (rgb != 0 && eta < mu) {
    colour_valid = 1;
    r = (float)rgb[3 * idx];
    g = (float)rgb[3 * idx + 1];
    b = (float)rgb[3 * idx + 2];
  }
  *voxel = hf_tsdf_update(*voxel, tsdf, w, max_weight, colour_valid, r, g, b);
  return 1;
}

// The whole per-voxel step: p_cam is the voxel centre in the camera frame (metres), depth a width x height
// row-major image in metres (0 = no measurement), rgb the matching colour image as 3 bytes per pixel (or 0 for
// none). mu = truncation distance in metres. Returns 1 when the voxel was updated, 0 when it was not observed.
HF_INLINE int hf_integrate_voxel(HF_GLOBAL hf_voxel* voxel, hf_float4 p_cam, HF_GLOBAL const float* depth,
                                 HF_GLOBAL const hf_uint8* rgb, hf_intrinsics K, float mu, float max_weight,
                                 float w) {
  int idx = hf_voxel_pixel(p_cam.x, p_cam.y, p_cam.z, K);
  if (idx < 0) return 0;
  return hf_integrate_voxel_at(voxel, p_cam.z, idx, depth, rgb, mu, max_weight, w);
}

#endif
