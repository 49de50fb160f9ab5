#include "core/push_pull.h"

#include "core/kernels/image_kernels.h"
#include "core/kernels/push_pull_kernels.h"
#include "core/parallel.h"

namespace hf {

const char* to_string(PushPullStatus status) {
  switch (status) {
    case PushPullStatus::ok: return "ok";
    case PushPullStatus::dropped_non_finite: return "dropped_non_finite";
    case PushPullStatus::no_samples: return "no_samples";
    case PushPullStatus::empty_image: return "empty_image";
    case PushPullStatus::bad_channels: return "bad_channels";
  }
  return "unknown";
}

std::vector<PushPullLevel> push_pull_levels(int width, int height, const PushPullOptions& options) {
  std::vector<PushPullLevel> levels{{width, height}};
  while ((width > 1 || height > 1) && (options.max_levels < 0 || int(levels.size()) <= options.max_levels)) {
    width = (width + 1) / 2;
    height = (height + 1) / 2;
    levels.push_back({width, height});
  }
  return levels;
}

namespace {

// Level 0 as push_pull_prepare_pixel leaves it; returns the number of dropped non-finite samples.
long prepare(int pixels, int channels, float* values, std::uint8_t* mask) {
  long dropped = 0;
  for (int i = 0; i < pixels; ++i) dropped += hf_push_pull_prepare_pixel(values, mask, channels, i);
  return dropped;
}

long count_set(const std::uint8_t* mask, long n) {
  long set = 0;
  for (long i = 0; i < n; ++i) set += mask[i] != 0;
  return set;
}

}  // namespace

PushPullResult push_pull_prepare(int width, int height, int channels, float* values, std::uint8_t* mask,
                                 long* samples) {
  PushPullResult result;
  *samples = 0;
  if (width < 1 || height < 1 || values == nullptr || mask == nullptr) {
    result.status = PushPullStatus::empty_image;
    return result;
  }
  if (channels < 1 || channels > 4) {
    result.status = PushPullStatus::bad_channels;
    return result;
  }
  const long pixels = long(width) * height;
  result.dropped_non_finite = prepare(int(pixels), channels, values, mask);
  *samples = count_set(mask, pixels);
  if (*samples == 0) {
    result.status = PushPullStatus::no_samples;
    result.empty_pixels = pixels;
    return result;
  }
  result.status = result.dropped_non_finite > 0 ? PushPullStatus::dropped_non_finite : PushPullStatus::ok;
  return result;
}

void push_pull_finish(const std::uint8_t* mask, long pixels, long samples, PushPullResult* result) {
  const long filled = count_set(mask, pixels);
  result->filled_pixels = filled - samples;
  result->empty_pixels = pixels - filled;
}

PushPullResult push_pull_fill(int width, int height, int channels, float* values, std::uint8_t* mask,
                              const PushPullOptions& options) {
  long samples = 0;
  PushPullResult result = push_pull_prepare(width, height, channels, values, mask, &samples);
  if (!push_pull_filled(result.status)) return result;

  const std::vector<PushPullLevel> levels = push_pull_levels(width, height, options);
  const int L = int(levels.size()) - 1;
  std::vector<std::vector<float>> level_values(levels.size());
  std::vector<std::vector<std::uint8_t>> level_masks(levels.size());
  auto values_of = [&](int l) { return l == 0 ? values : level_values[l].data(); };
  auto mask_of = [&](int l) { return l == 0 ? mask : level_masks[l].data(); };
  for (int l = 1; l <= L; ++l) {
    level_values[l].assign(size_t(levels[l].width) * levels[l].height * channels, 0.0f);
    level_masks[l].assign(size_t(levels[l].width) * levels[l].height, 0);
  }
  // Push: level l+1 from level l, coarsest last.
  for (int l = 0; l < L; ++l) {
    const PushPullLevel fine = levels[l], coarse = levels[l + 1];
    float* fv = values_of(l);
    std::uint8_t* fm = mask_of(l);
    float* cv = values_of(l + 1);
    std::uint8_t* cm = mask_of(l + 1);
    parallel_for_rows(coarse.height, [&](int y) {
      for (int x = 0; x < coarse.width; ++x) hf_push_pixel(fv, fm, fine.width, fine.height, channels, cv, cm, x, y);
    });
  }
  // Pull: level l from level l+1, level 0 last.
  for (int l = L - 1; l >= 0; --l) {
    const PushPullLevel fine = levels[l], coarse = levels[l + 1];
    float* fv = values_of(l);
    std::uint8_t* fm = mask_of(l);
    const float* cv = values_of(l + 1);
    const std::uint8_t* cm = mask_of(l + 1);
    parallel_for_rows(fine.height, [&](int y) {
      for (int x = 0; x < fine.width; ++x) hf_pull_pixel(fv, fm, fine.width, channels, cv, cm, coarse.width, x, y);
    });
  }
  result.levels = L;
  push_pull_finish(mask, long(width) * height, samples, &result);
  return result;
}

PushPullResult push_pull_fill_depth(DepthImage& depth, const PushPullOptions& options) {
  std::vector<std::uint8_t> mask(depth.size());
  for (size_t i = 0; i < depth.size(); ++i) mask[i] = hf_depth_is_valid(depth.pixels()[i]) ? 1 : 0;
  // Negative depths are not samples either; prepare only drops non-finite ones, so clear them here.
  for (size_t i = 0; i < depth.size(); ++i)
    if (!mask[i]) depth.pixels()[i] = 0.0f;
  return push_pull_fill(depth.width(), depth.height(), 1, depth.data(), mask.data(), options);
}

}  // namespace hf
