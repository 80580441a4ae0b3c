// Turns a stalled conversion into an error. A damaged file can leave
// GStreamer's demuxer and decoders waiting on each other with no error
// posted (seen with random bytes in a Matroska header: about 2 runs in 15
// stopped at 0 % CPU, and gst-launch's decodebin does the same about 1 in
// 20): the converter would then wait forever. The main loop feeds the
// frame count a few times a second; no new frame for `limit` seconds is a
// stall. Not used for pipes and FIFOs, whose writer may simply be slow.
#pragma once

#include <cstdint>

namespace p3d::convert {

class StallWatch {
 public:
  explicit StallWatch(double limit_seconds) : limit_us_(static_cast<int64_t>(limit_seconds * 1e6)) {}
  // The frame count at monotonic time now_us; true once no frame has come
  // for the limit (from the first call, or from the last new frame).
  bool stalled(uint64_t frames, int64_t now_us) {
    if (last_us_ < 0 || frames != frames_) {
      frames_ = frames;
      last_us_ = now_us;
      return false;
    }
    return now_us - last_us_ >= limit_us_;
  }
  double limit_seconds() const { return limit_us_ / 1e6; }

 private:
  int64_t limit_us_;
  uint64_t frames_ = 0;
  int64_t last_us_ = -1;
};

}  // namespace p3d::convert
