#include "fusion/raycast.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "fusion/kernels/raycast_kernels.h"
#include "fusion/raycast_stages.h"

namespace hf::fusion {

// ---------------------------------------------------------------------------------------------------------------
// BlockLookup

BlockLookup::BlockLookup(const std::vector<std::pair<BlockCoord, const VoxelBlock*>>& blocks,
                         const std::vector<std::uint8_t>* surface_free)
    : table_(blocks.size(), blocks.size()), regions_(blocks.size(), blocks.size()) {
  if (surface_free != nullptr && surface_free->size() != blocks.size())
    throw Error("BlockLookup: " + std::to_string(surface_free->size()) + " surface_free flags for " +
                std::to_string(blocks.size()) + " blocks");
  blocks_.reserve(blocks.size());
  skippable_.reserve(blocks.size());
  constexpr int R = VoxelBlockGrid::kRegionShift;
  for (size_t b = 0; b < blocks.size(); ++b) {
    const auto& [c, block] = blocks[b];
    if (block == nullptr) throw Error("BlockLookup: null block pointer");
    if (table_.find(c.x, c.y, c.z) != 0) continue;  // the same coordinate twice: the first one wins
    blocks_.push_back(block);
    skippable_.push_back(surface_free != nullptr && (*surface_free)[b] != 0);
    table_.insert(c.x, c.y, c.z, std::uint32_t(blocks_.size()));
    if (regions_.find(c.x >> R, c.y >> R, c.z >> R) == 0) regions_.insert(c.x >> R, c.y >> R, c.z >> R, 1);
  }
}

// ---------------------------------------------------------------------------------------------------------------
// VolumeSampler

VolumeSampler::VolumeSampler(const VoxelBlockGrid& grid, float min_weight, bool skip_surface_free)
    : grid_(&grid),
      skip_surface_free_(skip_surface_free),
      min_weight_raw_(std::max<std::uint16_t>(1, hf_quantise_weight(std::max(0.0f, min_weight)))) {}

VolumeSampler::VolumeSampler(const BlockLookup& lookup, float min_weight)
    : lookup_(&lookup),
      min_weight_raw_(std::max<std::uint16_t>(1, hf_quantise_weight(std::max(0.0f, min_weight)))) {}

namespace {

// What a missing block reads as: every voxel unobserved (weight 0 is below any min_weight_raw_, which is >= 1).
const VoxelBlock kEmptyBlock{};

// floor() of three coordinates as ints, and what remains (x - floor(x), exact), for |x| < limit (false beyond, or
// for NaN; limit <= 2^31). The build targets baseline x86-64, where std::floor is a dozen instructions per value
// without SSE4.1's roundss: truncate and step down where that rounded up (negative non-integers) instead, all three
// axes at once with SSE2. Exact: float(int(x)) is representable for |x| < 2^31, so the result is floor(x) bit for
// bit.
inline bool floor3(float x, float y, float z, float limit, int out[3], float frac[3]) {
#if defined(__SSE2__)
  const __m128 v = _mm_setr_ps(x, y, z, 0.0f);
  const __m128 abs_v = _mm_andnot_ps(_mm_set1_ps(-0.0f), v);
  if (_mm_movemask_ps(_mm_cmplt_ps(abs_v, _mm_set1_ps(limit))) != 0xF) return false;
  const __m128i t = _mm_cvttps_epi32(v);
  const __m128i f = _mm_add_epi32(t, _mm_castps_si128(_mm_cmpgt_ps(_mm_cvtepi32_ps(t), v)));  // -1 where t > v
  alignas(16) int fi[4];
  alignas(16) float fr[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(fi), f);
  _mm_store_ps(fr, _mm_sub_ps(v, _mm_cvtepi32_ps(f)));
  out[0] = fi[0], out[1] = fi[1], out[2] = fi[2];
  frac[0] = fr[0], frac[1] = fr[1], frac[2] = fr[2];
  return true;
#else
  const float v[3] = {x, y, z};
  for (int a = 0; a < 3; ++a) {
    if (!(std::fabs(v[a]) < limit)) return false;
    const int t = int(v[a]);
    out[a] = t - int(float(t) > v[a]);
    frac[a] = v[a] - float(out[a]);
  }
  return true;
#endif
}

// The cell of p_vox: (i, j, k) = floor(p_vox) and the fractional offset; false far outside the int range, where
// nothing is allocated (refused before the conversion would overflow).
inline bool cell_of(const Eigen::Vector3f& p_vox, int* i, int* j, int* k, float f[3]) {
  int c[3];
  if (!floor3(p_vox.x(), p_vox.y(), p_vox.z(), 1.0e9f, c, f)) return false;
  *i = c[0], *j = c[1], *k = c[2];
  return true;
}

// Trilinear interpolation is linear in the corner values: interpolating the raw int16 values and scaling once
// equals hf_voxel_sdf per corner up to float rounding, without eight divisions.
constexpr float kInvSdfScale = 1.0f / HF_SDF_SCALE;
float raw_trilinear(const Voxel* const v[8], const float f[3]) {
  return hf_trilinear(float(v[0]->sdf), float(v[1]->sdf), float(v[2]->sdf), float(v[3]->sdf), float(v[4]->sdf),
                      float(v[5]->sdf), float(v[6]->sdf), float(v[7]->sdf), f[0], f[1], f[2]);
}

}  // namespace

const VoxelBlock* VolumeSampler::block_or_empty(int bx, int by, int bz) {
  const VoxelBlock* b = block(bx, by, bz);
  return b != nullptr ? b : &kEmptyBlock;
}

void VolumeSampler::neighbour_blocks(int bx, int by, int bz, bool cx, bool cy, bool cz, const VoxelBlock* B[8]) {
  B[0] = block_or_empty(bx, by, bz);
  B[1] = cx ? block_or_empty(bx + 1, by, bz) : B[0];
  B[2] = cy ? block_or_empty(bx, by + 1, bz) : B[0];
  B[3] = cy ? (cx ? block_or_empty(bx + 1, by + 1, bz) : B[2]) : B[1];
  for (int c = 0; c < 4; ++c) B[4 + c] = B[c];
  if (cz) {
    B[4] = block_or_empty(bx, by, bz + 1);
    B[5] = cx ? block_or_empty(bx + 1, by, bz + 1) : B[4];
    B[6] = cy ? block_or_empty(bx, by + 1, bz + 1) : B[4];
    B[7] = cy ? (cx ? block_or_empty(bx + 1, by + 1, bz + 1) : B[6]) : B[5];
  }
}

void VolumeSampler::gather_cell(int i, int j, int k, const Voxel* v[8]) {
  const int lx = i & 7, ly = j & 7, lz = k & 7;
  const int bx = i >> 3, by = j >> 3, bz = k >> 3;
  if (lx != 7 && ly != 7 && lz != 7) {
    // All eight in one block (343 of 512 cells): fixed offsets.
    const Voxel* base = &block_or_empty(bx, by, bz)->voxels[hf_voxel_index(lx, ly, lz)];
    v[0] = base, v[1] = base + 1, v[2] = base + 8, v[3] = base + 9;
    v[4] = base + 64, v[5] = base + 65, v[6] = base + 72, v[7] = base + 73;
    return;
  }
  // Across a block border: each distinct block of the 2 x 2 x 2 looked up once.
  const VoxelBlock* B[8];
  neighbour_blocks(bx, by, bz, lx == 7, ly == 7, lz == 7, B);
  const int x[2] = {lx, (lx + 1) & 7}, y[2] = {ly, (ly + 1) & 7}, z[2] = {lz, (lz + 1) & 7};
  for (int c = 0; c < 8; ++c) v[c] = &B[c]->voxels[hf_voxel_index(x[c & 1], y[(c >> 1) & 1], z[c >> 2])];
}

#if defined(__SSE2__)
namespace {

// Two pairs of neighbouring voxels (p[0], p[1], q[0], q[1]) in one go: their raw SDF as floats (lanes in that
// order), and the lanes whose weight is below min_weight OR-ed into *bad. A voxel's low 32 bits are
// sdf | weight << 16 (little-endian x86, fusion/kernels/voxel.h).
inline __m128 sdf_weight_2x2(const Voxel* p, const Voxel* q, __m128i min_weight, __m128i* bad) {
  static_assert(offsetof(Voxel, sdf) == 0 && offsetof(Voxel, weight) == 2, "voxel layout");
  const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q));
  const __m128i lo = _mm_unpacklo_epi64(_mm_shuffle_epi32(a, _MM_SHUFFLE(3, 1, 2, 0)),
                                        _mm_shuffle_epi32(b, _MM_SHUFFLE(3, 1, 2, 0)));
  *bad = _mm_or_si128(*bad, _mm_cmplt_epi32(_mm_srli_epi32(lo, 16), min_weight));
  return _mm_cvtepi32_ps(_mm_srai_epi32(_mm_slli_epi32(lo, 16), 16));
}

// The same for four voxels anywhere.
inline std::int32_t low_bits(const Voxel* v) {
  std::int32_t x;
  std::memcpy(&x, v, sizeof x);
  return x;
}
inline __m128 sdf_weight_4(const Voxel* a, const Voxel* b, const Voxel* c, const Voxel* d, __m128i min_weight,
                           __m128i* bad) {
  const __m128i lo = _mm_setr_epi32(low_bits(a), low_bits(b), low_bits(c), low_bits(d));
  *bad = _mm_or_si128(*bad, _mm_cmplt_epi32(_mm_srli_epi32(lo, 16), min_weight));
  return _mm_cvtepi32_ps(_mm_srai_epi32(_mm_slli_epi32(lo, 16), 16));
}

}  // namespace
#endif

const float* VolumeSampler::cell(int i, int j, int k) {
  if (i == ci_ && j == cj_ && k == ck_) return cell_ok_ ? cell_ : nullptr;
  ci_ = i, cj_ = j, ck_ = k;
#if defined(__SSE2__)
  const __m128i min_weight = _mm_set1_epi32(min_weight_raw_);
  __m128i bad = _mm_setzero_si128();
  const int lx = i & 7, ly = j & 7, lz = k & 7;
  if (lx != 7) {
    // Corners (0, 1), (2, 3), (4, 5), (6, 7) are adjacent pairs in memory, in up to four blocks (y and z).
    const int bx = i >> 3, by = j >> 3, bz = k >> 3;
    const VoxelBlock* b00 = block_or_empty(bx, by, bz);
    const VoxelBlock* b10 = ly == 7 ? block_or_empty(bx, by + 1, bz) : b00;
    const VoxelBlock* b01 = lz == 7 ? block_or_empty(bx, by, bz + 1) : b00;
    const VoxelBlock* b11 = ly == 7 ? (lz == 7 ? block_or_empty(bx, by + 1, bz + 1) : b10) : b01;
    const int ly1 = (ly + 1) & 7, lz1 = (lz + 1) & 7;
    _mm_storeu_ps(cell_, sdf_weight_2x2(&b00->voxels[hf_voxel_index(lx, ly, lz)],
                                        &b10->voxels[hf_voxel_index(lx, ly1, lz)], min_weight, &bad));
    _mm_storeu_ps(cell_ + 4, sdf_weight_2x2(&b01->voxels[hf_voxel_index(lx, ly, lz1)],
                                            &b11->voxels[hf_voxel_index(lx, ly1, lz1)], min_weight, &bad));
  } else {
    const Voxel* v[8];
    gather_cell(i, j, k, v);
    _mm_storeu_ps(cell_, sdf_weight_4(v[0], v[1], v[2], v[3], min_weight, &bad));
    _mm_storeu_ps(cell_ + 4, sdf_weight_4(v[4], v[5], v[6], v[7], min_weight, &bad));
  }
  cell_ok_ = _mm_movemask_epi8(bad) == 0;
  return cell_ok_ ? cell_ : nullptr;
#else
  const Voxel* v[8];
  gather_cell(i, j, k, v);
  bool ok = true;
  for (int c = 0; c < 8; ++c) {
    ok &= v[c]->weight >= min_weight_raw_;  // no early exit: the eight loads are issued together
    cell_[c] = float(v[c]->sdf);
  }
  cell_ok_ = ok;
  return ok ? cell_ : nullptr;
#endif
}

bool VolumeSampler::sdf(const Eigen::Vector3f& p_vox, float* out) {
  int i, j, k;
  float f[3];
  if (!cell_of(p_vox, &i, &j, &k, f)) return false;
  const float* c = cell(i, j, k);
  if (c == nullptr) return false;
  *out = hf_trilinear(c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], f[0], f[1], f[2]) * kInvSdfScale;
  return true;
}

bool VolumeSampler::sdf_color(const Eigen::Vector3f& p_vox, float* out, Eigen::Vector3f* rgb) {
  int i, j, k;
  float f[3];
  if (!cell_of(p_vox, &i, &j, &k, f)) return false;
  const Voxel* v[8];
  gather_cell(i, j, k, v);
  bool ok = true;
  for (int c = 0; c < 8; ++c) ok &= v[c]->weight >= min_weight_raw_;
  if (!ok) return false;
  *out = raw_trilinear(v, f) * kInvSdfScale;
  auto channel = [&](auto get) {
    return hf_trilinear(float(get(v[0])), float(get(v[1])), float(get(v[2])), float(get(v[3])), float(get(v[4])),
                        float(get(v[5])), float(get(v[6])), float(get(v[7])), f[0], f[1], f[2]);
  };
  *rgb = Eigen::Vector3f(channel([](const Voxel* x) { return x->r; }), channel([](const Voxel* x) { return x->g; }),
                         channel([](const Voxel* x) { return x->b; }));
  return true;
}

namespace {

// The unit normal from the 4 x 4 x 4 neighbourhood s[1 + dz][1 + dy][1 + dx] = voxel (i + dx, j + dy, k + dz) of
// raw int16 values (only the 32 voxels central differences reach need be set; the gradient's scale drops out) at
// the shared offset f: central differences of the trilinear samples one voxel apart.
bool normal_of_neighbourhood(const float s[4][4][4], const float f[3], Eigen::Vector3f* n) {
  // The trilinear sample whose corner (0, 0, 0) is voxel (i + ox, j + oy, k + oz).
  auto sample = [&](int ox, int oy, int oz) {
    const int x = 1 + ox, y = 1 + oy, z = 1 + oz;
    return hf_trilinear(s[z][y][x], s[z][y][x + 1], s[z][y + 1][x], s[z][y + 1][x + 1], s[z + 1][y][x],
                        s[z + 1][y][x + 1], s[z + 1][y + 1][x], s[z + 1][y + 1][x + 1], f[0], f[1], f[2]);
  };
  const hf_float4 nn = hf_normal_from_differences(sample(1, 0, 0) - sample(-1, 0, 0),
                                                  sample(0, 1, 0) - sample(0, -1, 0),
                                                  sample(0, 0, 1) - sample(0, 0, -1));
  if (!hf_is_valid4(nn)) return false;
  *n = Eigen::Vector3f(nn.x, nn.y, nn.z);
  return true;
}

}  // namespace

bool VolumeSampler::normal(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n, float h_vox) {
  if (h_vox != 1.0f) {
    float d[3];
    for (int a = 0; a < 3; ++a) {
      Eigen::Vector3f lo = p_vox, hi = p_vox;
      lo[a] -= h_vox;
      hi[a] += h_vox;
      float s_lo = 0.0f, s_hi = 0.0f;
      if (!sdf(lo, &s_lo) || !sdf(hi, &s_hi)) return false;
      d[a] = s_hi - s_lo;
    }
    const hf_float4 nn = hf_normal_from_differences(d[0], d[1], d[2]);
    if (!hf_is_valid4(nn)) return false;
    *n = Eigen::Vector3f(nn.x, nn.y, nn.z);
    return true;
  }
  int i, j, k;
  float f[3];
  if (!cell_of(p_vox, &i, &j, &k, f)) return false;
  // Voxels (i - 1 .. i + 2) on each axis: offset o = 0..3 is in the lower (sel 0) or upper (sel 1) of at most two
  // blocks, at local coordinate l.
  int sx[4], sy[4], sz[4], lxo[4], lyo[4], lzo[4];
  for (int o = 0; o < 4; ++o) {
    sx[o] = ((i - 1 + o) >> 3) - ((i - 1) >> 3), lxo[o] = (i - 1 + o) & 7;
    sy[o] = ((j - 1 + o) >> 3) - ((j - 1) >> 3), lyo[o] = 8 * ((j - 1 + o) & 7);
    sz[o] = ((k - 1 + o) >> 3) - ((k - 1) >> 3), lzo[o] = 64 * ((k - 1 + o) & 7);
  }
  const int bx = (i - 1) >> 3, by = (j - 1) >> 3, bz = (k - 1) >> 3;
  const bool cx = sx[3] != 0, cy = sy[3] != 0, cz = sz[3] != 0;
  const VoxelBlock* blocks[8];
  neighbour_blocks(bx, by, bz, cx, cy, cz, blocks);
  const Voxel* B[8];
  for (int c = 0; c < 8; ++c) B[c] = blocks[c]->voxels.data();
  // s[oz][oy][ox] = voxel (i - 1 + ox, j - 1 + oy, k - 1 + oz). The samples at p -+ e_x need the central 2 x 2
  // rows (oy, oz in 1 .. 2) over ox = 0 .. 3; those at p -+ e_y and p -+ e_z need the rows around them over
  // ox = 1 .. 2. The four corner rows (oy and oz both outside 1 .. 2) are not needed.
  float s[4][4][4] = {};
#if defined(__SSE2__)
  {
    // Four voxels of a central row, or the x = 1 .. 2 voxels of two outer rows, per sdf_weight_2x2 (pairs
    // contiguous in memory when the four x offsets lie in one block, 5 of 8 cells) or sdf_weight_4.
    const __m128i min_weight = _mm_set1_epi32(min_weight_raw_);
    __m128i bad = _mm_setzero_si128();
    auto at = [&](int ox, int oy, int oz) {
      return B[sx[ox] + 2 * sy[oy] + 4 * sz[oz]] + lxo[ox] + lyo[oy] + lzo[oz];
    };
    __m128 central[4], ys[2], zs[2];
    if (!cx) {
      auto row = [&](int oy, int oz) { return B[2 * sy[oy] + 4 * sz[oz]] + lyo[oy] + lzo[oz] + lxo[0]; };
      for (int r = 0; r < 4; ++r) {
        const Voxel* v = row(1 + (r & 1), 1 + (r >> 1));
        central[r] = sdf_weight_2x2(v, v + 2, min_weight, &bad);
      }
      for (int e = 0; e < 2; ++e) {
        ys[e] = sdf_weight_2x2(row(3 * e, 1) + 1, row(3 * e, 2) + 1, min_weight, &bad);
        zs[e] = sdf_weight_2x2(row(1, 3 * e) + 1, row(2, 3 * e) + 1, min_weight, &bad);
      }
    } else {
      for (int r = 0; r < 4; ++r) {
        const int oy = 1 + (r & 1), oz = 1 + (r >> 1);
        central[r] = sdf_weight_4(at(0, oy, oz), at(1, oy, oz), at(2, oy, oz), at(3, oy, oz), min_weight, &bad);
      }
      for (int e = 0; e < 2; ++e) {
        ys[e] = sdf_weight_4(at(1, 3 * e, 1), at(2, 3 * e, 1), at(1, 3 * e, 2), at(2, 3 * e, 2), min_weight, &bad);
        zs[e] = sdf_weight_4(at(1, 1, 3 * e), at(2, 1, 3 * e), at(1, 2, 3 * e), at(2, 2, 3 * e), min_weight, &bad);
      }
    }
    if (_mm_movemask_epi8(bad) != 0) return false;
    for (int r = 0; r < 4; ++r) _mm_storeu_ps(&s[1 + (r >> 1)][1 + (r & 1)][0], central[r]);
    for (int e = 0; e < 2; ++e) {
      _mm_storel_pi(reinterpret_cast<__m64*>(&s[1][3 * e][1]), ys[e]);
      _mm_storeh_pi(reinterpret_cast<__m64*>(&s[2][3 * e][1]), ys[e]);
      _mm_storel_pi(reinterpret_cast<__m64*>(&s[3 * e][1][1]), zs[e]);
      _mm_storeh_pi(reinterpret_cast<__m64*>(&s[3 * e][2][1]), zs[e]);
    }
  }
#else
  unsigned ok = 1;
  // Rows along x; when the four x offsets lie in one block (5 of 8 cells) a row is contiguous in memory.
  auto gather = [&](auto x_in_one_block) {
    auto load_row = [&](int oy, int oz, int ox0, int ox1) {
      const int yz = 2 * sy[oy] + 4 * sz[oz], off = lyo[oy] + lzo[oz];
      if constexpr (decltype(x_in_one_block)::value) {
        const Voxel* r = B[yz] + off + lxo[0];
        for (int ox = ox0; ox <= ox1; ++ox) {
          ok &= unsigned(r[ox].weight >= min_weight_raw_);
          s[oz][oy][ox] = float(r[ox].sdf);
        }
      } else {
        for (int ox = ox0; ox <= ox1; ++ox) {
          const Voxel& v = B[yz + sx[ox]][off + lxo[ox]];
          ok &= unsigned(v.weight >= min_weight_raw_);
          s[oz][oy][ox] = float(v.sdf);
        }
      }
    };
    for (int oz = 1; oz <= 2; ++oz)
      for (int oy = 1; oy <= 2; ++oy) load_row(oy, oz, 0, 3);
    for (int e = 0; e <= 3; e += 3)
      for (int c = 1; c <= 2; ++c) {
        load_row(e, c, 1, 2);
        load_row(c, e, 1, 2);
      }
  };
  if (cx)
    gather(std::false_type{});
  else
    gather(std::true_type{});
  if (!ok) return false;
#endif
  return normal_of_neighbourhood(s, f, n);
}

// ---------------------------------------------------------------------------------------------------------------
// The general paths (references for the fast ones above)

bool VolumeSampler::corners_reference(const Eigen::Vector3f& p_vox, const Voxel* v[8], float f[3]) {
  int i, j, k;
  if (!cell_of(p_vox, &i, &j, &k, f)) return false;
  for (int c = 0; c < 8; ++c) v[c] = voxel(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
  for (int c = 0; c < 8; ++c)
    if (!observed(v[c])) return false;
  return true;
}

bool VolumeSampler::sdf_reference(const Eigen::Vector3f& p_vox, float* out) {
  const Voxel* v[8];
  float f[3];
  if (!corners_reference(p_vox, v, f)) return false;
  *out = raw_trilinear(v, f) * kInvSdfScale;
  return true;
}

template <int N>
bool VolumeSampler::row(int i, int j, int k, float* out) {
  for (int c = 0; c < N; ++c) {
    const Voxel* v = voxel(i + c, j, k);
    if (!observed(v)) return false;
    out[c] = float(v->sdf);
  }
  return true;
}

bool VolumeSampler::normal_reference(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n) {
  int i, j, k;
  float f[3];
  if (!cell_of(p_vox, &i, &j, &k, f)) return false;
  // s[1 + dz][1 + dy][1 + dx] = voxel (i + dx, j + dy, k + dz), dx, dy, dz in -1 .. 2.
  float s[4][4][4] = {};
  bool ok = true;
  for (int dz = 0; dz <= 1; ++dz)
    for (int dy = 0; dy <= 1; ++dy) ok = ok && row<4>(i - 1, j + dy, k + dz, &s[1 + dz][1 + dy][0]);
  for (int e = 0; e <= 1; ++e) {
    const int d = e == 0 ? -1 : 2;
    for (int c = 0; c <= 1; ++c) {
      ok = ok && row<2>(i, j + d, k + c, &s[1 + c][1 + d][1]);
      ok = ok && row<2>(i, j + c, k + d, &s[1 + d][1 + c][1]);
    }
  }
  if (!ok) return false;
  return normal_of_neighbourhood(s, f, n);
}

// ---------------------------------------------------------------------------------------------------------------
// raycast

void RaycastOptions::validate() const {
  auto fail = [](const std::string& what) { throw Error("invalid raycast options: " + what); };
  if (!(std::isfinite(min_depth_m) && std::isfinite(max_depth_m) && min_depth_m > 0.0 && max_depth_m > min_depth_m))
    fail("expected 0 < min_depth_m < max_depth_m, got " + std::to_string(min_depth_m) + " and " +
         std::to_string(max_depth_m));
  if (!(step_fraction > 0.0 && step_fraction < 1.0))
    fail("step_fraction must be in (0, 1), got " + std::to_string(step_fraction));
  if (!(min_step_vox > 0.0 && min_step_vox <= 4.0))
    fail("min_step_vox must be in (0, 4], got " + std::to_string(min_step_vox));
  if (!(min_weight >= 0.0f)) fail("min_weight must be >= 0, got " + std::to_string(min_weight));
  if (!(refine_tol_vox > 0.0 && refine_tol_vox <= 1.0))
    fail("refine_tol_vox must be in (0, 1], got " + std::to_string(refine_tol_vox));
}

void RaycastOptions::validate(const PinholeCamera& camera) const {
  validate();
  if (depth_hint != nullptr && (depth_hint->width() != camera.width || depth_hint->height() != camera.height))
    throw Error("invalid raycast options: expected a depth_hint of the camera's size " + std::to_string(camera.width) +
                "x" + std::to_string(camera.height) + ", got " + std::to_string(depth_hint->width()) + "x" +
                std::to_string(depth_hint->height()));
}

RaycastResult raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                      const RaycastOptions& options) {
  RaycastResult out;
  raycast(grid, camera, T_world_camera, options, &out);
  return out;
}

namespace {

template <class T>
void ensure_size(Image<T>* img, int w, int h) {
  if (img->width() != w || img->height() != h) *img = Image<T>(w, h);
}

struct Hit {
  float t = 0.0f;  // metres along the unit ray
  Eigen::Vector3f p_vox;
};

// What every ray of one raycast() shares (metres; step_fraction and min_step from RaycastOptions, refine_tol_m
// from its refine_tol_vox).
struct MarchParams {
  float mu_m, step_fraction, min_step_m, voxel_m, refine_tol_m;
};

// The crossing on a + to - bracket (ta, sa >= 0) .. (tb, sb < 0) along the ray: linear interpolation, then Illinois
// regula falsi on the same bracket until the bracket is narrower than refine_tol_m or the sample at the estimate
// predicts the crossing within refine_tol_m of it (|sdf| over the bracket's secant slope: regula falsi keeps one
// end of the bracket, which then shrinks slowly although the estimate has long converged).
// Converging, rather than stopping after a fixed number of steps, makes the result independent of where the march
// happened to sample the bracket (the hinted and the full march agree), and costs only samples of voxels already
// in cache. At most kRefineSteps samples.
void refine(VolumeSampler& sampler, const MarchParams& m, const Eigen::Vector3f& o_vox, const Eigen::Vector3f& d_vox,
            float ta, float sa, float tb, float sb, Hit* hit) {
  constexpr int kRefineSteps = 6;
  float tc = hf_zero_crossing(ta, sa, tb, sb);
  int kept = 0;
  for (int it = 0; it < kRefineSteps && tb - ta > m.refine_tol_m; ++it) {
    float sc = 0.0f;
    if (!sampler.sdf(o_vox + tc * d_vox, &sc) || hf_refine_converged(sc, ta, sa, tb, sb, m.refine_tol_m)) break;
    tc = hf_illinois_step(tc, sc, &ta, &sa, &tb, &sb, &kept);
  }
  hit->t = tc;
  hit->p_vox = o_vox + tc * d_vox;
}

// Marches one ray; see raycast.h for the scheme. o and d are in continuous voxel coordinates (d has length 1 voxel
// per voxel_m metres, i.e. d = unit direction / voxel_m) so block and voxel indices come without divisions.
//
// Each step first reads the voxel nearest to the ray point (one load from the cached block): an unobserved one is
// a corner of the trilinear sample, which is then invalid without computing it; an observed one far in front of
// the surface (sdf > kFarSdf) bounds the distance to the surface by sdf * mu - sqrt(3)/2 voxel (the SDF is a
// distance, the nearest voxel centre is at most sqrt(3)/2 voxel away), so the ray advances by step_fraction of that
// bound without interpolating. Only near the surface are trilinear samples taken; when a negative sample follows
// such a cheap step, the ray goes back to where that step started and walks the stretch again with trilinear
// samples only, so the bracket it refines is the one the all-trilinear march would have found.
bool march(VolumeSampler& sampler, const MarchParams& m, const Eigen::Vector3f& o_vox, const Eigen::Vector3f& d_vox,
           float t_min, float t_max, Hit* hit) {
  const float mu_m = m.mu_m, step_fraction = m.step_fraction, min_step_m = m.min_step_m, voxel_m = m.voxel_m;
  constexpr float kFarSdf = 0.5f;
  const float far_margin_m = 0.8660254f * voxel_m;
  const bool cheap_steps = kFarSdf * mu_m - far_margin_m > min_step_m;
  // Block b holds continuous voxel coordinates [8 b - 0.5, 8 b + 7.5).
  const Eigen::Vector3f inv_d(d_vox.x() != 0.0f ? 1.0f / d_vox.x() : std::numeric_limits<float>::infinity(),
                              d_vox.y() != 0.0f ? 1.0f / d_vox.y() : std::numeric_limits<float>::infinity(),
                              d_vox.z() != 0.0f ? 1.0f / d_vox.z() : std::numeric_limits<float>::infinity());
  const float skip_eps = 1e-3f * voxel_m;
  // Where the ray leaves the cube of 2^shift voxels (aligned to multiples of it) that holds voxel (i, j, k).
  auto exit_of = [&](int i, int j, int k, int shift) {
    const float size = float(1 << shift);
    const float lo[3] = {float(i >> shift) * size - 0.5f, float(j >> shift) * size - 0.5f,
                         float(k >> shift) * size - 0.5f};
    float t_exit = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (d_vox[a] == 0.0f) continue;
      const float plane = d_vox[a] > 0.0f ? lo[a] + size : lo[a];
      t_exit = std::min(t_exit, (plane - o_vox[a]) * inv_d[a]);
    }
    return t_exit;
  };
  float t = t_min;
  bool have_prev = false;    // a sample with sdf > 0 precedes t
  bool prev_exact = false;   // ... and it was trilinear (else the nearest voxel's value)
  float t_prev = 0.0f, s_prev = 0.0f;
  float fine_until = -1.0f;  // no cheap steps before this t (set when a bracket is walked again)
  while (t < t_max) {
    const Eigen::Vector3f p = o_vox + t * d_vox;
    int ijk[3];  // the nearest voxel
    float unused[3];
    if (!floor3(p.x() + 0.5f, p.y() + 0.5f, p.z() + 0.5f, 1e8f, ijk, unused)) return false;
    const int i = ijk[0], j = ijk[1], k = ijk[2];
    bool skippable = false;
    const VoxelBlock* block = sampler.block(i >> 3, j >> 3, k >> 3, &skippable);
    if (block == nullptr) {
      // Jump to where the ray leaves this block, or its whole region when that holds no block at all.
      constexpr int kRegionShift = VoxelBlockGrid::kRegionShift + 3;  // region size in voxels, log2
      const bool region_empty = !sampler.region_occupied(i >> kRegionShift, j >> kRegionShift, k >> kRegionShift);
      t = std::max(exit_of(i, j, k, region_empty ? kRegionShift : 3), t) + skip_eps;
      have_prev = false;
      continue;
    }
    if (skippable && t > fine_until) {
      // No surface inside this block (VoxelBlockGrid::surface_free): one long cheap step to where the ray leaves
      // it. A crossing in the half voxel along its faces (cells shared with the next block) shows as a negative
      // sample right after, which sends the ray back here to walk the block with trilinear samples.
      have_prev = true, prev_exact = false;
      t_prev = t, s_prev = 1.0f;
      t = std::max(exit_of(i, j, k, 3), t) + skip_eps;
      continue;
    }
    const Voxel& nearest = block->voxels[hf_voxel_index(i & 7, j & 7, k & 7)];
    if (!sampler.observed(&nearest)) {
      t += voxel_m;  // a corner of the trilinear sample is unobserved: invalid sample
      have_prev = false;
      continue;
    }
    if (cheap_steps && t > fine_until && nearest.sdf > hf_int16(kFarSdf * HF_SDF_SCALE)) {
      const float s_near = hf_voxel_sdf(nearest);
      have_prev = true, prev_exact = false;
      t_prev = t, s_prev = s_near;
      t += std::max(step_fraction * (s_near * mu_m - far_margin_m), min_step_m);
      continue;
    }
    float s = 0.0f;
    if (!sampler.sdf(p, &s)) {
      t += voxel_m;
      have_prev = false;
      continue;
    }
    if (s < 0.0f) {
      if (have_prev && !prev_exact) {
        // The + end came from a cheap step: go back there and walk the bracket with trilinear samples only.
        fine_until = t;
        t = t_prev;
        have_prev = false;
        continue;
      }
      if (have_prev) {
        refine(sampler, m, o_vox, d_vox, t_prev, s_prev, t, s, hit);
        return true;
      }
      // Inside or behind a back face: keep going until the SDF turns positive again.
      t += hf_raycast_step(s, mu_m, step_fraction, min_step_m);
      continue;
    }
    have_prev = true, prev_exact = true;
    t_prev = t, s_prev = s;
    t += hf_raycast_step(s, mu_m, step_fraction, min_step_m);
  }
  return false;
}

// The search around a hinted depth (RaycastOptions::depth_hint): t_hint is where the frame just integrated along
// this ray measured the surface, so the fused crossing is within noise of it. One trilinear sample there says on
// which side of the surface it lies: in front (sdf >= 0), the march goes on forward to t_max; behind it, the ray
// walks back towards the camera with the same SDF-bounded steps until a sample turns positive, which with the last
// negative one brackets the crossing. False when neither finds a + to - crossing within [t_min, t_max] or the
// walk back meets an unobserved sample (the caller then marches the whole ray).
bool march_from_hint(VolumeSampler& sampler, const MarchParams& m, const Eigen::Vector3f& o_vox,
                     const Eigen::Vector3f& d_vox, float t_hint, float t_min, float t_max, Hit* hit) {
  float sb = 0.0f;
  if (!sampler.sdf(o_vox + t_hint * d_vox, &sb)) return false;
  if (sb >= 0.0f) return march(sampler, m, o_vox, d_vox, t_hint, t_max, hit);
  for (float tb = t_hint;;) {
    const float ta = tb - hf_raycast_step(sb, m.mu_m, m.step_fraction, m.min_step_m);
    float sa = 0.0f;
    if (ta < t_min || !sampler.sdf(o_vox + ta * d_vox, &sa)) return false;
    if (sa >= 0.0f) {
      refine(sampler, m, o_vox, d_vox, ta, sa, tb, sb, hit);
      return true;
    }
    tb = ta, sb = sa;
  }
}

// The slab of the view frustum between the depths near and far, its sides through u = -1, u = W, v = -1, v = H
// (one pixel of slack around the pixel centres every ray passes through), for rejecting spheres wholly outside.
class ViewSlab {
 public:
  ViewSlab(const PinholeCamera& camera, double near_m, double far_m)
      : near_(near_m),
        far_(far_m),
        left_(side((-1.0 - camera.cx) / camera.fx)),
        right_(side((camera.width - camera.cx) / camera.fx)),
        top_(side((-1.0 - camera.cy) / camera.fy)),
        bottom_(side((camera.height - camera.cy) / camera.fy)) {}
  // True when the ball of this radius around the camera-frame point c lies wholly outside one of the six planes.
  bool ball_outside(const Eigen::Vector3d& c, double radius) const {
    return c.z() + radius < near_ || c.z() - radius > far_ || left_.distance(c.x(), c.z()) < -radius ||
           right_.distance(c.x(), c.z()) > radius || top_.distance(c.y(), c.z()) < -radius ||
           bottom_.distance(c.y(), c.z()) > radius;
  }

 private:
  // Signed distance of a camera-frame point (x or y, z) from the side plane {x = a z} (or y), positive on the side
  // of larger x: (x - a z) / sqrt(1 + a^2).
  struct Side {
    double a, inv_norm;
    double distance(double xy, double z) const { return (xy - a * z) * inv_norm; }
  };
  static Side side(double a) { return Side{a, 1.0 / std::sqrt(1.0 + a * a)}; }
  double near_, far_;
  Side left_, right_, top_, bottom_;
};

// The centre of block c in the camera frame.
Eigen::Vector3d block_centre_camera(const BlockCoord& c, double block_m, const SE3& T_camera_world) {
  return T_camera_world * ((Eigen::Vector3d(c.x, c.y, c.z) + Eigen::Vector3d::Constant(0.5)) * block_m);
}

}  // namespace

std::vector<std::pair<BlockCoord, const VoxelBlock*>> blocks_in_view(const VoxelBlockGrid& grid,
                                                                     const PinholeCamera& camera,
                                                                     const SE3& T_world_camera,
                                                                     const RaycastOptions& options,
                                                                     std::vector<std::uint8_t>* surface_free) {
  std::vector<std::uint8_t> all_flags;
  const auto all = grid.blocks_unordered(surface_free != nullptr ? &all_flags : nullptr);
  const ViewSlab slab(camera, options.min_depth_m, options.max_depth_m);
  const SE3 T_camera_world = T_world_camera.inverse();
  const double B = grid.params().block_m();
  // Every voxel centre of a block lies within its bounding sphere (the cube's, 0.866 B); every voxel a sample reads
  // lies within kRaycastReachVox voxels of a point of the slab.
  const double radius = 0.8660254037844386 * B + kRaycastReachVox * grid.params().voxel_m;
  std::vector<std::pair<BlockCoord, const VoxelBlock*>> out;
  if (surface_free != nullptr) surface_free->clear();
  for (size_t i = 0; i < all.size(); ++i) {
    if (slab.ball_outside(block_centre_camera(all[i].first, B, T_camera_world), radius)) continue;
    out.push_back(all[i]);
    if (surface_free != nullptr) surface_free->push_back(all_flags[i]);
  }
  return out;
}

void forward_project_depth(const VertexMap& vertices, const SE3& T_cur_prev, const PinholeCamera& camera,
                           DepthImage* out) {
  if (!T_cur_prev.is_finite()) throw Error("forward_project_depth: expected a finite T_cur_prev");
  const int W = camera.width, H = camera.height;
  ensure_size(out, W, H);
  std::fill(out->data(), out->data() + size_t(W) * H, 0.0f);
  const Eigen::Matrix3f R = T_cur_prev.rotation().cast<float>();
  const Eigen::Vector3f t = T_cur_prev.translation().cast<float>();
  const float fx = float(camera.fx), fy = float(camera.fy), cx = float(camera.cx), cy = float(camera.cy);
  for (int y = 0; y < vertices.height(); ++y)
    for (int x = 0; x < vertices.width(); ++x) {
      const hf_float4 v = vertices(x, y);
      if (v.w != 1.0f) continue;
      const Eigen::Vector3f p = R * Eigen::Vector3f(v.x, v.y, v.z) + t;
      if (!(p.z() > 0.0f)) continue;
      // Pixel centres at integers: the nearest pixel is the rounded projection. Compared before the conversion, so
      // far-off (or non-finite) projections are dropped without an overflowing cast.
      const float u = std::floor(fx * p.x() / p.z() + cx + 0.5f), w = std::floor(fy * p.y() / p.z() + cy + 0.5f);
      if (!(u >= 0.0f && u < float(W) && w >= 0.0f && w < float(H))) continue;
      float& d = (*out)(int(u), int(w));
      if (d == 0.0f || p.z() < d) d = p.z();
    }
}

namespace {

// Stage 1, InfiniTAM's FindVisibleBlocks + CreateExpectedDepths: the depth range per 8 x 8 pixel tile of the blocks
// in view (blocks_in_view). A ray can only hit inside an allocated block, so it starts at the nearest block its tile
// sees and stops after the farthest; tiles no block covers are not marched at all.
struct RangeImage {
  static constexpr int kTile = 8;
  int TW = 0, TH = 0;
  std::vector<float> near, far;  // per tile, metres along the optical axis; near > far: nothing to march
  size_t tile_of(int x, int y) const { return size_t(y / kTile) * size_t(TW) + size_t(x / kTile); }
};

RangeImage range_image(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                       const RaycastOptions& options) {
  constexpr int kTile = RangeImage::kTile;
  // The blocks the rays can read (the range image does not depend on their order): the map outgrows the view on
  // every real sequence. The rays look blocks up in the grid itself (VoxelBlockGrid::find is lock-free).
  const auto blocks = blocks_in_view(grid, camera, T_world_camera, options);
  // Each block is clipped against the near plane before it is projected: a block straddling the
  // near plane projects to a bounded region (its part in front of the plane), so it cannot widen every tile.
  const int W = camera.width, H = camera.height;
  RangeImage r;
  r.TW = (W + kTile - 1) / kTile, r.TH = (H + kTile - 1) / kTile;
  r.near.assign(size_t(r.TW) * r.TH, std::numeric_limits<float>::infinity());
  r.far.assign(size_t(r.TW) * r.TH, 0.0f);
  const int TW = r.TW, TH = r.TH;
  {
    const SE3 T_camera_world = T_world_camera.inverse();
    const Eigen::Matrix3d Rcw = T_camera_world.rotation();
    const Eigen::Vector3d tcw = T_camera_world.translation();
    const double B = grid.params().block_m(), near_m = options.min_depth_m, far_m = options.max_depth_m;
    const Eigen::Vector3d ex = Rcw.col(0) * B, ey = Rcw.col(1) * B, ez = Rcw.col(2) * B;
    // A block whose bounding sphere is wholly beyond the near or far plane, or beyond a side plane of the
    // slack-widened image (the bounds tested below), has every corner and near-plane crossing there too, so the
    // exact test below would drop it as well: dropping it first changes no tile, only the cost.
    const double radius = 0.8660254037844386 * B;
    const ViewSlab slab(camera, near_m, far_m);
    for (const auto& [c, block] : blocks) {
      (void)block;
      Eigen::Vector3d p[8];
      const Eigen::Vector3d p0 = Rcw * (Eigen::Vector3d(c.x, c.y, c.z) * B) + tcw;
      if (slab.ball_outside(p0 + 0.5 * (ex + ey + ez), radius)) continue;
      double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
      for (int k = 0; k < 8; ++k) {
        p[k] = p0 + double(k & 1) * ex + double((k >> 1) & 1) * ey + double(k >> 2) * ez;
        zmin = std::min(zmin, p[k].z());
        zmax = std::max(zmax, p[k].z());
      }
      if (zmax < near_m || zmin > far_m) continue;
      // Bounding box of the projection of the block's part in front of the near plane: the projections of its
      // corners in front and of the points where its edges cross the plane (a convex polytope in front of the
      // camera projects to the convex hull of its vertices' projections).
      double umin = std::numeric_limits<double>::infinity(), umax = -umin, vmin = umin, vmax = -umin;
      auto add = [&](const Eigen::Vector3d& q) {
        const double u = camera.fx * q.x() / q.z() + camera.cx, v = camera.fy * q.y() / q.z() + camera.cy;
        umin = std::min(umin, u), umax = std::max(umax, u);
        vmin = std::min(vmin, v), vmax = std::max(vmax, v);
      };
      for (int k = 0; k < 8; ++k) {
        if (p[k].z() >= near_m) add(p[k]);
        for (int axis = 0; axis < 3; ++axis) {
          const int j = k | (1 << axis);
          if (j == k) continue;  // each edge once, from its lower corner
          const double za = p[k].z() - near_m, zb = p[j].z() - near_m;
          if ((za < 0.0) != (zb < 0.0)) {
            Eigen::Vector3d q = p[k] + (za / (za - zb)) * (p[j] - p[k]);
            q.z() = near_m;
            add(q);
          }
        }
      }
      // Pixel x's ray passes through u = x; one pixel of slack covers rounding.
      if (umax < -1.0 || vmax < -1.0 || umin > W || vmin > H) continue;
      const int tx0 = std::max(0, int(std::floor(umin - 1.0)) / kTile);
      const int tx1 = std::min(TW - 1, int(std::min(std::ceil(umax + 1.0), double(W))) / kTile);
      const int ty0 = std::max(0, int(std::floor(vmin - 1.0)) / kTile);
      const int ty1 = std::min(TH - 1, int(std::min(std::ceil(vmax + 1.0), double(H))) / kTile);
      const float zn = float(std::max(zmin, near_m)), zf = float(zmax);
      for (int ty = ty0; ty <= ty1; ++ty)
        for (int tx = tx0; tx <= tx1; ++tx) {
          float& n = r.near[size_t(ty) * TW + tx];
          float& f = r.far[size_t(ty) * TW + tx];
          n = std::min(n, zn);
          f = std::max(f, zf);
        }
    }
  }

  return r;
}

// What every ray of one raycast shares, and the two per-pixel stages.
class RayCaster {
 public:
  RayCaster(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
            const RaycastOptions& options)
      : camera_(camera),
        options_(options),
        range_(range_image(grid, camera, T_world_camera, options)),
        voxel_m_(float(grid.params().voxel_m)),
        mu_m_(float(grid.params().truncation_m())),
        R_(T_world_camera.rotation().cast<float>()),
        R_cw_(R_.transpose()),
        o_vox_((T_world_camera.translation() / grid.params().voxel_m).cast<float>() - Eigen::Vector3f::Constant(0.5f)),
        march_{mu_m_, float(options.step_fraction), float(options.min_step_vox * grid.params().voxel_m), voxel_m_,
               float(options.refine_tol_vox * grid.params().voxel_m)} {}

  // Stage 2, GenericRaycast: marches pixel (x, y)'s ray (first around its hint, then over its tile's range);
  // true at a hit. *d_cam: the ray through the pixel at z = 1, *len its length.
  bool cast(VolumeSampler& sampler, int x, int y, Eigen::Vector3f* d_cam, float* len, Hit* hit) const {
    *d_cam = Eigen::Vector3f(float((x - camera_.cx) / camera_.fx), float((y - camera_.cy) / camera_.fy), 1.0f);
    *len = d_cam->norm();
    const Eigen::Vector3f d_vox = (R_ * (*d_cam / *len)) / voxel_m_;
    const float hint = options_.depth_hint != nullptr ? (*options_.depth_hint)(x, y) : 0.0f;
    if (hint > 0.0f && std::isfinite(hint)) {
      // The bracket around the depth this frame measured: a + to - crossing there is the surface.
      const float w = hf_raycast_hint_halfwidth(hint, mu_m_, voxel_m_);
      const float z0 = std::max(float(options_.min_depth_m), hint - w);
      const float z1 = std::min(float(options_.max_depth_m), hint + w);
      if (z0 <= hint && hint <= z1 &&
          march_from_hint(sampler, march_, o_vox_, d_vox, hint * *len, z0 * *len, z1 * *len, hit))
        return true;
    }
    const size_t tile = range_.tile_of(x, y);
    // One voxel of slack on both sides covers float rounding of the corner projections.
    const float z0 = std::max(float(options_.min_depth_m), range_.near[tile] - voxel_m_);
    const float z1 = std::min(float(options_.max_depth_m), range_.far[tile] + voxel_m_);
    return z0 < z1 && march(sampler, march_, o_vox_, d_vox, z0 * *len, z1 * *len, hit);
  }

  // Stage 3, the pixel write: depth, vertex, colour, normal and shading of a hit.
  void write_hit(VolumeSampler& sampler, int x, int y, const Eigen::Vector3f& d_cam, float len, const Hit& hit,
                 RaycastResult* out) const {
    const float z = hit.t / len;
    out->depth(x, y) = z;
    out->vertices(x, y) = hf_make_float4(d_cam.x() * z, d_cam.y() * z, z, 1.0f);
    float s = 0.0f;
    Eigen::Vector3f rgb(0.0f, 0.0f, 0.0f);
    if (options_.color && sampler.sdf_color(hit.p_vox, &s, &rgb)) {
      auto to8 = [](float c) { return std::uint8_t(std::clamp(c + 0.5f, 0.0f, 255.0f)); };
      out->color(x, y) = Rgb8{to8(rgb.x()), to8(rgb.y()), to8(rgb.z())};
    } else {
      out->color(x, y) = Rgb8{};
    }
    Eigen::Vector3f n_world;
    if (sampler.normal(hit.p_vox, &n_world)) {
      const Eigen::Vector3f n = R_cw_ * n_world;
      out->normals(x, y) = hf_make_float4(n.x(), n.y(), n.z(), 1.0f);
      if (options_.shade) {
        const hf_float4 to_cam = hf_make_float4(-d_cam.x() / len, -d_cam.y() / len, -1.0f / len, 0.0f);
        const auto g = std::uint8_t(255.0f * hf_headlight_shade(out->normals(x, y), to_cam) + 0.5f);
        out->shaded(x, y) = Rgb8{g, g, g};
      }
    } else {
      out->normals(x, y) = hf_invalid4();
      if (options_.shade) out->shaded(x, y) = Rgb8{40, 40, 40};
    }
  }

  // The pixel write of a miss (or of a pixel not cast).
  void write_miss(int x, int y, RaycastResult* out) const {
    out->depth(x, y) = 0.0f;
    out->vertices(x, y) = hf_invalid4();
    out->normals(x, y) = hf_invalid4();
    out->color(x, y) = Rgb8{};
    if (options_.shade) out->shaded(x, y) = Rgb8{};
  }

 private:
  const PinholeCamera& camera_;
  const RaycastOptions& options_;
  RangeImage range_;
  float voxel_m_, mu_m_;
  Eigen::Matrix3f R_, R_cw_;
  Eigen::Vector3f o_vox_;
  MarchParams march_;
};

}  // namespace

void raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
             const RaycastOptions& options, RaycastResult* out) {
  raycast_pixels(grid, camera, T_world_camera, options, nullptr, out);
}

void raycast_pixels(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                    const RaycastOptions& options, const Image<std::uint8_t>* rays, RaycastResult* out) {
  options.validate(camera);
  if (camera.width <= 0 || camera.height <= 0 || !(camera.fx > 0.0 && camera.fy > 0.0))
    throw Error("raycast: expected a camera with positive size and focal lengths, got " + camera.describe());
  if (!T_world_camera.is_finite()) throw Error("raycast: expected a finite T_world_camera");
  const int W = camera.width, H = camera.height;
  if (rays != nullptr && (rays->width() != W || rays->height() != H))
    throw Error("raycast: the ray mask is " + std::to_string(rays->width()) + "x" + std::to_string(rays->height()) +
                " but the camera is " + camera.describe());
  out->device_copies.clear();  // the images are written here, in place: a device's copies no longer mirror them
  ensure_size(&out->depth, W, H);
  ensure_size(&out->vertices, W, H);
  ensure_size(&out->normals, W, H);
  ensure_size(&out->color, W, H);
  if (options.shade)
    ensure_size(&out->shaded, W, H);
  else
    out->shaded = ColorImage();
  const RayCaster caster(grid, camera, T_world_camera, options);

  // Parallel over 16 x 16 pixel tiles rather than rows: neighbouring rays read the same voxels and find them still
  // in cache (the march is bound by memory latency, not arithmetic). Each pixel is written once: deterministic.
  constexpr int kWork = 16;
  const int WX = (W + kWork - 1) / kWork, WY = (H + kWork - 1) / kWork;
  std::vector<int> tile_hits(size_t(WX) * WY, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, WX * WY), [&](const tbb::blocked_range<int>& work) {
    VolumeSampler sampler(grid, options.min_weight, options.skip_blocks);
    for (int wi = work.begin(); wi != work.end(); ++wi) {
      const int x0 = (wi % WX) * kWork, y0 = (wi / WX) * kWork;
      const int x1 = std::min(x0 + kWork, W), y1 = std::min(y0 + kWork, H);
      int hits = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          Eigen::Vector3f d_cam;
          float len = 0.0f;
          Hit hit;
          if ((rays == nullptr || (*rays)(x, y) != 0) && caster.cast(sampler, x, y, &d_cam, &len, &hit)) {
            caster.write_hit(sampler, x, y, d_cam, len, hit, out);
            ++hits;
          } else {
            caster.write_miss(x, y, out);
          }
        }
      tile_hits[size_t(wi)] = hits;
    }
  });
  int total = 0;
  for (int h : tile_hits) total += h;
  out->hit_count = total;
}

ColorImage colored_shading(const RaycastResult& result) {
  const ColorImage& shaded = result.shaded;
  if (shaded.empty()) throw Error("colored_shading: the raycast has no shading (RaycastOptions::shade was off)");
  const bool has_color = result.color.width() == shaded.width() && result.color.height() == shaded.height();
  ColorImage out(shaded.width(), shaded.height());
  for (size_t i = 0; i < shaded.size(); ++i) {
    const Rgb8 g = shaded.pixels()[i];
    const Rgb8 c = has_color ? result.color.pixels()[i] : Rgb8{};
    if (c.r == 0 && c.g == 0 && c.b == 0) {
      out.pixels()[i] = g;  // no colour fused here (or a miss, which is black in both)
      continue;
    }
    const auto mod = [&](std::uint8_t channel) { return std::uint8_t((unsigned(channel) * g.r + 127u) / 255u); };
    out.pixels()[i] = Rgb8{mod(c.r), mod(c.g), mod(c.b)};
  }
  return out;
}

}  // namespace hf::fusion
