#include "photogrammetry/network.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "core/error.h"
#include "io/image_io.h"

namespace hf::photogrammetry {

Matrix34d Shot::P() const {
  Matrix34d Rt;
  Rt.leftCols<3>() = R_camera_world;
  Rt.col(3) = -R_camera_world * C_world;
  return K * Rt;
}

std::optional<Eigen::Vector2d> Shot::project(const Eigen::Vector3d& X_world) const {
  const Eigen::Vector3d x = K * to_camera(X_world);
  // Strictly in front: a point on the camera's principal plane has no pixel.
  if (!(x.z() > 1e-12 * std::max(1.0, x.head<2>().norm()))) return std::nullopt;
  return Eigen::Vector2d(x.x() / x.z(), x.y() / x.z());
}

Eigen::Vector3d Shot::ray_world(const Eigen::Vector2d& uv) const {
  const Eigen::Vector3d d_cam = K.inverse() * Eigen::Vector3d(uv.x(), uv.y(), 1.0);
  return (R_camera_world.transpose() * d_cam).normalized();
}

bool Shot::in_image(const Eigen::Vector2d& uv) const {
  return uv.x() >= 0.0 && uv.y() >= 0.0 && uv.x() <= width - 1.0 && uv.y() <= height - 1.0;
}

bool Cloud::visible_in(size_t i, int s) const {
  if (views.empty() || views[i].empty()) return true;
  return std::find(views[i].begin(), views[i].end(), s) != views[i].end();
}

int Network::shot_index(const std::string& name) const {
  for (size_t i = 0; i < shots.size(); ++i)
    if (shots[i].name == name) return int(i);
  return -1;
}

void Network::validate() const {
  std::unordered_set<std::string> names;
  for (const Shot& s : shots) {
    const std::string where = source + ": shot " + quote_for_message(s.name) + ": ";
    if (s.name.empty()) throw Error(source + ": a shot has no image name");
    if (!names.insert(s.name).second) throw Error(where + "the name is used by two shots");
    if (s.width <= 0 || s.height <= 0 || s.width > 65536 || s.height > 65536)
      throw Error(where + "expected an image size within 1..65536 pixels, got " + std::to_string(s.width) + "x" +
                  std::to_string(s.height));
    if (!s.K.allFinite() || !s.R_camera_world.allFinite() || !s.C_world.allFinite())
      throw Error(where + "the camera has a non-finite value");
    if (!(s.K(0, 0) > 0) || !(s.K(1, 1) > 0) || s.K(2, 0) != 0 || s.K(2, 1) != 0 || s.K(2, 2) != 1 || s.K(1, 0) != 0)
      throw Error(where + "expected K = [fx s cx; 0 fy cy; 0 0 1] with fx, fy > 0");
    const double orthonormality = (s.R_camera_world * s.R_camera_world.transpose() -
                                   Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(orthonormality <= 1e-6) || !(s.R_camera_world.determinant() > 0))
      throw Error(where + "expected a rotation R (R R^T = I within 1e-6, det R = +1)");
  }
  const Cloud& c = cloud;
  if (!c.colors.empty() && c.colors.size() != c.positions.size())
    throw Error(source + ": " + std::to_string(c.colors.size()) + " colours for " + std::to_string(c.size()) +
                " points");
  if (!c.views.empty() && c.views.size() != c.positions.size())
    throw Error(source + ": " + std::to_string(c.views.size()) + " visibility lists for " +
                std::to_string(c.size()) + " points");
  for (size_t i = 0; i < c.size(); ++i) {
    if (!c.positions[i].allFinite())
      throw Error(source + ": point " + std::to_string(i) + " has a non-finite coordinate");
    if (!c.views.empty())
      for (const int v : c.views[i])
        if (v < 0 || size_t(v) >= shots.size())
          throw Error(source + ": point " + std::to_string(i) + " is seen by shot " + std::to_string(v) +
                      ", outside the " + std::to_string(shots.size()) + " shots");
  }
}

ColorImage load_shot_image(const Shot& shot) {
  if (!shot.image_available)
    throw Error(shot.image_path + ": the image of shot " + quote_for_message(shot.name) + " is missing");
  ColorImage image = load_color(shot.image_path);
  if (image.width() != shot.width || image.height() != shot.height)
    throw Error(shot.image_path + ": expected a " + std::to_string(shot.width) + "x" + std::to_string(shot.height) +
                " image (the shot's camera), got " + std::to_string(image.width()) + "x" +
                std::to_string(image.height()));
  return image;
}

}  // namespace hf::photogrammetry
