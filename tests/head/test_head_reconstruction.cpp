// End to end (issue 21): a head mesh of ../shared/data/head_meshes (libigl's, scaled to a real head: RMS radius
// 9 cm) is rendered as an RGB-D orbit around the face through the Kinect sensor model (datasets/mesh_orbit.h),
// fused into the TSDF at the ground-truth poses (what `hashfusion run --registration groundtruth` does: integrate
// with point-to-plane distances, the setting for objects scanned all round, then marching cubes), and the head
// features run on the fused mesh. Its control points are compared, name by name, with those found on the source
// mesh: the target is 2 voxels. Skipped without ../shared.
//
// The test runs a coarse configuration (3 mm voxels, 18 frames at 320 x 240, 0.45 m from the head, 10 degrees
// above it) in seconds; with
// HF_HEAD_E2E_REPORT=1 it also runs the configurations of bench/results/head.md and prints their tables; with
// HF_HEAD_E2E_WRITE=DIR it writes the fused and the (scaled) source mesh there as PLY.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <cmath>

#include "datasets/mesh_orbit.h"
#include "fusion/integrate.h"
#include "fusion/mesh.h"
#include "head/head_features.h"
#include "io/mesh_file.h"
#include "io/ply.h"

namespace hf::head {
namespace {

const std::string kMesh = std::string(HF_SHARED_DIR) + "/data/head_meshes/libigl_face_head.obj";

struct Outcome {
  std::map<std::string, double> distance_vox;  // per control point found on both meshes
  double nose_tip_vox = 0;
  Eigen::Vector3d axis_cos = Eigen::Vector3d::Zero();  // cosines between the fused and the source head frames' x, y, z
  size_t fused_vertices = 0;
  int source_points = 0, fused_points = 0;
  std::vector<std::string> fused_warnings;
  double median_vox() const {
    std::vector<double> d;
    for (const auto& [name, v] : distance_vox) d.push_back(v);
    std::sort(d.begin(), d.end());
    return d.empty() ? 1e9 : d[d.size() / 2];
  }
  double fraction_within(double vox) const {
    size_t n = 0;
    for (const auto& [name, v] : distance_vox) n += v <= vox;
    return distance_vox.empty() ? 0 : double(n) / double(distance_vox.size());
  }
};

HeadFeatureOptions automatic() {
  HeadFeatureOptions o;
  o.automatic = true;
  return o;
}

// The source mesh in metres (centred, RMS radius 9 cm) with its features; the fused mesh's features; distances.
struct Config {
  double voxel_m = 0.003;
  int frames = 18;
  bool noise = true;
  double max_incidence_deg = 70.0;
  double elevation_deg = 10.0;
  double swing_deg = 0.0;
  // A second ring of as many frames at this elevation (NaN: none), seeing what the first ring cannot (from 10 degrees
  // above: the nose's and the chin's undersides, the nostrils).
  double second_elevation_deg = std::numeric_limits<double>::quiet_NaN();
};

Outcome reconstruct(const TriangleMesh& source, const HeadFeatureResult& on_source, const Config& config) {
  const double voxel_m = config.voxel_m;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& v : source.vertices) centroid += v.cast<double>();
  centroid /= double(source.vertices.size());
  double sq = 0;
  for (const auto& v : source.vertices) sq += (v.cast<double>() - centroid).squaredNorm();
  const double scale = 0.09 / std::sqrt(sq / double(source.vertices.size()));
  const auto to_world = [&](const Eigen::Vector3f& p) { return Eigen::Vector3d(scale * (p.cast<double>() - centroid)); };
  TriangleMesh world = source;
  for (auto& v : world.vertices) v = to_world(v).cast<float>();

  datasets::MeshOrbitOptions orbit;
  orbit.frames = config.frames;
  orbit.distance_m = 0.45;
  orbit.elevation_deg = config.elevation_deg;
  orbit.elevation_swing_deg = config.swing_deg;
  // Around the face: the head frame's nose direction starts the orbit, its z is up (rows of R_head_input).
  orbit.start_world = on_source.frame.R_head_input.row(1).transpose();
  orbit.up_world = on_source.frame.R_head_input.row(2).transpose();
  orbit.camera = PinholeCamera::preset("ros").scaled(1);  // 320 x 240
  if (!config.noise) orbit.noise = datasets::NoiseOptions::none();
  // Pixels beyond 70 degrees of incidence are dropped (the sensor model's default keeps them up to 80): the axial
  // noise grows as theta^2 / (pi/2 - theta)^2, about 1 cm at 80 degrees and 0.45 m, and the fins those pixels fuse
  // at the head's silhouettes win the nose-tip search (bench/results/head.md has both).
  orbit.noise.max_incidence_deg = config.max_incidence_deg;
  fusion::VolumeParams volume;
  volume.voxel_m = voxel_m;
  volume.capacity_blocks = 1 << 14;
  fusion::VoxelBlockGrid grid(volume);
  fusion::IntegrateParams integrate;
  integrate.point_to_plane = true;
  for (int i = 0; i < config.frames; ++i) {
    const datasets::SyntheticFrame f = datasets::mesh_orbit_frame(world, orbit, i);
    fusion::integrate(grid, f.depth, f.color, orbit.camera, f.T_world_camera, integrate);
  }
  if (std::isfinite(config.second_elevation_deg)) {
    datasets::MeshOrbitOptions below = orbit;
    below.elevation_deg = config.second_elevation_deg;
    below.seed = orbit.seed + 1;  // other noise than the first ring's
    for (int i = 0; i < config.frames; ++i) {
      const datasets::SyntheticFrame f = datasets::mesh_orbit_frame(world, below, i);
      fusion::integrate(grid, f.depth, f.color, below.camera, f.T_world_camera, integrate);
    }
  }
  const TriangleMesh fused = fusion::extract_mesh(grid);
  const HeadFeatureResult on_fused = detect_head_features(fused, automatic());
  if (const char* dir = std::getenv("HF_HEAD_E2E_WRITE")) {  // both meshes, for `hashfusion head-features` and a look
    write_ply(std::string(dir) + "/fused.ply", fused);
    write_ply(std::string(dir) + "/source_m.ply", world);
  }
  Outcome out;
  const Eigen::Matrix3d agree = on_fused.frame.R_head_input * on_source.frame.R_head_input.transpose();
  out.axis_cos = agree.diagonal();
  out.fused_vertices = fused.vertices.size();
  out.fused_warnings = on_fused.warnings;
  // What tilts the fused frame: the mean normal around the tip over growing balls, source against fused, as
  // pitch (degrees about the head's x axis) in the source's head frame.
  if (std::getenv("HF_HEAD_E2E_REPORT")) {
    auto ns = mls_vertex_normals(world, on_source.topology);
    auto nf = mls_vertex_normals(fused, on_fused.topology);
    const Eigen::Vector3d ts = to_world(source.vertices[on_source.frame.nose_tip_vertex]);
    const Eigen::Vector3d tf = fused.vertices[on_fused.frame.nose_tip_vertex].cast<double>();
    const double rho = on_fused.frame.cap_scale;
    for (double k : {0.25, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0}) {
      Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
      for (size_t i = 0; i < world.vertices.size(); ++i) if ((world.vertices[i].cast<double>() - ts).norm() < k * rho) a += ns[i].cast<double>();
      for (size_t i = 0; i < fused.vertices.size(); ++i) if ((fused.vertices[i].cast<double>() - tf).norm() < k * rho) b += nf[i].cast<double>();
      a.normalize(); b.normalize();
      const Eigen::Vector3d ah = on_source.frame.R_head_input * a, bh = on_source.frame.R_head_input * b;
      std::printf("  r %.2f rho: angle %.1f deg; pitch source %.1f fused %.1f\n", k, std::acos(std::min(1.0, a.dot(b))) * 57.3,
                  std::atan2(ah.z(), ah.y()) * 57.3, std::atan2(bh.z(), bh.y()) * 57.3);
    }
  }
  std::printf("  rho source %.2f mm, fused %.2f mm; edge source %.2f mm, fused %.2f mm\n", 1e3 * scale * on_source.frame.cap_scale,
              1e3 * on_fused.frame.cap_scale, 1e3 * scale * on_source.frame.mean_edge_length, 1e3 * on_fused.frame.mean_edge_length);
  out.source_points = int(on_source.control_points.size()), out.fused_points = int(on_fused.control_points.size());
  std::map<std::string, Eigen::Vector3d> expected;
  for (const ControlPoint& c : on_source.control_points) expected[c.name] = to_world(c.position);
  for (const ControlPoint& c : on_fused.control_points)
    if (auto it = expected.find(c.name); it != expected.end())
      out.distance_vox[c.name] = (c.position.cast<double>() - it->second).norm() / voxel_m;
  out.nose_tip_vox = (fused.vertices[on_fused.frame.nose_tip_vertex].cast<double>() -
                      to_world(source.vertices[on_source.frame.nose_tip_vertex])).norm() / voxel_m;
  return out;
}

void print(const char* what, const Config& c, const Outcome& o) {
  std::printf("%s: %.1f mm voxels, %d frames, %s, incidence <= %.0f deg, elevation %.0f +- %.0f deg (second ring %.0f): fused %zu vertices, frame axes cos %.2f %.2f %.2f, "
              "control points %d (source %d), matched %zu, nose tip %.2f vox, median %.2f vox, within 2 vox %.0f %%\n",
              what, c.voxel_m * 1e3, c.frames, c.noise ? "Kinect noise" : "no noise", c.max_incidence_deg, c.elevation_deg, c.swing_deg, c.second_elevation_deg, o.fused_vertices,
              o.axis_cos.x(), o.axis_cos.y(), o.axis_cos.z(), o.fused_points, o.source_points, o.distance_vox.size(), o.nose_tip_vox,
              o.median_vox(), 100 * o.fraction_within(2.0));
  std::map<std::string, std::vector<double>> groups;  // by area: eye_right, lips, nose, ...
  for (const auto& [name, d] : o.distance_vox) groups[name.substr(0, name.find('.'))].push_back(d);
  for (auto& [g, d] : groups) {
    std::sort(d.begin(), d.end());
    std::printf("  %-10s %2zu points: median %.2f, max %.2f vox\n", g.c_str(), d.size(), d[d.size() / 2], d.back());
  }
  for (const std::string& w : o.fused_warnings) std::printf("  fused mesh: %s\n", w.c_str());
  for (const auto& [name, d] : o.distance_vox) std::printf("    %-24s %6.2f vox\n", name.c_str(), d);
}

TEST(HeadReconstruction, FusedControlPointsMatchTheSource) {
  if (!std::filesystem::exists(kMesh)) GTEST_SKIP() << kMesh << " is absent (../shared not mounted)";
  const TriangleMesh source = read_mesh_file(kMesh);
  const HeadFeatureResult on_source = detect_head_features(source, automatic());
  ASSERT_EQ(on_source.control_points.size(), control_point_names().size());

  const Config config;  // 3 mm voxels, 18 frames, Kinect noise, incidence <= 70 degrees, 10 degrees above

  const Outcome o = reconstruct(source, on_source, config);
  print("test", config, o);
  // Measured (bench/results/head.md, with every point's distance): the frame's axes agree within 16 degrees, the
  // nose tip lies 0.5 voxel from the source's, the median control point 3.9 voxels, 28 % within 2 voxels; the
  // fused ears are reported absent (their flaps span 0.55 / 0.70 rho: the TSDF thickens the pinna, the ear test
  // needs 1 rho), so 40 of 52 points are compared. The bounds leave room for noise realisations but catch a wrong
  // frame (a wrong tip is > 20 voxels off, a flipped z has cosine -1). The 2-voxel target holds for the
  // tip, not for the other control points.
  EXPECT_GE(o.axis_cos.minCoeff(), 0.9);
  EXPECT_LE(o.nose_tip_vox, 2.0);
  EXPECT_GE(o.distance_vox.size(), 38u);  // 52 less the 10 ear points less 2 nostrils (the unseen nose underside)
  EXPECT_LE(o.median_vox(), 5.0);

  if (std::getenv("HF_HEAD_E2E_REPORT")) {
    for (const Config& c : {Config{0.002, 36, true, 70}, Config{0.002, 36, false, 70}, Config{0.003, 36, true, 70},
                            Config{0.004, 36, true, 70}, Config{0.003, 18, true, 80}, Config{0.002, 36, true, 80},
                            Config{0.003, 18, true, 70, -20.0}, Config{0.003, 36, true, 70, 10.0, 20.0},
                            Config{0.003, 18, true, 70, 10.0, 0.0, -20.0}, Config{0.003, 18, true, 70, 10.0, 0.0, -30.0}})
      print("report", c, reconstruct(source, on_source, c));
  }
}

}  // namespace
}  // namespace hf::head
