// GPU cross-bilateral filter: the function of common/bilateral.h, both
// modes (cuda/bilateral.cu: one tiled kernel per mode and radius).
//
// One instance per stream: the weight tables live in this instance's device
// memory and are rewritten (stream-ordered, cudaMemcpyAsync) only when the
// sanitised parameters change, so calls on one instance must be ordered on
// one stream. No host synchronisation except the one the driver may do when
// the tables are uploaded from pageable memory (on parameter changes only).
#pragma once

#include <vector>

#include "../common/bilateral.h"
#include "change_gpu.h"
#include "cuda_check.h"
#include "device_buffer.h"
#include "high_bytes_gpu.h"

namespace p3d {

class BilateralFilterGpu {
 public:
  // guide, depth_in, depth_out: device memory; depth_in != depth_out
  // (cudaErrorInvalidValue otherwise, as for a guide or output whose size
  // differs from depth_in). Parameters are sanitised as on the CPU
  // (bilateral_sanitize). Empty images: no-op.
  CudaStatus run(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                 ImageView<float> depth_out, cudaStream_t stream);
  // The same on grids (p3d_defs.h DepthGrid): depth_in at any shift (the
  // estimator's block grid is read in place), depth_out at shift 0 (the
  // full-size map) or at bilateral_grid_shift(), one value a cell of the
  // coarse grid, which the filter then writes once instead of to each of
  // the cell's pixels. Widths and heights are the picture's; another
  // output shift, or cells that do not fit (grid_fits), give
  // cudaErrorInvalidValue.
  //
  // Adaptive (bilateral_filter_changed_cpu on the device): dirty, the
  // tiles within bilateral_reach() of a changed guide or depth tile; a
  // block of outputs outside them copies its values from `kept`, the
  // previous frame's output (depth_out's geometry, cudaErrorInvalidValue
  // otherwise), instead of filtering. Default flags: every block filters.
  CudaStatus run(const BilateralParams &params, const FrameView &guide, DepthGrid<const float> depth_in,
                 DepthGrid<float> depth_out, cudaStream_t stream, const TileFlags &dirty = {},
                 DepthGrid<const float> kept = {});

 private:
  CudaStatus upload_tables(const BilateralParams &sanitised, cudaStream_t stream);

  HighByteFrame high_bytes_;  // a deep input's 8-bit copy (cuda/high_bytes_gpu.h)
  DeviceBuffer tables_;  // range (511, symmetric) then space ((2r+1)^2) weights, uploaded when params change
  std::vector<float> host_tables_;  // source of the last upload; outlives the async copy
  BilateralParams uploaded_{-1, 0.f, 0.f};
};

}  // namespace p3d
