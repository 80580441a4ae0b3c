// GstHarness tests of each element: every input format, odd sizes, property
// specs, passthrough where a stage has nothing to do, caps that must fail.
#include <gst/base/gstaggregator.h>
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "element_helpers.h"
#include "test_data.h"

#include "bilateral.h"
#include "depth_estimate.h"
#include "depth_grey.h"
#include "pack.h"
#include "warp.h"

using namespace p3d;
using namespace p3d::test;

namespace {

const char *kFactories[] = {"pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp", "pseudo3dpack",
                             "pseudo3dconvert", "pseudo3dsignal", "pseudo3ddepthmux", "pseudo3ddepthout"};

// A frame with a top/bottom colour split, so depth and edges are non-trivial.
HostFrame test_frame(PixelFormat f, int w, int h, uint32_t seed) {
  cv::Mat bgr(h, w, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 255);
  if (h > 2) bgr(cv::Rect(0, 0, w, h / 2)).setTo(cv::Scalar(200, 120, 40));
  return HostFrame::from_bgr(bgr, f, 0);
}

GstHarness *harness(const std::string &launch, PixelFormat f, int w, int h) {
  GstHarness *hx = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(hx, raw_caps(f, w, h).c_str());
  return hx;
}

struct Size {
  int w, h;
};

// gtest names of (format, size) parameterised cases, e.g. "NV12_3x2".
std::string format_and_size_name(const ::testing::TestParamInfo<std::tuple<PixelFormat, Size>> &info) {
  const Size s = std::get<1>(info.param);
  return std::string(format_name(std::get<0>(info.param))) + "_" + std::to_string(s.w) + "x" + std::to_string(s.h);
}

}  // namespace

TEST(Plugin, RegistersEveryElement) {
  for (const char *name : kFactories) {
    GstElementFactory *f = gst_element_factory_find(name);
    ASSERT_NE(f, nullptr) << name;
    gst_object_unref(f);
  }
}

// Every property: a blurb that says more than the nick, a default inside its range.
TEST(Plugin, PropertiesAreDocumented) {
  for (const char *name : kFactories) {
    GstElement *e = gst_element_factory_make(name, nullptr);
    ASSERT_NE(e, nullptr);
    guint n = 0;
    GParamSpec **specs = g_object_class_list_properties(G_OBJECT_GET_CLASS(e), &n);
    for (guint i = 0; i < n; ++i) {
      GParamSpec *p = specs[i];
      if (p->owner_type == GST_TYPE_OBJECT || p->owner_type == GST_TYPE_ELEMENT || p->owner_type == GST_TYPE_BIN ||
          p->owner_type == GST_TYPE_BASE_TRANSFORM || p->owner_type == GST_TYPE_AGGREGATOR ||
          p->owner_type == G_TYPE_OBJECT)
        continue;
      const std::string nick = g_param_spec_get_nick(p), blurb = g_param_spec_get_blurb(p);
      EXPECT_GT(blurb.size(), nick.size()) << name << "::" << p->name;
      GValue v = G_VALUE_INIT;
      g_value_init(&v, p->value_type);
      g_object_get_property(G_OBJECT(e), p->name, &v);
      EXPECT_TRUE(g_param_value_defaults(p, &v)) << name << "::" << p->name << " starts at its default";
      g_value_unset(&v);
    }
    g_free(specs);
    gst_object_unref(e);
  }
}

// Every numeric property at both ends of its range (and every enum value)
// runs through the whole chain: no error, a finite depth in [0, 1], output
// of the expected size. (Range checks themselves are GObject's job.)
TEST(Plugin, EveryPropertyAtItsExtremesProcessesFrames) {
  const char *kStages[] = {"pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp", "pseudo3dpack"};
  for (int stage = 0; stage < 4; ++stage) {
    GstElement *probe = gst_element_factory_make(kStages[stage], nullptr);
    guint n = 0;
    GParamSpec **specs = g_object_class_list_properties(G_OBJECT_GET_CLASS(probe), &n);
    for (guint i = 0; i < n; ++i) {
      GParamSpec *p = specs[i];
      if (!(p->flags & GST_PARAM_MUTABLE_PLAYING)) continue;
      std::vector<std::string> values;
      if (G_IS_PARAM_SPEC_INT(p)) {
        values = {std::to_string(G_PARAM_SPEC_INT(p)->minimum), std::to_string(G_PARAM_SPEC_INT(p)->maximum)};
      } else if (G_IS_PARAM_SPEC_FLOAT(p)) {
        values = {std::to_string(G_PARAM_SPEC_FLOAT(p)->minimum), std::to_string(G_PARAM_SPEC_FLOAT(p)->maximum)};
      } else if (G_IS_PARAM_SPEC_ENUM(p)) {
        GEnumClass *e = G_PARAM_SPEC_ENUM(p)->enum_class;
        for (guint k = 0; k < e->n_values; ++k) values.push_back(e->values[k].value_nick);
      } else if (G_IS_PARAM_SPEC_BOOLEAN(p)) {
        values = {"true", "false"};
      }
      for (const std::string &v : values) {
        // rgbd needs a frame that holds colour and depth: keep the pipeline's own input otherwise.
        if (std::string(p->name) == "method" && v == "rgbd") continue;
        // The warp's own layout packs the pair itself: no pseudo3dpack after it.
        const int stages = stage == 2 && std::string(p->name) == "layout" ? 3 : 4;
        std::string chain;
        for (int k = 0; k < stages; ++k)
          chain += std::string(k ? " ! " : "") + kStages[k] + (k == stage ? std::string(" ") + p->name + "=" + v : "");
        GstHarness *h = gst_harness_new_parse((chain + " ! capsfilter caps=video/x-raw,format=RGBA").c_str());
        BusMessages bus(h->element);
        gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::NV12, 40, 24).c_str());
        GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(test_frame(PixelFormat::NV12, 40, 24, 3)));
        EXPECT_NE(out, nullptr) << kStages[stage] << " " << p->name << "=" << v;
        EXPECT_EQ(bus.take(GST_MESSAGE_ERROR), std::vector<std::string>{}) << p->name << "=" << v;
        if (out) {
          GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
          GstVideoInfo info;
          ASSERT_TRUE(gst_video_info_from_caps(&info, caps));
          EXPECT_GE(gst_buffer_get_size(out), GST_VIDEO_INFO_SIZE(&info));
          gst_caps_unref(caps);
          gst_buffer_unref(out);
        }
        gst_harness_teardown(h);
        // The depth itself at these settings: finite and in range.
        if (stage < 2) {
          GstHarness *d = gst_harness_new_parse(
              (std::string("pseudo3ddepth ! pseudo3dfilter") + " " + (stage == 1 ? std::string(p->name) + "=" + v : "")).c_str());
          if (stage == 0) {
            gst_harness_teardown(d);
            d = gst_harness_new_parse((std::string("pseudo3ddepth ") + p->name + "=" + v + " ! pseudo3dfilter").c_str());
          }
          gst_harness_set_src_caps_str(d, raw_caps(PixelFormat::NV12, 40, 24).c_str());
          GstBuffer *o = gst_harness_push_and_pull(d, buffer_from_frame(test_frame(PixelFormat::NV12, 40, 24, 3)));
          ASSERT_NE(o, nullptr);
          const cv::Mat depth = buffer_depth(o);
          EXPECT_TRUE(cv::checkRange(depth, true, nullptr, 0.0, 1.0 + 1e-6)) << p->name << "=" << v;
          gst_buffer_unref(o);
          gst_harness_teardown(d);
        }
      }
    }
    g_free(specs);
    gst_object_unref(probe);
  }
}

class DepthFormats : public ::testing::TestWithParam<std::tuple<PixelFormat, Size>> {};

// Depth is attached with the frame's size, values in [0,1], frame untouched.
TEST_P(DepthFormats, AttachesDepthAndKeepsFrame) {
  const auto [fmt, size] = GetParam();
  GstHarness *h = harness("pseudo3ddepth", fmt, size.w, size.h);
  const HostFrame frame = test_frame(fmt, size.w, size.h, 7);
  GstBuffer *in = buffer_from_frame(frame);
  GstMapInfo before;
  gst_buffer_map(in, &before, GST_MAP_READ);
  const std::vector<uint8_t> bytes(before.data, before.data + before.size);
  gst_buffer_unmap(in, &before);

  GstBuffer *out = gst_harness_push_and_pull(h, in);
  ASSERT_NE(out, nullptr);
  const cv::Mat depth = buffer_depth(out);
  ASSERT_EQ(depth.cols, size.w);
  ASSERT_EQ(depth.rows, size.h);
  double lo = 0, hi = 0;
  cv::minMaxLoc(depth, &lo, &hi);
  EXPECT_GE(lo, 0.0);
  EXPECT_LE(hi, 1.0);
  EXPECT_TRUE(cv::checkRange(depth));
  GstMapInfo after;
  gst_buffer_map(out, &after, GST_MAP_READ);
  ASSERT_EQ(after.size, bytes.size());
  EXPECT_EQ(0, memcmp(after.data, bytes.data(), bytes.size())) << "the frame must pass unchanged";
  gst_buffer_unmap(out, &after);
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}

INSTANTIATE_TEST_SUITE_P(AllFormatsAndSizes, DepthFormats,
                         ::testing::Combine(::testing::ValuesIn(kAllFormats),
                                            ::testing::Values(Size{1, 1}, Size{3, 2}, Size{64, 48}, Size{4097, 2161})),
                         format_and_size_name);

// top-bottom hypothesis: the top of the picture is farther than the bottom.
TEST(Depth, TopIsFartherThanBottom) {
  GstHarness *h = harness("pseudo3ddepth hypothesis=top-bottom region-weight=0.5", PixelFormat::RGBA, 64, 64);
  GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(test_frame(PixelFormat::RGBA, 64, 64, 3)));
  const cv::Mat d = buffer_depth(out);
  ASSERT_FALSE(d.empty());
  EXPECT_LT(cv::mean(d.rowRange(0, 8))[0], cv::mean(d.rowRange(56, 64))[0]);
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}

// ground-contact reaches the estimator: the element's map is the CPU
// reference's with the same value, and the cue changes the map.
TEST(Depth, GroundContactPropertyReachesTheEstimator) {
  const int w = 64, h = 64;
  const HostFrame frame = test_frame(PixelFormat::RGBA, w, h, 3);
  std::vector<cv::Mat> maps;
  for (float g : {0.f, 0.5f, 1.f}) {
    GstHarness *hx = harness("pseudo3ddepth ground-contact=" + std::to_string(g), PixelFormat::RGBA, w, h);
    GstBuffer *out = gst_harness_push_and_pull(hx, buffer_from_frame(frame));
    ASSERT_NE(out, nullptr);
    maps.push_back(buffer_depth(out).clone());
    DepthParams p;
    p.ground_contact = g;
    DepthEstimatorCpu cpu;
    cv::Mat want(h, w, CV_32FC1);
    cpu.estimate(p, frame.view(), depth_view_of(want));
    EXPECT_EQ(cv::norm(maps.back(), want, cv::NORM_INF), 0) << "ground-contact " << g;
    gst_buffer_unref(out);
    gst_harness_teardown(hx);
  }
  EXPECT_GT(cv::norm(maps.front(), maps.back(), cv::NORM_INF), 0.01) << "the cue changes nothing on this frame";
}

// Depth supplied upstream is kept, not re-estimated.
TEST(Depth, SuppliedDepthIsNotEstimatedAgain) {
  GstHarness *h = harness("pseudo3ddepth hypothesis=top-bottom ! pseudo3ddepth hypothesis=flat region-weight=1",
                          PixelFormat::RGBA, 32, 32);
  GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(test_frame(PixelFormat::RGBA, 32, 32, 4)));
  const cv::Mat d = buffer_depth(out);
  ASSERT_FALSE(d.empty());
  double lo, hi;
  cv::minMaxLoc(d, &lo, &hi);
  EXPECT_GT(hi - lo, 0.05) << "a flat estimate would be constant: the first element's depth must survive";
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}

// RGBD: colour half out, grey half as depth (white = near).
TEST(Depth, RgbdSplitsColourAndDepth) {
  for (PixelFormat fmt : kAllFormats) {
    const int w = 16, h = 8;
    cv::Mat bgr(h, 2 * w, CV_8UC3, cv::Scalar(0, 0, 255));                // colour half: red
    bgr(cv::Rect(w, 0, w, h)).setTo(cv::Scalar(255, 255, 255));           // depth: white = near...
    bgr(cv::Rect(w, 0, w, h / 2)).setTo(cv::Scalar(0, 0, 0));             // ...top rows black = far
    GstHarness *hx = harness("pseudo3ddepth method=rgbd", fmt, 2 * w, h);
    GstBuffer *out = gst_harness_push_and_pull(hx, buffer_from_frame(HostFrame::from_bgr(bgr, fmt)));
    ASSERT_NE(out, nullptr);
    GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
    const cv::Mat colour = buffer_to_bgra(out, caps);
    ASSERT_EQ(colour.cols, w) << format_name(fmt);
    const cv::Vec4b c = colour.at<cv::Vec4b>(h / 2, w / 2);
    EXPECT_GT(c[2], 200) << format_name(fmt);
    EXPECT_LT(c[1], 60) << format_name(fmt);
    const cv::Mat d = buffer_depth(out);
    ASSERT_EQ(d.cols, w);
    EXPECT_NEAR(d.at<float>(0, 3), 0.f, 0.03f) << format_name(fmt);
    EXPECT_NEAR(d.at<float>(h - 1, 3), 1.f, 0.03f) << format_name(fmt);
    gst_caps_unref(caps);
    gst_buffer_unref(out);
    gst_harness_teardown(hx);
  }
}

// 4:2:0 RGBD halves must start on a chroma sample: 14 wide is refused with
// the element's own reason, once, and that reason is the width rule (14 is
// twice 7, so "must be twice as wide as its colour half" would be wrong);
// 16 wide is accepted.
TEST(Depth, RgbdRejectsUnsplittableYuvWidth) {
  GstHarness *h = gst_harness_new_parse("pseudo3ddepth method=rgbd");
  BusMessages bus(h->element);
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::NV12, 14, 8).c_str());
  EXPECT_NE(gst_harness_push(h, buffer_from_frame(test_frame(PixelFormat::NV12, 14, 8, 1))), GST_FLOW_OK);
  EXPECT_NE(gst_harness_push(h, buffer_from_frame(test_frame(PixelFormat::NV12, 14, 8, 1))), GST_FLOW_OK);
  const std::vector<std::string> errors = bus.take(GST_MESSAGE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("RGBD input in a YUV format needs a width that is a multiple of 4"), std::string::npos)
      << errors[0];
  gst_harness_teardown(h);
  GstHarness *ok = gst_harness_new_parse("pseudo3ddepth method=rgbd");
  gst_harness_set_src_caps_str(ok, raw_caps(PixelFormat::NV12, 16, 8).c_str());
  EXPECT_EQ(gst_harness_push(ok, buffer_from_frame(test_frame(PixelFormat::NV12, 16, 8, 1))), GST_FLOW_OK);
  gst_harness_teardown(ok);
}

// Interlaced video is refused with a message, not processed as progressive.
TEST(Depth, InterlacedInputIsRefused) {
  GstHarness *h = gst_harness_new_parse("pseudo3ddepth");
  BusMessages bus(h->element);
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::I420, 16, 8, ",interlace-mode=interleaved").c_str());
  EXPECT_NE(gst_harness_push(h, buffer_from_frame(test_frame(PixelFormat::I420, 16, 8, 1))), GST_FLOW_OK);
  const std::vector<std::string> errors = bus.take(GST_MESSAGE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("Interlaced video is not supported"), std::string::npos) << errors[0];
  EXPECT_NE(errors[0].find("deinterlace"), std::string::npos) << errors[0];
  gst_harness_teardown(h);
}

// An H.265 stereo stream leaves pseudo3dsignal as mono, like H.264, but
// x265enc writes no frame-packing SEI, so the file would carry no stereo
// signalling at all: the element says so, once per caps, instead of
// dropping it silently. H.264 gets no such warning (x264 writes the SEI).
TEST(Signal, H265StereoIsMonoWithAWarning) {
  for (const char *codec : {"video/x-h265", "video/x-h264"}) {
    GstHarness *h = gst_harness_new("pseudo3dsignal");
    BusMessages bus(h->element);
    gst_harness_set_src_caps_str(h, (std::string(codec) +
                                     ", stream-format=byte-stream, alignment=au, width=64, height=96, "
                                     "multiview-mode=top-bottom, multiview-flags=(GstVideoMultiviewFlagsSet)0:ffffffff")
                                        .c_str());
    const uint8_t start[] = {0, 0, 0, 1, 0x40, 0x01, 0x0c};  // a NAL start, nothing the SEI scan acts on
    ASSERT_EQ(gst_harness_push(h, gst_buffer_new_memdup(start, sizeof start)), GST_FLOW_OK);
    ASSERT_EQ(gst_harness_push(h, gst_buffer_new_memdup(start, sizeof start)), GST_FLOW_OK);
    GstCaps *out = gst_pad_get_current_caps(h->sinkpad);
    ASSERT_NE(out, nullptr);
    EXPECT_STREQ(gst_structure_get_string(gst_caps_get_structure(out, 0), "multiview-mode"), "mono") << codec;
    gst_caps_unref(out);
    const std::vector<std::string> warnings = bus.take(GST_MESSAGE_WARNING);
    if (std::string(codec) == "video/x-h265") {
      ASSERT_EQ(warnings.size(), 1u);
      EXPECT_NE(warnings[0].find("no stereo signalling"), std::string::npos) << warnings[0];
      EXPECT_NE(warnings[0].find("pseudo3d-mkvstereo"), std::string::npos) << warnings[0];
    } else {
      EXPECT_TRUE(warnings.empty()) << warnings[0];
    }
    gst_harness_teardown(h);
  }
}

// pseudo3dconvert deinterlaces in front of its stages: interlaced frames
// (top field first) come out progressive, a frame for each field at twice
// the frame rate, each half a frame long; progressive input passes the
// deinterlacer untouched (same count and rate).
TEST(Convert, InterlacedInputIsDeinterlacedAtFieldRate) {
  for (bool interlaced : {true, false}) {
    GstHarness *h = gst_harness_new_parse("pseudo3dconvert processing=cpu layout=side-by-side-half");
    gst_harness_set_src_caps_str(
        h, raw_caps(PixelFormat::I420, 64, 48, interlaced ? ",interlace-mode=interleaved,field-order=top-field-first" : "")
               .c_str());
    const int frames = 4;
    for (int i = 0; i < frames; ++i) {
      GstBuffer *b = buffer_from_frame(test_frame(PixelFormat::I420, 64, 48, i + 1));
      GST_BUFFER_PTS(b) = i * GST_SECOND / 30;
      GST_BUFFER_DURATION(b) = GST_SECOND / 30;
      if (interlaced) GST_BUFFER_FLAG_SET(b, GST_VIDEO_BUFFER_FLAG_INTERLACED | GST_VIDEO_BUFFER_FLAG_TFF);
      ASSERT_EQ(gst_harness_push(h, b), GST_FLOW_OK) << (interlaced ? "interlaced" : "progressive");
    }
    gst_harness_push_event(h, gst_event_new_eos());
    EXPECT_EQ(gst_harness_buffers_received(h), static_cast<guint>(interlaced ? 2 * frames : frames));
    GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
    ASSERT_NE(caps, nullptr);
    GstVideoInfo info;
    ASSERT_TRUE(gst_video_info_from_caps(&info, caps));
    EXPECT_EQ(GST_VIDEO_INFO_INTERLACE_MODE(&info), GST_VIDEO_INTERLACE_MODE_PROGRESSIVE);
    EXPECT_EQ(GST_VIDEO_INFO_FPS_N(&info), interlaced ? 60 : 30);
    EXPECT_EQ(GST_VIDEO_INFO_FPS_D(&info), 1);
    gst_caps_unref(caps);
    GstBuffer *first = gst_harness_pull(h);
    ASSERT_NE(first, nullptr);
    EXPECT_EQ(GST_BUFFER_DURATION(first), interlaced ? GST_SECOND / 60 : GST_SECOND / 30);
    gst_buffer_unref(first);
    gst_harness_teardown(h);
  }
}

// The caps admit what the kernels accept: frames up to 8192 pixels a side
// for the source stages, stereo frames up to twice that after the warp.
TEST(Caps, LimitedToWhatTheKernelsAccept) {
  struct Limit {
    const char *factory;
    const char *pad;
    int max;
  };
  for (const Limit &l : {Limit{"pseudo3ddepth", "sink", 8192}, Limit{"pseudo3dfilter", "sink", 8192},
                         Limit{"pseudo3dwarp", "sink", 8192}, Limit{"pseudo3dwarp", "src", 16384},
                         Limit{"pseudo3dpack", "sink", 16384}, Limit{"pseudo3dconvert", "sink", 8192}}) {
    GstElement *e = gst_element_factory_make(l.factory, nullptr);
    GstPad *pad = gst_element_get_static_pad(e, l.pad);
    const char *extra = std::string(l.factory) == "pseudo3dpack" ? ",multiview-mode=side-by-side" : "";
    for (int w : {l.max, l.max + 1}) {
      GstCaps *caps = gst_caps_from_string(raw_caps(PixelFormat::RGBA, w, 16, extra).c_str());
      EXPECT_EQ(gst_pad_query_accept_caps(pad, caps), w == l.max) << l.factory << " " << l.pad << " width " << w;
      gst_caps_unref(caps);
    }
    gst_object_unref(pad);
    gst_object_unref(e);
  }
}

// radius 0: the buffer passes through untouched (same buffer).
// A stage with nothing to do hands on the very buffer it was given.
static void expect_passthrough(const char *launch, const std::string &caps, int w, int h) {
  GstHarness *hx = gst_harness_new_parse(launch);
  gst_harness_set_src_caps_str(hx, caps.c_str());
  GstBuffer *in = buffer_from_frame(test_frame(PixelFormat::RGBA, w, h, 1));
  GstBuffer *out = gst_harness_push_and_pull(hx, gst_buffer_ref(in));
  EXPECT_EQ(out, in) << launch;
  if (out) gst_buffer_unref(out);
  gst_buffer_unref(in);
  gst_harness_teardown(hx);
}

// A frame without a depth map is a flow error, not a crash or a guess.
static void expect_error_without_depth(const char *launch) {
  GstHarness *h = gst_harness_new_parse(launch);
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::RGBA, 8, 8).c_str());
  EXPECT_EQ(gst_harness_push(h, buffer_from_frame(test_frame(PixelFormat::RGBA, 8, 8, 1))), GST_FLOW_ERROR) << launch;
  gst_harness_teardown(h);
}

TEST(Filter, RadiusZeroIsPassthrough) {
  expect_passthrough("pseudo3dfilter radius=0", raw_caps(PixelFormat::RGBA, 8, 8), 8, 8);
}

TEST(Filter, WithoutDepthIsAnError) { expect_error_without_depth("pseudo3dfilter radius=2"); }

// The element runs the project's default mode (separable) unless told
// otherwise, and says so in its property's default.
TEST(Filter, DefaultModeIsTheProjectDefault) {
  GstElement *f = gst_element_factory_make("pseudo3dfilter", nullptr);
  ASSERT_NE(f, nullptr);
  gint mode = -1;
  g_object_get(f, "mode", &mode, nullptr);
  EXPECT_EQ(mode, static_cast<gint>(kDefaultFilterMode));
  EXPECT_EQ(kDefaultFilterMode, BilateralMode::Separable);
  GParamSpec *spec = g_object_class_find_property(G_OBJECT_GET_CLASS(f), "mode");
  ASSERT_NE(spec, nullptr);
  EXPECT_EQ(G_PARAM_SPEC_ENUM(spec)->default_value, static_cast<gint>(kDefaultFilterMode));
  gst_object_unref(f);
}

class FilterFormats : public ::testing::TestWithParam<std::tuple<PixelFormat, Size>> {};

// The element's filtered depth is bilateral_filter_cpu of the depth it was
// given, guided by the frame, bit for bit.
TEST_P(FilterFormats, FiltersDepth) {
  const auto [fmt, size] = GetParam();
  const HostFrame frame = test_frame(fmt, size.w, size.h, 9);
  GstHarness *ref = harness("pseudo3ddepth", fmt, size.w, size.h);
  GstBuffer *a = gst_harness_push_and_pull(ref, buffer_from_frame(frame));
  const cv::Mat da = buffer_depth(a);
  cv::Mat by_mode[2];
  for (BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable}) {
    const bool separable = mode == BilateralMode::Separable;
    GstHarness *h = harness(std::string("pseudo3ddepth ! pseudo3dfilter radius=3 mode=") +
                                (separable ? "separable" : "exact"),
                            fmt, size.w, size.h);
    GstBuffer *b = gst_harness_push_and_pull(h, buffer_from_frame(frame));
    const cv::Mat db = buffer_depth(b);
    ASSERT_EQ(db.size(), cv::Size(size.w, size.h));
    cv::Mat want(size.h, size.w, CV_32FC1);
    BilateralParams p;
    p.radius = 3;
    p.mode = mode;
    bilateral_filter_cpu(p, frame.view(), depth_view_of(da), depth_view_of(want));
    EXPECT_EQ(cv::norm(db, want, cv::NORM_INF), 0) << "the element is bilateral_filter_cpu, mode " << separable;
    if (size.w >= 16) {
      EXPECT_GT(cv::norm(da, db, cv::NORM_INF), 1e-4) << "a radius-3 filter changes blocky depth";
    }
    by_mode[separable] = db.clone();
    gst_buffer_unref(b);
    gst_harness_teardown(h);
  }
  if (size.w >= 16) {
    EXPECT_GT(cv::norm(by_mode[0], by_mode[1], cv::NORM_INF), 0) << "mode reaches the filter";
  }
  // The coarse grid: scale=2 is bilateral_filter_cpu at step 2, and differs
  // from every pixel's filter.
  GstHarness *h = harness("pseudo3ddepth ! pseudo3dfilter radius=3 scale=2", fmt, size.w, size.h);
  GstBuffer *b = gst_harness_push_and_pull(h, buffer_from_frame(frame));
  const cv::Mat db = buffer_depth(b);
  cv::Mat want(size.h, size.w, CV_32FC1);
  BilateralParams p = default_filter_params();
  p.radius = 3;
  p.scale = 2;
  bilateral_filter_cpu(p, frame.view(), depth_view_of(da), depth_view_of(want));
  EXPECT_EQ(cv::norm(db, want, cv::NORM_INF), 0) << "the element is bilateral_filter_cpu at scale 2";
  if (size.w >= 16) {
    EXPECT_GT(cv::norm(by_mode[1], db, cv::NORM_INF), 0) << "scale reaches the filter";
  }
  gst_buffer_unref(b);
  gst_harness_teardown(h);
  gst_buffer_unref(a);
  gst_harness_teardown(ref);
}

// The grid step is automatic by default (full resolution up to 1080p, 2 at
// 4K) and the property's default says so.
TEST(Filter, DefaultScaleIsAutomatic) {
  GstElement *f = gst_element_factory_make("pseudo3dfilter", nullptr);
  ASSERT_NE(f, nullptr);
  gint scale = -1;
  g_object_get(f, "scale", &scale, nullptr);
  EXPECT_EQ(scale, 0);
  EXPECT_EQ(default_filter_params().scale, 0);
  GParamSpec *spec = g_object_class_find_property(G_OBJECT_GET_CLASS(f), "scale");
  ASSERT_NE(spec, nullptr);
  EXPECT_EQ(G_PARAM_SPEC_INT(spec)->default_value, 0);
  EXPECT_EQ(G_PARAM_SPEC_INT(spec)->maximum, kMaxBilateralScale);
  gst_object_unref(f);
}

INSTANTIATE_TEST_SUITE_P(AllFormatsAndSizes, FilterFormats,
                         ::testing::Combine(::testing::ValuesIn(kAllFormats),
                                            ::testing::Values(Size{1, 1}, Size{3, 2}, Size{64, 48})),
                         format_and_size_name);

class WarpFormats : public ::testing::TestWithParam<std::tuple<PixelFormat, Size>> {};

// Output: 2W x H, side-by-side caps; zero disparity gives two copies of the input.
TEST_P(WarpFormats, ZeroDisparityGivesTwoCopies) {
  const auto [fmt, size] = GetParam();
  GstHarness *h = harness("pseudo3ddepth ! pseudo3dwarp max-disparity=0 ! capsfilter caps=video/x-raw,format=BGRA",
                          fmt, size.w, size.h);
  const HostFrame frame = test_frame(fmt, size.w, size.h, 5);
  GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(frame));
  ASSERT_NE(out, nullptr);
  GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
  GstVideoInfo info;
  ASSERT_TRUE(gst_video_info_from_caps(&info, caps));
  EXPECT_EQ(GST_VIDEO_INFO_WIDTH(&info), 2 * size.w);
  EXPECT_EQ(GST_VIDEO_INFO_HEIGHT(&info), size.h);
  EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_MODE(&info), GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE);
  const cv::Mat pair = buffer_to_bgra(out, caps);
  const cv::Mat expect = frame.to_bgra(yuv_to_rgb_params(0.299, 0.114, false));  // the caps' BT.601
  EXPECT_EQ(cv::norm(pair(cv::Rect(0, 0, size.w, size.h)), expect, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(pair(cv::Rect(size.w, 0, size.w, size.h)), expect, cv::NORM_INF), 0);
  gst_caps_unref(caps);
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}

INSTANTIATE_TEST_SUITE_P(AllFormatsAndSizes, WarpFormats,
                         ::testing::Combine(::testing::ValuesIn(kAllFormats),
                                            ::testing::Values(Size{1, 1}, Size{3, 2}, Size{64, 48}, Size{4097, 2161})),
                         format_and_size_name);

// With disparity the warp leaves holes (fill=none paints them magenta) and
// the default fill closes every one of them: the output is warp_render_cpu's
// for the frame and the depth the element received.
TEST(Warp, LeavesHolesAndFillsThem) {
  const HostFrame frame = test_frame(PixelFormat::RGBA, 128, 64, 11);
  auto render = [&](const char *fill, cv::Mat *depth) {
    GstHarness *h = harness(std::string("pseudo3ddepth ! pseudo3dwarp max-disparity=5 fill=") + fill +
                                " ! capsfilter caps=video/x-raw,format=RGBA",
                            PixelFormat::RGBA, 128, 64);
    GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(frame));
    GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
    const cv::Mat pair = buffer_to_bgra(out, caps);
    // The depth the warp got: the same estimate on the same frame.
    GstHarness *d = harness("pseudo3ddepth", PixelFormat::RGBA, 128, 64);
    GstBuffer *dout = gst_harness_push_and_pull(d, buffer_from_frame(frame));
    *depth = buffer_depth(dout).clone();
    gst_buffer_unref(dout);
    gst_harness_teardown(d);
    gst_caps_unref(caps);
    gst_buffer_unref(out);
    gst_harness_teardown(h);
    return pair;
  };
  cv::Mat depth;
  const cv::Mat holes = render("none", &depth);
  cv::Mat magenta;
  cv::inRange(holes, cv::Scalar(255, 0, 255, 0), cv::Scalar(255, 0, 255, 255), magenta);
  EXPECT_GT(cv::countNonZero(magenta), 10) << "5% disparity over a depth edge must disocclude pixels";
  const cv::Mat filled = render("background-smooth", &depth);
  HostFrame want(PixelFormat::RGBA, 256, 64);
  WarpParams p;
  p.max_disparity = 5.f;
  p.fill = HoleFill::BackgroundSmooth;
  ASSERT_GT(warp_render_cpu(p, frame.view(), YuvToRgb(), as_const(depth_view_of(depth)), want.view()), 0);
  EXPECT_EQ(cv::norm(filled, want.to_bgra(), cv::NORM_INF), 0) << "the fill must close every hole as the reference does";
  EXPECT_GT(cv::norm(filled(cv::Rect(0, 0, 128, 64)), filled(cv::Rect(128, 0, 128, 64)), cv::NORM_L1), 0);
}

TEST(Warp, WithoutDepthIsAnError) { expect_error_without_depth("pseudo3dwarp"); }

// A full side-by-side pair is already packed: the same buffer comes out.
TEST(Pack, SideBySideIsPassthrough) {
  expect_passthrough("pseudo3dpack layout=side-by-side", raw_caps(PixelFormat::RGBA, 16, 4, ",multiview-mode=side-by-side"),
                     16, 4);
}

// YUV cannot be packed directly (pseudo3dwarp outputs packed RGB).
TEST(Pack, RejectsYuvInput) {
  GstHarness *h = gst_harness_new_parse("pseudo3dpack");
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::NV12, 16, 4).c_str());
  EXPECT_EQ(gst_harness_push(h, buffer_from_frame(test_frame(PixelFormat::NV12, 16, 4, 1))), GST_FLOW_NOT_NEGOTIATED);
  gst_harness_teardown(h);
}

// The bin exposes its stages' properties and forwards them.
TEST(Convert, ForwardsProperties) {
  GstElement *bin = gst_element_factory_make("pseudo3dconvert", nullptr);
  ASSERT_NE(bin, nullptr);
  g_object_set(bin, "max-disparity", 7.5f, "radius", 2, "scale", 3, NULL);
  GstElement *warp = gst_bin_get_by_name(GST_BIN(bin), "warp");
  GstElement *filter = gst_bin_get_by_name(GST_BIN(bin), "filter");
  ASSERT_NE(warp, nullptr);
  ASSERT_NE(filter, nullptr);
  gfloat md = 0;
  gint radius = 0;
  g_object_get(warp, "max-disparity", &md, NULL);
  gint scale = 0;
  g_object_get(filter, "radius", &radius, "scale", &scale, NULL);
  EXPECT_FLOAT_EQ(md, 7.5f);
  EXPECT_EQ(radius, 2);
  EXPECT_EQ(scale, 3);
  gst_object_unref(warp);
  gst_object_unref(filter);
  gst_object_unref(bin);
}

// The GStreamer enum types are the names tables of common/ (enum_name.h):
// the same values and nicks, in order; input-layout adds from-caps before
// the table's values.
template <typename E, std::size_t N>
static void expect_enum_is_table(const char *type_name, const p3d::EnumName<E> (&table)[N], int extra_first = 0) {
  GEnumClass *klass = G_ENUM_CLASS(g_type_class_ref(g_type_from_name(type_name)));
  ASSERT_NE(klass, nullptr) << type_name;
  ASSERT_EQ(klass->n_values, N + extra_first) << type_name;
  for (std::size_t i = 0; i < N; ++i) {
    const GEnumValue &v = klass->values[i + extra_first];
    EXPECT_EQ(v.value, static_cast<int>(table[i].value) + extra_first) << type_name;
    EXPECT_STREQ(v.value_nick, table[i].nick) << type_name;
  }
  g_type_class_unref(klass);
}

TEST(Properties, EnumTypesAreTheNamesTables) {
  // The elements' classes register the types.
  for (const char *factory : {"pseudo3dconvert", "pseudo3dpack", "pseudo3ddepthmux"}) {
    GstElement *e = gst_element_factory_make(factory, nullptr);
    ASSERT_NE(e, nullptr) << factory;
    gst_object_unref(gst_object_ref_sink(e));
  }
  expect_enum_is_table("GstPseudo3DHypothesis", p3d::kHypothesisNames);
  expect_enum_is_table("GstPseudo3DFilterMode", p3d::kFilterModeNames);
  expect_enum_is_table("GstPseudo3DDepthConvention", p3d::kDepthConventionNames);
  expect_enum_is_table("GstPseudo3DView", p3d::kStereoViewNames);
  expect_enum_is_table("GstPseudo3DFill", p3d::kHoleFillNames);
  expect_enum_is_table("GstPseudo3DLayout", p3d::kPackLayoutNames);
  expect_enum_is_table("GstPseudo3DGlasses", p3d::kGlassesNames);
  expect_enum_is_table("GstPseudo3DAnaglyphMethod", p3d::kAnaglyphMethodNames);
  expect_enum_is_table("GstPseudo3DInputLayout", p3d::kStereoInputNames, 1);
}
