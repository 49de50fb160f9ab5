// Multi-shot DLT triangulation (photogrammetry/dlt_triangulation.h): exact points come back to double rounding,
// noisy ones within the first-order error the noise predicts, degenerate geometry yields a status and no NaN; the
// exact Middlebury cameras and the Sceaux SfM network re-triangulate their points.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <filesystem>
#include <random>

#include "photogrammetry/dlt_triangulation.h"
#include "photogrammetry/scene_readers.h"
#include "tests/photogrammetry/synthetic_shots.h"

namespace hf::photogrammetry {
namespace {

using testing::look_at;
const std::string kDltShared = HF_SHARED_DIR;

std::vector<Shot> ring_of_shots(int n, double radius, const Eigen::Vector3d& target) {
  std::vector<Shot> shots;
  for (int k = 0; k < n; ++k) {
    const double a = -0.6 + 1.2 * k / std::max(1, n - 1);  // a 70-degree arc in front of the target
    std::string name = "s";  // (not "s" + ...: GCC 12's -Wstringop-overflow misfires on it)
    name += std::to_string(k);
    shots.push_back(look_at(name,
                            target + Eigen::Vector3d(radius * std::sin(a), -radius * std::cos(a), 1.0), target));
  }
  return shots;
}

std::vector<DltObservation> observe(const std::vector<Shot>& shots, const Eigen::Vector3d& X, double sigma_px = 0,
                                    std::mt19937* rng = nullptr) {
  std::vector<DltObservation> obs;
  std::normal_distribution<double> noise(0.0, 1.0);
  for (const Shot& s : shots) {
    Eigen::Vector2d uv = *s.project(X);
    if (sigma_px > 0) uv += sigma_px * Eigen::Vector2d(noise(*rng), noise(*rng));
    obs.push_back(observation(s, uv));
  }
  return obs;
}

// First-order covariance of the least-squares point under isotropic pixel noise sigma: (J^T J)^-1 sigma^2, J the
// stacked 2x3 projection Jacobians. The DLT is not the maximum-likelihood estimate, but for well-conditioned views
// its error agrees with this to first order (HZ 12.2-12.3).
double predicted_rms_error(const std::vector<Shot>& shots, const Eigen::Vector3d& X, double sigma_px) {
  Eigen::Matrix3d JtJ = Eigen::Matrix3d::Zero();
  for (const Shot& s : shots) {
    const Eigen::Vector3d x = s.K * s.to_camera(X);
    Eigen::Matrix<double, 2, 3> d;  // d(u, v)/d(x) of u = x0/x2, v = x1/x2
    d << 1 / x.z(), 0, -x.x() / (x.z() * x.z()), 0, 1 / x.z(), -x.y() / (x.z() * x.z());
    const Eigen::Matrix<double, 2, 3> J = d * s.K * s.R_camera_world;
    JtJ += J.transpose() * J;
  }
  return sigma_px * std::sqrt(JtJ.inverse().trace());
}

TEST(DltTriangulation, ExactPointsComeBackToRounding) {
  const Eigen::Vector3d target(5, 0, 3);
  for (const int n : {2, 3, 7}) {
    const std::vector<Shot> shots = ring_of_shots(n, 15, target);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-3, 3);
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector3d X = target + Eigen::Vector3d(u(rng), u(rng), u(rng));
      const Triangulation t = triangulate_dlt(observe(shots, X));
      ASSERT_TRUE(t.ok()) << to_string(t.status);
      EXPECT_LT((t.X_world - X).norm(), 1e-9 * X.norm()) << n << " views";
      ASSERT_EQ(t.reprojection_error_px.size(), size_t(n));
      for (const double e : t.reprojection_error_px) EXPECT_LT(e, 1e-8);
    }
  }
}

TEST(DltTriangulation, NoisyPointsWithinThePredictedError) {
  const Eigen::Vector3d target(5, 0, 3);
  const double sigma = 0.5;
  for (const int n : {2, 3, 6}) {
    const std::vector<Shot> shots = ring_of_shots(n, 15, target);
    std::mt19937 rng(11);
    double sum_sq = 0, predicted_sq = 0, residual_sq = 0;
    const int trials = 400;
    for (int i = 0; i < trials; ++i) {
      const Eigen::Vector3d X = target + Eigen::Vector3d(0.01 * i - 2, 0, 0.005 * i - 1);
      const Triangulation t = triangulate_dlt(observe(shots, X, sigma, &rng));
      ASSERT_TRUE(t.ok());
      sum_sq += (t.X_world - X).squaredNorm();
      predicted_sq += std::pow(predicted_rms_error(shots, X, sigma), 2);
      for (const double e : t.reprojection_error_px) residual_sq += e * e;
    }
    const double rms = std::sqrt(sum_sq / trials), predicted = std::sqrt(predicted_sq / trials);
    // 400 trials estimate an RMS to about 1/sqrt(2 * 400) = 3.5 %; 20 % leaves room for the DLT's bias.
    EXPECT_NEAR(rms, predicted, 0.2 * predicted) << n << " views";
    // The residual of a 3-parameter fit to 2n measurements: E[sum of the n squared errors] = (2n - 3) sigma^2 for
    // the maximum-likelihood fit; the DLT's algebraic fit lies slightly above it.
    const double expected_residual = std::sqrt((2.0 * n - 3.0) / n) * sigma;
    const double residual = std::sqrt(residual_sq / (trials * n));
    EXPECT_GE(residual, 0.9 * expected_residual);
    EXPECT_LE(residual, 1.15 * expected_residual);
  }
}

TEST(DltTriangulation, DegenerateGeometryGivesAStatusNotNaN) {
  // Parallel rays: two shots side by side looking straight ahead, both sketching their own principal point.
  Shot a = look_at("a.png", {0, 0, 0}, {0, 10, 0});
  Shot b = look_at("b.png", {1, 0, 0}, {1, 10, 0});
  const Eigen::Vector2d centre(319.5, 239.5);
  Triangulation t = triangulate_dlt({observation(a, centre), observation(b, centre)});
  EXPECT_EQ(t.status, TriangulationStatus::degenerate);
  EXPECT_TRUE(t.X_world.allFinite());
  EXPECT_TRUE(t.reprojection_error_px.empty());
  // Coincident rays: the second shot stands on the first one's ray.
  Shot c = look_at("c.png", {0, 3, 0}, {0, 10, 0});
  t = triangulate_dlt({observation(a, centre), observation(c, centre)});
  EXPECT_EQ(t.status, TriangulationStatus::degenerate);
  EXPECT_TRUE(t.X_world.allFinite());
  // One view fixes nothing.
  EXPECT_EQ(triangulate_dlt({observation(a, centre)}).status, TriangulationStatus::too_few_views);
  // Rays that meet behind the cameras.
  Shot d = look_at("d.png", {4, 0, 0}, {4, 10, 0});
  const Eigen::Vector3d behind(2, -10, 0);
  const Eigen::Vector3d xa = a.K * a.to_camera(behind), xd = d.K * d.to_camera(behind);
  t = triangulate_dlt({observation(a, (xa / xa.z()).head<2>()), observation(d, (xd / xd.z()).head<2>())});
  EXPECT_EQ(t.status, TriangulationStatus::behind_camera);
  EXPECT_TRUE(t.X_world.allFinite());
  // Non-finite input.
  t = triangulate_dlt({observation(a, {NAN, 1}), observation(b, centre)});
  EXPECT_EQ(t.status, TriangulationStatus::degenerate);
  EXPECT_TRUE(t.X_world.allFinite());
}

TEST(DltTriangulation, MiddleburyExactCamerasRecoverPointsFromTheirProjections) {
  const std::string dir = kDltShared + "/data/photogrammetry_middlebury_templeRing19";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not found (../shared absent)";
  const Network n = read_network(dir);
  const Eigen::Vector3d lo(-0.023121, -0.038009, -0.091940), hi(0.078626, 0.121636, -0.017395);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Shot> present;
  for (const Shot& s : n.shots)
    if (s.image_available) present.push_back(s);
  ASSERT_EQ(present.size(), 19u);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d X = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    // Every consecutive pair (about 22 degrees apart on the ring) and all 19 views.
    const size_t k = size_t(i) % (present.size() - 1);
    for (const std::vector<Shot>& views :
         {std::vector<Shot>{present[k], present[k + 1]}, present}) {
      const Triangulation t = triangulate_dlt(observe(views, X));
      ASSERT_TRUE(t.ok());
      EXPECT_LT((t.X_world - X).norm(), 1e-11);  // the object is 0.16 units across
      for (const double e : t.reprojection_error_px) EXPECT_LT(e, 1e-7);
    }
  }
}

TEST(DltTriangulation, SceauxSparsePointsRetriangulateWithinTheSfmError) {
  const std::string dir = kDltShared + "/data/photogrammetry_sceaux_castle";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " not found (../shared absent)";
  const Network n = read_network(dir);
  // The dump has no 2D keypoints (PROVENANCE.md), so the observations are the points' projections into their
  // views, perturbed by the pixel noise of a good SfM (0.5 px, OpenMVG's typical final RMS residual).
  const double sigma = 0.5;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, sigma);
  size_t tested = 0, exact_ok = 0, within = 0, residual_ok = 0;
  for (size_t i = 0; i < n.cloud.size(); i += 7) {
    std::vector<Shot> views;
    for (const int v : n.cloud.views[i]) {
      const auto uv = n.shots[size_t(v)].project(n.cloud.positions[i]);
      if (uv && n.shots[size_t(v)].in_image(*uv)) views.push_back(n.shots[size_t(v)]);
    }
    if (views.size() < 2) continue;
    const Eigen::Vector3d& X = n.cloud.positions[i];
    ++tested;
    const Triangulation exact = triangulate_dlt(observe(views, X));
    exact_ok += exact.ok() && (exact.X_world - X).norm() < 1e-9 * std::max(1.0, X.norm());
    std::vector<DltObservation> obs;
    for (const Shot& s : views) obs.push_back(observation(s, *s.project(X) + Eigen::Vector2d(noise(rng), noise(rng))));
    const Triangulation t = triangulate_dlt(obs);
    if (!t.ok()) continue;
    // Within 3 predicted standard deviations (per-point, from the views' geometry), and a reprojection residual
    // no larger than the noise put in (a least-squares fit absorbs part of it).
    within += (t.X_world - X).norm() <= 3.0 * predicted_rms_error(views, X, sigma);
    double r2 = 0;
    for (const double e : t.reprojection_error_px) r2 += e * e;
    residual_ok += std::sqrt(r2 / double(views.size())) <= 3.0 * sigma;
  }
  ASSERT_GT(tested, 1500u);
  EXPECT_EQ(exact_ok, tested);
  // A 3-D Gaussian lies within 3 sigma of its RMS radius for > 97 % of samples; 95 % allows for the DLT's bias.
  EXPECT_GT(double(within), 0.95 * double(tested));
  EXPECT_GT(double(residual_ok), 0.99 * double(tested));
}

}  // namespace
}  // namespace hf::photogrammetry
