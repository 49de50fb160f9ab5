// Combined ICP (report eq. 47-48), one pixel: the geometric row and the photometric row of the same pixel, the
// photometric one weighted by lambda (its params' weight; scaling J and r of a row by sqrt(lambda) is the same as
// weighting it by lambda; eq. 48's sqrt(lambda) on J^T r alone would be inconsistent with its lambda on J^T J).
// Common C++/OpenCL-C subset. Reads the maps of both kernels.
#ifndef HF_REGISTRATION_KERNELS_COMBINED_KERNEL_H
#define HF_REGISTRATION_KERNELS_COMBINED_KERNEL_H

#include "registration/kernels/icp_kernel.h"
#include "registration/kernels/photometric_kernel.h"

typedef struct {
  hf_icp_params icp;
  hf_photometric_params photometric;
} hf_combined_params;

// Writes 0..2 rows: the ICP row (if any) first.
HF_INLINE int hf_combined_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T,
                                hf_combined_params p, hf_reg_row* rows) {
  const int n = hf_icp_pixel(x, y, maps, K, T, p.icp, rows);
  return n + hf_photometric_pixel(x, y, maps, K, T, p.photometric, rows + n);
}

HF_REG_OPENCL_KERNEL(combined, hf_combined_pixel, hf_combined_params)

#endif
