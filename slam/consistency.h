// Whether a frame's depth agrees with a reference: the test the pipeline's failure policy (slam/pipeline.h,
// PipelineConfig::min_consistent), relocalisation and loop verification (slam/backend.h) share.
//
// Every 4th pixel of the frame's vertex map in x and y is moved into the reference and compared; a sample
// OVERLAPS where it lands on reference data and AGREES within 3 sigma of the Kinect axial noise (Nguyen et al.
// 2012) plus one voxel.
// Thread-safety: pure functions; volume_consistency reads the grid (no concurrent writer allowed).
#pragma once

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "fusion/voxel_block_grid.h"
#include "registration/frame_pyramid.h"

namespace hf::slam {

// (pixels sampled, pixels landing on the reference, pixels agreeing).
struct Consistency {
  long sampled = 0, overlap = 0, consistent = 0;
};

// Against a reference depth image (metres, 0 = none) seen by `camera`; T_ref_cur moves the frame's points into it.
Consistency depth_consistency(const VertexMap& current, const DepthImage& reference_depth, const PinholeCamera& camera,
                              const SE3& T_ref_cur, double voxel_m);

// The same question asked of the map itself, for a method that aligns to the volume (no raycast to compare with):
// a sample overlaps where the TSDF around its world point is observed, and agrees where its distance to the
// surface there is within the same noise bound.
Consistency volume_consistency(const VertexMap& current, const fusion::VoxelBlockGrid& grid, const SE3& T_world_cur);

}  // namespace hf::slam
