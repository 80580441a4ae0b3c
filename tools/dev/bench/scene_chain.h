// The CPU chain of pseudo3d-bench's scene mode, a frame at a time, as the
// elements run it on system memory: depth (pseudo3ddepth), filter
// (pseudo3dfilter), warp writing the layout's output (pseudo3dwarp).
// FullChain is adaptive=false: every stage computes the whole frame.
// AdaptiveChain is adaptive=true (common/adaptive.h): it does what the
// elements' process functions do, step for step, with the same hand-offs
// (an unchanged depth is the previous plane itself, the warp's output starts
// as a copy of the previous output), so that its time is the elements'.
#pragma once

#include <chrono>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "adaptive.h"
#include "bars.h"
#include "bench_gpu.h"  // StageParams
#include "depth_estimate.h"
#include "host_frame.h"

namespace p3d::bench {

// Milliseconds a stage took on one frame (the warp's time includes its pack
// and, adaptive, the copy of the previous output).
struct StageMs {
  double depth = 0, filter = 0, warp = 0;
  double total() const { return depth + filter + warp; }
};

// Times consecutive steps: lap() returns the milliseconds since the previous
// lap (or construction).
class Stopwatch {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    return ms;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// The warp's output in the bench's stereo format (bench_gpu.h
// stereo_format()) at the layout's size, and the pair it renders the views
// into first: the output itself where the layout is the pair (as
// StereoPacking::pair_target), else a frame kept from one call to the next.
class WarpTarget {
 public:
  WarpTarget(const PackParams &pack, int width, int height, PixelFormat input);
  bool pair_is_output() const { return pair_is_output_; }
  FrameView pair(const FrameView &output) const { return pair_is_output_ ? output : pair_.view(); }
  HostFrame new_output() const;

 private:
  bool pair_is_output_;
  PixelFormat format_;
  int out_width_ = 0, out_height_ = 0;
  HostFrame pair_;
};

// crop: crop-bars=auto, as pseudo3ddepth, pseudo3dfilter and pseudo3dwarp
// run it: the bars decided from the frames before this one (BarTracker's
// order; the counts taken with the depth), each stage on the picture
// between them.
class FullChain {
 public:
  FullChain(const StageParams &p, int width, int height, PixelFormat input, bool crop = false);
  void frame(const FrameView &src, StageMs *ms);
  const HostFrame &output() const { return out_; }

 private:
  StageParams p_;
  bool crop_;
  DepthEstimatorCpu estimator_;
  cv::Mat depth_, filtered_;
  WarpTarget target_;
  HostFrame out_;
  WarpCpuScratch warp_scratch_;
  BarTracker bars_;
  BarCounts counts_;
  PixelRect rect_;
  HostFrame active_pair_;  // the views of a rect narrower than the frame
};

// Depth planes of one size, recycled once nobody holds them: the elements'
// DepthPlanePool (gst/depth_plane.h), so that a frame allocates nothing.
class PlanePool {
 public:
  using Plane = std::shared_ptr<cv::Mat>;
  // `ready` planes are allocated and written at once: the first frames find
  // them mapped, as a stream that has run a while does.
  PlanePool(int width, int height, int ready);
  Plane acquire();

 private:
  int width_, height_;
  std::vector<Plane> planes_;
};

// With crop-bars=auto, the elements' default, as FullChain's crop.
class AdaptiveChain {
 public:
  AdaptiveChain(const StageParams &p, int width, int height, PixelFormat input, float tolerance);
  void frame(const FrameView &src, StageMs *ms);
  const HostFrame &output() const { return out_; }
  // The last frame's shares of the picture that the stages took as
  // changed (1 on a whole frame): the depth stage's tiles (the input), the
  // filter's and the warp's tiles (input or depth), and the source pixels
  // in the columns of each row the warp was given as changed (ColumnSpan);
  // warp_rows: the GPU chain's (GpuSceneChain::warp_rows_share).
  struct Shares {
    double input = 0, filter = 0, warp = 0, warp_spans = 0, warp_rows = 0;
  };
  const Shares &shares() const { return shares_; }

 private:
  using Plane = PlanePool::Plane;
  // Each stage as its element runs it; `changes` gets the tiles it took as
  // changed (all of them on a whole frame).
  Plane depth(const FrameView &src, ChangeMap *changes);
  Plane filter(const FrameView &src, const Plane &depth, ChangeMap *changes);
  void warp(const FrameView &src, const Plane &depth, ChangeMap *changes);

  StageParams p_;
  float tolerance_;
  // pseudo3ddepth: the frame history, the estimator and the last plane;
  // the bars and the rect the depth was estimated in.
  StageInputs depth_inputs_;
  DepthEstimatorCpu estimator_;
  PlanePool depth_pool_;
  Plane depth_last_;
  BarTracker bars_;
  BarCounts counts_;
  PixelRect rect_;
  HostFrame active_pair_;
  // pseudo3dfilter: its inputs (the depth plane held), its last output.
  StageInputs filter_inputs_;
  Plane filter_depth_, filter_last_;
  PixelRect filter_rect_;
  PlanePool filter_pool_;
  BilateralScratch filter_scratch_;
  // pseudo3dwarp: its inputs, the output buffer and the copy of the
  // previous output the element keeps (gst/stage_adaptive.h OutputHistory),
  // the pair and the warp's state.
  StageInputs warp_inputs_{ChangeReach::Spans};
  Plane warp_depth_;
  WarpTarget target_;
  HostFrame out_, kept_;  // the new output buffer; the element's copy of the previous output
  PixelRect warp_rect_;
  bool have_output_ = false, seen_ = false;
  WarpCpuScratch warp_scratch_;
  Shares shares_;
};

}  // namespace p3d::bench
