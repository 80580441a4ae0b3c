// StallWatch (tools/convert/stall_watch.h): a conversion that gets no new
// frame for the limit counts as stalled; any new frame restarts the clock.
#include <gtest/gtest.h>

#include "convert/stall_watch.h"

using p3d::convert::StallWatch;

namespace {
constexpr int64_t kSecond = 1000000;
}

TEST(StallWatch, NoFrameForTheLimitIsAStall) {
  StallWatch w(120);
  EXPECT_FALSE(w.stalled(0, 5 * kSecond));  // the clock starts at the first call
  EXPECT_FALSE(w.stalled(0, 124 * kSecond));
  EXPECT_TRUE(w.stalled(0, 125 * kSecond));
  EXPECT_TRUE(w.stalled(0, 500 * kSecond));
}

TEST(StallWatch, EachNewFrameRestartsTheClock) {
  StallWatch w(2);
  int64_t t = 0;
  for (uint64_t frames = 0; frames < 50; ++frames, t += kSecond) EXPECT_FALSE(w.stalled(frames, t)) << frames;
  EXPECT_FALSE(w.stalled(49, t + kSecond / 2));
  EXPECT_TRUE(w.stalled(49, t + kSecond));  // frame 49 came at t - 1 s: 2 s without a new one
  EXPECT_FALSE(w.stalled(50, t + 5 * kSecond));
}

TEST(StallWatch, SlowButSteadyIsNoStall) {
  StallWatch w(3);
  for (uint64_t frames = 0; frames < 20; ++frames) EXPECT_FALSE(w.stalled(frames, frames * 29 * kSecond / 10));
}
