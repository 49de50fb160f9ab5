// `ferns`: random ferns, Glocker, Shotton, Criminisi & Izadi, "Real-Time RGB-D Camera Relocalization via
// Randomized Ferns for Keyframe Encoding" (TVCG 2015), the keyframe code of InfiniTAM and ElasticFusion.
//
// The frame is block-averaged to width x height (80x60). Fern k is a pixel u_k and four thresholds tau_k,c drawn
// once from `seed`: one per colour channel c in {R, G, B} (uniform in [0, 255]) and one for depth (uniform in
// [min_depth_m, max_depth_m]); its code is the 4 bits [I_c(u_k) >= tau_k,c]. A pixel without depth tests as 0
// (below every threshold, as ElasticFusion does); without colour (empty image) the colour bits are left out of the
// comparison. Dissimilarity is the block-wise Hamming distance
//   BlockHD(I, J) = (1 / m) * sum_k [code_k(I) != code_k(J)]   in [0, 1] (Glocker et al., eq. 3)
// compared over the bits both frames have. Query cost O(size() * m); memory m bytes per keyframe (one code byte per
// fern) plus 1/size() of the fern table.
#pragma once

#include <cstdint>

#include "slam/appearance.h"

namespace hf::slam {

struct FernsOptions {
  int ferns = 1000;             // m (ElasticFusion: 500); 1000 ranked best on the tuning part (appearance.tuning.md)
  int width = 80, height = 60;  // the downsampled frame the tests read
  double min_depth_m = 0.8, max_depth_m = 4.0;  // depth threshold range (ElasticFusion: 800..4000 mm)
  std::uint64_t seed = 1;       // fern positions and thresholds (deterministic; same seed, same codes)
  void validate() const;        // hf::Error naming the bad field
};

class FernsIndex : public AppearanceIndex {
 public:
  explicit FernsIndex(const FernsOptions& options = {});  // hf::Error for bad options
  std::string name() const override { return "ferns"; }
  void add(size_t id, const ColorImage& colour, const DepthImage& depth) override;
  std::vector<AppearanceMatch> query(const ColorImage& colour, const DepthImage& depth, size_t k) const override;
  size_t size() const override { return ids_.size(); }
  size_t bytes_per_keyframe() const override;

  // The frame's fern codes (bits 0-2: R, G, B; bit 3: depth) and whether the colour bits are meaningful.
  struct Code {
    std::vector<std::uint8_t> bits;
    bool has_colour = false;
  };
  Code encode(const ColorImage& colour, const DepthImage& depth) const;

 private:
  struct Fern {
    int x = 0, y = 0;
    float tau_rgb[3] = {0, 0, 0};
    float tau_depth_m = 0;
  };
  FernsOptions options_;
  std::vector<Fern> ferns_;
  std::vector<size_t> ids_;
  std::vector<Code> codes_;
};

}  // namespace hf::slam
