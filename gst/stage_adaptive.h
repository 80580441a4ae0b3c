// The adaptive work of a stage (adaptive=true, the default): what a stage
// keeps of its inputs and its output from one frame to the next, so that it
// recomputes only the tiles a change can reach (common/change_map.h; on
// CUDA memory cuda/change_gpu.h, all of it on the device). With
// reuse-tolerance 0 the output is byte for byte that of adaptive=false.
#pragma once

#include <gst/video/video.h>

#include <cstdint>
#include <vector>

#include "adaptive.h"
#include "config.h"
#include "depth_plane.h"
#include "gstpseudo3dbase.h"
#if HAVE_CUDA
#include "change_gpu.h"
#endif

namespace p3d::gst {

// The stage's adaptive settings for this frame, read once.
// tolerance: reuse-tolerance (common/change_map.h FrameHistory).
struct AdaptiveSettings {
  bool on = false;
  float tolerance = 0.f;
};
AdaptiveSettings adaptive_settings(GstPseudo3DBase *self);

// A stage's inputs of the previous frame (common/adaptive.h StageInputs,
// with its back-off), holding on to the depth plane (planes never change
// once attached).
class InputHistory {
 public:
  // reach: as StageInputs'.
  explicit InputHistory(ChangeReach reach = ChangeReach::Tiles) : inputs_(reach) {}
  void set_reach(ChangeReach reach) { inputs_.set_reach(reach); }
  // StageInputs::begin: false when the frame is computed whole, uncompared.
  bool begin(bool adaptive);
  // The tiles in which this frame or its depth (a host plane; null: the
  // stage reads none) differ from the previous call's; every tile after
  // reset().
  ChangeMap compare(const FrameView &frame, const DepthPlanePtr &depth, float tolerance);
  void reset();

 private:
  StageInputs inputs_;
  DepthPlanePtr depth_;
};

// The output of the previous frame, for the stages that write a new
// buffer each frame: a copy of its pixels. (Holding the buffer itself
// would keep one buffer of a downstream pool out of circulation, which
// hangs a pool with a fixed number of buffers.)
class OutputHistory {
 public:
  // reach: what the stage redoes of a change; a frame busy for it
  // (busy_for) leaves nothing of its output worth keeping.
  explicit OutputHistory(ChangeReach reach) : reach_(reach) {}
  void set_reach(ChangeReach reach) { reach_ = reach; }
  // The previous output, a frame of `info` (KeptOutput::previous: the
  // stage's call copies the rows it does not write); false when there is
  // none of that size and format.
  bool previous(const GstVideoInfo *info, FrameView *view) const;
  // After a frame: keeps a copy of `out` (mapped, of `info`) where it
  // changed (whole, or `changes` has a tile; of a frame computed from
  // previous(), the rows `written`). Not after a busy frame, the stream's
  // first apart: its successor likely is too and would not read it (a
  // frame that changes less after such a run is computed whole).
  void update(const GstVideoInfo *info, const GstVideoFrame *out, const ChangeMap &changes, bool whole,
              const std::vector<uint8_t> &written);
  void reset() { valid_ = seen_ = false; }

 private:
  ChangeReach reach_;
  bool valid_ = false, seen_ = false;
  GstVideoInfo info_;
  std::vector<uint8_t> planes_[GST_VIDEO_MAX_PLANES];
};

#if HAVE_CUDA
// InputHistory on CUDA memory: the frame compared with a copy on the
// device, the depth grid with the previous frame's plane (held), the tiles
// that changed left in changes().
class InputHistoryGpu {
 public:
  // frame: device memory; depth: a device plane or null (the stage reads
  // none). Queued on `stream`.
  CudaStatus compare(const FrameView &frame, const DepthPlanePtr &depth, float tolerance, cudaStream_t stream);
  const ChangeMapGpu &changes() const { return changes_; }
  // Whether the last compare() had the previous frame's inputs (else it
  // flagged every tile).
  bool compared() const { return compared_; }
  void reset();

 private:
  FrameHistoryGpu frame_;
  ChangeMapGpu changes_;
  DepthPlanePtr depth_;
  bool compared_ = false;
};

// The adaptive steps on CUDA memory of a stage that keeps a whole copy of
// its output (pseudo3dwarp, pseudo3dpack): its inputs compared, the device's
// decision (KeptOutputGpu; the warp's rows), the back-off
// (ChangeBackOff). Per frame: begin() before the GPU block; inside it
// decide(), the stage's kernels behind the gate, finish(); end() after
// the block's wait.
class WholeOutputGpu {
 public:
  // Whether this frame is compared (adaptive and not backing off); when
  // not, what was kept is dropped and the frame is computed whole.
  bool begin(bool adaptive);
  // Compares the inputs (depth: as InputHistoryGpu::compare) and queues
  // the decision for the output `out`; whole: the parameters changed.
  // *gate: the stage's; with its rows where reach_rows >= 0
  // (KeptOutputGpu::decide).
  CudaStatus decide(const FrameView &frame, const DepthPlanePtr &depth, float tolerance, const FrameView &out,
                    bool whole, cudaStream_t stream, StageGate *gate, int reach_rows = -1);
  CudaStatus finish(const FrameView &out, cudaStream_t stream) { return output_.finish(out, stream); }
  // After the frame's work was waited for (ok: it succeeded; a failed
  // frame leaves nothing kept).
  void end(bool ok);
  void reset();

 private:
  InputHistoryGpu inputs_;
  KeptOutputGpu output_;
  ChangeBackOff backoff_;
  bool comparing_ = false;
};
#endif

// The parameters of the previous frame: whatever was kept was made with
// them, and any change makes the stage compute the whole frame.
template <typename T>
class KeptParams {
 public:
  // Whether p differs from the previous call's (true at the first call and
  // after reset()); p becomes the previous.
  bool changed(const T &p) {
    const bool differs = !have_ || !(p == last_);
    last_ = p;
    have_ = true;
    return differs;
  }
  void reset() { have_ = false; }

 private:
  T last_{};
  bool have_ = false;
};

// The frame's depth plane as the meta holds it (shared), or null.
DepthPlanePtr frame_depth_plane(GstBuffer *buf);

}  // namespace p3d::gst
