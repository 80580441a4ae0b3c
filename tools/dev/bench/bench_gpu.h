// GPU side of pseudo3d-bench: CUDA-event timings of each stage, of the whole
// chain and of a device-to-device copy. The interface uses no CUDA types, so
// pseudo3d_bench.cpp (built by the host compiler) only sees plain C++; it is
// compiled in only when meson defines P3D_BENCH_GPU.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "bilateral.h"
#include "depth_estimate.h"
#include "host_frame.h"
#include "pack.h"
#include "warp.h"

namespace p3d::bench {

// The parameters every stage runs with, shared by the CPU and GPU timings.
struct StageParams {
  DepthParams depth;
  BilateralParams filter;
  WarpParams warp;
  PackParams pack;
  YuvToRgb yuv;
  // GPU: the stages hand depth on as the elements do on CUDA memory, on
  // grids (p3d_defs.h DepthGrid: the estimator's blocks, the filter's
  // cells); false: as full-size maps (as the host planes hold it), for
  // same-binary A/B runs (--depth-handoff full).
  bool depth_grids = true;
};

// Stages in the order they are timed; "convert" is load_rgba -> RGBA, the
// colour-conversion cost on its own; "chain" is depth, filter, warp and pack
// back to back.
inline const std::vector<std::string> &stage_names() {
  static const std::vector<std::string> names = {"convert", "depth", "filter", "warp", "pack", "warp-pack", "chain"};
  return names;
}

// The format the warp renders into (and pack reads and writes): the input's
// own packed RGB format, or RGBA for YUV input.
inline PixelFormat stereo_format(PixelFormat input) {
  return is_packed_rgb(input) ? input : (is_deep(input) ? PixelFormat::RGBA64 : PixelFormat::RGBA);
}

// Per-iteration times of one stage in milliseconds, in run order.
struct StageTimes {
  std::string stage;
  std::vector<double> ms;
};

struct TimingPlan {
  int warmup = 10;
  int iterations = 50;
};

// Whether a CUDA device can be used, and the name of the current one.
bool gpu_present();
std::string gpu_name();

// Times cudaMemcpyAsync of `bytes` between two device buffers. On error
// returns false with *error set (the failed call and its CUDA error).
bool gpu_time_copy(size_t bytes, const TimingPlan &plan, std::vector<double> *ms, std::string *error);

// Uploads `frames` (all one format and size) and times every stage of
// stage_names() on them, iteration i reading frame i % frames.size().
bool gpu_time_stages(const StageParams &params, const std::vector<HostFrame> &frames, const TimingPlan &plan,
                     std::vector<StageTimes> *out, std::string *error);

}  // namespace p3d::bench
