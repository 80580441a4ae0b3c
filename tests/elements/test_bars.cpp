// crop-bars through the elements. What the tests prove:
//  * a letterboxed film gets, from its first frame on, the depth that
//    pseudo3ddepth gives the picture without its bars (byte for byte,
//    history included), and 0 in the bars; with crop-bars=off it does
//    not (the bars' edge makes its own depth);
//  * pseudo3dconvert leaves the bars black in both views, a letterbox
//    and a pillarbox; with crop-bars=off the pillarbox picture shifts
//    into its bars;
//  * a fade to black and back, and a subtitle in a bar, do not move the
//    rect; a cut to other bars moves it at the next frame; crop-bars=off
//    and a caps change start from the whole frame;
//  * adaptive=true gives the bytes of adaptive=false on letterboxed and
//    pillarboxed sequences with a cut to a full frame and back.
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

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


// A film: a picture with a box moving over it.
std::vector<cv::Mat> film(int w, int h, int frames, uint32_t seed) {
  const cv::Mat base = textured_picture(w, h, seed);
  std::vector<cv::Mat> out;
  for (int k = 0; k < frames; ++k) {
    cv::Mat f = base.clone();
    cv::rectangle(f, cv::Rect(4 + 3 * k, h / 3, 12, 10), cv::Scalar(230, 40, 40), cv::FILLED);
    out.push_back(f);
  }
  return out;
}

// The pictures in black bars: top/bottom rows and left/right columns.
std::vector<cv::Mat> in_bars(const std::vector<cv::Mat> &pictures, int rows, int cols) {
  std::vector<cv::Mat> out;
  for (const cv::Mat &p : pictures) {
    cv::Mat f;
    cv::copyMakeBorder(p, f, rows, rows, cols, cols, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
    out.push_back(f);
  }
  return out;
}

struct Output {
  std::vector<cv::Mat> frames, depth;  // BGRA frames, depth planes (CV_32FC1)
  std::vector<DepthPlaneInfo> info;
};

// Every frame of `frames` pushed through `launch`: its output as BGRA and
// the depth it carries. between(k, harness) runs before frame k.
Output run(const std::string &launch, PixelFormat f, const std::vector<cv::Mat> &frames,
           const std::function<void(int, GstHarness *)> &between = {}) {
  Output out;
  push_frames(
      launch, f, frames,
      [&](GstBuffer *b, GstHarness *h) {
        GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
        out.frames.push_back(buffer_to_bgra(b, caps));
        gst_caps_unref(caps);
        out.depth.push_back(buffer_depth(b));
        out.info.push_back(buffer_depth_info(b));
      },
      between);
  return out;
}

std::string rect_text(const PixelRect &r) {
  return std::to_string(r.width()) + "x" + std::to_string(r.height()) + " at " + std::to_string(r.x0) + "," +
         std::to_string(r.y0);
}

TEST(CropBars, LetterboxDepthIsThatOfThePictureAlone) {
  // 160 x 80 in 24-row bars: the rect lies on kBarAlign cells.
  const std::vector<cv::Mat> pictures = film(160, 80, 8, 3);
  const std::vector<cv::Mat> frames = in_bars(pictures, 24, 0);
  const std::string depth = "pseudo3ddepth processing=cpu edge-threshold=12";
  const Output boxed = run(depth, PixelFormat::I420, frames);
  const PixelRect rect{0, 24, 160, 104};
  // The first frame's bars are adopted at once: every frame's depth is the
  // picture's alone.
  const Output alone = run(depth, PixelFormat::I420, pictures);
  ASSERT_EQ(boxed.depth.size(), frames.size());
  for (size_t k = 0; k < frames.size(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    ASSERT_EQ(boxed.info[k].active, rect) << rect_text(boxed.info[k].active);
    const cv::Mat inside = boxed.depth[k](cv::Rect(0, 24, 160, 80));
    EXPECT_EQ(cv::norm(inside, alone.depth[k], cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(boxed.depth[k](cv::Rect(0, 0, 160, 24)), cv::NORM_INF), 0.0) << "top bar";
    EXPECT_EQ(cv::norm(boxed.depth[k](cv::Rect(0, 104, 160, 24)), cv::NORM_INF), 0.0) << "bottom bar";
  }
  // Without the crop the bars change the picture's depth.
  const Output whole = run(depth + " crop-bars=off", PixelFormat::I420, frames);
  EXPECT_EQ(whole.info.back().active, (PixelRect{0, 0, 160, 128}));
  EXPECT_GT(cv::norm(whole.depth.back()(cv::Rect(0, 24, 160, 80)), alone.depth.back(), cv::NORM_INF), 0.01);
}

// The largest channel value of the BGRA pixels of r in both views of a
// side-by-side pair of views w wide.
double brightest_in_both_views(const cv::Mat &pair, const cv::Rect &r, int w) {
  double a = 0, b = 0;
  std::vector<cv::Mat> ch;
  cv::Mat left, right;
  cv::cvtColor(pair(r), left, cv::COLOR_BGRA2BGR);
  cv::cvtColor(pair(r + cv::Point(w, 0)), right, cv::COLOR_BGRA2BGR);
  cv::minMaxLoc(left.reshape(1), nullptr, &a);
  cv::minMaxLoc(right.reshape(1), nullptr, &b);
  return std::max(a, b);
}

TEST(CropBars, ConvertLeavesTheBarsBlackInBothViews) {
  const std::string convert = "pseudo3dconvert processing=cpu layout=side-by-side max-disparity=8";
  // A letterbox: rows 0-23 and 104-127.
  {
    const Output out = run(convert, PixelFormat::NV12, in_bars(film(160, 80, 6, 5), 24, 0));
    for (size_t k = 0; k < out.frames.size(); ++k) {
      EXPECT_EQ(brightest_in_both_views(out.frames[k], cv::Rect(0, 0, 160, 24), 160), 0.0) << "frame " << k;
      EXPECT_EQ(brightest_in_both_views(out.frames[k], cv::Rect(0, 104, 160, 24), 160), 0.0) << "frame " << k;
    }
  }
  // A pillarbox: columns 0-31 and 128-159.
  const std::vector<cv::Mat> pillar = in_bars(film(96, 120, 6, 6), 0, 32);
  const cv::Rect left_bar(0, 0, 32, 120), right_bar(128, 0, 32, 120);
  const Output out = run(convert, PixelFormat::RGBA, pillar);
  for (size_t k = 0; k < out.frames.size(); ++k) {
    EXPECT_EQ(brightest_in_both_views(out.frames[k], left_bar, 160), 0.0) << "frame " << k;
    EXPECT_EQ(brightest_in_both_views(out.frames[k], right_bar, 160), 0.0) << "frame " << k;
  }
  const Output off = run(convert + " crop-bars=off", PixelFormat::RGBA, pillar);
  EXPECT_GT(std::max(brightest_in_both_views(off.frames.back(), left_bar, 160),
                     brightest_in_both_views(off.frames.back(), right_bar, 160)),
            0.0)
      << "without the crop the picture's parallax reaches into the bars";
}

TEST(CropBars, FadesAndSubtitlesKeepTheRect) {
  const std::vector<cv::Mat> pictures = film(160, 80, 40, 7);
  std::vector<cv::Mat> frames = in_bars(pictures, 24, 0);
  // Frames 4-13 fade to black, 14-21 are black, 22-29 fade back in; 30-39
  // carry a subtitle in the bottom bar.
  for (int k = 4; k < 30; ++k) {
    const double gain = k < 14 ? 1.0 - (k - 3) / 10.0 : (k < 22 ? 0.0 : (k - 21) / 8.0);
    frames[k].convertTo(frames[k], -1, gain);
  }
  for (int k = 30; k < 40; ++k)
    cv::putText(frames[k], "subtitle", cv::Point(30, 120), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255));
  const Output out = run("pseudo3ddepth processing=cpu", PixelFormat::I420, frames);
  ASSERT_EQ(out.info.size(), frames.size());
  for (size_t k = 0; k < frames.size(); ++k)
    EXPECT_EQ(out.info[k].active, (PixelRect{0, 24, 160, 104})) << "frame " << k << ": " << rect_text(out.info[k].active);
}

TEST(CropBars, OffAndNewCapsStartFromTheWholeFrame) {
  const std::vector<cv::Mat> frames = in_bars(film(160, 80, 6, 9), 24, 0);
  auto switch_off = [](int k, GstHarness *h) {
    if (k != 3) return;
    GstElement *depth = gst_bin_get_by_name(GST_BIN(h->element), "d");
    g_object_set(depth, "crop-bars", 0, NULL);
    gst_object_unref(depth);
  };
  const Output out = run("pseudo3ddepth name=d processing=cpu", PixelFormat::I420, frames, switch_off);
  EXPECT_EQ(out.info[2].active, (PixelRect{0, 24, 160, 104}));
  for (size_t k = 3; k < out.info.size(); ++k) EXPECT_EQ(out.info[k].active, (PixelRect{0, 0, 160, 128})) << k;
  // New caps (another format) decide afresh: the frames after them have
  // other bars (20 rows), adopted at once, where a running decision would
  // wait kBarConfirmFrames frames for them.
  const std::vector<cv::Mat> other = in_bars(film(160, 88, 3, 10), 20, 0);
  GstHarness *h = gst_harness_new_parse("pseudo3ddepth processing=cpu");
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::I420, 160, 128).c_str());
  for (int k = 0; k < 6; ++k) {
    if (k == 3) gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::RGBA, 160, 128).c_str());
    const HostFrame f = k < 3 ? HostFrame::from_bgr(frames[k], PixelFormat::I420)
                              : HostFrame::from_bgr(other[k - 3], PixelFormat::RGBA);
    GstBuffer *b = gst_harness_push_and_pull(h, buffer_from_frame(f));
    ASSERT_NE(b, nullptr);
    const PixelRect want = k < 3 ? PixelRect{0, 24, 160, 104} : PixelRect{0, 16, 160, 108};
    EXPECT_EQ(buffer_depth_info(b).active, want) << "frame " << k << ": " << rect_text(buffer_depth_info(b).active);
    gst_buffer_unref(b);
  }
  gst_harness_teardown(h);
}

// A cut from one letterbox to a film in other bars: the rect of a frame
// comes from the bars of the frames before it (common/bars.h, step 4),
// so the cut moves it at the next frame, which is decided at once (no
// kBarConfirmFrames wait); the depth of every frame is 0 outside the
// rect it carries.
TEST(CropBars, ACutMovesTheRectAtTheNextFrame) {
  std::vector<cv::Mat> frames = in_bars(film(160, 80, 4, 15), 24, 0);
  for (const cv::Mat &f : in_bars(film(160, 112, 4, 16), 8, 0)) frames.push_back(f);
  for (const bool adaptive : {false, true}) {
    const std::string launch = std::string("pseudo3ddepth processing=cpu adaptive=") + (adaptive ? "true" : "false");
    const Output out = run(launch, PixelFormat::I420, frames);
    ASSERT_EQ(out.info.size(), frames.size());
    for (size_t k = 0; k < out.info.size(); ++k) {
      const PixelRect want = k <= 4 ? PixelRect{0, 24, 160, 104} : PixelRect{0, 8, 160, 120};
      EXPECT_EQ(out.info[k].active, want) << "adaptive " << adaptive << " frame " << k << ": "
                                          << rect_text(out.info[k].active);
      const PixelRect r = out.info[k].active;
      EXPECT_EQ(cv::norm(out.depth[k](cv::Rect(0, 0, 160, r.y0)), cv::NORM_INF), 0.0) << "top bar, frame " << k;
    }
  }
}

// crop-bars switched off and on again while playing, over unchanged
// frames: the frame it comes back on is counted afresh (the counts taken
// before it was switched off were of a letterbox whose top bar has gone
// since), with and without adaptive. The top bar is a quarter of the
// tiles: not busy, so the adaptive stage goes on comparing.
TEST(CropBars, BackOnCountsTheFrameItself) {
  std::vector<cv::Mat> frames = in_bars(film(160, 80, 3, 13), 24, 0);
  cv::Mat no_top_bar = frames.back().clone();
  textured_picture(160, 24, 14).copyTo(no_top_bar(cv::Rect(0, 0, 160, 24)));
  for (int k = 0; k < 5; ++k) frames.push_back(no_top_bar);
  auto toggle = [](int k, GstHarness *h) {
    if (k != 3 && k != 6) return;
    GstElement *depth = gst_bin_get_by_name(GST_BIN(h->element), "d");
    g_object_set(depth, "crop-bars", k == 3 ? 0 : 1, NULL);
    gst_object_unref(depth);
  };
  for (const bool adaptive : {false, true}) {
    const std::string launch = std::string("pseudo3ddepth name=d processing=cpu adaptive=") + (adaptive ? "true" : "false");
    const Output out = run(launch, PixelFormat::I420, frames, toggle);
    ASSERT_EQ(out.info.size(), frames.size());
    EXPECT_EQ(out.info[2].active, (PixelRect{0, 24, 160, 104}));
    for (size_t k = 3; k < out.info.size(); ++k)
      EXPECT_EQ(out.info[k].active, (PixelRect{0, 0, 160, 128})) << "adaptive " << adaptive << " frame " << k;
  }
}

TEST(CropBars, AdaptiveGivesTheSameBytes) {
  // A letterbox and a pillarbox, each with a cut to a full frame and back.
  for (const bool pillar : {false, true}) {
    std::vector<cv::Mat> frames = pillar ? in_bars(film(96, 120, 12, 11), 0, 32) : in_bars(film(160, 80, 12, 11), 24, 0);
    const cv::Mat full = textured_picture(160, pillar ? 120 : 128, 12);
    for (int k = 6; k < 8; ++k) frames[k] = full;
    for (const std::string chain : {"pseudo3dconvert processing=cpu layout=side-by-side-half",
                                    "pseudo3dconvert processing=cpu layout=anaglyph fill=background"}) {
      SCOPED_TRACE(chain + (pillar ? " pillarbox" : " letterbox"));
      const Output a = run(chain + " adaptive=false", PixelFormat::I420, frames);
      const Output b = run(chain + " adaptive=true", PixelFormat::I420, frames);
      ASSERT_EQ(a.frames.size(), b.frames.size());
      for (size_t k = 0; k < a.frames.size(); ++k)
        EXPECT_EQ(cv::norm(a.frames[k], b.frames[k], cv::NORM_INF), 0.0) << "frame " << k;
    }
  }
}

}  // namespace
