// adaptive=true against adaptive=false through the elements: the same
// sequences of frames (unchanged runs, small changes, big changes, scene
// cuts) give byte-identical output frames through every stage and through
// pseudo3dconvert, for several layouts, formats and fills; a property
// changed between frames, a flush and a caps change give what a fresh
// element gives; the previous output that a stage keeps is not written to;
// memory stays flat over a long run of small changes.
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "element_helpers.h"
#include "test_data.h"

using namespace p3d;
using namespace p3d::test;

namespace {


// The element named "c" in a harness's pipeline.
GstElement *element_c(GstHarness *hx) {
  GstElement *c = gst_bin_get_by_name(GST_BIN(hx->element), "c");
  gst_object_unref(c);  // the pipeline holds it
  return c;
}

struct Case {
  std::string chain;
  PixelFormat format;
};

TEST(AdaptiveElements, SameBytesAsFullComputation) {
  const int w = 160, h = 100;
  const std::vector<Case> cases = {
      {"pseudo3dconvert processing=cpu layout=side-by-side-half", PixelFormat::I420},
      {"pseudo3ddepth processing=cpu edge-threshold=8 ! pseudo3dfilter processing=cpu ! pseudo3dwarp processing=cpu max-disparity=12", PixelFormat::RGBA},
      {"pseudo3dconvert processing=cpu layout=anaglyph", PixelFormat::NV12},
      {"pseudo3dconvert processing=cpu layout=top-bottom-half fill=background", PixelFormat::RGBA},
      {"pseudo3dconvert processing=cpu layout=row-interleaved fill=neighbor-average", PixelFormat::BGRx},
      {"pseudo3dconvert processing=cpu layout=checkerboard view=right scale=3", PixelFormat::I420},
      {"pseudo3ddepth processing=cpu block-size=5 temporal-smoothing=0.3 ! pseudo3dfilter processing=cpu mode=exact ! "
       "pseudo3dwarp processing=cpu ! pseudo3dpack processing=cpu layout=top-bottom",
       PixelFormat::RGBA},
      {"pseudo3ddepth processing=cpu ! pseudo3dfilter processing=cpu ! pseudo3dwarp processing=cpu layout=left "
       "fill=none ! capsfilter caps=video/x-raw,format=NV12",
       PixelFormat::RGBx},
      // A flat depth map (one value): the filter passes it on unfiltered.
      {"pseudo3dconvert processing=cpu hypothesis=flat layout=side-by-side-half", PixelFormat::I420},
  };
  for (const Case &c : cases) {
    const std::vector<cv::Mat> frames = changing_sequence(w, h, 7);
    const auto full = output_bytes(with_adaptive(c.chain, false), c.format, frames);
    const auto adaptive = output_bytes(with_adaptive(c.chain, true), c.format, frames);
    expect_same_bytes(full, adaptive, c.chain);
  }
}

// Busy frames make the stages back off (ChangeBackOff: whole frames,
// uncompared, their histories dropped); calm frames after the pause make
// them compare and keep again. Every frame is byte for byte the full
// computation's across both transitions. 160 x 100: 20 tiles, so that a
// small box is not busy.
TEST(AdaptiveElements, BackingOffAndBackChangesNoByte) {
  const int w = 160, h = 100;
  std::vector<cv::Mat> frames;
  std::mt19937 rng(17);
  cv::Mat cur;
  for (int k = 0; k < 60; ++k) {
    // Cuts at 0-3 and 30-32; between, a small box moves on every third
    // frame and the others are unchanged.
    if (k < 4 || (k >= 30 && k < 33)) {
      cur = textured_picture(w, h, 200 + k);
    } else if (k % 3 == 0) {
      cur = cur.clone();
      const cv::Rect r(static_cast<int>(rng() % (w - 12)), static_cast<int>(rng() % (h - 10)), 12, 10);
      cv::rectangle(cur, r, cv::Scalar(rng() % 256, rng() % 256, rng() % 256), cv::FILLED);
    }
    frames.push_back(cur);
  }
  const std::vector<Case> cases = {
      {"pseudo3dconvert processing=cpu layout=side-by-side-half", PixelFormat::I420},
      {"pseudo3ddepth processing=cpu ! pseudo3dfilter processing=cpu ! pseudo3dwarp processing=cpu ! "
       "pseudo3dpack processing=cpu layout=top-bottom-half",
       PixelFormat::RGBA},
  };
  for (const Case &c : cases)
    expect_same_bytes(output_bytes(with_adaptive(c.chain, false), c.format, frames),
                      output_bytes(with_adaptive(c.chain, true), c.format, frames), c.chain);
}

// A property changed between frames: the stage recomputes what it kept.
TEST(AdaptiveElements, PropertyChangeBetweenFramesInvalidatesWhatWasKept) {
  const int w = 80, h = 48;
  const std::vector<cv::Mat> frames = changing_sequence(w, h, 11);
  const std::string chain = "pseudo3dconvert processing=cpu layout=side-by-side-half name=c";
  auto change = [](int k, GstHarness *hx) {
    GstElement *c = element_c(hx);
    if (k == 3) g_object_set(c, "max-disparity", 6.0f, NULL);
    if (k == 5) g_object_set(c, "radius", 2, NULL);
    if (k == 8) g_object_set(c, "fill", 0, NULL);  // background
    if (k == 9) g_object_set(c, "convergence", 0.2f, NULL);
    if (k == 11) g_object_set(c, "hypothesis", 1, NULL);  // left-right
  };
  const auto full = output_bytes(with_adaptive(chain, false), PixelFormat::I420, frames, change);
  expect_same_bytes(full, output_bytes(with_adaptive(chain, true), PixelFormat::I420, frames, change), "property changes");
  // The changes took effect: without them the last frame differs.
  EXPECT_FALSE(full.back() == output_bytes(with_adaptive(chain, false), PixelFormat::I420, frames).back());
}

// Switching adaptive itself while frames flow changes no byte.
TEST(AdaptiveElements, TogglingAdaptiveChangesNoByte) {
  const std::vector<cv::Mat> frames = changing_sequence(64, 40, 5);
  const std::string chain = "pseudo3dconvert processing=cpu layout=anaglyph name=c";
  auto toggle = [](int k, GstHarness *hx) {
    g_object_set(element_c(hx), "adaptive", k % 3 != 1, NULL);
    gboolean on = FALSE;
    g_object_get(element_c(hx), "adaptive", &on, NULL);
    EXPECT_EQ(on, k % 3 != 1);
  };
  expect_same_bytes(output_bytes(with_adaptive(chain, false), PixelFormat::NV12, frames),
              output_bytes(chain, PixelFormat::NV12, frames, toggle), "adaptive toggled");
}

// After a flush the output is that of an element that never saw the
// frames before it.
TEST(AdaptiveElements, FlushStartsAfresh) {
  const std::vector<cv::Mat> frames = changing_sequence(64, 40, 3);
  const std::string chain = "pseudo3dconvert processing=cpu layout=side-by-side-half";
  auto flush = [](int k, GstHarness *hx) {
    if (k != 6) return;
    gst_harness_push_event(hx, gst_event_new_flush_start());
    gst_harness_push_event(hx, gst_event_new_flush_stop(TRUE));
    GstSegment seg;
    gst_segment_init(&seg, GST_FORMAT_TIME);
    gst_harness_push_event(hx, gst_event_new_segment(&seg));
  };
  const auto with_flush = output_bytes(with_adaptive(chain, true), PixelFormat::I420, frames, flush);
  const std::vector<cv::Mat> after(frames.begin() + 6, frames.end());
  const auto fresh = output_bytes(with_adaptive(chain, false), PixelFormat::I420, after);
  ASSERT_EQ(with_flush.size(), frames.size());
  expect_same_bytes(std::vector<std::vector<uint8_t>>(with_flush.begin() + 6, with_flush.end()), fresh, "after the flush");
}

// A caps change mid stream (another size): the kept results of the old
// size are not used.
TEST(AdaptiveElements, CapsChangeStartsAfresh) {
  const std::string launch = "pseudo3dconvert processing=cpu layout=side-by-side-half";
  GstHarness *h = gst_harness_new_parse(launch.c_str());
  GstHarness *ref = gst_harness_new_parse((launch + " adaptive=false").c_str());
  for (const auto &[w, hgt] : {std::pair{64, 40}, std::pair{48, 32}, std::pair{64, 40}}) {
    for (GstHarness *hx : {h, ref}) gst_harness_set_src_caps_str(hx, raw_caps(PixelFormat::I420, w, hgt).c_str());
    for (const cv::Mat &f : changing_sequence(w, hgt, 9)) {
      GstBuffer *a = gst_harness_push_and_pull(h, buffer_from_frame(HostFrame::from_bgr(f, PixelFormat::I420)));
      GstBuffer *b = gst_harness_push_and_pull(ref, buffer_from_frame(HostFrame::from_bgr(f, PixelFormat::I420)));
      ASSERT_TRUE(a && b);
      GstMapInfo mb;
      gst_buffer_map(b, &mb, GST_MAP_READ);
      EXPECT_EQ(gst_buffer_get_size(a), mb.size);
      EXPECT_EQ(gst_buffer_memcmp(a, 0, mb.data, mb.size), 0) << w << "x" << hgt;
      gst_buffer_unmap(b, &mb);
      gst_buffer_unref(a);
      gst_buffer_unref(b);
    }
  }
  gst_harness_teardown(h);
  gst_harness_teardown(ref);
}

// The output a stage keeps is the one it pushed: a downstream element that
// writes into the frame it was given (here the test) does not change what
// the next frame starts from.
TEST(AdaptiveElements, KeptOutputIsNotWrittenDownstream) {
  const std::vector<cv::Mat> frames = changing_sequence(64, 40, 21);
  GstHarness *h = gst_harness_new_parse("pseudo3dconvert processing=cpu layout=side-by-side-half");
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::RGBA, 64, 40).c_str());
  std::vector<std::vector<uint8_t>> got;
  for (const cv::Mat &f : frames) {
    GstBuffer *b = gst_harness_push_and_pull(h, buffer_from_frame(HostFrame::from_bgr(f, PixelFormat::RGBA)));
    ASSERT_TRUE(b);
    b = gst_buffer_make_writable(b);
    GstMapInfo map;
    ASSERT_TRUE(gst_buffer_map(b, &map, GST_MAP_READWRITE));
    got.emplace_back(map.data, map.data + map.size);
    std::fill(map.data, map.data + map.size, 0x5a);  // scribble over the frame
    gst_buffer_unmap(b, &map);
    gst_buffer_unref(b);
  }
  gst_harness_teardown(h);
  expect_same_bytes(output_bytes("pseudo3dconvert processing=cpu layout=side-by-side-half adaptive=false", PixelFormat::RGBA,
                      frames),
              got, "scribbled downstream");
}

long resident_kib() {
  long pages = 0, resident = 0;
  FILE *f = std::fopen("/proc/self/statm", "r");
  if (!f) return -1;
  if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = -1;
  std::fclose(f);
  return resident < 0 ? -1 : resident * 4;
}

// 3000 frames of small changes: what the stages keep is one frame's worth,
// so the resident memory after the first hundred frames stays put.
TEST(AdaptiveElements, MemoryStaysFlatOverALongRun) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's quarantine holds freed memory, so resident memory grows by design";
#endif
  const int w = 64, h = 48;
  GstHarness *hx = gst_harness_new_parse("pseudo3dconvert processing=cpu layout=anaglyph");
  gst_harness_set_src_caps_str(hx, raw_caps(PixelFormat::I420, w, h).c_str());
  cv::Mat pic = textured_picture(w, h, 2);
  long after_warmup = 0;
  for (int k = 0; k < 3000; ++k) {
    cv::rectangle(pic, cv::Rect(k % (w - 8), (k / 7) % (h - 8), 8, 8), cv::Scalar(k % 256, 90, 200), cv::FILLED);
    GstBuffer *b = gst_harness_push_and_pull(hx, buffer_from_frame(HostFrame::from_bgr(pic, PixelFormat::I420)));
    ASSERT_TRUE(b);
    gst_buffer_unref(b);
    if (k == 100) after_warmup = resident_kib();
  }
  const long end = resident_kib();
  gst_harness_teardown(hx);
  if (after_warmup < 0 || end < 0) GTEST_SKIP() << "/proc/self/statm unreadable";
  EXPECT_LT(end - after_warmup, 2048) << "resident memory grew from " << after_warmup << " KiB to " << end << " KiB";
}

}  // namespace
