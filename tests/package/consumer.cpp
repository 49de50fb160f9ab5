// Integrates one synthetic frame into a TSDF, extracts its mesh and evaluates the ground-truth trajectory against
// itself, through the installed hashfusion package. Exit 0 when the mesh has surface where the frame saw it and
// the ATE is zero.
#include <cmath>
#include <cstdio>

#include <hashfusion/datasets/synthetic_sequence.h>
#include <hashfusion/fusion/integrate.h>
#include <hashfusion/fusion/mesh.h>
#include <hashfusion/fusion/voxel_block_grid.h>
#include <hashfusion/slam/eval.h>

int main() {
  hf::datasets::SyntheticOptions options;
  options.frames = 3;
  options.noise_enabled = false;
  options.camera = hf::PinholeCamera::preset("ros").scaled(2);  // 160x120: fast
  const hf::datasets::SyntheticSequence sequence(options);
  const hf::datasets::SyntheticFrame frame = sequence.frame(0);

  hf::fusion::VolumeParams volume;
  volume.voxel_m = 0.04;
  volume.capacity_blocks = 1 << 12;
  hf::fusion::VoxelBlockGrid grid(volume);
  hf::fusion::integrate(grid, frame.depth, frame.color, options.camera, frame.T_world_camera);
  const hf::TriangleMesh mesh = hf::fusion::extract_mesh(grid);
  mesh.validate();

  hf::Trajectory gt;
  for (int i = 0; i < sequence.size(); ++i) gt.push_back({sequence.timestamp_s(i), sequence.T_world_camera(i)});
  const double ate_m = hf::evaluate_ate(gt, gt).error_m.rmse;

  std::printf("consumer: %zu vertices, %zu triangles, ATE %g m\n", mesh.vertices.size(), mesh.triangles.size(),
              ate_m);
  return mesh.triangles.size() > 100 && std::abs(ate_m) < 1e-9 ? 0 : 1;
}
