// Appearance codes (slam/appearance.h) over every registered method: retrieval of views of the synthetic room
// (exact ground truth), bad input, and the multiple-eigenspaces selection rule and rebuild schedule.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <memory>

#include "core/error.h"
#include "datasets/synthetic_sequence.h"
#include "slam/appearance.h"
#include "slam/appearance/eigenspaces.h"
#include "slam/appearance/ferns.h"

namespace hf::slam {
namespace {

// The room's orbit turns 0.22 rad/s: keyframes every 60 frames are 25 degrees of orbit apart and cover it.
constexpr int kKeyframeStep = 60;
constexpr int kKeyframes = 14;

datasets::SyntheticSequence room(std::uint64_t seed) {
  datasets::SyntheticOptions o;
  o.preset = "room";
  o.frames = kKeyframeStep * kKeyframes;
  o.seed = seed;
  o.camera = PinholeCamera::preset("ros").scaled(2);  // 160x120: fast to render, above every code's grid
  return datasets::SyntheticSequence(o);
}

// Rendered once for the whole file: keyframes (seed 0) and other realisations of the sensor noise (seed 1).
struct Views {
  std::map<int, datasets::SyntheticFrame> frames;  // by frame index, seed 0
  std::map<int, datasets::SyntheticFrame> noisy;   // same frames, seed 1
  static const Views& get() {
    static const Views v = [] {
      Views out;
      const datasets::SyntheticSequence a = room(0), b = room(1);
      for (int k = 0; k < kKeyframes; ++k) {
        const int i = k * kKeyframeStep;
        out.frames.emplace(i, a.frame(i));
        out.frames.emplace(i + 20, a.frame(i + 20));
        out.noisy.emplace(i, b.frame(i));
      }
      return out;
    }();
    return v;
  }
};

std::unique_ptr<AppearanceIndex> index_of_keyframes(const std::string& name) {
  std::unique_ptr<AppearanceIndex> index = make_appearance_index(name);
  for (int k = 0; k < kKeyframes; ++k) {
    const datasets::SyntheticFrame& f = Views::get().frames.at(k * kKeyframeStep);
    index->add(size_t(k), f.color, f.depth);
  }
  return index;
}

void expect_valid_ranking(const std::vector<AppearanceMatch>& m, size_t expected_size) {
  ASSERT_EQ(m.size(), expected_size);
  for (size_t i = 0; i < m.size(); ++i) {
    EXPECT_TRUE(std::isfinite(m[i].distance));
    EXPECT_GE(m[i].distance, 0.0);
    if (i > 0) {
      EXPECT_LE(m[i - 1].distance, m[i].distance);
    }
  }
}

class EveryAppearanceIndex : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryAppearanceIndex, KeyframeWithOtherSensorNoiseIsRankOne) {
  const std::unique_ptr<AppearanceIndex> index = index_of_keyframes(GetParam());
  EXPECT_EQ(index->size(), size_t(kKeyframes));
  EXPECT_GT(index->bytes_per_keyframe(), 0u);
  for (int k = 0; k < kKeyframes; ++k) {
    const datasets::SyntheticFrame& q = Views::get().noisy.at(k * kKeyframeStep);
    const std::vector<AppearanceMatch> m = index->query(q.color, q.depth, 5);
    expect_valid_ranking(m, 5);
    EXPECT_EQ(m[0].id, size_t(k)) << GetParam() << ": keyframe " << k;
  }
}

// A view 20 frames (8 degrees of orbit) after keyframe k: the best match is k or k + 1, the keyframes within
// one keyframe spacing of it.
TEST_P(EveryAppearanceIndex, NearbyViewRetrievesANeighbouringKeyframe) {
  const std::unique_ptr<AppearanceIndex> index = index_of_keyframes(GetParam());
  for (int k = 0; k < kKeyframes; ++k) {
    const datasets::SyntheticFrame& q = Views::get().frames.at(k * kKeyframeStep + 20);
    const std::vector<AppearanceMatch> m = index->query(q.color, q.depth, 1);
    ASSERT_EQ(m.size(), 1u);
    const int frame_of_match = int(m[0].id) * kKeyframeStep;
    EXPECT_LE(std::abs(frame_of_match - q.index), kKeyframeStep) << GetParam() << ": query frame " << q.index;
  }
}

TEST_P(EveryAppearanceIndex, BadPixelsAndEmptyIndexGiveFiniteAnswers) {
  const std::unique_ptr<AppearanceIndex> empty = make_appearance_index(GetParam());
  const datasets::SyntheticFrame& f = Views::get().frames.at(0);
  EXPECT_TRUE(empty->query(f.color, f.depth, 5).empty());
  EXPECT_EQ(empty->size(), 0u);

  const ColorImage black(f.color.width(), f.color.height());
  DepthImage nan_depth(f.depth.width(), f.depth.height(), std::numeric_limits<float>::quiet_NaN());
  nan_depth(3, 4) = std::numeric_limits<float>::infinity();
  const DepthImage no_depth(f.depth.width(), f.depth.height(), 0.0f);

  const std::unique_ptr<AppearanceIndex> index = make_appearance_index(GetParam());
  index->add(7, black, nan_depth);  // a degenerate keyframe among good ones must not poison the codes
  for (int k = 0; k < 4; ++k) {
    const datasets::SyntheticFrame& g = Views::get().frames.at(k * kKeyframeStep);
    index->add(size_t(k), g.color, g.depth);
  }
  index->add(8, ColorImage{}, f.depth);  // depth only
  expect_valid_ranking(index->query(black, nan_depth, 10), 6);
  expect_valid_ranking(index->query(black, no_depth, 3), 3);
  expect_valid_ranking(index->query(ColorImage{}, f.depth, 6), 6);
  expect_valid_ranking(index->query(ColorImage{}, DepthImage{}, 2), 2);
  expect_valid_ranking(index->query(f.color, nan_depth, 6), 6);
  // A tiny image (smaller than any code's grid) is coded, not rejected.
  expect_valid_ranking(index->query(ColorImage(3, 2, Rgb8{200, 10, 10}), DepthImage(3, 2, 1.5f), 1), 1);
  // The good keyframe still comes first for its own (noisy) view despite the degenerate ones.
  const datasets::SyntheticFrame& q = Views::get().noisy.at(kKeyframeStep);
  EXPECT_EQ(index->query(q.color, q.depth, 1).at(0).id, 1u);
}

TEST_P(EveryAppearanceIndex, SameInputSameAnswer) {
  const std::unique_ptr<AppearanceIndex> a = index_of_keyframes(GetParam()), b = index_of_keyframes(GetParam());
  const datasets::SyntheticFrame& q = Views::get().frames.at(3 * kKeyframeStep + 20);
  const std::vector<AppearanceMatch> ma = a->query(q.color, q.depth, kKeyframes),
                                     mb = b->query(q.color, q.depth, kKeyframes);
  ASSERT_EQ(ma.size(), mb.size());
  for (size_t i = 0; i < ma.size(); ++i) {
    EXPECT_EQ(ma[i].id, mb[i].id);
    EXPECT_EQ(ma[i].distance, mb[i].distance);
  }
}

INSTANTIATE_TEST_SUITE_P(Appearance, EveryAppearanceIndex, ::testing::ValuesIn(appearance_index_names()),
                         [](const auto& info) { return info.param; });

TEST(AppearanceRegistry, NamesAndDefault) {
  const std::vector<std::string> names = appearance_index_names();
  EXPECT_EQ(names, (std::vector<std::string>{"eigenspaces", "ferns", "thumbnail"}));
  EXPECT_NE(std::find(names.begin(), names.end(), default_appearance_index_name()), names.end());
  for (const std::string& n : names) EXPECT_EQ(make_appearance_index(n)->name(), n);
  try {
    make_appearance_index("bow");
    FAIL() << "no error for an unknown name";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("known: eigenspaces, ferns, thumbnail"), std::string::npos) << e.what();
  }
}

// Leonardis' selection rule: every keyframe is coded in the eigenspace that reconstructs it best, right after a
// build and for keyframes added between builds; the stored residual is that eigenspace's (float rounding).
// Two tight groups of views (9 frames 1.7 degrees of orbit apart, half an orbit between the groups) plus the 14
// scattered keyframes: the groups grow into real eigenspaces (dimension >= 1), the scattered views stay raw.
TEST(Eigenspaces, EachCodeIsInTheEigenspaceThatReconstructsItBest) {
  EigenspacesOptions o;
  o.residual_fraction = 0.2;  // looser than the default 0.1, at which these groups do not grow
  EigenspacesIndex index(o);
  const datasets::SyntheticSequence seq = room(0);
  for (int start : {100, 500})
    for (int i = start; i < start + 45; i += 5) {
      const datasets::SyntheticFrame f = seq.frame(i);
      index.add(size_t(i), f.color, f.depth);
    }
  for (int k = 0; k < kKeyframes; ++k) {
    const datasets::SyntheticFrame& f = Views::get().frames.at(k * kKeyframeStep);
    index.add(size_t(k * kKeyframeStep), f.color, f.depth);
  }
  ASSERT_GE(index.eigenspace_count(), 2u);
  int real = 0;
  for (size_t j = 0; j < index.eigenspace_count(); ++j) real += index.dimension(j) >= 1;
  EXPECT_GE(real, 1);
  for (size_t j = 0; j < index.eigenspace_count(); ++j) EXPECT_LE(index.dimension(j), o.max_dimension);
  for (size_t i = 0; i < index.size(); ++i) {
    const size_t own = index.eigenspace_of(i);
    const double r_own = index.residual(i, own);
    EXPECT_NEAR(index.code_residual(i), r_own, 1e-5 * (1.0 + r_own));
    for (size_t j = 0; j < index.eigenspace_count(); ++j)
      if (j != own) {
        EXPECT_LE(r_own, index.residual(i, j)) << "keyframe " << i << " eigenspace " << j;
      }
  }
}

// The thumbnails have squared norm 2 (intensity + depth parts), so a keyframe's residual is at most 2 in the
// eigenspace whose mean is 0 and no better than the raw thumbnail; an eigenspace grown around a keyframe and
// its neighbours reconstructs it within theta unless it stayed an outlier.
TEST(Eigenspaces, ResidualsAreBoundedAndMostCodesWithinTheta) {
  EigenspacesIndex index;
  for (int k = 0; k < kKeyframes; ++k) {
    const datasets::SyntheticFrame& f = Views::get().frames.at(k * kKeyframeStep);
    index.add(size_t(k), f.color, f.depth);
  }
  const double theta = EigenspacesOptions{}.residual_fraction * 2.0;
  int within = 0;
  for (size_t i = 0; i < index.size(); ++i) {
    EXPECT_GE(index.code_residual(i), 0.0);
    EXPECT_LE(index.code_residual(i), 4.0 * 2.0);
    within += index.code_residual(i) < theta;
  }
  EXPECT_GE(within, kKeyframes / 2);
}

// Rebuild schedule: on every add below min_build_size, then whenever the size reaches rebuild_factor times the
// size at the last build: 20 adds with 8 and 1.5 build at sizes 1..7, 11 and 17.
TEST(Eigenspaces, RebuildsGeometrically) {
  EigenspacesOptions o;
  EigenspacesIndex index(o);
  const datasets::SyntheticFrame& f = Views::get().frames.at(0);
  std::vector<size_t> builds;
  for (int i = 0; i < 20; ++i) {
    index.add(size_t(i), f.color, f.depth);
    builds.push_back(index.builds());
  }
  EXPECT_EQ(builds[6], 7u);
  EXPECT_EQ(builds[9], 7u);
  EXPECT_EQ(builds[10], 8u);
  EXPECT_EQ(builds[15], 8u);
  EXPECT_EQ(builds[16], 9u);
  EXPECT_EQ(builds[19], 9u);
}

TEST(Eigenspaces, BadOptionsNameTheField) {
  EigenspacesOptions o;
  o.rebuild_factor = 1.0;
  EXPECT_THROW(EigenspacesIndex{o}, Error);
  o = {};
  o.thumbnail.width = 0;
  EXPECT_THROW(EigenspacesIndex{o}, Error);
}

// Ferns are a function of the seed alone: same seed, same codes; another seed, other tests.
TEST(Ferns, CodesAreDeterministicBySeed) {
  const datasets::SyntheticFrame& f = Views::get().frames.at(0);
  FernsOptions o;
  const FernsIndex a(o), b(o);
  o.seed = 2;
  const FernsIndex c(o);
  const FernsIndex::Code ca = a.encode(f.color, f.depth), cb = b.encode(f.color, f.depth),
                         cc = c.encode(f.color, f.depth);
  EXPECT_EQ(ca.bits, cb.bits);
  EXPECT_NE(ca.bits, cc.bits);
  EXPECT_EQ(ca.bits.size(), size_t(o.ferns));
  // BlockHD of a frame to itself is 0 and to a black frame with no depth is the fraction of ferns with a bit set.
  FernsIndex index(FernsOptions{});
  index.add(0, f.color, f.depth);
  EXPECT_EQ(index.query(f.color, f.depth, 1).at(0).distance, 0.0);
  size_t set = 0;
  for (std::uint8_t bits : ca.bits) set += bits != 0;
  const double hd = index.query(ColorImage(f.color.width(), f.color.height()), DepthImage(), 1).at(0).distance;
  EXPECT_DOUBLE_EQ(hd, double(set) / o.ferns);
}

}  // namespace
}  // namespace hf::slam
