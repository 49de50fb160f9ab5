// End to end (issue 21): a head mesh of ../shared/data/head_meshes (libigl's, scaled to a real head: RMS radius
// 9 cm) is rendered as an RGB-D orbit around the face through the Kinect sensor model (datasets/mesh_orbit.h),
// fused into the TSDF at the ground-truth poses (what `hashfusion run --registration groundtruth` does: integrate
// with point-to-plane distances, the setting for objects scanned all round, then marching cubes), and the head
// features run on the fused mesh. Its control points are compared, name by name, with those found on the source
// mesh: the target is 2 voxels. Skipped without ../shared.
//
// The test runs 3 mm voxels, 18 frames at 320 x 240, 0.45 m from the head, 10 degrees above it, then 18 frames 30
// degrees below over a 120-degree arc in front of the face, with head_features.h's physical scales, in seconds
// (and the one-ring, paper-scale configuration it improved on); with
// HF_HEAD_E2E_REPORT=1 it also runs the configurations of bench/results/head.md and prints their tables; with
// HF_HEAD_E2E_WRITE=DIR it writes the fused and the (scaled) source mesh there as PLY.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <tuple>
#include <cmath>
#include <numbers>
#include <Eigen/Geometry>

#include "datasets/mesh_orbit.h"
#include "fusion/integrate.h"
#include "fusion/mesh.h"
#include "head/head_features.h"
#include "io/mesh_file.h"
#include "io/ply.h"
#include "tests/common/sanitizer.h"

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
  // Per side (right, left): whether each mesh has an ear, and the distance between the two ears' flap centres
  // (important_areas.h's ear_centre_rho) in the source's rho (NaN unless both have one).
  std::array<bool, 2> source_ear{}, fused_ear{};
  std::array<Eigen::Vector3d, 2> fused_ear_centre_rho{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};  // its head frame
  std::array<double, 2> ear_offset_rho{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
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

HeadFeatureOptions automatic(bool physical) {
  HeadFeatureOptions o;
  o.automatic = true;
  if (physical) use_physical_scale(o);
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
  double second_sweep_deg = 360.0;  // the second ring's arc, centred on the face
  bool physical = false;  // head_features.h's use_physical_scale() on both meshes, else the paper's scales
  std::uint64_t seed = 0;  // the sensor noise's (the second ring's is seed + 1)
};

Outcome reconstruct(const TriangleMesh& source, const Config& config) {
  const HeadFeatureResult on_source = detect_head_features(source, automatic(config.physical));
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
  orbit.seed = config.seed;
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
    below.sweep_deg = config.second_sweep_deg;
    if (config.second_sweep_deg < 360.0) {  // start half the arc to the side of the face
      const double a = -0.5 * config.second_sweep_deg * std::numbers::pi / 180.0;
      const Eigen::Vector3d up = orbit.up_world.normalized();
      below.start_world = Eigen::AngleAxisd(a, up) * orbit.start_world;
    }
    for (int i = 0; i < config.frames; ++i) {
      const datasets::SyntheticFrame f = datasets::mesh_orbit_frame(world, below, i);
      fusion::integrate(grid, f.depth, f.color, below.camera, f.T_world_camera, integrate);
    }
  }
  const TriangleMesh fused = fusion::extract_mesh(grid);
  const HeadFeatureResult on_fused = detect_head_features(fused, automatic(config.physical));
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
  for (const HeadFeatureResult* r : {&on_source, &on_fused}) {
    const double mm = 1e3 * (r == &on_source ? scale : 1.0) / r->frame.scale;  // head units -> mm
    std::printf("  %s: k %d, root z %.1f y %.1f, nose half-width %.1f, z eyes/nose %.1f mm, nose/lips %.1f mm, areas eyes %d/%d nose %d lips %d, features %d/%d/%d/%d, thresholds %.1f/%.1f/%.1f/%.1f %%\n",
                r == &on_source ? "source" : "fused", r->areas.k, r->areas.z_root * mm, r->areas.y_root * mm, r->areas.nose_half_width * mm, r->areas.z_eyes_nose * mm, r->areas.z_nose_lips * mm,
                r->areas.counts[1], r->areas.counts[2], r->areas.counts[3], r->areas.counts[4],
                [&] { int c = 0; for (size_t i = 0; i < r->areas.label.size(); ++i) c += r->areas.label[i] == Area::eye_right && r->area_features.features[i]; return c; }(),
                [&] { int c = 0; for (size_t i = 0; i < r->areas.label.size(); ++i) c += r->areas.label[i] == Area::eye_left && r->area_features.features[i]; return c; }(),
                [&] { int c = 0; for (size_t i = 0; i < r->areas.label.size(); ++i) c += r->areas.label[i] == Area::nose && r->area_features.features[i]; return c; }(),
                [&] { int c = 0; for (size_t i = 0; i < r->areas.label.size(); ++i) c += r->areas.label[i] == Area::lips && r->area_features.features[i]; return c; }(),
                r->area_features.threshold_percent[1], r->area_features.threshold_percent[2], r->area_features.threshold_percent[3], r->area_features.threshold_percent[4]);
  }
  if (std::getenv("HF_HEAD_E2E_POINTS")) {  // head-frame mm (the source's frame) of both meshes' points
    for (const ControlPoint& c : on_fused.control_points)
      if (auto it = std::find_if(on_source.control_points.begin(), on_source.control_points.end(), [&](const ControlPoint& s) { return s.name == c.name; }); it != on_source.control_points.end()) {
        const Eigen::Vector3d a = 1e3 * (on_source.frame.R_head_input * (to_world(it->position) - to_world(on_source.frame.origin_input.cast<float>())));
        const Eigen::Vector3d b = 1e3 * (on_source.frame.R_head_input * (c.position.cast<double>() - to_world(on_source.frame.origin_input.cast<float>())));
        std::printf("    %-24s source %+6.1f %+6.1f %+6.1f  fused %+6.1f %+6.1f %+6.1f mm\n", c.name.c_str(), a.x(), a.y(), a.z(), b.x(), b.y(), b.z());
      }
  }
  out.source_points = int(on_source.control_points.size()), out.fused_points = int(on_fused.control_points.size());
  std::map<std::string, Eigen::Vector3d> expected;
  for (const ControlPoint& c : on_source.control_points) expected[c.name] = to_world(c.position);
  for (const ControlPoint& c : on_fused.control_points)
    if (auto it = expected.find(c.name); it != expected.end())
      out.distance_vox[c.name] = (c.position.cast<double>() - it->second).norm() / voxel_m;
  // The flap centres in metres: head frame (rho) -> input units -> world.
  for (int side = 0; side < 2; ++side) {
    const int a = static_cast<int>(side == 0 ? Area::ear_right : Area::ear_left);
    out.source_ear[side] = on_source.areas.counts[a] > 0;
    out.fused_ear[side] = on_fused.areas.counts[a] > 0;
    out.fused_ear_centre_rho[side] = on_fused.areas.ear_centre_rho[side];
    if (!out.source_ear[side] || !out.fused_ear[side]) continue;
    const HeadFrame& fs = on_source.frame;
    const HeadFrame& ff = on_fused.frame;
    const Eigen::Vector3d cs = to_world((fs.origin_input + fs.R_head_input.transpose() * (on_source.areas.ear_centre_rho[side] * fs.cap_scale)).cast<float>());
    const Eigen::Vector3d cf = ff.origin_input + ff.R_head_input.transpose() * (on_fused.areas.ear_centre_rho[side] * ff.cap_scale);
    out.ear_offset_rho[side] = (cf - cs).norm() / (scale * fs.cap_scale);
  }
  out.nose_tip_vox = (fused.vertices[on_fused.frame.nose_tip_vertex].cast<double>() -
                      to_world(source.vertices[on_source.frame.nose_tip_vertex])).norm() / voxel_m;
  return out;
}

void expect_ears_absent_or_right(const Outcome& o) {
  for (int side = 0; side < 2; ++side) {
    EXPECT_TRUE(o.source_ear[side]) << "libigl's source head has both ears (test_head_real)";
    if (o.fused_ear[side]) {
      EXPECT_LE(o.ear_offset_rho[side], 1.5) << (side == 0 ? "right" : "left") << " ear";
    }
  }
}

void print(const char* what, const Config& c, const Outcome& o) {
  std::printf("%s: %s scales, seed %d, %.1f mm voxels, %d frames, %s, incidence <= %.0f deg, elevation %.0f +- %.0f deg (second ring %.0f over %.0f deg): fused %zu vertices, frame axes cos %.2f %.2f %.2f, "
              "control points %d (source %d), matched %zu, nose tip %.2f vox, median %.2f vox, within 2 vox %.0f %%\n",
              what, c.physical ? "physical" : "paper's", int(c.seed), c.voxel_m * 1e3, c.frames, c.noise ? "Kinect noise" : "no noise", c.max_incidence_deg, c.elevation_deg, c.swing_deg, c.second_elevation_deg, c.second_sweep_deg, o.fused_vertices,
              o.axis_cos.x(), o.axis_cos.y(), o.axis_cos.z(), o.fused_points, o.source_points, o.distance_vox.size(), o.nose_tip_vox,
              o.median_vox(), 100 * o.fraction_within(2.0));
  std::map<std::string, std::vector<double>> groups;  // by area: eye_right, lips, nose, ...
  for (const auto& [name, d] : o.distance_vox) groups[name.substr(0, name.find('.'))].push_back(d);
  for (auto& [g, d] : groups) {
    std::sort(d.begin(), d.end());
    std::printf("  %-10s %2zu points: median %.2f, max %.2f vox\n", g.c_str(), d.size(), d[d.size() / 2], d.back());
  }
  for (int side = 0; side < 2; ++side)
    std::printf("  %s ear: source %s, fused %s (flap centre %+.2f %+.2f %+.2f rho), flap centres %.2f rho apart\n",
                side == 0 ? "right" : "left", o.source_ear[side] ? "found" : "absent", o.fused_ear[side] ? "found" : "absent",
                o.fused_ear_centre_rho[side].x(), o.fused_ear_centre_rho[side].y(), o.fused_ear_centre_rho[side].z(),
                o.ear_offset_rho[side]);
  for (const std::string& w : o.fused_warnings) std::printf("  fused mesh: %s\n", w.c_str());
  for (const auto& [name, d] : o.distance_vox) std::printf("    %-24s %6.2f vox\n", name.c_str(), d);
}

// Per area ("eye_right", "lips", ...), the median distance in voxels.
std::map<std::string, double> group_medians(const Outcome& o) {
  std::map<std::string, std::vector<double>> groups;
  for (const auto& [name, d] : o.distance_vox) groups[name.substr(0, name.find('.'))].push_back(d);
  std::map<std::string, double> out;
  for (auto& [g, d] : groups) {
    std::sort(d.begin(), d.end());
    out[g] = d[d.size() / 2];
  }
  return out;
}

// The target: the two-ring capture (10 degrees above all round, 30 degrees below over a 120 degree arc in
// front of the face: the nose's and lips' undersides) and head_features.h's physical scales on both meshes. Chosen
// here, on this configuration (libigl's head, 3 mm voxels, 18 + 18 frames, Kinect noise seeds 0 and 1);
// reported on the others of bench/results/head.md (2 / 2.5 / 4 mm, 36 frames, a -20 degree ring, one ring).
TEST(HeadReconstruction, FusedControlPointsMatchTheSource) {
  if (!std::filesystem::exists(kMesh)) GTEST_SKIP() << kMesh << " is absent (../shared not mounted)";
  const TriangleMesh source = read_mesh_file(kMesh);
  Config config;
  config.second_elevation_deg = -30.0;
  config.second_sweep_deg = 120.0;
  config.physical = true;
  const Outcome o = reconstruct(source, config);
  print("test", config, o);
  // Measured: frame cosines 1.00, nose tip 0.59 voxel, 42 of 52 points matched (both fused ears reported absent:
  // the right has no flap of an ear's span, the left's one flap is a fin 8 rho behind and 1.8 rho above the tip,
  // rejected by important_areas.h's ear_implausible; before that test its 5 points lay ~24 voxels off), median
  // 1.59 voxels, 69 % within 2; per area eyes 1.09 / 0.96, nose 1.66 (8 points), lips 2.22.
  // Over 10 noise seeds the median spans 1.49 .. 2.43 voxels (8 of 10 within 2; bench/results/head.md).
  // Bounds: the 2 voxels on the median, the tip, the eyes and the nose; the lips at 3 voxels (one voxel
  // above what they reach); the ears either absent or on the source's ear (expect_ears_absent_or_right).
  const double target = 2.0;
  EXPECT_GE(o.axis_cos.minCoeff(), 0.95);
  EXPECT_LE(o.nose_tip_vox, target);
  EXPECT_GE(o.distance_vox.size(), 42u);  // 52 less the 10 ear points
  EXPECT_LE(o.median_vox(), target);
  const std::map<std::string, double> g = group_medians(o);
  for (const char* area : {"eye_right", "eye_left", "nose"}) {
    ASSERT_TRUE(g.count(area)) << area;
    EXPECT_LE(g.at(area), target) << area;
  }
  ASSERT_TRUE(g.count("lips"));
  EXPECT_LE(g.at("lips"), target + 1.0);
  expect_ears_absent_or_right(o);
}

// A fused ear, when one is reported, lies on the source's: its flap's centre within 1.5 rho of the source ear's
// flap centre (rho ~19 mm here). An ear is ~6 cm = 3 rho tall, so a centre within half of that lies on the ear;
// the fins the flap test took for ears before ear_implausible (seed 0 at 2 / 2.5 / 3 mm, seed 18) lie 2.76 .. 3.38 rho from
// it (bench/results/head.md), the fused ears it now keeps at 2 mm 0.54 and 1.04.
TEST(HeadReconstruction, FusedEarsAreAbsentOrOnTheSourceEar) {
  HF_RELEASE_ONLY_ACCURACY("HeadReconstruction.FusedControlPointsMatchTheSource and OneRingAtThePapersScales");
  if (!std::filesystem::exists(kMesh)) GTEST_SKIP() << kMesh << " is absent (../shared not mounted)";
  const TriangleMesh source = read_mesh_file(kMesh);
  // 2 mm: both ears found, formerly on fins 32 / 38 voxels off; 2.5 mm and seed 18: one fin each, now rejected.
  for (const auto& [voxel_m, seed, ears] : {std::tuple{0.002, 0, 2}, std::tuple{0.0025, 0, 0}, std::tuple{0.003, 18, 0}}) {
    Config config;
    config.voxel_m = voxel_m;
    config.seed = seed;
    config.second_elevation_deg = -30.0;
    config.second_sweep_deg = 120.0;
    config.physical = true;
    const Outcome o = reconstruct(source, config);
    print("ears", config, o);
    expect_ears_absent_or_right(o);
    EXPECT_EQ(int(o.fused_ear[0]) + int(o.fused_ear[1]), ears) << voxel_m << " m, seed " << seed;
  }
}

// The capture and scales before: one ring 10 degrees above, the paper's scales (1-ring evaluations, MLS h the
// 1-ring edge, the eyes/nose boundary at half the widest feature's height). Measured: nose tip 0.52 voxel, median
// 3.91 over 40 points, 28 % within 2 voxels (the nose's underside unseen: alae 15 voxels off, nostrils absent).
TEST(HeadReconstruction, OneRingAtThePapersScales) {
  if (!std::filesystem::exists(kMesh)) GTEST_SKIP() << kMesh << " is absent (../shared not mounted)";
  const TriangleMesh source = read_mesh_file(kMesh);
  const Config config;
  const Outcome o = reconstruct(source, config);
  print("paper scales", config, o);
  EXPECT_GE(o.axis_cos.minCoeff(), 0.9);
  EXPECT_LE(o.nose_tip_vox, 2.0);
  EXPECT_GE(o.distance_vox.size(), 38u);  // 52 less the 10 ear points less 2 nostrils (the unseen nose underside)
  EXPECT_LE(o.median_vox(), 5.0);
}

// HF_HEAD_E2E_CONFIG="voxel_m,frames,elevation,second_elevation(nan: none),second_sweep,physical(0/1)[,seed]" runs one
// configuration; HF_HEAD_E2E_REPORT=1 the rows of bench/results/head.md.
TEST(HeadReconstruction, Report) {
  if (!std::filesystem::exists(kMesh)) GTEST_SKIP() << kMesh << " is absent (../shared not mounted)";
  const TriangleMesh source = read_mesh_file(kMesh);
  if (const char* e = std::getenv("HF_HEAD_E2E_CONFIG")) {
    Config c;
    int physical = 0;
    unsigned seed = 0;
    ASSERT_GE(std::sscanf(e, "%lf,%d,%lf,%lf,%lf,%d,%u", &c.voxel_m, &c.frames, &c.elevation_deg, &c.second_elevation_deg,
                          &c.second_sweep_deg, &physical, &seed), 6) << "HF_HEAD_E2E_CONFIG: " << e;
    c.seed = seed;
    c.physical = physical != 0;
    print("config", c, reconstruct(source, c));
  }
  if (std::getenv("HF_HEAD_E2E_REPORT")) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (bool physical : {false, true})
      for (const Config& c0 : {Config{0.003, 18, true, 70, 10, 0, nan, 360}, Config{0.003, 18, true, 70, 10, 0, -30, 120},
                               Config{0.003, 18, true, 70, 10, 0, -20, 120}, Config{0.003, 36, true, 70, 10, 0, -30, 120},
                               Config{0.002, 18, true, 70, 10, 0, -30, 120}, Config{0.0025, 18, true, 70, 10, 0, -30, 120},
                               Config{0.004, 18, true, 70, 10, 0, -30, 120}, Config{0.003, 18, false, 70, 10, 0, -30, 120}}) {
        Config c = c0;
        c.physical = physical;
        print("report", c, reconstruct(source, c));
      }
    // The test's configuration over noise seeds (0: the test; 2 and 8 showed what the eyes' truncation and the lips'
    // plane rule fix; the others were not looked at before the choice).
    for (std::uint64_t seed = 2; seed <= 18; seed += 2) {
      Config c{0.003, 18, true, 70, 10, 0, -30, 120};
      c.physical = true;
      c.seed = seed;
      print("report seed", c, reconstruct(source, c));
    }
  }
}

}  // namespace
}  // namespace hf::head
