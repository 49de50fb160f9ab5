// integrate()'s loops: the plain spelling and the AVX2 one of each. This file is compiled with -ffp-contract=off
// (fusion/CMakeLists.txt): both spellings must round every operation alike.
#include "fusion/integrate_cpu.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "core/error.h"
#include "core/simd_avx2.h"

namespace hf::fusion::detail {

namespace {

// The packed block keys hold +-2^20 blocks per axis (fusion/integrate.cpp); two blocks of margin.
constexpr double kBandLimit = double(1 << 20) - 2.0;

// Centre of voxel (0, y, z) of the block, the start of its row.
void row_start(const BlockFrame& b, int y, int z, float out[3]) {
  for (int a = 0; a < 3; ++a) out[a] = (b.p0[a] + float(z) * b.s_z[a]) + float(y) * b.s_y[a];
}

}  // namespace

void band_row(const float* depth, int width, const double* ray_x, double ray_y, const BandFrame& f,
              const BandRow& out) {
  const double* R = f.R;
  for (int u = 0; u < width; ++u) {
    const double d = depth[u];
    bool ok = d >= f.min_depth_m && d <= f.max_depth_m;  // also false for NaN
    const double z[2] = {std::max(d - f.mu, 1e-3), d + f.mu};
    for (int end = 0; end < 2; ++end) {
      const double x = ray_x[u] * z[end], y = ray_y * z[end];
      double* const* p = end == 0 ? out.a : out.b;
      for (int i = 0; i < 3; ++i) {
        const double q = (((R[3 * i] * x + R[3 * i + 1] * y) + R[3 * i + 2] * z[end]) + f.t[i]) * f.inv_block;
        p[i][u] = q;
        ok = ok && q > -kBandLimit && q < kBandLimit;
      }
    }
    for (int i = 0; i < 3; ++i) {
      out.cell_a[i][u] = ok ? std::int32_t(std::floor(out.a[i][u])) : 0;
      out.cell_b[i][u] = ok ? std::int32_t(std::floor(out.b[i][u])) : 0;
    }
    out.ok[u] = ok;
  }
}

// The camera-frame depth of each voxel of block row (y, z) and the pixel it projects to (-1: none); branch-free.
void project_row(const BlockFrame& b, int y, int z, const hf_intrinsics& K, float pz[HF_BLOCK_SIZE],
                 int pixel[HF_BLOCK_SIZE]) {
  float p[3];
  row_start(b, y, z, p);
  float px[HF_BLOCK_SIZE], py[HF_BLOCK_SIZE];
  for (int x = 0; x < HF_BLOCK_SIZE; ++x) {
    px[x] = p[0] + float(x) * b.s_x[0];
    py[x] = p[1] + float(x) * b.s_x[1];
    pz[x] = p[2] + float(x) * b.s_x[2];
  }
  for (int x = 0; x < HF_BLOCK_SIZE; ++x) pixel[x] = hf_voxel_pixel(px[x], py[x], pz[x], K);
}

int update_block(Voxel* voxels, const BlockFrame& b, const FrameInputs& in, bool* wrote_surface) {
  int updated = 0;
  bool surface = false;
  for (int z = 0; z < HF_BLOCK_SIZE; ++z) {
    for (int y = 0; y < HF_BLOCK_SIZE; ++y) {
      // Two passes: the projections (branch-free), then the voxels that land in the image.
      float pz[HF_BLOCK_SIZE];
      int pixel[HF_BLOCK_SIZE];
      project_row(b, y, z, in.K, pz, pixel);
      Voxel* row = voxels + hf_voxel_index(0, y, z);
      for (int x = 0; x < HF_BLOCK_SIZE; ++x) {
        if (pixel[x] >= 0 && hf_integrate_voxel_mu(row + x, pz[x], pixel[x], in.depth, in.incidence, in.mu_scale,
                                                   in.w_scale, in.rgb, in.mu, in.max_weight, in.w)) {
          ++updated;
          surface |= row[x].weight != 0 && row[x].sdf <= 0;
        }
      }
    }
  }
  *wrote_surface = surface;
  return updated;
}

int deintegrate_block(Voxel* voxels, const BlockFrame& b, const FrameInputs& in) {
  int updated = 0;
  for (int z = 0; z < HF_BLOCK_SIZE; ++z) {
    for (int y = 0; y < HF_BLOCK_SIZE; ++y) {
      float pz[HF_BLOCK_SIZE];
      int pixel[HF_BLOCK_SIZE];
      project_row(b, y, z, in.K, pz, pixel);
      Voxel* row = voxels + hf_voxel_index(0, y, z);
      for (int x = 0; x < HF_BLOCK_SIZE; ++x)
        if (pixel[x] >= 0)
          updated += hf_deintegrate_voxel_mu(row + x, pz[x], pixel[x], in.depth, in.incidence, in.mu_scale,
                                             in.w_scale, in.rgb, in.mu, in.w);
    }
  }
  return updated;
}

#ifdef HF_HAVE_AVX2_PATH

namespace {

using namespace hf::avx2;

HF_AVX2_INLINE __m256 as_ps(__m256i v) { return _mm256_castsi256_ps(v); }
HF_AVX2_INLINE __m256i as_si(__m256 v) { return _mm256_castps_si256(v); }
HF_AVX2_INLINE __m256i splat_i(int v) { return _mm256_set1_epi32(v); }

// A row of eight voxels split into its two 32-bit halves, in voxel order: lo = sdf | weight << 16,
// hi = r | g << 8 | b << 16 | flags << 24 (hf_voxel's layout on a little-endian machine).
struct RowHalves {
  __m256i lo, hi;
};

HF_AVX2_INLINE RowHalves load_row(const Voxel* row) {
  static_assert(sizeof(Voxel) == 8 && offsetof(Voxel, weight) == 2 && offsetof(Voxel, r) == 4, "hf_voxel layout");
  const __m256 a = _mm256_loadu_ps(reinterpret_cast<const float*>(row));      // voxels 0-3
  const __m256 b = _mm256_loadu_ps(reinterpret_cast<const float*>(row + 4));  // voxels 4-7
  // shuffle_ps gives voxels (0 1 4 5 | 2 3 6 7) per half; the 64-bit permute puts them in order.
  const __m256i lo = as_si(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)));
  const __m256i hi = as_si(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
  return {_mm256_permute4x64_epi64(lo, _MM_SHUFFLE(3, 1, 2, 0)), _mm256_permute4x64_epi64(hi, _MM_SHUFFLE(3, 1, 2, 0))};
}

HF_AVX2_INLINE void store_row(Voxel* row, const RowHalves& v) {
  const __m256 lo = as_ps(_mm256_permute4x64_epi64(v.lo, _MM_SHUFFLE(3, 1, 2, 0)));  // (0 1 4 5 | 2 3 6 7)
  const __m256 hi = as_ps(_mm256_permute4x64_epi64(v.hi, _MM_SHUFFLE(3, 1, 2, 0)));
  _mm256_storeu_ps(reinterpret_cast<float*>(row), _mm256_unpacklo_ps(lo, hi));
  _mm256_storeu_ps(reinterpret_cast<float*>(row + 4), _mm256_unpackhi_ps(lo, hi));
}

// (T)(x) of a value the scalar code has already clamped into T's range: truncation toward zero.
HF_AVX2_INLINE __m256i truncate(__m256 x) { return _mm256_cvttps_epi32(x); }

}  // namespace

HF_AVX2 void band_row_avx2(const float* depth, int width, const double* ray_x, double ray_y, const BandFrame& f,
                           const BandRow& out) {
  const double* R = f.R;
  const __m256d lo = _mm256_set1_pd(-kBandLimit), hi = _mm256_set1_pd(kBandLimit);
  const __m256d min_d = _mm256_set1_pd(f.min_depth_m), max_d = _mm256_set1_pd(f.max_depth_m);
  const __m256d mu = _mm256_set1_pd(f.mu), near = _mm256_set1_pd(1e-3), y_ray = _mm256_set1_pd(ray_y);
  const __m256d inv_block = _mm256_set1_pd(f.inv_block);
  int u = 0;
  for (; u + 4 <= width; u += 4) {
    const __m256d d = _mm256_cvtps_pd(_mm_loadu_ps(depth + u));
    __m256d ok = _mm256_and_pd(_mm256_cmp_pd(d, min_d, _CMP_GE_OQ), _mm256_cmp_pd(d, max_d, _CMP_LE_OQ));
    // std::max(a, b) is (a < b) ? b : a; maxpd returns its second operand when they are unordered, as that does.
    const __m256d z[2] = {_mm256_max_pd(near, _mm256_sub_pd(d, mu)), _mm256_add_pd(d, mu)};
    const __m256d x_ray = _mm256_loadu_pd(ray_x + u);
    for (int end = 0; end < 2; ++end) {
      const __m256d x = _mm256_mul_pd(x_ray, z[end]), y = _mm256_mul_pd(y_ray, z[end]);
      double* const* p = end == 0 ? out.a : out.b;
      for (int i = 0; i < 3; ++i) {
        __m256d q = _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(R[3 * i]), x), _mm256_mul_pd(_mm256_set1_pd(R[3 * i + 1]), y));
        q = _mm256_add_pd(q, _mm256_mul_pd(_mm256_set1_pd(R[3 * i + 2]), z[end]));
        q = _mm256_mul_pd(_mm256_add_pd(q, _mm256_set1_pd(f.t[i])), inv_block);
        _mm256_storeu_pd(p[i] + u, q);
        ok = _mm256_and_pd(ok, _mm256_and_pd(_mm256_cmp_pd(q, lo, _CMP_GT_OQ), _mm256_cmp_pd(q, hi, _CMP_LT_OQ)));
      }
    }
    const int mask = _mm256_movemask_pd(ok);
    for (int end = 0; end < 2; ++end) {
      double* const* p = end == 0 ? out.a : out.b;
      std::int32_t* const* cell = end == 0 ? out.cell_a : out.cell_b;
      for (int i = 0; i < 3; ++i) {
        // Lanes that are not ok may hold NaN or huge values: they convert to 0 like the plain loop's.
        const __m256d q = _mm256_and_pd(_mm256_floor_pd(_mm256_loadu_pd(p[i] + u)), ok);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(cell[i] + u), _mm256_cvttpd_epi32(q));
      }
    }
    for (int k = 0; k < 4; ++k) out.ok[u + k] = std::uint8_t((mask >> k) & 1);
  }
  if (u < width) {
    BandRow rest = out;
    for (int i = 0; i < 3; ++i) {
      rest.a[i] += u, rest.b[i] += u;
      rest.cell_a[i] += u, rest.cell_b[i] += u;
    }
    rest.ok += u;
    band_row(depth + u, width - u, ray_x + u, ray_y, f, rest);
  }
}

namespace {

// What both AVX2 block loops hold for a whole block: the frame's constants as lanes.
struct BlockLanes {
  __m256 zero, one, half, fx, fy, cx, cy, width_f, height_f, inf, mu, neg_mu, w, max_weight;
  __m256 sdf_scale, neg_sdf_scale, weight_scale, inv_weight_scale, weight_max_raw, c255;
  __m256i width_i, byte, low16;
  __m256 step_x, step_y, step_z;  // float(x) * s_x per lane, as the scalar loop
};

HF_AVX2_INLINE BlockLanes block_lanes(const BlockFrame& b, const FrameInputs& in) {
  BlockLanes l;
  l.zero = _mm256_setzero_ps(), l.one = splat(1.0f), l.half = splat(0.5f);
  l.fx = splat(in.K.fx), l.fy = splat(in.K.fy), l.cx = splat(in.K.cx), l.cy = splat(in.K.cy);
  l.width_f = splat(float(in.K.width)), l.height_f = splat(float(in.K.height));
  l.width_i = splat_i(in.K.width);
  l.inf = splat(std::numeric_limits<float>::infinity());
  l.mu = splat(in.mu), l.neg_mu = splat(-in.mu), l.w = splat(in.w), l.max_weight = splat(in.max_weight);
  l.sdf_scale = splat(HF_SDF_SCALE), l.neg_sdf_scale = splat(-HF_SDF_SCALE);
  l.weight_scale = splat(HF_WEIGHT_SCALE), l.inv_weight_scale = splat(1.0f / HF_WEIGHT_SCALE);
  l.weight_max_raw = splat(float(HF_WEIGHT_MAX_RAW)), l.c255 = splat(255.0f);
  l.byte = splat_i(0xFF), l.low16 = splat_i(0xFFFF);
  l.step_x = mul(iota(), splat(b.s_x[0]));
  l.step_y = mul(iota(), splat(b.s_x[1]));
  l.step_z = mul(iota(), splat(b.s_x[2]));
  return l;
}

// hf_voxel_pixel and hf_observe_voxel_at on block row (y, z): the pixel of each lane, its projective eta, the
// lanes the frame observes (upd) and their tsdf. False when no lane is observed.
struct RowObservation {
  __m256i pixel;
  __m256 eta, upd, tsdf;
};

HF_AVX2_INLINE bool observe_row(const BlockFrame& b, int y, int z, const FrameInputs& in, const BlockLanes& l,
                                RowObservation* o) {
  float p[3];
  row_start(b, y, z, p);
  const __m256 px = add(splat(p[0]), l.step_x), py = add(splat(p[1]), l.step_y), pz = add(splat(p[2]), l.step_z);
  const __m256 inv_z = div(l.one, pz);
  const __m256 u = add(add(mul(mul(l.fx, px), inv_z), l.cx), l.half);
  const __m256 v = add(add(mul(mul(l.fy, py), inv_z), l.cy), l.half);
  const __m256 inside = and_(and_(and_(and_(cmp_gt(pz, l.zero), cmp_ge(u, l.zero)), cmp_ge(v, l.zero)),
                                  cmp_lt(u, l.width_f)),
                             cmp_lt(v, l.height_f));
  if (none(inside)) return false;
  o->pixel = _mm256_and_si256(_mm256_add_epi32(_mm256_mullo_epi32(truncate(v), l.width_i), truncate(u)),
                              as_si(inside));
  // Lanes outside the image read no depth and get d = 0, which fails d > 0.
  const __m256 d = gather(in.depth, o->pixel, inside);
  o->eta = sub(d, pz);
  o->upd = and_(and_(cmp_gt(d, l.zero), cmp_lt(d, l.inf)), cmp_ge(o->eta, l.neg_mu));
  if (none(o->upd)) return false;
  __m256 sdf = o->eta;
  if (in.incidence != nullptr) {
    const __m256 c = gather(in.incidence, o->pixel, o->upd);
    sdf = select(cmp_gt(c, l.zero), mul(o->eta, c), o->eta);
  }
  o->tsdf = select(cmp_ge(sdf, l.mu), l.one, select(cmp_le(sdf, l.neg_mu), splat(-1.0f), div(sdf, l.mu)));
  return true;
}

// The colour pixels (r | g << 8 | b << 16) of the lanes in mask, 0 elsewhere. Pixel i's bytes are 3 i .. 3 i + 2: a
// 32-bit load from 3 i - 1 (from 0 for pixel 0) stays inside the image, and the shift drops the byte before.
HF_AVX2_INLINE __m256i gather_rgb(const hf_uint8* rgb, __m256i pixel, __m256 mask) {
  const __m256i after_first = _mm256_cmpgt_epi32(pixel, _mm256_setzero_si256());  // -1 or 0
  const __m256i offset = _mm256_add_epi32(_mm256_mullo_epi32(pixel, splat_i(3)), after_first);
  const __m256i c = _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(rgb), offset,
                                                as_si(mask), 1);
  return _mm256_srlv_epi32(c, _mm256_and_si256(after_first, splat_i(8)));
}

// Round-to-nearest of an sdf in units of HF_SDF_SCALE, clamped (hf_quantise_sdf), as the low 16 bits of each lane.
HF_AVX2_INLINE __m256i quantise_sdf(__m256 s, const BlockLanes& l) {
  s = select(cmp_gt(s, l.sdf_scale), l.sdf_scale, select(cmp_lt(s, l.neg_sdf_scale), l.neg_sdf_scale, s));
  s = select(cmp_ge(s, l.zero), add(s, l.half), sub(s, l.half));
  return _mm256_and_si256(truncate(s), l.low16);
}

// hf_quantise_weight of each lane.
HF_AVX2_INLINE __m256i quantise_weight(__m256 weight, const BlockLanes& l) {
  __m256 wq = add(mul(weight, l.weight_scale), l.half);
  wq = select(cmp_gt(wq, l.weight_max_raw), l.weight_max_raw, select(cmp_lt(wq, l.zero), l.zero, wq));
  return truncate(wq);
}

}  // namespace

HF_AVX2 int update_block_avx2(Voxel* voxels, const BlockFrame& b, const FrameInputs& in, bool* wrote_surface) {
  if (in.K.width * in.K.height < 2) throw Error("update_block_avx2: the image must have at least two pixels");
  if (in.mu_scale != nullptr || in.w_scale != nullptr)
    throw Error("update_block_avx2: no per-pixel truncation or weight (the plain loop has them)");
  const BlockLanes l = block_lanes(b, in);
  int updated = 0;
  __m256i surface = _mm256_setzero_si256();  // lanes that wrote an observed sdf <= 0
  for (int z = 0; z < HF_BLOCK_SIZE; ++z) {
    for (int y = 0; y < HF_BLOCK_SIZE; ++y) {
      RowObservation o;
      if (!observe_row(b, y, z, in, l, &o)) continue;
      const __m256 upd = o.upd;

      // hf_tsdf_update.
      Voxel* row = voxels + hf_voxel_index(0, y, z);
      RowHalves vox = load_row(row);
      const __m256 W = mul(_mm256_cvtepi32_ps(_mm256_srli_epi32(vox.lo, 16)), l.inv_weight_scale);  // exact: 2^-4
      const __m256 D = div(_mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(vox.lo, 16), 16)), l.sdf_scale);
      const __m256 W_new = add(W, l.w);
      const __m256 inv = div(l.one, W_new);
      const __m256 s = mul(mul(add(mul(D, W), mul(o.tsdf, l.w)), inv), l.sdf_scale);
      const __m256 W_capped = select(cmp_gt(W_new, l.max_weight), l.max_weight, W_new);
      const __m256i lo_new = _mm256_or_si256(quantise_sdf(s, l), _mm256_slli_epi32(quantise_weight(W_capped, l), 16));
      vox.lo = as_si(select(upd, as_ps(lo_new), as_ps(vox.lo)));
      const __m256i sdf16 = _mm256_srai_epi32(_mm256_slli_epi32(lo_new, 16), 16);
      const __m256i unobserved = _mm256_cmpeq_epi32(_mm256_srli_epi32(lo_new, 16), _mm256_setzero_si256());
      const __m256i written_surface = _mm256_andnot_si256(unobserved, _mm256_cmpgt_epi32(splat_i(1), sdf16));
      surface = _mm256_or_si256(surface, _mm256_and_si256(as_si(upd), written_surface));

      if (in.rgb != nullptr) {
        const __m256 colour = and_(upd, cmp_lt(o.eta, l.mu));
        if (!none(colour)) {
          const __m256i rgb = gather_rgb(in.rgb, o.pixel, colour);
          const __m256 has_colour = as_ps(_mm256_cmpeq_epi32(
              _mm256_and_si256(_mm256_srli_epi32(vox.hi, 24), splat_i(HF_VOXEL_FLAG_COLOUR)),
              splat_i(HF_VOXEL_FLAG_COLOUR)));
          const __m256 Wc = and_(has_colour, W);
          const __m256 inv_c = div(l.one, add(Wc, l.w));
          __m256i hi_new = _mm256_or_si256(vox.hi, splat_i(HF_VOXEL_FLAG_COLOUR << 24));
          hi_new = _mm256_andnot_si256(splat_i(0xFFFFFF), hi_new);  // keep the flags, colour below
          for (int channel = 0; channel < 3; ++channel) {
            const int shift = 8 * channel;
            const __m256 old_c = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(vox.hi, shift), l.byte));
            const __m256 obs_c = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(rgb, shift), l.byte));
            __m256 c = add(mul(add(mul(old_c, Wc), mul(obs_c, l.w)), inv_c), l.half);
            c = select(cmp_gt(c, l.c255), l.c255, c);
            hi_new = _mm256_or_si256(hi_new, _mm256_slli_epi32(truncate(c), shift));
          }
          vox.hi = as_si(select(colour, as_ps(hi_new), as_ps(vox.hi)));
        }
      }
      store_row(row, vox);
      updated += count(upd);
    }
  }
  *wrote_surface = !_mm256_testz_si256(surface, surface);
  return updated;
}

HF_AVX2 int deintegrate_block_avx2(Voxel* voxels, const BlockFrame& b, const FrameInputs& in) {
  if (in.K.width * in.K.height < 2) throw Error("deintegrate_block_avx2: the image must have at least two pixels");
  if (in.mu_scale != nullptr || in.w_scale != nullptr)
    throw Error("deintegrate_block_avx2: no per-pixel truncation or weight (the plain loop has them)");
  const BlockLanes l = block_lanes(b, in);
  int updated = 0;
  for (int z = 0; z < HF_BLOCK_SIZE; ++z) {
    for (int y = 0; y < HF_BLOCK_SIZE; ++y) {
      RowObservation o;
      if (!observe_row(b, y, z, in, l, &o)) continue;
      // hf_tsdf_downdate, on the observed lanes that hold weight.
      Voxel* row = voxels + hf_voxel_index(0, y, z);
      RowHalves vox = load_row(row);
      const __m256i weight_raw = _mm256_srli_epi32(vox.lo, 16);
      const __m256 upd = _mm256_andnot_ps(as_ps(_mm256_cmpeq_epi32(weight_raw, _mm256_setzero_si256())), o.upd);
      if (none(upd)) continue;
      const __m256 W = mul(_mm256_cvtepi32_ps(weight_raw), l.inv_weight_scale);  // exact: 2^-4
      const __m256 D = div(_mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(vox.lo, 16), 16)), l.sdf_scale);
      const __m256 W_old = sub(W, l.w);
      const __m256i weight_old = quantise_weight(W_old, l);
      const __m256 reset = as_ps(_mm256_cmpeq_epi32(weight_old, _mm256_setzero_si256()));
      const __m256 inv = div(l.one, W_old);
      const __m256 s = mul(mul(sub(mul(D, W), mul(o.tsdf, l.w)), inv), l.sdf_scale);
      const __m256i lo_new = _mm256_andnot_si256(
          as_si(reset), _mm256_or_si256(quantise_sdf(s, l), _mm256_slli_epi32(weight_old, 16)));
      vox.lo = as_si(select(upd, as_ps(lo_new), as_ps(vox.lo)));

      __m256i hi_new = vox.hi;
      if (in.rgb != nullptr) {
        const __m256 has_colour = as_ps(_mm256_cmpeq_epi32(
            _mm256_and_si256(_mm256_srli_epi32(vox.hi, 24), splat_i(HF_VOXEL_FLAG_COLOUR)),
            splat_i(HF_VOXEL_FLAG_COLOUR)));
        const __m256 colour = _mm256_andnot_ps(reset, and_(and_(upd, cmp_lt(o.eta, l.mu)), has_colour));
        if (!none(colour)) {
          const __m256i rgb = gather_rgb(in.rgb, o.pixel, colour);
          __m256i c_new = _mm256_andnot_si256(splat_i(0xFFFFFF), vox.hi);  // keep the flags, colour below
          for (int channel = 0; channel < 3; ++channel) {
            const int shift = 8 * channel;
            const __m256 old_c = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(vox.hi, shift), l.byte));
            const __m256 obs_c = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(rgb, shift), l.byte));
            __m256 c = add(mul(sub(mul(old_c, W), mul(obs_c, l.w)), inv), l.half);
            c = select(cmp_gt(c, l.c255), l.c255, select(cmp_lt(c, l.zero), l.zero, c));
            c_new = _mm256_or_si256(c_new, _mm256_slli_epi32(truncate(c), shift));
          }
          hi_new = as_si(select(colour, as_ps(c_new), as_ps(hi_new)));
        }
      }
      vox.hi = as_si(select(and_(upd, reset), l.zero, as_ps(hi_new)));
      store_row(row, vox);
      updated += count(upd);
    }
  }
  return updated;
}

#else

void band_row_avx2(const float*, int, const double*, double, const BandFrame&, const BandRow&) {
  throw Error("band_row_avx2: this build has no AVX2 path");
}

int update_block_avx2(Voxel*, const BlockFrame&, const FrameInputs&, bool*) {
  throw Error("update_block_avx2: this build has no AVX2 path");
}

int deintegrate_block_avx2(Voxel*, const BlockFrame&, const FrameInputs&) {
  throw Error("deintegrate_block_avx2: this build has no AVX2 path");
}

#endif

}  // namespace hf::fusion::detail
