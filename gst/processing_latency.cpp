#include "processing_latency.h"

#include <algorithm>

namespace p3d::gst {

bool ProcessingLatency::observe(uint64_t ns) {
  if (seen_ < kWarmUp) {
    ++seen_;
    return false;
  }
  frames_[next_] = ns;
  next_ = (next_ + 1) % kWindow;
  count_ = std::min(count_ + 1, kWindow);
  // The second longest frame of the window (the longest while it holds one).
  uint64_t longest = 0, second = 0;
  for (int i = 0; i < count_; ++i) {
    const uint64_t t = frames_[i];
    if (t > longest) {
      second = longest;
      longest = t;
    } else if (t > second) {
      second = t;
    }
  }
  if (count_ == 1) second = longest;
  // What to report for it: an eighth more, so that the frames' jitter does
  // not post a message on every few frames, in whole milliseconds.
  constexpr uint64_t kMs = 1000000;
  const uint64_t margin = second + second / 8, wanted = (margin + kMs - 1) / kMs * kMs;
  const uint64_t now = reported();
  // Longer frames raise it at once; kShrinkAfter frames in a row whose
  // full windows ask for under half of it lower it.
  short_ = count_ == kWindow && 2 * wanted < now ? short_ + 1 : 0;
  const bool grow = second > now, shrink = short_ >= kShrinkAfter;
  if (!grow && !shrink) return false;
  short_ = 0;
  reported_.store(wanted, std::memory_order_relaxed);
  return true;
}

void ProcessingLatency::restart() {
  seen_ = count_ = next_ = short_ = 0;
}

void ProcessingLatency::reset() {
  restart();
  reported_.store(0, std::memory_order_relaxed);
  live_.store(false, std::memory_order_relaxed);
}

}  // namespace p3d::gst
