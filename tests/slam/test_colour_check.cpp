// The colour-registration check (slam/colour_check.h): the disagreement statistic against its closed form, the
// window's median decision, and the pipeline on the `unregistered` preset (colour from a camera 2.5 cm aside with a
// 0.9x focal length) against the `room` preset it is rendered from.
#include "slam/colour_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "datasets/synthetic_sequence.h"
#include "datasets/synthetic_source.h"
#include "pipeline_test_util.h"
#include "slam/pipeline.h"
#include "slam/sequence_run.h"
#include "tests/common/sanitizer.h"

namespace hf::slam {
namespace {

RegistrationResult::Term term(const char* name, const Matrix6d& information, const Vector6d& step, double cost,
                              long rows) {
  RegistrationResult::Term t;
  t.name = name;
  t.information = information;
  t.step = step;
  t.cost = cost;
  t.rows = rows;
  return t;
}

Matrix6d spd(double scale, int seed) {
  Matrix6d a = Matrix6d::Random();
  for (int i = 0; i < seed; ++i) a = a * Matrix6d::Random() * 0.5;
  return scale * (a * a.transpose() + Matrix6d::Identity());
}

TEST(TermDisagreement, MatchesTheClosedForm) {
  std::srand(3);
  const Matrix6d Hi = spd(1e4, 1), Hp = spd(2e2, 2);
  Vector6d si, sp;
  si << 1e-3, -2e-3, 5e-4, 0.01, -0.02, 0.003;
  sp << -1e-3, 1e-3, 0.0, -0.01, 0.01, 0.02;
  RegistrationResult r;
  // sigma^2 = cost / rows: 4e-6 and 25.
  r.terms = {term("icp", Hi, si, 4e-6 * 1000, 1000), term("photometric", Hp, sp, 25.0 * 500, 500)};
  const TermDisagreement t = term_disagreement(r);
  ASSERT_TRUE(t.valid);
  const Vector6d d = sp - si;
  const Matrix6d S = 4e-6 * Hi.inverse() + 25.0 * Hp.inverse();
  const double expected = d.dot(S.inverse() * d);
  EXPECT_NEAR(t.chi2, expected, 1e-9 * expected);
  EXPECT_NEAR(t.translation_m, d.tail<3>().norm(), 1e-15);
  EXPECT_NEAR(t.rotation_deg, d.head<3>().norm() * 180.0 / M_PI, 1e-12);
  EXPECT_NEAR(t.sigma_icp_m, 2e-3, 1e-15);
  EXPECT_NEAR(t.sigma_photometric, 5.0, 1e-12);
}

TEST(TermDisagreement, AgreeingTermsReadZero) {
  RegistrationResult r;
  Vector6d s;
  s << 1e-3, 0, 0, 0.01, 0, 0;
  r.terms = {term("icp", Matrix6d::Identity() * 1e3, s, 1.0, 100),
             term("photometric", Matrix6d::Identity() * 10, s, 2.0, 100)};
  const TermDisagreement t = term_disagreement(r);
  ASSERT_TRUE(t.valid);
  EXPECT_EQ(t.chi2, 0.0);
}

// A direction one term leaves free (a corridor's axis for icp) carries a huge covariance: disagreement along it is
// no evidence, so chi2 stays finite and small.
TEST(TermDisagreement, AFreeDirectionOfOneTermIsNoEvidence) {
  RegistrationResult r;
  Matrix6d Hi = Matrix6d::Identity() * 1e4;
  Hi(3, 3) = 0.0;  // x translation unconstrained by icp
  Vector6d si = Vector6d::Zero(), sp = Vector6d::Zero();
  sp(3) = 0.05;    // the photometric optimum 5 cm along it
  r.terms = {term("icp", Hi, si, 1e-6 * 100, 100), term("photometric", Matrix6d::Identity() * 1e4, sp, 1.0, 100)};
  const TermDisagreement t = term_disagreement(r);
  ASSERT_TRUE(t.valid);
  EXPECT_TRUE(std::isfinite(t.chi2));
  // The free eigenvalue is raised to 1e-9 of the largest (1e4): icp's covariance there is 1e-6 / 1e-5 = 0.1 m^2,
  // so 5 cm reads at most 0.05^2 / 0.1 = 0.025, three orders below any threshold of interest.
  EXPECT_LE(t.chi2, 0.05 * 0.05 / (1e-6 / (1e-9 * 1e4)) * (1.0 + 1e-9));

}

TEST(TermDisagreement, MissingOrBrokenTermsAreInvalidNeverNaN) {
  RegistrationResult r;
  EXPECT_FALSE(term_disagreement(r).valid);  // no terms (a single-term method)
  r.terms = {term("icp", Matrix6d::Identity(), Vector6d::Zero(), 1.0, 100)};
  EXPECT_FALSE(term_disagreement(r).valid);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Matrix6d bad = Matrix6d::Identity();
  bad(2, 2) = nan;
  r.terms = {term("icp", bad, Vector6d::Zero(), 1.0, 100),
             term("photometric", Matrix6d::Identity(), Vector6d::Zero(), 1.0, 100)};
  EXPECT_FALSE(term_disagreement(r).valid);
  r.terms = {term("icp", Matrix6d::Zero(), Vector6d::Zero(), 1.0, 100),
             term("photometric", Matrix6d::Identity(), Vector6d::Zero(), 1.0, 100)};
  EXPECT_FALSE(term_disagreement(r).valid);  // no information at all
  r.terms = {term("icp", Matrix6d::Identity(), Vector6d::Zero(), 0.0, 100),
             term("photometric", Matrix6d::Identity(), Vector6d::Zero(), 1.0, 100)};
  EXPECT_FALSE(term_disagreement(r).valid);  // zero residual: no noise estimate
  r.terms = {term("icp", Matrix6d::Identity(), Vector6d::Zero(), 1.0, 3),
             term("photometric", Matrix6d::Identity(), Vector6d::Zero(), 1.0, 100)};
  EXPECT_FALSE(term_disagreement(r).valid);  // fewer rows than unknowns
}

ColourAlignment estimate(double scale) {
  ColourAlignment a;
  a.valid = true;
  a.scale = scale;
  return a;
}

TEST(ColourCheck, DecidesByTheWindowsMedianOnce) {
  ColourCheckOptions o;
  o.window_estimates = 5;
  o.frame_step = 2;
  o.max_scale_error = 0.05;
  ColourCheck c(o);
  EXPECT_TRUE(c.wants(0));
  EXPECT_FALSE(c.wants(1));
  EXPECT_FALSE(c.add(ColourAlignment{}, 0));  // an invalid estimate does not count
  EXPECT_FALSE(c.add(estimate(0.5), 2));       // one alien colour frame
  EXPECT_FALSE(c.add(estimate(1.01), 4));
  EXPECT_FALSE(c.add(estimate(0.6), 6));       // and another
  EXPECT_FALSE(c.add(estimate(0.99), 8));
  EXPECT_EQ(c.verdict(), ColourVerdict::undecided);
  EXPECT_TRUE(c.add(estimate(1.0), 10));
  EXPECT_EQ(c.verdict(), ColourVerdict::registered);  // median of {0.5, 0.6, 0.99, 1.0, 1.01} = 0.99
  EXPECT_DOUBLE_EQ(c.median_scale(), 0.99);
  EXPECT_EQ(c.decided_at_frame(), 10u);
  EXPECT_FALSE(c.wants(12));                // taken once
  EXPECT_FALSE(c.add(estimate(0.5), 12));
  EXPECT_EQ(c.verdict(), ColourVerdict::registered);

  ColourCheck u(o);
  for (int i = 0; i < 4; ++i) EXPECT_FALSE(u.add(estimate(0.88 + 0.01 * i), size_t(2 * i)));
  EXPECT_TRUE(u.add(estimate(1.0), 8));
  EXPECT_EQ(u.verdict(), ColourVerdict::unregistered);
  EXPECT_DOUBLE_EQ(u.median_scale(), 0.90);
  o.enabled = false;
  EXPECT_FALSE(ColourCheck(o).wants(0));
}

TEST(ColourCheck, BadOptionsAreRejected) {
  const auto bad = [](auto change) {
    ColourCheckOptions o;
    change(o);
    return o;
  };
  EXPECT_THROW(ColourCheck{bad([](ColourCheckOptions& o) { o.window_estimates = 0; })}, Error);
  EXPECT_THROW(ColourCheck{bad([](ColourCheckOptions& o) { o.frame_step = 0; })}, Error);
  EXPECT_THROW(ColourCheck{bad([](ColourCheckOptions& o) { o.max_scale_error = std::nan(""); })}, Error);
  EXPECT_THROW(ColourCheck{bad([](ColourCheckOptions& o) { o.max_zoom = 1.0; })}, Error);
  EXPECT_THROW(ColourCheck{bad([](ColourCheckOptions& o) { o.max_chamfer_px = 9.0; })}, Error);
  EXPECT_THROW(ColourCheck{bad([](ColourCheckOptions& o) { o.depth_only_registration.clear(); })}, Error);
  PipelineConfig c;
  c.colour_check.depth_only_registration = "nope";
  EXPECT_THROW(c.validate(), Error);
}

// The first level of the pipeline's tracking pyramid (320x240) of one synthetic frame, without sensor noise.
FramePyramidLevel tracking_level(const std::string& preset, int frame) {
  datasets::SyntheticOptions o = test::half_res(preset, frame + 1);
  o.camera = PinholeCamera::preset("ros");  // 640x480, tracked from its 320x240 level as the pipeline does
  o.noise_enabled = false;
  const datasets::SyntheticSequence seq(o);
  const datasets::SyntheticFrame f = seq.frame(frame);
  FramePyramidOptions po;
  po.first_level = 1;
  return build_frame_pyramid(f.depth, &f.color, seq.camera(), po).levels[0];
}

// The room's colour is its depth camera's: s = 1, read within half the decision threshold (synthetic frames read
// 0.975-1.0: contours on their nearer pixel sit half a pixel towards the objects, mostly towards the image
// centre). The unregistered preset's colour camera has 0.9x the focal length (525 / 585 = 0.897); its 2.5 cm
// baseline adds a depth-dependent shift that no similarity fits, so s is read within 0.045 of it (0.857-0.902
// measured), always beyond the threshold.
TEST(ColourAlignmentEstimate, ReadsTheColourCamerasZoom) {
  const ColourCheckOptions o;
  for (int frame : {0, 20, 40}) {
    const ColourAlignment room = estimate_colour_alignment(tracking_level("room", frame), o);
    ASSERT_TRUE(room.valid) << frame << " chamfer " << room.chamfer_px << " edges " << room.depth_edges;
    EXPECT_LE(std::abs(room.scale - 1.0), 0.5 * o.max_scale_error) << frame;
    const ColourAlignment unreg = estimate_colour_alignment(tracking_level("unregistered", frame), o);
    ASSERT_TRUE(unreg.valid) << frame << " chamfer " << unreg.chamfer_px;
    EXPECT_NEAR(unreg.scale, 525.0 / 585.0, 0.045) << frame;
    EXPECT_GT(std::abs(unreg.scale - 1.0), o.max_scale_error) << frame;
  }
}

TEST(ColourAlignmentEstimate, NoColourOrNoContoursGiveNoEstimate) {
  const ColourCheckOptions o;
  FramePyramidLevel room = tracking_level("room", 0);
  FramePyramidLevel grey = room;
  grey.intensity = IntensityImage();
  EXPECT_FALSE(estimate_colour_alignment(grey, o).valid);  // no colour
  FramePyramidLevel flat = room;
  for (float& i : flat.intensity.pixels()) i = 0.5f;
  EXPECT_FALSE(estimate_colour_alignment(flat, o).valid);  // no intensity edges
  // The wall preset: one plane, no occluding contour.
  EXPECT_FALSE(estimate_colour_alignment(tracking_level("wall", 0), o).valid);
  FramePyramidLevel nan_depth = room;
  for (hf_float4& v : nan_depth.vertices.pixels()) v = {std::nanf(""), std::nanf(""), std::nanf(""), 0.0f};
  EXPECT_FALSE(estimate_colour_alignment(nan_depth, o).valid);  // no valid depth
  EXPECT_FALSE(estimate_colour_alignment(FramePyramidLevel{}, o).valid);
}

TEST(ColourCheck, OnlyMethodsThatReadColourAreReplaced) {
  for (const std::string& name : registration_names()) {
    const bool colour = name == "combined" || name == "photometric" || name == "ndt-color" || name == "mrsmap" ||
                        name == "sparse";
    EXPECT_EQ(make_registration(name)->reads_colour(), colour) << name;
  }
}

struct CheckedRun {
  RunSummary summary;
  double ate_m = 0.0;
};

// At 640x480 (tracked, and checked, at 320x240: at 160x120 a contour is too coarse to read a 10 % zoom), with a
// shorter window than the default so the runs stay short: 5 estimates, every 2nd frame.
CheckedRun run_preset(const std::string& preset, bool check, int frames) {
  datasets::SyntheticOptions so = test::half_res(preset, frames);
  so.camera = PinholeCamera::preset("ros");
  auto source = datasets::open_synthetic(preset, so);
  PipelineConfig c;
  c.registration = "combined";
  c.volume.capacity_blocks = 1 << 16;
  c.colour_check.enabled = check;
  c.colour_check.window_estimates = 5;
  c.colour_check.frame_step = 2;
  Pipeline pipeline(c, source->camera());
  const SequenceRun run = run_sequence(*source, pipeline);
  CheckedRun out;
  out.summary = summarize(run, pipeline, *source, "synthetic:" + preset);
  out.ate_m = out.summary.ate_rmse_m().value_or(1e9);
  return out;
}

// The room's colour is registered: the check says so and combined tracks on. The same orbit with the colour
// camera aside: the check says unregistered after its window, the depth-only method (sdf) tracks from then on, and
// the trajectory is no worse than combined's with the check off (which the photometric rows pull away from the
// geometry).
TEST(ColourCheckPipeline, TellsRegisteredFromUnregisteredColour) {
  HF_RELEASE_ONLY_ACCURACY("ColourCheck.* (the estimate and the verdict on both presets' frames) and "
                           "ColourCheckPipeline.DepthOnlyPrimaryIsNotChecked");
  const int frames = 24;
  const CheckedRun room = run_preset("room", true, frames);
  EXPECT_EQ(room.summary.colour_verdict, "registered") << room.summary.colour_median_scale;
  EXPECT_EQ(room.summary.tracking_registration, "combined");
  EXPECT_EQ(room.summary.frames_lost, 0);
  EXPECT_EQ(room.summary.frames_fallback, 0);

  const CheckedRun unreg = run_preset("unregistered", true, frames);
  EXPECT_EQ(unreg.summary.colour_verdict, "unregistered") << unreg.summary.colour_median_scale;
  EXPECT_EQ(unreg.summary.tracking_registration, ColourCheckOptions{}.depth_only_registration);
  ASSERT_TRUE(unreg.summary.colour_decided_at_frame);
  EXPECT_LE(*unreg.summary.colour_decided_at_frame, 12u);  // frames 2, 4, .., 10 give the 5 estimates
  EXPECT_EQ(unreg.summary.frames_lost, 0);
  EXPECT_EQ(unreg.summary.frames_fallback, 0);  // icp is the primary after the verdict, not a fallback

  const CheckedRun told_nothing = run_preset("unregistered", false, frames);
  EXPECT_EQ(told_nothing.summary.colour_verdict, "undecided");
  EXPECT_LE(unreg.ate_m, told_nothing.ate_m * 1.05 + 2e-4)
      << "check on " << unreg.ate_m << " m, off " << told_nothing.ate_m << " m";
}

// A depth-only primary has nothing to replace: the check does not run.
TEST(ColourCheckPipeline, DepthOnlyPrimaryIsNotChecked) {
  auto source = datasets::open_synthetic("unregistered", test::half_res("unregistered", 35));
  PipelineConfig c;
  c.registration = "icp";
  c.volume.capacity_blocks = 1 << 15;
  Pipeline pipeline(c, source->camera());
  const SequenceRun run = run_sequence(*source, pipeline);
  const RunSummary s = summarize(run, pipeline, *source, "synthetic:unregistered");
  EXPECT_EQ(s.colour_verdict, "undecided");
  EXPECT_EQ(s.tracking_registration, "icp");
  for (const FrameResult& f : run.frames) EXPECT_FALSE(f.colour_alignment) << f.index;
}

}  // namespace
}  // namespace hf::slam
