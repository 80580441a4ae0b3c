// The depth meta follows the frame or goes away: kept through tee and queue
// (the same buffer) and whole-buffer copies; dropped by GStreamer's own
// geometry changes (videoflip, videoscale down and up, videocrop) and by
// videoconvert, whereupon the next stage says that it needs pseudo3ddepth,
// and a pseudo3ddepth placed after them estimates afresh. Its own scale
// transform resamples a host plane. Decoder-style padded strides give the
// same result as tight ones.
#include <gst/check/gstharness.h>
#include <gst/video/video.h>
#include <gtest/gtest.h>

#include <string>

#include "depth_meta.h"
#include "element_helpers.h"
#include "test_data.h"

#include <opencv2/imgproc.hpp>

using namespace p3d;
using namespace p3d::test;

namespace {

HostFrame scene(int w, int h) {
  cv::Mat bgr(h, w, CV_8UC3);
  cv::RNG rng(9);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 255);
  cv::rectangle(bgr, cv::Point(w / 4, h / 3), cv::Point(w / 2, h - 1), cv::Scalar(20, 220, 60), cv::FILLED);
  return HostFrame::from_bgr(bgr, PixelFormat::RGBA);
}

struct Outcome {
  GstFlowReturn flow = GST_FLOW_OK;
  cv::Mat bgra, depth;
  std::vector<std::string> errors;
};

Outcome run_one(const std::string &launch, const HostFrame &frame) {
  Outcome r;
  GstHarness *h = gst_harness_new_parse(launch.c_str());
  BusMessages bus(h->element);
  gst_harness_set_src_caps_str(h, raw_caps(frame.format(), frame.width(), frame.height()).c_str());
  r.flow = gst_harness_push(h, buffer_from_frame(frame));
  if (r.flow == GST_FLOW_OK) {
    GstBuffer *out = gst_harness_pull(h);
    GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
    r.bgra = buffer_to_bgra(out, caps);
    r.depth = buffer_depth(out).clone();
    gst_caps_unref(caps);
    gst_buffer_unref(out);
  }
  r.errors = bus.take(GST_MESSAGE_ERROR);
  gst_harness_teardown(h);
  return r;
}

double max_diff(const cv::Mat &a, const cv::Mat &b) { return a.size() == b.size() ? cv::norm(a, b, cv::NORM_INF) : 1e9; }

const char *kWarp = "pseudo3dwarp max-disparity=6";

}  // namespace

// (videoflip is driven by video-direction: 1.22's deprecated method property
// ends up as identity once the stream starts.)

// tee and queue hand on the buffer itself: the warp renders with the depth.
TEST(DepthMeta, KeptThroughTeeAndQueue) {
  const HostFrame f = scene(64, 48);
  const Outcome direct = run_one(std::string("pseudo3ddepth ! ") + kWarp, f);
  const Outcome teed = run_one(std::string("pseudo3ddepth ! tee ! queue ! ") + kWarp, f);
  ASSERT_EQ(teed.flow, GST_FLOW_OK) << (teed.errors.empty() ? "" : teed.errors[0]);
  EXPECT_EQ(max_diff(direct.bgra, teed.bgra), 0);
}

class GeometryChange : public ::testing::TestWithParam<const char *> {};

// After an element that changes the frame's geometry the depth is gone: the
// warp refuses with a message naming pseudo3ddepth, never renders stale depth.
TEST_P(GeometryChange, DropsTheDepthAndTheWarpSaysSo) {
  const HostFrame f = scene(64, 48);
  const Outcome r = run_one(std::string("pseudo3ddepth ! ") + GetParam() + " ! " + kWarp, f);
  EXPECT_EQ(r.flow, GST_FLOW_ERROR) << GetParam();
  ASSERT_EQ(r.errors.size(), 1u) << GetParam();
  EXPECT_NE(r.errors[0].find("needs a depth map"), std::string::npos) << r.errors[0];
  EXPECT_NE(r.errors[0].find("put pseudo3ddepth before pseudo3dwarp"), std::string::npos) << r.errors[0];
}

// A pseudo3ddepth after the change estimates afresh: the result is the one
// of estimating on the changed frame in the first place.
TEST_P(GeometryChange, APseudo3DDepthAfterItEstimatesAfresh) {
  const HostFrame f = scene(64, 48);
  const Outcome twice = run_one(std::string("pseudo3ddepth ! ") + GetParam() + " ! pseudo3ddepth", f);
  const Outcome once = run_one(std::string(GetParam()) + " ! pseudo3ddepth", f);
  ASSERT_EQ(twice.flow, GST_FLOW_OK) << GetParam();
  ASSERT_FALSE(once.depth.empty());
  EXPECT_EQ(max_diff(twice.depth, once.depth), 0) << GetParam();
  EXPECT_EQ(twice.depth.size(), cv::Size(twice.bgra.cols, twice.bgra.rows)) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(
    Elements, GeometryChange,
    ::testing::Values("videoflip video-direction=horiz", "videoflip video-direction=90r",
                      "videoscale ! video/x-raw,width=32,height=24 ! videoscale ! video/x-raw,width=64,height=48",
                      "videocrop left=4 top=2", "videoconvert ! video/x-raw,format=BGRx"),
    [](const auto &info) {
      const std::string s = info.param;
      if (s.rfind("videoflip video-direction=h", 0) == 0) return std::string("flip");
      if (s.rfind("videoflip", 0) == 0) return std::string("rotate");
      if (s.rfind("videoscale", 0) == 0) return std::string("scale_down_up");
      if (s.rfind("videocrop", 0) == 0) return std::string("crop");
      return std::string("convert");
    });

namespace {

// A buffer of a 2D frame with the depth pseudo3ddepth attached (host plane).
GstBuffer *buffer_with_depth(const HostFrame &f) {
  GstHarness *h = gst_harness_new_parse("pseudo3ddepth");
  gst_harness_set_src_caps_str(h, raw_caps(f.format(), f.width(), f.height()).c_str());
  GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(f));
  gst_harness_teardown(h);
  return out;
}

const GstMetaInfo *depth_meta_info() {
  const GType api = g_type_from_name("Pseudo3DDepthMetaAPI");
  GstBuffer *probe = buffer_with_depth(scene(8, 8));
  GstMeta *m = probe ? gst_buffer_get_meta(probe, api) : nullptr;
  const GstMetaInfo *info = m ? m->info : nullptr;
  if (probe) gst_buffer_unref(probe);
  return info;
}

}  // namespace

// The tags GStreamer's transforms decide by.
TEST(DepthMeta, RegistersVideoSizeOrientationAndMemoryTags) {
  const GType api = g_type_from_name("Pseudo3DDepthMetaAPI");
  ASSERT_NE(depth_meta_info(), nullptr);
  for (const char *tag : {GST_META_TAG_VIDEO_STR, GST_META_TAG_VIDEO_SIZE_STR, GST_META_TAG_VIDEO_ORIENTATION_STR,
                          GST_META_TAG_MEMORY_STR})
    EXPECT_TRUE(gst_meta_api_type_has_tag(api, g_quark_from_string(tag))) << tag;
}

// A whole-buffer copy shares the depth; the meta's own scale transform
// resamples a host plane to the new size; a copy of part of the bytes drops it.
TEST(DepthMeta, TransformsCopyScaleAndRegion) {
  const HostFrame f = scene(64, 48);
  GstBuffer *buf = buffer_with_depth(f);
  ASSERT_NE(buf, nullptr);
  const cv::Mat depth = buffer_depth(buf).clone();
  ASSERT_FALSE(depth.empty());

  GstBuffer *copy = gst_buffer_copy(buf);
  EXPECT_EQ(max_diff(buffer_depth(copy), depth), 0);
  gst_buffer_unref(copy);

  GstBuffer *part = gst_buffer_copy_region(buf, GST_BUFFER_COPY_ALL, 0, 100);
  EXPECT_TRUE(buffer_depth(part).empty()) << "a byte region is not a frame";
  gst_buffer_unref(part);

  const GType api = g_type_from_name("Pseudo3DDepthMetaAPI");
  GstMeta *meta = gst_buffer_get_meta(buf, api);
  GstVideoInfo in, out;
  gst_video_info_set_format(&in, GST_VIDEO_FORMAT_RGBA, 64, 48);
  gst_video_info_set_format(&out, GST_VIDEO_FORMAT_RGBA, 32, 20);
  GstVideoMetaTransform scale = {&in, &out};
  GstBuffer *scaled = gst_buffer_new();
  ASSERT_TRUE(meta->info->transform_func(scaled, meta, buf, gst_video_meta_transform_scale_get_quark(), &scale));
  const cv::Mat got = buffer_depth(scaled);
  cv::Mat want;
  cv::resize(depth, want, cv::Size(32, 20), 0, 0, cv::INTER_LINEAR);
  ASSERT_EQ(got.size(), cv::Size(32, 20));
  EXPECT_LT(max_diff(got, want), 1e-6);
  gst_buffer_unref(scaled);

  // A scale that does not start from the depth's own size cannot be followed.
  gst_video_info_set_format(&in, GST_VIDEO_FORMAT_RGBA, 60, 48);
  GstBuffer *wrong = gst_buffer_new();
  EXPECT_FALSE(meta->info->transform_func(wrong, meta, buf, gst_video_meta_transform_scale_get_quark(), &scale));
  EXPECT_TRUE(buffer_depth(wrong).empty());
  gst_buffer_unref(wrong);
  gst_buffer_unref(buf);
}

// Frames as decoders hand them out: padded strides and plane offsets
// described by a GstVideoMeta. The whole chain gives what tight frames give.
TEST(Strides, DecoderStylePaddingGivesTheSameResult) {
  for (PixelFormat fmt : {PixelFormat::I420, PixelFormat::NV12, PixelFormat::RGBA}) {
    const int w = 70, h = 38;
    const HostFrame tight = [&] {
      cv::Mat bgr(h, w, CV_8UC3);
      cv::randu(bgr, 0, 256);
      return HostFrame::from_bgr(bgr, fmt);
    }();
    const HostFrame padded = HostFrame(tight);
    // Copy into a buffer with 64 bytes of padding per row and 4096 between planes.
    GstVideoInfo info;
    gst_video_info_set_format(&info, gst_video_format_from_string(format_name(fmt)), w, h);
    gsize offsets[GST_VIDEO_MAX_PLANES] = {0};
    gint strides[GST_VIDEO_MAX_PLANES] = {0};
    gsize total = 0;
    for (int p = 0; p < frame_plane_count(fmt); ++p) {
      int row = 0, rows = 0;
      frame_plane_size(fmt, w, h, p, &row, &rows);
      offsets[p] = total + 4096;
      strides[p] = row + 64;
      total = offsets[p] + static_cast<gsize>(strides[p]) * rows;
    }
    GstBuffer *buf = gst_buffer_new_allocate(nullptr, total + 4096, nullptr);
    gst_buffer_memset(buf, 0, 0xAB, total + 4096);
    GstMapInfo map;
    gst_buffer_map(buf, &map, GST_MAP_WRITE);
    for (int p = 0; p < frame_plane_count(fmt); ++p) {
      int row = 0, rows = 0;
      frame_plane_size(fmt, w, h, p, &row, &rows);
      for (int y = 0; y < rows; ++y)
        memcpy(map.data + offsets[p] + static_cast<gsize>(y) * strides[p],
               tight.view().plane[p] + static_cast<size_t>(y) * tight.view().stride[p], row);
    }
    gst_buffer_unmap(buf, &map);
    gst_buffer_add_video_meta_full(buf, GST_VIDEO_FRAME_FLAG_NONE, GST_VIDEO_INFO_FORMAT(&info), w, h,
                                   GST_VIDEO_INFO_N_PLANES(&info), offsets, strides);
    const char *chain = "pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack layout=side-by-side-half";
    GstHarness *hp = gst_harness_new_parse(chain), *ht = gst_harness_new_parse(chain);
    gst_harness_set_src_caps_str(hp, raw_caps(fmt, w, h).c_str());
    gst_harness_set_src_caps_str(ht, raw_caps(fmt, w, h).c_str());
    GstBuffer *a = gst_harness_push_and_pull(hp, buf), *b = gst_harness_push_and_pull(ht, buffer_from_frame(padded));
    ASSERT_NE(a, nullptr);
    ASSERT_NE(b, nullptr);
    GstCaps *caps = gst_pad_get_current_caps(hp->sinkpad);
    EXPECT_EQ(max_diff(buffer_to_bgra(a, caps), buffer_to_bgra(b, caps)), 0) << format_name(fmt);
    gst_caps_unref(caps);
    gst_buffer_unref(a);
    gst_buffer_unref(b);
    gst_harness_teardown(hp);
    gst_harness_teardown(ht);
  }
}
