// A missing frame, a black colour frame and an unrelated colour frame in the middle of a real excerpt (TUM fr1/rpy,
// ../shared/data) cost at most the faulty frame itself and a few after it, for every registration (issue 13).
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <random>
#include <string>

#include "io/dataset.h"
#include "registration/registration.h"
#include "slam/pipeline.h"
#include "slam/sequence_run.h"
#include "tests/slam/pipeline_test_util.h"

namespace hf::slam {
namespace {

constexpr int kFrames = 16, kFault = 8;

// What happens to frame kFault: dropped (a missing frame), colour black, or colour replaced by random 16x16
// blocks (an image of something else).
enum class Fault { missing, black, alien };

std::unique_ptr<FrameSource> faulty(const std::string& dir, Fault fault) {
  auto modify = [fault](RgbdFrame& f) {
    if (f.index != size_t(kFault) || fault == Fault::missing) return;
    for (int y = 0; y < f.color.height(); ++y)
      for (int x = 0; x < f.color.width(); ++x) {
        std::mt19937 block(unsigned((y / 16) * 1000 + x / 16));
        f.color(x, y) = fault == Fault::black
                            ? Rgb8{}
                            : Rgb8{std::uint8_t(block()), std::uint8_t(block()), std::uint8_t(block())};
      }
  };
  auto drop = [fault](const RgbdFrame& f) { return fault == Fault::missing && f.index == size_t(kFault); };
  return std::make_unique<test::ModifiedSource>(open_dataset(dir), modify, drop);
}

// One test per registry method (each runs its three faults), so CTest spreads the methods over the cores.
class RealFaults : public ::testing::TestWithParam<std::string> {};

TEST_P(RealFaults, CostAtMostTheFaultyFrame) {
  const std::string dir = std::string(HF_SHARED_DIR) + "/data/tum_fr1_rpy_first150";
  if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << dir << " is absent (../shared/data not beside the repo)";
  const std::string& method = GetParam();
  for (Fault fault : {Fault::missing, Fault::black, Fault::alien}) {
    SCOPED_TRACE(method + ", fault " + std::to_string(int(fault)));
    const std::unique_ptr<FrameSource> faulty_source = faulty(dir, fault);
    FrameSource& source = *faulty_source;
    PipelineConfig c;
    c.registration = method;
    c.volume.capacity_blocks = 1 << 16;
    Pipeline pipeline(c, source.camera());
    RunControl control;
    control.max_frames = kFrames;
    const SequenceRun run = run_sequence(source, pipeline, control);
    ASSERT_GE(run.frames.size(), size_t(kFrames - 1));
    long lost_after = 0;
    for (const FrameResult& f : run.frames) {
      EXPECT_TRUE(f.T_world_camera.matrix().allFinite());
      if (f.state == TrackState::lost && f.index > size_t(kFault)) ++lost_after;
      // Frames before the fault are never lost on this excerpt.
      if (f.index < size_t(kFault)) {
        EXPECT_NE(f.state, TrackState::lost) << f.index << ": " << f.message;
      }
    }
    // The faulty frame and at most two after it.
    EXPECT_LE(lost_after, 2);
    const RunSummary s = summarize(run, pipeline, source, "faults");
    ASSERT_TRUE(s.ate_rmse_m());
    // Over every frame; the clean excerpt reads 0.7-1.7 cm over these frames, a frame frozen far off would not.
    EXPECT_LT(*s.ate_rmse_m(), 0.03);
  }
}

INSTANTIATE_TEST_SUITE_P(EveryRegistration, RealFaults, ::testing::ValuesIn(registration_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& ch : name)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return name;
                         });

}  // namespace
}  // namespace hf::slam
