// The latency a stage adds to a live pipeline: the time it takes to
// process a frame. GstBaseTransform answers a LATENCY query with upstream's
// latency alone, as if a frame took no time; a live sink (sync=true) then
// renders each frame at its timestamp plus that latency plus its own
// processing-deadline (20 ms by default), and a stage whose frames take
// longer makes every frame late, which QoS turns into dropped frames even
// where the stage keeps up with the frame rate.
//
// Each stage measures its frames (observe()) and adds to the query what
// its frames take (reported()): the second longest of the last kWindow
// frames (one spike does not count; a single frame while there is only
// one), plus an eighth (so that jitter does not post a message every few
// frames), rounded up to a whole millisecond. Every change makes the
// sinks re-time their frames, so it changes rarely: it grows as soon as
// that time exceeds what is reported, and shrinks only when the windows
// of kShrinkAfter frames in a row (about 2 s at 30 frames/s) ask for
// under half of it: the first frames, which fill the stages' pools and
// are computed whole, take much longer than the frames of a still or
// slowly changing picture, while a picture that changes now and then
// (slides) keeps what its changes take. A shrink can cost frames: in a
// pipeline of one thread a live source runs behind by what the sink
// waited, so frames taken against a much larger latency arrive late
// against the new one; for the same reason a stage reports nothing
// before it has measured frames. On a change in a live
// pipeline the stage posts a LATENCY message, on which the application
// recalculates the pipeline's latency (gst_bin_recalculate_latency, as
// gst-launch does). The first kWarmUp frames after a start or a caps
// change are not counted: they allocate the stage's buffers. Plain C++
// so that a unit test can drive it.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

namespace p3d::gst {

class ProcessingLatency {
 public:
  static constexpr int kWarmUp = 1, kWindow = 16, kShrinkAfter = 4 * kWindow;

  // One frame's processing time in nanoseconds (streaming thread). Returns
  // true when reported() changed: post a LATENCY message.
  bool observe(uint64_t ns);
  // Nanoseconds to add to the latency (any thread); 0 before a frame was
  // measured.
  uint64_t reported() const { return reported_.load(std::memory_order_relaxed); }
  // Whether the last LATENCY query found the pipeline live (any thread): a
  // LATENCY message means nothing to a pipeline that is not, so the stage
  // posts none there.
  void set_live(bool live) { live_.store(live, std::memory_order_relaxed); }
  bool live() const { return live_.load(std::memory_order_relaxed); }
  // New caps: the next frames allocate again; what was reported stays.
  void restart();
  // Stopped: nothing reported.
  void reset();

 private:
  std::array<uint64_t, kWindow> frames_{};
  int seen_ = 0, count_ = 0, next_ = 0, short_ = 0;
  std::atomic<uint64_t> reported_{0};
  std::atomic<bool> live_{false};
};

}  // namespace p3d::gst
