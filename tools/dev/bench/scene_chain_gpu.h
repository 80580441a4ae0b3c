// The GPU chain of pseudo3d-bench's scene mode (--device gpu): depth,
// filter and the warp writing the layout's output, on frames in device
// memory, as the elements run them on CUDA memory: depth handed on as
// grids in planes of a pool, every stage's output a new buffer. With
// adaptive, each stage does what its element's GPU path does (cuda/
// change_gpu.h): it compares its inputs on the device, the depth sums the
// blocks of changed tiles, the filter the cells within its reach, and the
// warp's kernels return at once on a frame whose inputs did not change,
// whose output is then the kept copy, and render only the rows a change
// reaches. crop-bars off, or (adaptive off) auto: the bars counted on the
// device and read back at the next frame as pseudo3ddepth does (the first
// frame's waited for), the depth estimated and
// filtered inside them (the planes 0 outside), the views rendered by
// ActiveWarpGpu. Host code on the CUDA runtime API (built by the host
// compiler, linked with the kernels).
#pragma once

#include <memory>
#include <vector>

#include "bench_gpu.h"      // StageParams
#include "device_frames.h"  // DevFrame: the frames a chain reads
#include "scene_chain.h"    // StageMs

namespace p3d::bench {

class GpuSceneChain {
 public:
  // crop: crop-bars=auto, with adaptive false only.
  GpuSceneChain(const StageParams &p, int width, int height, PixelFormat input, bool adaptive, float tolerance,
                bool crop = false);
  ~GpuSceneChain();
  GpuSceneChain(GpuSceneChain &&) noexcept;
  // One frame (device memory: a DevFrame); ms: each stage's GPU time (CUDA events).
  // Throws std::runtime_error naming a failed CUDA call.
  void frame(const FrameView &src, StageMs *ms);
  // The last frame's output, copied to the host.
  const HostFrame &output() const;
  // The share of the rows the warp rendered in the last frame: every row
  // of a frame it did not compare (the first, backing off, adaptive
  // off), else those its changes reach (KeptOutputGpu::last_rows_share).
  double warp_rows_share() const;

 private:
  void frame_cropped(const FrameView &src, StageMs *ms);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace p3d::bench
