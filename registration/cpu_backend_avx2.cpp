// Eight pixels per step: registration/kernels/icp_kernel.h and photometric_kernel.h in AVX2 lanes.
//
// Why a second spelling of the kernels: the scalar per-pixel function is branchy (each rejection returns early)
// and compilers do not vectorise it, so the "cpu" backend spent ~100 ns per pixel; here a pixel costs a few
// gathers and ~100 lane operations shared by eight. Every rejection becomes a lane mask, rejected lanes get
// J = r = w = 0 (their maps may hold anything, even NaN, which a mask-and-blend never lets through), and the
// operations keep the scalar kernel's order without contraction into FMA (the target has no "fma"), so each
// lane's row is the scalar row exactly.
#include "registration/cpu_backend_avx2.h"

#include <cstdint>

#include "core/error.h"
#include "core/simd_avx2.h"
#include "registration/kernels/combined_kernel.h"

namespace hf::detail {

#ifdef HF_HAVE_AVX2_PATH

namespace {

using namespace hf::avx2;

struct Lanes3 {
  __m256 x, y, z;
};

struct Lanes4 {
  __m256 x, y, z, w;
};

// The rows of eight lanes and which lanes hold one.
struct Rows8 {
  __m256 J[6];
  __m256 r, w;
  __m256 valid;  // all-ones where the lane has a row
};

// Expressions written as in the scalar kernels: a.x * b.x + a.y * b.y + a.z * b.z, left to right.
HF_AVX2_INLINE __m256 dot3(const Lanes3& a, const Lanes3& b) {
  return add(add(mul(a.x, b.x), mul(a.y, b.y)), mul(a.z, b.z));
}

// The hf_float4 at eight pixel indices (invalid lanes must hold a safe index, e.g. 0) as four lane vectors:
// eight 16-byte loads and a 4x4 transpose per half, cheaper than four gathers.
HF_AVX2_INLINE Lanes4 gather4(const hf_float4* map, __m256i pixel) {
  alignas(32) std::int32_t i[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(i), pixel);
  const float* m = reinterpret_cast<const float*>(map);
  auto pair = [m](std::int32_t a, std::int32_t b) HF_AVX2_LAMBDA {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(m + 4 * a)), _mm_load_ps(m + 4 * b), 1);
  };
  const __m256 r0 = pair(i[0], i[4]), r1 = pair(i[1], i[5]), r2 = pair(i[2], i[6]), r3 = pair(i[3], i[7]);
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
  const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
  return {_mm256_shuffle_ps(t0, t2, 0x44), _mm256_shuffle_ps(t0, t2, 0xEE), _mm256_shuffle_ps(t1, t3, 0x44),
          _mm256_shuffle_ps(t1, t3, 0xEE)};
}

// hf_reg_transform_point / hf_reg_rotate.
HF_AVX2_INLINE Lanes3 transform(const hf_transform12& T, const Lanes4& p, bool translate) {
  const float* m = T.m;
  Lanes3 out;
  out.x = add(add(mul(splat(m[0]), p.x), mul(splat(m[1]), p.y)), mul(splat(m[2]), p.z));
  out.y = add(add(mul(splat(m[3]), p.x), mul(splat(m[4]), p.y)), mul(splat(m[5]), p.z));
  out.z = add(add(mul(splat(m[6]), p.x), mul(splat(m[7]), p.y)), mul(splat(m[8]), p.z));
  if (translate) {
    out.x = add(out.x, splat(m[9]));
    out.y = add(out.y, splat(m[10]));
    out.z = add(out.z, splat(m[11]));
  }
  return out;
}

// hf_reg_term_weight.
HF_AVX2_INLINE __m256 robust_weight(const hf_reg_robust& robust, __m256 r) {
  const float scale = robust.scale, dof = robust.t_dof;
  if (robust.type == HF_ROBUST_HUBER) {
    const __m256 a = _mm256_andnot_ps(splat(-0.0f), r);
    return _mm256_blendv_ps(_mm256_div_ps(splat(scale), a), splat(1.0f), cmp_le(a, splat(scale)));
  }
  if (robust.type == HF_ROBUST_STUDENT_T) {
    const __m256 u = _mm256_div_ps(r, splat(scale));
    return _mm256_div_ps(splat(dof + 1.0f), add(splat(dof), mul(u, u)));
  }
  return splat(1.0f);
}

// hf_reg_set_row, with rejected lanes zeroed.
HF_AVX2_INLINE void set_rows(const Lanes3& v, const Lanes3& a, __m256 r, __m256 w, __m256 valid, Rows8* rows) {
  rows->J[0] = and_(sub(mul(v.y, a.z), mul(v.z, a.y)), valid);
  rows->J[1] = and_(sub(mul(v.z, a.x), mul(v.x, a.z)), valid);
  rows->J[2] = and_(sub(mul(v.x, a.y), mul(v.y, a.x)), valid);
  rows->J[3] = and_(a.x, valid);
  rows->J[4] = and_(a.y, valid);
  rows->J[5] = and_(a.z, valid);
  rows->r = and_(r, valid);
  rows->w = and_(w, valid);
  rows->valid = valid;
}

// Per-lane double accumulators: 28 sums of hf_reg_accumulate, lanes 0-3 and 4-7 apart (AVX2 has four doubles
// per register); the count is kept as an integer.
struct Accumulator {
  __m256d lo[28], hi[28];
  std::int64_t count = 0;

  HF_AVX2 Accumulator() {
    for (int k = 0; k < 28; ++k) lo[k] = hi[k] = _mm256_setzero_pd();
  }

  // hf_reg_accumulate for eight rows: products in double, w * J_i first, as the scalar code.
  HF_AVX2_INLINE void add(const Rows8& rows) {
    count += __builtin_popcount(unsigned(_mm256_movemask_ps(rows.valid)));
    __m256d jl[6], jh[6];
    for (int i = 0; i < 6; ++i) {
      jl[i] = _mm256_cvtps_pd(_mm256_castps256_ps128(rows.J[i]));
      jh[i] = _mm256_cvtps_pd(_mm256_extractf128_ps(rows.J[i], 1));
    }
    const __m256d wl = _mm256_cvtps_pd(_mm256_castps256_ps128(rows.w));
    const __m256d wh = _mm256_cvtps_pd(_mm256_extractf128_ps(rows.w, 1));
    const __m256d rl = _mm256_cvtps_pd(_mm256_castps256_ps128(rows.r));
    const __m256d rh = _mm256_cvtps_pd(_mm256_extractf128_ps(rows.r, 1));
    int k = 0;
    for (int i = 0; i < 6; ++i) {
      const __m256d wjl = _mm256_mul_pd(wl, jl[i]), wjh = _mm256_mul_pd(wh, jh[i]);
      for (int j = i; j < 6; ++j) {
        lo[k] = _mm256_fmadd_pd(wjl, jl[j], lo[k]);
        hi[k] = _mm256_fmadd_pd(wjh, jh[j], hi[k]);
        ++k;
      }
      lo[21 + i] = _mm256_fmadd_pd(wjl, rl, lo[21 + i]);
      hi[21 + i] = _mm256_fmadd_pd(wjh, rh, hi[21 + i]);
    }
    lo[27] = _mm256_fmadd_pd(_mm256_mul_pd(wl, rl), rl, lo[27]);
    hi[27] = _mm256_fmadd_pd(_mm256_mul_pd(wh, rh), rh, hi[27]);
  }

  // Adds the lanes, in lane order, to sums.
  HF_AVX2 void flush(double* sums) const {
    for (int k = 0; k < 28; ++k) {
      alignas(32) double l[4], h[4];
      _mm256_store_pd(l, lo[k]);
      _mm256_store_pd(h, hi[k]);
      sums[k] += ((l[0] + l[1]) + (l[2] + l[3])) + ((h[0] + h[1]) + (h[2] + h[3]));
    }
    sums[HF_REG_SUM_COUNT] += double(count);
  }
};

// Eight current pixels: linear indices and whether each lies in the image (the last step of a row may overhang).
struct Pixels8 {
  __m256i index;   // y * width + x, 0 for lanes outside the row
  __m256 inside;   // all-ones for lanes with x < width
};

HF_AVX2_INLINE Pixels8 pixels(int x0, int step, int y, int width) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i x = _mm256_add_epi32(_mm256_set1_epi32(x0), _mm256_mullo_epi32(lane, _mm256_set1_epi32(step)));
  const __m256i in = _mm256_cmpgt_epi32(_mm256_set1_epi32(width), x);
  const __m256i index = _mm256_add_epi32(_mm256_set1_epi32(y * width), x);
  return {_mm256_and_si256(index, in), _mm256_castsi256_ps(in)};
}

// The problem's map at `slot` (the driver filled it with the pyramid's map of that element type).
template <class T>
HF_AVX2_INLINE const T* map(const ResidualProblem& p, int slot) {
  return static_cast<const T*>(p.maps[slot].data);
}

// hf_icp_pixel for eight pixels; false when no lane has a row.
HF_AVX2_INLINE bool icp_rows(const ResidualProblem& p, const hf_icp_params& prm, const Pixels8& px8, Rows8* rows) {
  const hf_intrinsics& K = p.camera;
  const Lanes4 vc = gather4(map<hf_float4>(p, HF_REG_IN_CUR_VERTICES), px8.index);
  const Lanes4 nc = gather4(map<hf_float4>(p, HF_REG_IN_CUR_NORMALS), px8.index);
  const __m256 zero = _mm256_setzero_ps();
  __m256 valid = and_(px8.inside, and_(cmp_ne(vc.w, zero), cmp_ne(nc.w, zero)));
  const Lanes3 v = transform(p.T_ref_cur, vc, true);
  valid = and_(valid, cmp_gt(v.z, zero));
  // hf_project: fx * v.x / v.z + cx.
  const __m256 u = add(_mm256_div_ps(mul(splat(K.fx), v.x), v.z), splat(K.cx));
  const __m256 w = add(_mm256_div_ps(mul(splat(K.fy), v.y), v.z), splat(K.cy));
  valid = and_(valid, and_(and_(cmp_gt(u, splat(-0.5f)), cmp_gt(w, splat(-0.5f))),
                           and_(cmp_lt(u, splat(float(K.width) - 0.5f)), cmp_lt(w, splat(float(K.height) - 0.5f)))));
  if (none(valid)) return false;
  const __m256i ui = _mm256_cvttps_epi32(add(u, splat(0.5f)));
  const __m256i wi = _mm256_cvttps_epi32(add(w, splat(0.5f)));
  __m256i ridx = _mm256_add_epi32(_mm256_mullo_epi32(wi, _mm256_set1_epi32(K.width)), ui);
  ridx = _mm256_and_si256(ridx, _mm256_castps_si256(valid));
  const Lanes4 vr = gather4(map<hf_float4>(p, HF_REG_IN_REF_VERTICES), ridx);
  const Lanes4 nr = gather4(map<hf_float4>(p, HF_REG_IN_REF_NORMALS), ridx);
  valid = and_(valid, and_(cmp_ne(vr.w, zero), cmp_ne(nr.w, zero)));
  const Lanes3 d{sub(vr.x, v.x), sub(vr.y, v.y), sub(vr.z, v.z)};
  valid = and_(valid, cmp_le(dot3(d, d), splat(prm.max_dist_m * prm.max_dist_m)));
  const Lanes3 rn = transform(p.T_ref_cur, nc, false);
  const Lanes3 n{nr.x, nr.y, nr.z};
  valid = and_(valid, cmp_ge(dot3(rn, n), splat(prm.min_normal_cos)));
  const __m256 r = dot3(d, n);
  __m256 weight;
  if (prm.depth_noise_ref_m > 0.0f) {
    // hf_icp_depth_scale, s = min(1, ref / z)^2, and the scalar kernel's order of products (bit for bit). z > 0 on
    // every valid lane; the others' rows are masked.
    const __m256 q = _mm256_min_ps(_mm256_div_ps(splat(prm.depth_noise_ref_m), _mm256_max_ps(vc.z, splat(1e-30f))),
                                   splat(1.0f));
    const __m256 s = mul(q, q);
    weight = mul(mul(mul(splat(prm.weight), s), s), robust_weight(prm.robust, mul(s, r)));
  } else {
    weight = mul(splat(prm.weight), robust_weight(prm.robust, r));
  }
  const __m256 minus = splat(-1.0f);
  set_rows(v, Lanes3{mul(n.x, minus), mul(n.y, minus), mul(n.z, minus)}, r, weight, valid, rows);
  return !none(valid);
}

// hf_sample_bilinear (require_valid_depth = 0) of three images at the same (x, y), whose bounds check the caller
// has made: the weights are shared.
struct Bilinear {
  __m256i i00, i10, i01, i11;
  __m256 w00, w10, w01, w11;
};

HF_AVX2_INLINE Bilinear bilinear_taps(__m256 x, __m256 y, __m256 inside, int width, int height) {
  const __m256i zero = _mm256_setzero_si256();
  const __m256i x0 = _mm256_max_epi32(
      zero, _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_floor_ps(x)), _mm256_set1_epi32(width > 2 ? width - 2 : 0)));
  const __m256i y0 = _mm256_max_epi32(
      zero, _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_floor_ps(y)), _mm256_set1_epi32(height > 2 ? height - 2 : 0)));
  const __m256i x1 = _mm256_min_epi32(_mm256_add_epi32(x0, _mm256_set1_epi32(1)), _mm256_set1_epi32(width - 1));
  const __m256i y1 = _mm256_min_epi32(_mm256_add_epi32(y0, _mm256_set1_epi32(1)), _mm256_set1_epi32(height - 1));
  const __m256 ax = sub(x, _mm256_cvtepi32_ps(x0)), ay = sub(y, _mm256_cvtepi32_ps(y0));
  const __m256 one = splat(1.0f);
  Bilinear b;
  b.w00 = mul(sub(one, ax), sub(one, ay));
  b.w10 = mul(ax, sub(one, ay));
  b.w01 = mul(sub(one, ax), ay);
  b.w11 = mul(ax, ay);
  const __m256i in = _mm256_castps_si256(inside);
  const __m256i W = _mm256_set1_epi32(width);
  const __m256i row0 = _mm256_mullo_epi32(y0, W), row1 = _mm256_mullo_epi32(y1, W);
  b.i00 = _mm256_and_si256(_mm256_add_epi32(row0, x0), in);
  b.i10 = _mm256_and_si256(_mm256_add_epi32(row0, x1), in);
  b.i01 = _mm256_and_si256(_mm256_add_epi32(row1, x0), in);
  b.i11 = _mm256_and_si256(_mm256_add_epi32(row1, x1), in);
  return b;
}

HF_AVX2_INLINE __m256 bilinear_sample(const float* img, const Bilinear& b) {
  // Zero-weight taps are skipped as in the scalar kernel: an invalid neighbour cannot poison the sum.
  const __m256 zero = _mm256_setzero_ps();
  __m256 v = and_(mul(b.w00, gather(img, b.i00)), cmp_gt(b.w00, zero));
  v = add(v, and_(mul(b.w10, gather(img, b.i10)), cmp_gt(b.w10, zero)));
  v = add(v, and_(mul(b.w01, gather(img, b.i01)), cmp_gt(b.w01, zero)));
  v = add(v, and_(mul(b.w11, gather(img, b.i11)), cmp_gt(b.w11, zero)));
  return v;
}

// hf_photometric_pixel for eight pixels on its step grid; false when no lane has a row.
HF_AVX2_INLINE bool photometric_rows(const ResidualProblem& p, const hf_photometric_params& prm, const Pixels8& px8,
                                     Rows8* rows) {
  const hf_intrinsics& K = p.camera;
  const Lanes4 vc = gather4(map<hf_float4>(p, HF_REG_IN_CUR_VERTICES), px8.index);
  const __m256 zero = _mm256_setzero_ps();
  __m256 valid = and_(px8.inside, cmp_ne(vc.w, zero));
  const Lanes3 v = transform(p.T_ref_cur, vc, true);
  valid = and_(valid, cmp_gt(v.z, zero));
  const __m256 u = add(_mm256_div_ps(mul(splat(K.fx), v.x), v.z), splat(K.cx));
  const __m256 w = add(_mm256_div_ps(mul(splat(K.fy), v.y), v.z), splat(K.cy));
  valid = and_(valid, and_(and_(cmp_ge(u, zero), cmp_ge(w, zero)),
                           and_(cmp_le(u, splat(float(K.width - 1))), cmp_le(w, splat(float(K.height - 1))))));
  if (none(valid)) return false;
  // Rejected lanes sample at (0, 0): their coordinates may be NaN or far outside.
  const __m256 us = and_(u, valid), ws = and_(w, valid);
  const Bilinear taps = bilinear_taps(us, ws, valid, K.width, K.height);
  const __m256 i_ref = bilinear_sample(map<float>(p, HF_REG_IN_REF_INTENSITY), taps);
  const __m256 gx = bilinear_sample(map<float>(p, HF_REG_IN_REF_GRAD_X), taps);
  const __m256 gy = bilinear_sample(map<float>(p, HF_REG_IN_REF_GRAD_Y), taps);
  valid = and_(valid, cmp_ge(add(mul(gx, gx), mul(gy, gy)), splat(prm.min_gradient_sq)));
  if (prm.occlusion_check) {
    const __m256i ui = _mm256_cvttps_epi32(add(us, splat(0.5f)));
    const __m256i wi = _mm256_cvttps_epi32(add(ws, splat(0.5f)));
    __m256i ridx = _mm256_add_epi32(_mm256_mullo_epi32(wi, _mm256_set1_epi32(K.width)), ui);
    ridx = _mm256_and_si256(ridx, _mm256_castps_si256(valid));
    const float* base = map<float>(p, HF_REG_IN_REF_VERTICES);
    const __m256i i4 = _mm256_slli_epi32(ridx, 2);
    const __m256 vr_z = gather(base + 2, i4), vr_w = gather(base + 3, i4);
    const __m256 occluded =
        and_(cmp_ne(vr_w, zero),
             cmp_gt(_mm256_andnot_ps(splat(-0.0f), sub(vr_z, v.z)), splat(prm.occlusion_max_depth_m)));
    valid = _mm256_andnot_ps(occluded, valid);
  }
  const __m256 r = sub(i_ref, mul(splat(prm.gain), gather(map<float>(p, HF_REG_IN_CUR_INTENSITY), px8.index)));
  const __m256 inv_z = _mm256_div_ps(splat(1.0f), v.z);
  const __m256 ax = mul(mul(gx, splat(K.fx)), inv_z);
  const __m256 ay = mul(mul(gy, splat(K.fy)), inv_z);
  const __m256 az = mul(_mm256_xor_ps(add(mul(ax, v.x), mul(ay, v.y)), splat(-0.0f)), inv_z);
  const __m256 weight = mul(splat(prm.weight), robust_weight(prm.robust, r));
  set_rows(v, Lanes3{ax, ay, az}, r, weight, valid, rows);
  return !none(valid);
}

// The rows hf_combined_pixel() writes for rows [y_begin, y_end), either term alone when the other is null: the
// geometric rows of every pixel, then the photometric rows of the pixels on its step grid.
HF_AVX2_INLINE void rows_avx2(const ResidualProblem& p, const hf_icp_params* icp, const hf_photometric_params* pho,
                              int y_begin, int y_end, double* sums) {
  const int step = pho != nullptr && pho->step > 1 ? pho->step : 1;
  const int width = p.width();
  Accumulator acc;
  Rows8 rows;
  for (int y = y_begin; y < y_end; ++y) {
    if (icp != nullptr) {
      for (int x = 0; x < width; x += 8) {
        if (icp_rows(p, *icp, pixels(x, 1, y, width), &rows)) acc.add(rows);
      }
    }
    if (pho != nullptr && y % step == 0) {
      for (int x = 0; x < width; x += 8 * step) {
        if (photometric_rows(p, *pho, pixels(x, step, y, width), &rows)) acc.add(rows);
      }
    }
  }
  acc.flush(sums);
}

}  // namespace

HF_AVX2 void icp_rows_avx2(const ResidualProblem& p, int y_begin, int y_end, double* sums) {
  rows_avx2(p, static_cast<const hf_icp_params*>(p.params), nullptr, y_begin, y_end, sums);
}

HF_AVX2 void photometric_rows_avx2(const ResidualProblem& p, int y_begin, int y_end, double* sums) {
  rows_avx2(p, nullptr, static_cast<const hf_photometric_params*>(p.params), y_begin, y_end, sums);
}

HF_AVX2 void combined_rows_avx2(const ResidualProblem& p, int y_begin, int y_end, double* sums) {
  const auto* params = static_cast<const hf_combined_params*>(p.params);
  rows_avx2(p, &params->icp, &params->photometric, y_begin, y_end, sums);
}

#else

void icp_rows_avx2(const ResidualProblem&, int, int, double*) { throw Error("this build has no AVX2 path"); }
void photometric_rows_avx2(const ResidualProblem&, int, int, double*) {
  throw Error("this build has no AVX2 path");
}
void combined_rows_avx2(const ResidualProblem&, int, int, double*) { throw Error("this build has no AVX2 path"); }

#endif

}  // namespace hf::detail
