// Temporal state and stream events: pseudo3ddepth's history (smoothing,
// static reuse, cut detection) resets on a flushing seek, FLUSH_STOP,
// STREAM_START, a new SEGMENT and DISCONT buffers, so the first frame after
// any of them is exactly what a fresh element gives for that frame; without
// them the history is in effect (the control that makes the tests able to fail).
#include <gst/app/gstappsink.h>
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

#include <string>

#include "depth_estimate.h"
#include "element_helpers.h"
#include "test_data.h"

using namespace p3d;
using namespace p3d::test;

namespace {

// The depth a fresh estimator (the element's defaults) gives for `frames`, in order; the last one's.
cv::Mat reference_depth(const std::vector<HostFrame> &frames) {
  DepthEstimatorCpu est;
  cv::Mat d;
  for (const HostFrame &f : frames) {
    d = cv::Mat(f.height(), f.width(), CV_32FC1);
    est.estimate(DepthParams(), f.view(), depth_view_of(d));
  }
  return d;
}

// A textured frame and slight variations of it: close enough for the
// history to smooth (not a cut), different enough not to be reused as static.
std::vector<HostFrame> similar_frames(int n) {
  cv::Mat base(48, 64, CV_8UC3);
  cv::RNG rng(5);
  rng.fill(base, cv::RNG::UNIFORM, 0, 255);
  base(cv::Rect(0, 0, 64, 20)).setTo(cv::Scalar(200, 120, 40));
  std::vector<HostFrame> frames;
  for (int i = 0; i < n; ++i) {
    cv::Mat noise(base.size(), CV_8UC3), f;
    rng.fill(noise, cv::RNG::UNIFORM, 0, 12);
    cv::add(base, noise, f);
    frames.push_back(HostFrame::from_bgr(f, PixelFormat::RGBA));
  }
  return frames;
}

double max_diff(const cv::Mat &a, const cv::Mat &b) { return a.size() == b.size() ? cv::norm(a, b, cv::NORM_INF) : 1e9; }

// Pushes frames[0..n-2] and then, after `between`, frames[n-1]; returns the
// depth of the last frame.
template <typename Between>
cv::Mat depth_after(const std::vector<HostFrame> &frames, Between &&between, bool discont_last = false) {
  GstHarness *h = gst_harness_new_parse("pseudo3ddepth");
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::RGBA, 64, 48).c_str());
  for (size_t i = 0; i + 1 < frames.size(); ++i) {
    GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(frames[i]));
    gst_buffer_unref(out);
  }
  between(h);
  GstBuffer *in = buffer_from_frame(frames.back());
  if (discont_last) GST_BUFFER_FLAG_SET(in, GST_BUFFER_FLAG_DISCONT);
  GstBuffer *out = gst_harness_push_and_pull(h, in);
  cv::Mat d = out ? buffer_depth(out).clone() : cv::Mat();
  if (out) gst_buffer_unref(out);
  gst_harness_teardown(h);
  return d;
}

GstEvent *time_segment() {
  GstSegment seg;
  gst_segment_init(&seg, GST_FORMAT_TIME);
  return gst_event_new_segment(&seg);
}

}  // namespace

// The control: in a plain stream the last frame's depth carries history.
TEST(History, CarriesOverWithinAStream) {
  const std::vector<HostFrame> frames = similar_frames(4);
  const cv::Mat got = depth_after(frames, [](GstHarness *) {});
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(max_diff(got, reference_depth(frames)), 0) << "the element is the reference, history included";
  EXPECT_GT(max_diff(got, reference_depth({frames.back()})), 1e-4) << "history must change this frame's depth";
}

TEST(History, ResetsOnFlush) {
  const std::vector<HostFrame> frames = similar_frames(4);
  const cv::Mat got = depth_after(frames, [](GstHarness *h) {
    gst_harness_push_event(h, gst_event_new_flush_start());
    gst_harness_push_event(h, gst_event_new_flush_stop(TRUE));
    gst_harness_push_event(h, time_segment());
  });
  EXPECT_EQ(max_diff(got, reference_depth({frames.back()})), 0);
}

TEST(History, ResetsOnStreamStart) {
  const std::vector<HostFrame> frames = similar_frames(4);
  const cv::Mat got =
      depth_after(frames, [](GstHarness *h) { gst_harness_push_event(h, gst_event_new_stream_start("second")); });
  EXPECT_EQ(max_diff(got, reference_depth({frames.back()})), 0);
}

TEST(History, ResetsOnNewSegment) {
  const std::vector<HostFrame> frames = similar_frames(4);
  const cv::Mat got = depth_after(frames, [](GstHarness *h) { gst_harness_push_event(h, time_segment()); });
  EXPECT_EQ(max_diff(got, reference_depth({frames.back()})), 0);
}

TEST(History, ResetsOnDiscontBuffer) {
  const std::vector<HostFrame> frames = similar_frames(4);
  const cv::Mat got = depth_after(frames, [](GstHarness *) {}, true);
  EXPECT_EQ(max_diff(got, reference_depth({frames.back()})), 0);
}

namespace {

struct Pulled {
  HostFrame frame;
  cv::Mat depth;
  GstClockTime pts = GST_CLOCK_TIME_NONE;
};

Pulled pull(GstElement *sink) {
  Pulled p;
  GstSample *s = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 20 * GST_SECOND);
  if (!s) return p;
  GstBuffer *buf = gst_sample_get_buffer(s);
  GstVideoInfo info;
  gst_video_info_from_caps(&info, gst_sample_get_caps(s));
  GstVideoFrame vf;
  if (gst_video_frame_map(&vf, &info, buf, GST_MAP_READ)) {
    HostFrame f(PixelFormat::I420, info.width, info.height);
    for (int pl = 0; pl < 3; ++pl) {
      int row = 0, rows = 0;
      frame_plane_size(PixelFormat::I420, info.width, info.height, pl, &row, &rows);
      for (int y = 0; y < rows; ++y)
        memcpy(f.view().plane[pl] + y * f.view().stride[pl],
               static_cast<uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&vf, pl)) + y * GST_VIDEO_FRAME_PLANE_STRIDE(&vf, pl),
               row);
    }
    gst_video_frame_unmap(&vf);
    p.frame = std::move(f);
  }
  p.depth = buffer_depth(buf).clone();
  p.pts = GST_BUFFER_PTS(buf);
  gst_sample_unref(s);
  return p;
}

cv::Mat reference_depth_i420(const std::vector<const HostFrame *> &frames) {
  DepthEstimatorCpu est;
  cv::Mat d;
  for (const HostFrame *f : frames) {
    d = cv::Mat(f->height(), f->width(), CV_32FC1);
    est.estimate(DepthParams(), f->view(), depth_view_of(d));
  }
  return d;
}

}  // namespace

// A player's seek on a real file (vtest.avi): after 40 frames of history, a
// flushing seek to 3 s; the first frame after the seek has the depth a
// fresh element gives for it, and the second continues the new history.
TEST(History, FlushingSeekOnARealFile) {
  const std::string avi = data_dir() + "/vtest.avi";
  ASSERT_TRUE(g_file_test(avi.c_str(), G_FILE_TEST_EXISTS)) << "run scripts/get-test-data.sh";
  GError *err = nullptr;
  GstElement *pipe = gst_parse_launch(("filesrc location=" + avi +
                                       " ! decodebin ! videoconvert ! video/x-raw,format=I420 ! pseudo3ddepth ! "
                                       "appsink name=sink sync=false max-buffers=4")
                                          .c_str(),
                                      &err);
  ASSERT_NE(pipe, nullptr) << (err ? err->message : "");
  GstElement *sink = gst_bin_get_by_name(GST_BIN(pipe), "sink");
  ASSERT_EQ(gst_element_set_state(pipe, GST_STATE_PLAYING), GST_STATE_CHANGE_ASYNC);
  Pulled before;
  for (int i = 0; i < 40; ++i) before = pull(sink);
  ASSERT_FALSE(before.depth.empty());
  ASSERT_TRUE(gst_element_seek_simple(pipe, GST_FORMAT_TIME,
                                      (GstSeekFlags)(GST_SEEK_FLAG_FLUSH | GST_SEEK_FLAG_ACCURATE), 3 * GST_SECOND));
  const Pulled first = pull(sink), second = pull(sink);
  ASSERT_FALSE(first.depth.empty());
  ASSERT_FALSE(second.depth.empty());
  EXPECT_EQ(first.pts, 3 * GST_SECOND);
  EXPECT_EQ(max_diff(first.depth, reference_depth_i420({&first.frame})), 0)
      << "the first frame after the seek must be estimated afresh";
  EXPECT_EQ(max_diff(second.depth, reference_depth_i420({&first.frame, &second.frame})), 0);
  // The control: the history (pre-seek frame, then this one) would have given another depth.
  EXPECT_GT(max_diff(first.depth, reference_depth_i420({&before.frame, &first.frame})), 1e-4);
  gst_element_set_state(pipe, GST_STATE_NULL);
  gst_object_unref(sink);
  gst_object_unref(pipe);
}
