// Per-sample and per-pixel maths of raycasting and meshing the TSDF, shared by the C++ loops (fusion/raycast.cpp,
// fusion/mesh.cpp) and OpenCL kernels (core/kernels/cl_compat.h subset: no templates, no references).
//
// Conventions: SDF values here are normalised (sdf_m / mu, in [-1, 1]), positive in free space. Continuous voxel
// coordinates put voxel centres at integers; a sample at fractional offset (fx, fy, fz) in [0, 1)^3 from voxel
// (i, j, k) interpolates the eight voxels (i..i+1, j..j+1, k..k+1), corner c = x + 2 y + 4 z as below.
#ifndef HF_FUSION_KERNELS_RAYCAST_KERNELS_H
#define HF_FUSION_KERNELS_RAYCAST_KERNELS_H

#include "core/kernels/cl_compat.h"
#include "core/kernels/image_kernels.h"

// Trilinear interpolation of eight corner values; cXYZ is the corner at offset (X, Y, Z).
HF_INLINE float hf_trilinear(float c000, float c100, float c010, float c110, float c001, float c101, float c011,
                             float c111, float fx, float fy, float fz) {
  float c00 = c000 + (c100 - c000) * fx;
  float c10 = c010 + (c110 - c010) * fx;
  float c01 = c001 + (c101 - c001) * fx;
  float c11 = c011 + (c111 - c011) * fx;
  float c0 = c00 + (c10 - c00) * fy;
  float c1 = c01 + (c11 - c01) * fy;
  return c0 + (c1 - c0) * fz;
}

// The zero crossing between two samples of opposite sign along a ray, by linear interpolation: the parameter t in
// [t0, t1] where the line through (t0, sdf0) and (t1, sdf1) is zero. Needs sdf0 != sdf1 (guaranteed by the signs).
HF_INLINE float hf_zero_crossing(float t0, float sdf0, float t1, float sdf1) {
  return t0 + (t1 - t0) * sdf0 / (sdf0 - sdf1);
}

// The refinement of a crossing on a + to - bracket (ta, sa >= 0) .. (tb, sb < 0) along a ray (raycast.cpp's
// refine, raycast.cl's hf_raycast_refine), from the estimate tc = hf_zero_crossing(ta, sa, tb, sb) and the sample
// sc there. Converged when the sample predicts the crossing within tol of tc: |sc| over the bracket's secant slope
// (sa - sb) / (tb - ta); regula falsi keeps one end, so the bracket itself may shrink slowly long after that.
HF_INLINE int hf_refine_converged(float sc, float ta, float sa, float tb, float sb, float tol) {
  return hf_fabs(sc) * (tb - ta) <= tol * (sa - sb);
}

// One Illinois regula falsi step: sc replaces the end of its sign, and an end kept twice in a row has its value
// halved, so the estimate closes in from both sides. *kept: +1 the + end stayed last time, -1 the - end, 0 none
// yet. Returns the next estimate.
HF_INLINE float hf_illinois_step(float tc, float sc, float* ta, float* sa, float* tb, float* sb, int* kept) {
  if (sc > 0.0f) {
    *ta = tc, *sa = sc;
    if (*kept == -1) *sb *= 0.5f;
    *kept = -1;
  } else {
    *tb = tc, *sb = sc;
    if (*kept == 1) *sa *= 0.5f;
    *kept = 1;
  }
  return hf_zero_crossing(*ta, *sa, *tb, *sb);
}

// The fine raycasting step in metres at a sample of normalised SDF sdf: a fraction of the distance to the surface
// the SDF promises (sdf * mu), never below min_step_m, so a step cannot jump over the zero crossing as long as
// step_fraction < 1 (the TSDF is a distance bound) and the ray always advances.
HF_INLINE float hf_raycast_step(float sdf, float mu, float step_fraction, float min_step_m) {
  float s = step_fraction * hf_fabs(sdf) * mu;
  return s > min_step_m ? s : min_step_m;
}

// Half-width in metres of the bracket [d - w, d + w] a ray searches first when the depth image just integrated from
// the same pose measured depth d there (RaycastOptions::depth_hint): w = mu + 2 voxels + 3 sigma_z(d), with
// sigma_z(d) = 0.0012 + 0.0019 (d - 0.4)^2 m the Kinect's axial noise at normal incidence (hf_kinect_axial_sigma_m,
// core/kernels/image_kernels.h). The fused zero crossing lies between d and the surface the earlier frames saw,
// i.e. within the noise of d; mu in front guarantees the bracket starts in the positive band (the frame has just
// written sdf = +1 there along this very ray), the 2 voxels cover the trilinear interpolation's reach across
// voxel centres and the projective distance's bias.
HF_INLINE float hf_raycast_hint_halfwidth(float d, float mu, float voxel) {
  return mu + 2.0f * voxel + 3.0f * hf_kinect_axial_sigma_m(d);
}

// The unit normal from the SDF gradient by central differences: (dx, dy, dz) = f(p + h e_i) - f(p - h e_i); the
// scale drops out. Invalid (w = 0) when the gradient vanishes.
HF_INLINE hf_float4 hf_normal_from_differences(float dx, float dy, float dz) {
  float n2 = dx * dx + dy * dy + dz * dz;
  if (!(n2 > 1e-20f)) return hf_invalid4();
  float inv = 1.0f / hf_sqrt(n2);
  return hf_make_float4(dx * inv, dy * inv, dz * inv, 1.0f);
}

// Intensity of a head-light Phong shading for people: the light sits at the camera, so with a unit normal n and
// a unit direction v from the surface point towards the camera, I = ambient + diffuse (n.v) + specular (n.v)^16
// (the half vector equals v for a head light), clamped to [0, 1]. Back-facing normals (n.v < 0) get ambient.
HF_INLINE float hf_headlight_shade(hf_float4 n, hf_float4 to_camera) {
  float c = hf_dot3(n, to_camera);
  if (c < 0.0f) c = 0.0f;
  float c2 = c * c, c4 = c2 * c2, c8 = c4 * c4;
  float i = 0.2f + 0.7f * c + 0.1f * c8 * c8;
  return i > 1.0f ? 1.0f : i;
}

#endif
