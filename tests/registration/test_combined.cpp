// combined's per-term degeneracy (registration/combined.h): each term is reduced on its own and its own
// degenerate directions are projected out before the two are added (Zhang et al. 2016 per term).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "core/error.h"
#include "reg_test_util.h"
#include "registration/combined.h"

namespace hf {
namespace {

RegistrationResult align(const std::string& method, const test::FramePair& pair) {
  return make_registration(method)->align(pair.current, pair.reference, SE3());
}

// The result carries both terms' information, and with the projection off their sum is the information of the
// single-reduction system (the combined kernel's rows are the two kernels' rows, so the sums agree to the double
// additions' order, 1e-9 relative).
TEST(Combined, ResultCarriesEachTermsInformation) {
  const test::FramePair pair = test::make_pair("room", 10, 11, true, 3);
  RegistrationOptions plain = default_registration_options("combined");
  plain.method_as<CombinedOptions>().icp_term_threshold = 0.0;
  const RegistrationResult r = make_registration("combined", plain, make_backend("cpu"))
                                   ->align(pair.current, pair.reference, SE3());
  ASSERT_EQ(r.terms.size(), 2u);
  EXPECT_EQ(r.terms[0].name, "icp");
  EXPECT_EQ(r.terms[1].name, "photometric");
  EXPECT_GT(r.terms[0].rows, 1000);
  EXPECT_GT(r.terms[1].rows, 1000);
  EXPECT_EQ(r.terms[0].rows + r.terms[1].rows, r.inliers);
  // The terms' problems are the combined kernel's rows split in two: at any pose their sums add up to the
  // single reduction's (to the order of the double additions).
  test::MethodUnderTest m = test::method_under_test("combined");
  auto backend = make_backend("cpu");
  ResidualProblem level = m.dense->level_problem(pair.current, pair.reference, 0, r.T_ref_cur);
  const NormalEquations all = backend->reduce(level);
  NormalEquations split;
  for (int t = 0; t < 2; ++t) {
    const NormalEquations ne = backend->reduce(m.dense->method().term_problem(t, level));
    split.JtJ += ne.JtJ;
    split.Jtr += ne.Jtr;
    split.count += ne.count;
  }
  EXPECT_EQ(split.count, all.count);
  EXPECT_LT((split.JtJ - all.JtJ).norm(), 1e-9 * all.JtJ.norm());
  EXPECT_LT((split.Jtr - all.Jtr).norm(), 1e-9 * all.Jtr.norm() + 1e-12);
  // Each term alone is well constrained on the room (icp's smallest balanced eigenvalue far above zero).
  for (const auto& t : r.terms) EXPECT_GT(t.information.trace(), 0.0) << t.name;
  EXPECT_TRUE(make_registration("icp")->align(pair.current, pair.reference, SE3()).terms.empty());
}

// The corridor: icp's information along the axis is weak (balanced ratio ~5e-3) and biased towards the initial
// guess; with icp_term_threshold 3e-2 its weak directions (0.005 / 0.020 / 0.026) are projected out, the
// photometric term alone decides them, and combined lands within 1.5x of the better single method (photometric;
// 1.4 mm against 1.8 mm), where the plain sum (threshold 0) stays nearer the guess (8.5 mm). The default (1e-2,
// chosen on TUM) projects out only the axis: 9.7 mm, a third of the motion.
TEST(Combined, CorridorAxisComesFromThePhotometricTerm) {
  const test::FramePair pair = test::make_pair("corridor", 5, 6, true);
  const double motion = pair.T_ref_cur_true.translation().norm();
  RegistrationOptions wide = default_registration_options("combined");
  wide.method_as<CombinedOptions>().icp_term_threshold = 3e-2;
  const RegistrationResult combined =
      make_registration("combined", wide, make_backend("cpu"))->align(pair.current, pair.reference, SE3());
  EXPECT_LT(test::translation_error_m(align("combined", pair).T_ref_cur, pair.T_ref_cur_true), motion / 3.0);
  const RegistrationResult photometric = align("photometric", pair);
  const double ec = test::translation_error_m(combined.T_ref_cur, pair.T_ref_cur_true);
  const double ep = test::translation_error_m(photometric.T_ref_cur, pair.T_ref_cur_true);
  std::printf("corridor: combined %.2f mm (%s), photometric %.2f mm, motion %.1f mm\n", ec * 1e3,
              to_string(combined.status), ep * 1e3, motion * 1e3);
  EXPECT_TRUE(combined.usable()) << combined.message;
  EXPECT_EQ(combined.degenerate_dims, 0);
  EXPECT_LT(ec, std::max(1.5 * ep, 2e-3));
  RegistrationOptions plain = default_registration_options("combined");
  plain.method_as<CombinedOptions>().icp_term_threshold = 0.0;
  const RegistrationResult summed =
      make_registration("combined", plain, make_backend("cpu"))->align(pair.current, pair.reference, SE3());
  EXPECT_GT(test::translation_error_m(summed.T_ref_cur, pair.T_ref_cur_true), ec);
}

// On every hard case with colour but the corridor (above), combined is within 1.5x of the better single method
// (or within 2 mm / 0.1 deg of it where both are at the noise floor).
TEST(Combined, HardCasesWithinOneAndAHalfOfTheBestSingleMethod) {
  for (const char* preset : {"wall", "textureless", "holes", "exposure", "room"}) {
    const test::FramePair pair = test::make_pair(preset, 5, 6, true);
    double best_t = 1e9, best_r = 1e9;
    for (const char* single : {"icp", "photometric"}) {
      const RegistrationResult r = align(single, pair);
      if (!r.usable()) continue;
      best_t = std::min(best_t, test::translation_error_m(r.T_ref_cur, pair.T_ref_cur_true));
      best_r = std::min(best_r, test::rotation_error_deg(r.T_ref_cur, pair.T_ref_cur_true));
    }
    const RegistrationResult c = align("combined", pair);
    test::expect_finite(c);
    const double et = test::translation_error_m(c.T_ref_cur, pair.T_ref_cur_true);
    const double er = test::rotation_error_deg(c.T_ref_cur, pair.T_ref_cur_true);
    std::printf("%-12s combined %.3f mm %.4f deg (%s), best single %.3f mm %.4f deg\n", preset, et * 1e3, er,
                to_string(c.status), best_t * 1e3, best_r);
    EXPECT_TRUE(c.usable()) << preset << ": " << c.message;
    EXPECT_LT(et, std::max(1.5 * best_t, best_t + 2e-3)) << preset;
    EXPECT_LT(er, std::max(1.5 * best_r, best_r + 0.1)) << preset;
  }
}

TEST(Combined, TermThresholdsAreValidated) {
  RegistrationOptions o = default_registration_options("combined");
  EXPECT_TRUE(o.set("icp_term_threshold", 0.05));
  EXPECT_NO_THROW(o.validate());
  EXPECT_TRUE(o.set("photometric_term_threshold", 1.0));
  EXPECT_THROW(o.validate(), Error);
}

}  // namespace
}  // namespace hf
