// gicp (registration/gicp.h): Segal's covariances from image-space neighbourhoods, and the plane-to-plane rows.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "core/error.h"
#include "reg_test_util.h"
#include "registration/gicp.h"

namespace hf {
namespace {

Eigen::Matrix3d unpack(const hf_float4& a, const hf_float4& b) {
  Eigen::Matrix3d C;
  C << a.x, a.y, a.z, a.y, a.w, b.x, a.z, b.x, b.y;
  return C;
}

// A plane z = 1.5 + 0.3 x seen by the camera, with a step to z = 3 in the right half: every pixel whose window
// lies on one plane gets Segal's covariance, eigenvalues (epsilon, 1, 1) with the plane's normal as the epsilon
// direction (exact up to float rounding: 1e-5); the gate keeps the step's far side out of the near side's windows.
TEST(Gicp, CovariancesArePlanesRegularisedAsSegal) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(2);  // 160 x 120
  VertexMap vertices(cam.width, cam.height);
  const Eigen::Vector3d normal = Eigen::Vector3d(-0.3, 0.0, 1.0).normalized();
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const double rx = (x - cam.cx) / cam.fx, ry = (y - cam.cy) / cam.fy;
      const double z = x < cam.width / 2 ? 1.5 / (1.0 - 0.3 * rx) : 3.0;  // on z = 1.5 + 0.3 x, or z = 3
      vertices(x, y) = hf_make_float4(float(rx * z), float(ry * z), float(z), 1.0f);
    }
  }
  GicpOptions o;
  std::vector<hf_float4> a, b;
  gicp_covariances(vertices, cam, o, &a, &b);
  int checked = 0;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width / 2; ++x) {  // the tilted half, up to the step
      const size_t i = size_t(y) * size_t(cam.width) + size_t(x);
      ASSERT_EQ(b[i].w, 1.0f) << x << " " << y;
      const Eigen::Matrix3d C = unpack(a[i], b[i]);
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
      EXPECT_NEAR(eig.eigenvalues()(0), o.gicp_epsilon, 1e-5);
      EXPECT_NEAR(eig.eigenvalues()(1), 1.0, 1e-5);
      EXPECT_NEAR(eig.eigenvalues()(2), 1.0, 1e-5);
      EXPECT_NEAR(normal.dot(C * normal), o.gicp_epsilon, 1e-5) << x << " " << y;
      ++checked;
    }
  }
  EXPECT_EQ(checked, cam.width / 2 * cam.height);
  // A single valid pixel, or a line of them, has no plane.
  VertexMap line(cam.width, cam.height);
  for (int x = 10; x < 30; ++x) line(x, 50) = hf_make_float4(0.01f * float(x), 0.0f, 2.0f, 1.0f);
  gicp_covariances(line, cam, o, &a, &b);
  for (const hf_float4& v : b) EXPECT_EQ(v.w, 0.0f);
}

// Plane-to-plane uses both surfaces' shape, so sensor noise moves it less than point-to-plane: on noisy room
// pairs (three noise seeds) gicp's error is below icp's, and within the 3 mm / 0.2 deg noise class of the
// accuracy tests.
TEST(Gicp, NoisyRoomPairsMoreAccurateThanIcp) {
  for (const std::uint64_t seed : {3u, 5u, 7u}) {
    const test::FramePair pair = test::make_pair("room", 10, 11, true, seed);
    const RegistrationResult g = make_registration("gicp")->align(pair.current, pair.reference, SE3());
    const RegistrationResult i = make_registration("icp")->align(pair.current, pair.reference, SE3());
    const double eg = test::translation_error_m(g.T_ref_cur, pair.T_ref_cur_true);
    const double ei = test::translation_error_m(i.T_ref_cur, pair.T_ref_cur_true);
    std::printf("seed %d: gicp %.3f mm (%s), icp %.3f mm\n", int(seed), eg * 1e3, to_string(g.status), ei * 1e3);
    EXPECT_EQ(g.status, RegistrationStatus::good) << g.message;
    EXPECT_LT(eg, ei) << seed;
    EXPECT_LT(eg, 3e-3);
    EXPECT_LT(test::rotation_error_deg(g.T_ref_cur, pair.T_ref_cur_true), 0.2);
  }
}

TEST(Gicp, OptionsAreValidated) {
  RegistrationOptions o = default_registration_options("gicp");
  EXPECT_NO_THROW(o.validate());
  EXPECT_TRUE(o.set("gicp_epsilon", 0.0));
  EXPECT_THROW(o.validate(), Error);
  o = default_registration_options("gicp");
  EXPECT_TRUE(o.set("gicp_window_px", 1));
  EXPECT_TRUE(o.set("gicp_min_neighbours", 10));  // more than a 3 x 3 window holds
  EXPECT_THROW(o.validate(), Error);
}

}  // namespace
}  // namespace hf
