// Synthetic sequences: determinism, exact geometry against the scene's signed distance, and what each hard
// preset promises (motion per frame, missing fraction, exposure changes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image.h"
#include "datasets/presets.h"
#include "datasets/sensor_noise.h"
#include "datasets/synthetic_sequence.h"
#include "datasets/synthetic_source.h"

namespace hf::datasets {
namespace {

using Eigen::Vector3d;

SyntheticOptions small(const std::string& preset, int frames = 10, std::uint64_t seed = 0) {
  SyntheticOptions o;
  o.preset = preset;
  o.frames = frames;
  o.seed = seed;
  o.camera = PinholeCamera::preset("ros").scaled(2);  // 160x120: the tests do not need full resolution
  return o;
}

double fraction_missing(const DepthImage& d) {
  return double(std::count(d.pixels().begin(), d.pixels().end(), 0.0f)) / double(d.size());
}

double mean_intensity(const ColorImage& c) {
  const IntensityImage i = intensity_from_color(c);
  double s = 0;
  for (float v : i.pixels()) s += v;
  return s / double(i.size());
}

TEST(SyntheticSequence, SameSeedSameBytesDifferentSeedDifferentNoise) {
  const SyntheticSequence a(small("room", 10, 3)), b(small("room", 10, 3)), c(small("room", 10, 4));
  const SyntheticFrame fa = a.frame(7), fb = b.frame(7), fc = c.frame(7);
  EXPECT_EQ(fa.depth.pixels(), fb.depth.pixels());
  EXPECT_EQ(fa.color.pixels(), fb.color.pixels());
  EXPECT_NE(fa.depth.pixels(), fc.depth.pixels());
  EXPECT_NE(fa.color.pixels(), fc.color.pixels());
  // Only the noise differs: same pose, same exact depth.
  EXPECT_EQ(fa.depth_clean.pixels(), fc.depth_clean.pixels());
  EXPECT_TRUE(fa.T_world_camera.matrix().isApprox(fc.T_world_camera.matrix(), 0.0));
  // Frames are independent of rendering order.
  const SyntheticFrame f3_first = a.frame(3);
  (void)a.frame(8);
  EXPECT_EQ(a.frame(3).depth.pixels(), f3_first.depth.pixels());
  // Consecutive frames differ in noise, not only in pose (the realisation depends on the frame index).
  SyntheticOptions still = small("room", 2);
  EXPECT_NE(SyntheticSequence(still).frame(0).depth.pixels(), SyntheticSequence(still).frame(1).depth.pixels());
}

TEST(SyntheticSequence, TimestampsAt30Hz) {
  const SyntheticSequence s(small("room", 100));
  EXPECT_EQ(s.timestamp_s(0), 0.0);
  EXPECT_NEAR(s.timestamp_s(1), 1.0 / 30.0, 1e-6);
  EXPECT_NEAR(s.timestamp_s(99), 99.0 / 30.0, 1e-6);
  EXPECT_EQ(s.frame(30).timestamp_s, 1.0);
}

TEST(SyntheticSequence, NoNoiseGivesExactDepth) {
  SyntheticOptions o = small("room", 5);
  o.noise_enabled = false;
  const SyntheticFrame f = SyntheticSequence(o).frame(2);
  EXPECT_EQ(f.depth.pixels(), f.depth_clean.pixels());
  EXPECT_EQ(fraction_missing(f.depth), 0.0);  // a closed room: every ray hits
}

// Back-projecting depth with the ground-truth pose lands on the scene surface.
TEST(SyntheticSequence, BackProjectedDepthLiesOnTheSurface) {
  for (const std::string preset : {"room", "corridor", "wall", "sphere"}) {
    const SyntheticSequence seq(small(preset, 40, 1));
    const SyntheticFrame f = seq.frame(31);
    const PinholeCamera& cam = seq.camera();
    std::vector<double> clean_err, noisy_err;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        if (f.depth_clean(x, y) > 0.0f) {
          const Vector3d p = f.T_world_camera * cam.backproject(x, y, f.depth_clean(x, y));
          clean_err.push_back(std::abs(seq.scene().sdf(p)));
        }
        if (f.depth(x, y) > 0.0f) {
          // In units of the model's axial standard deviation at that depth (with the rounding's share).
          const double z = f.depth(x, y), q = quantisation_step_m(z), sz = axial_sigma_m(z, 0.0);
          const Vector3d p = f.T_world_camera * cam.backproject(x, y, z);
          noisy_err.push_back(std::abs(seq.scene().sdf(p)) / std::sqrt(sz * sz + q * q / 12.0));
        }
      }
    ASSERT_GT(noisy_err.size(), size_t(cam.width * cam.height / 5)) << preset;
    // Float depth: relative precision 6e-8, at most ~10 m here.
    EXPECT_LT(*std::max_element(clean_err.begin(), clean_err.end()), 2e-6) << preset;
    // With noise: the distance to the surface is at most the axial error (less on slanted surfaces), whose
    // median is 0.67 sigma for a Gaussian; lateral shifts add errors only near depth edges.
    std::sort(noisy_err.begin(), noisy_err.end());
    EXPECT_LT(noisy_err[noisy_err.size() / 2], 0.8) << preset;
    EXPECT_LT(noisy_err[noisy_err.size() * 95 / 100], 4.0) << preset;
  }
}

TEST(Presets, UnknownNameListsTheKnownOnes) {
  try {
    SyntheticSequence s(small("kitchen"));
    FAIL();
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'kitchen'"), std::string::npos) << m;
    for (const auto& n : preset_names()) EXPECT_NE(m.find(n), std::string::npos) << m;
  }
  EXPECT_EQ(preset_names().size(), 11u);
  for (const auto& n : preset_names()) EXPECT_FALSE(make_preset(n).description.empty()) << n;
}

TEST(Presets, BadOptionsAreRejected) {
  SyntheticOptions o = small("room");
  o.frames = 0;
  EXPECT_THROW(SyntheticSequence{o}, Error);
  o.frames = -3;
  EXPECT_THROW(SyntheticSequence{o}, Error);
  o = small("room");
  o.camera.width = 0;
  EXPECT_THROW(SyntheticSequence{o}, Error);
  const SyntheticSequence s(small("room", 3));
  EXPECT_THROW(s.frame(3), Error);
  EXPECT_THROW(s.frame(-1), Error);
}

TEST(Presets, FastMoves15DegreesAnd10CentimetresPerFrame) {
  const SyntheticSequence s(small("fast", 30));
  for (int i = 0; i + 1 < s.size(); ++i) {
    const SE3 delta = s.T_world_camera(i).inverse() * s.T_world_camera(i + 1);
    EXPECT_NEAR(delta.angle_rad() * 180.0 / std::numbers::pi, 15.0, 1e-6);
    EXPECT_NEAR(delta.translation().norm(), 0.10, 1e-9);
  }
  // And the views stay inside the room, mostly within the sensor's range.
  const SyntheticFrame f = s.frame(5);
  EXPECT_LT(fraction_missing(f.depth), 0.2);
}

TEST(Presets, OtherPresetsMoveSmoothly) {
  for (const std::string preset : {"room", "wall", "corridor", "sphere", "textureless", "holes", "exposure"}) {
    const SyntheticSequence s(small(preset, 300));
    for (int i = 0; i + 1 < s.size(); i += 7) {
      const SE3 delta = s.T_world_camera(i).inverse() * s.T_world_camera(i + 1);
      EXPECT_LT(delta.angle_rad(), 2.0 * std::numbers::pi / 180.0) << preset << " " << i;
      EXPECT_LT(delta.translation().norm(), 0.05) << preset << " " << i;
    }
  }
}

TEST(Presets, HolesMissAboutThirtyPercent) {
  SyntheticOptions only_holes = small("holes", 3);
  NoiseOptions o = NoiseOptions::none();
  o.hole_fraction = 0.3;
  only_holes.noise = o;
  EXPECT_NEAR(fraction_missing(SyntheticSequence(only_holes).frame(1).depth), 0.3, 1e-4);
  // The full preset: holes on top of the ordinary dropouts (edges, grazing, range) of the room.
  const double room = fraction_missing(SyntheticSequence(small("room", 3)).frame(1).depth);
  const double holes = fraction_missing(SyntheticSequence(small("holes", 3)).frame(1).depth);
  EXPECT_NEAR(holes, room + 0.3 * (1.0 - room), 0.03);
}

TEST(Presets, ExposureChangesMeanIntensity) {
  const SyntheticSequence exposure(small("exposure", 10)), room(small("room", 10));
  std::vector<double> ratios;
  for (int i = 0; i < 6; ++i) {
    const SyntheticFrame e = exposure.frame(i), r = room.frame(i);
    EXPECT_EQ(e.depth_clean.pixels(), r.depth_clean.pixels());  // same geometry and poses
    ratios.push_back(mean_intensity(e.color) / mean_intensity(r.color));
  }
  const auto [lo, hi] = std::minmax_element(ratios.begin(), ratios.end());
  EXPECT_GT(*hi - *lo, 0.3) << "the gain must vary by tens of percent between frames";
  for (double r : ratios) EXPECT_TRUE(r > 0.5 && r < 1.5) << r;
  // The room itself keeps its brightness between neighbouring frames (smooth motion, constant lighting).
  EXPECT_NEAR(mean_intensity(room.frame(0).color), mean_intensity(room.frame(1).color), 0.01);
}

TEST(Presets, TexturelessHasNoTextureGradients) {
  // Without noise, neighbouring pixels on one face of the uniform room have the same colour; only shading on
  // curved objects and face boundaries change it. Count horizontal colour changes against the textured room.
  auto changes = [](const std::string& preset) {
    SyntheticOptions o = small(preset, 1);
    o.noise_enabled = false;
    const ColorImage c = SyntheticSequence(o).frame(0).color;
    int n = 0;
    for (int y = 0; y < c.height(); ++y)
      for (int x = 0; x + 1 < c.width(); ++x) n += !(c(x, y) == c(x + 1, y));
    return n;
  };
  const int textureless = changes("textureless"), room = changes("room");
  EXPECT_LT(textureless * 5, room) << textureless << " vs " << room;
}

TEST(Presets, SphereHelpersLookAtTheCentre) {
  for (const auto& poses :
       {ring_poses(kSphereCentre, 1.5, 12, 0.3), hemisphere_poses(kSphereCentre, 2.0, 20)}) {
    for (const SE3& T : poses) {
      const Vector3d c_camera = T.inverse() * kSphereCentre;
      EXPECT_NEAR(c_camera.x(), 0.0, 1e-9);
      EXPECT_NEAR(c_camera.y(), 0.0, 1e-9);
      EXPECT_GT(c_camera.z(), 1.0);
      EXPECT_TRUE(T.is_finite());
    }
  }
  const auto hemi = hemisphere_poses(kSphereCentre, 2.0, 20);
  for (const SE3& T : hemi) EXPECT_GT(T.translation().z(), 2.0 * std::sin(0.17));
  // The sphere preset renders the analytic sphere: sdf is the distance to it.
  const SyntheticSequence s(small("sphere", 1));
  EXPECT_NEAR(s.scene().sdf({1.0, 0.0, 0.0}), 1.0 - kSphereRadius_m, 1e-15);
}

TEST(SyntheticSource, YieldsEveryFrameWithGroundTruthThenEnd) {
  SyntheticOptions o = small("room", 3, 2);
  auto source = open_synthetic_input("synthetic:wall", o);
  ASSERT_EQ(source->size(), 3u);
  EXPECT_EQ(source->ground_truth().size(), 3u);
  EXPECT_NE(source->name().find("wall"), std::string::npos);
  const SyntheticSequence direct(small("wall", 3, 2));
  for (int i = 0; i < 3; ++i) {
    FrameRead r = source->next();
    ASSERT_EQ(r.status, FrameStatus::ok);
    EXPECT_EQ(r.frame.index, size_t(i));
    ASSERT_TRUE(r.frame.T_world_camera_gt.has_value());
    const SyntheticFrame f = direct.frame(i);
    EXPECT_EQ(r.frame.depth.pixels(), f.depth.pixels());
    EXPECT_EQ(r.frame.color.pixels(), f.color.pixels());
    EXPECT_EQ(r.frame.timestamp_s, f.timestamp_s);
    EXPECT_EQ(r.frame.depth.width(), source->camera().width);
  }
  EXPECT_EQ(source->next().status, FrameStatus::end);
  EXPECT_EQ(source->next().status, FrameStatus::end);
  EXPECT_TRUE(is_synthetic_input("synthetic:room"));
  EXPECT_FALSE(is_synthetic_input("data/rgbd_dataset"));
  EXPECT_THROW(open_synthetic_input("synthetic:nope", o), Error);
}


// `unregistered`: the depth is the room's, frame for frame; the colour is the image of a camera 2.5 cm aside with a
// 0.9x focal length, so it differs from the room's where the scene is textured, and matches what that camera sees.
TEST(Presets, UnregisteredColourComesFromTheColourCamera) {
  SyntheticOptions o = small("unregistered", 3);
  o.noise_enabled = false;
  SyntheticOptions r = o;
  r.preset = "room";
  const SyntheticSequence unreg(o), room(r);
  const Preset p = make_preset("unregistered");
  EXPECT_FALSE(p.colour_registered());
  EXPECT_TRUE(make_preset("room").colour_registered());
  const SyntheticFrame a = unreg.frame(2), b = room.frame(2);
  ASSERT_EQ(a.depth.size(), b.depth.size());
  for (size_t i = 0; i < a.depth.size(); ++i) ASSERT_EQ(a.depth.pixels()[i], b.depth.pixels()[i]) << i;
  // What the colour camera itself renders, without noise and at gain 1: the frame's colour exactly.
  PinholeCamera cc = o.camera;
  cc.fx *= p.colour_focal_scale;
  cc.fy *= p.colour_focal_scale;
  const ColorImage expected = finish_colour(
      render_view(p.scene, cc, a.T_world_camera * p.T_depth_colour, p.lighting).color, 1.0, 0.0, o.seed, 2);
  ASSERT_EQ(expected.size(), a.color.size());
  long differ_from_room = 0;
  for (size_t i = 0; i < a.color.size(); ++i) {
    const Rgb8& x = a.color.pixels()[i];
    const Rgb8& y = expected.pixels()[i];
    ASSERT_TRUE(x.r == y.r && x.g == y.g && x.b == y.b) << i;
    const Rgb8& z = b.color.pixels()[i];
    differ_from_room += (x.r != z.r || x.g != z.g || x.b != z.b) ? 1 : 0;
  }
  // Most pixels see another texel: a 10 % zoom moves everything but the centre by pixels.
  EXPECT_GT(differ_from_room, long(a.color.size() / 2));
}

}  // namespace
}  // namespace hf::datasets
