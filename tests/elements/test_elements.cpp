// GstHarness tests of each element: every input format, odd sizes, property
// specs, passthrough where a stage has nothing to do, caps that must fail.
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "element_helpers.h"
#include "test_data.h"

using namespace p3d;
using namespace p3d::test;

namespace {

const char *kFactories[] = {"pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp", "pseudo3dpack", "pseudo3dconvert"};

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

TEST(Plugin, RegistersFiveElements) {
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
          p->owner_type == GST_TYPE_BASE_TRANSFORM || p->owner_type == G_TYPE_OBJECT)
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

// Out-of-range values are refused by GObject (value unchanged).
TEST(Plugin, OutOfRangePropertyIsRejected) {
  GstElement *warp = gst_element_factory_make("pseudo3dwarp", nullptr);
  GValue v = G_VALUE_INIT;
  g_value_init(&v, G_TYPE_FLOAT);
  g_value_set_float(&v, 1000.f);
  GParamSpec *p = g_object_class_find_property(G_OBJECT_GET_CLASS(warp), "max-disparity");
  EXPECT_TRUE(g_param_value_validate(p, &v)) << "1000% must be clamped by the spec";
  EXPECT_LE(g_value_get_float(&v), 25.f);
  g_value_unset(&v);
  gst_object_unref(warp);
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

// 4:2:0 RGBD halves must start on a chroma sample.
TEST(Depth, RgbdRejectsUnsplittableYuvWidth) {
  GstHarness *h = gst_harness_new_parse("pseudo3ddepth method=rgbd");
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::NV12, 14, 8).c_str());
  GstBuffer *in = buffer_from_frame(test_frame(PixelFormat::NV12, 14, 8, 1));
  EXPECT_NE(gst_harness_push(h, in), GST_FLOW_OK);
  gst_harness_teardown(h);
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

class FilterFormats : public ::testing::TestWithParam<std::tuple<PixelFormat, Size>> {};

// The filtered depth differs from the blocky estimate and stays in [0,1].
TEST_P(FilterFormats, FiltersDepth) {
  const auto [fmt, size] = GetParam();
  GstHarness *ref = harness("pseudo3ddepth", fmt, size.w, size.h);
  GstHarness *h = harness("pseudo3ddepth ! pseudo3dfilter radius=3", fmt, size.w, size.h);
  const HostFrame frame = test_frame(fmt, size.w, size.h, 9);
  GstBuffer *a = gst_harness_push_and_pull(ref, buffer_from_frame(frame));
  GstBuffer *b = gst_harness_push_and_pull(h, buffer_from_frame(frame));
  const cv::Mat da = buffer_depth(a), db = buffer_depth(b);
  ASSERT_EQ(db.size(), cv::Size(size.w, size.h));
  EXPECT_TRUE(cv::checkRange(db, true, nullptr, 0.0, 1.0 + 1e-6));
  if (size.w >= 16) {
    EXPECT_GT(cv::norm(da, db, cv::NORM_INF), 1e-4) << "a radius-3 filter changes blocky depth";
  }
  gst_buffer_unref(a);
  gst_buffer_unref(b);
  gst_harness_teardown(ref);
  gst_harness_teardown(h);
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

// With disparity, the two views differ and nothing is left unfilled (no magenta).
TEST(Warp, ViewsDifferAndHolesAreFilled) {
  GstHarness *h = harness("pseudo3ddepth ! pseudo3dwarp max-disparity=5 ! capsfilter caps=video/x-raw,format=RGBA",
                          PixelFormat::RGBA, 128, 64);
  GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(test_frame(PixelFormat::RGBA, 128, 64, 11)));
  GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
  const cv::Mat pair = buffer_to_bgra(out, caps);
  EXPECT_GT(cv::norm(pair(cv::Rect(0, 0, 128, 64)), pair(cv::Rect(128, 0, 128, 64)), cv::NORM_L1), 0);
  cv::Mat magenta;
  cv::inRange(pair, cv::Scalar(255, 0, 255, 0), cv::Scalar(255, 0, 255, 255), magenta);
  EXPECT_EQ(cv::countNonZero(magenta), 0);
  gst_caps_unref(caps);
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}

TEST(Warp, WithoutDepthIsAnError) { expect_error_without_depth("pseudo3dwarp"); }

struct LayoutCase {
  const char *layout;
  int w_num, w_den, h_num;  // output size over the W x H view
  GstVideoMultiviewMode mode;
  bool half_aspect;
};

class PackLayouts : public ::testing::TestWithParam<LayoutCase> {};

// Sizes and multiview signalling of every layout, on a 2W x H pair.
TEST_P(PackLayouts, SizeAndMultiviewCaps) {
  const LayoutCase c = GetParam();
  const int w = 21, hgt = 9;  // odd view sizes
  GstHarness *h = gst_harness_new_parse((std::string("pseudo3dpack layout=") + c.layout).c_str());
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::BGRx, 2 * w, hgt, ",multiview-mode=side-by-side").c_str());
  GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(test_frame(PixelFormat::BGRx, 2 * w, hgt, 2)));
  ASSERT_NE(out, nullptr) << c.layout;
  GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
  GstVideoInfo info;
  ASSERT_TRUE(gst_video_info_from_caps(&info, caps));
  EXPECT_EQ(GST_VIDEO_INFO_WIDTH(&info), w * c.w_num / c.w_den) << c.layout;
  EXPECT_EQ(GST_VIDEO_INFO_HEIGHT(&info), hgt * c.h_num) << c.layout;
  EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_MODE(&info), c.mode) << c.layout;
  EXPECT_EQ((GST_VIDEO_INFO_MULTIVIEW_FLAGS(&info) & GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT) != 0, c.half_aspect)
      << c.layout;
  // As gst_video_info_to_caps does: half-aspect doubles the PAR along the squeezed axis.
  const bool sbs = c.mode == GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, tb = c.mode == GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM;
  EXPECT_EQ(GST_VIDEO_INFO_PAR_N(&info), c.half_aspect && sbs ? 2 : 1) << c.layout;
  EXPECT_EQ(GST_VIDEO_INFO_PAR_D(&info), c.half_aspect && tb ? 2 : 1) << c.layout;
  gst_caps_unref(caps);
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}

INSTANTIATE_TEST_SUITE_P(
    Layouts, PackLayouts,
    ::testing::Values(LayoutCase{"anaglyph", 1, 1, 1, GST_VIDEO_MULTIVIEW_MODE_MONO, false},
                      LayoutCase{"side-by-side", 2, 1, 1, GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, false},
                      LayoutCase{"side-by-side-half", 1, 1, 1, GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, true},
                      LayoutCase{"top-bottom", 1, 1, 2, GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM, false},
                      LayoutCase{"top-bottom-half", 1, 1, 1, GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM, true},
                      LayoutCase{"row-interleaved", 1, 1, 1, GST_VIDEO_MULTIVIEW_MODE_ROW_INTERLEAVED, false},
                      LayoutCase{"column-interleaved", 1, 1, 1, GST_VIDEO_MULTIVIEW_MODE_COLUMN_INTERLEAVED, false},
                      LayoutCase{"checkerboard", 1, 1, 1, GST_VIDEO_MULTIVIEW_MODE_CHECKERBOARD, false},
                      LayoutCase{"left", 1, 1, 1, GST_VIDEO_MULTIVIEW_MODE_LEFT, false},
                      LayoutCase{"right", 1, 1, 1, GST_VIDEO_MULTIVIEW_MODE_RIGHT, false}),
    [](const auto &info) {
      std::string n = info.param.layout;
      for (char &ch : n)
        if (ch == '-') ch = '_';
      return n;
    });

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
  g_object_set(bin, "max-disparity", 7.5f, "radius", 2, NULL);
  GstElement *warp = gst_bin_get_by_name(GST_BIN(bin), "warp");
  GstElement *filter = gst_bin_get_by_name(GST_BIN(bin), "filter");
  ASSERT_NE(warp, nullptr);
  ASSERT_NE(filter, nullptr);
  gfloat md = 0;
  gint radius = 0;
  g_object_get(warp, "max-disparity", &md, NULL);
  g_object_get(filter, "radius", &radius, NULL);
  EXPECT_FLOAT_EQ(md, 7.5f);
  EXPECT_EQ(radius, 2);
  gst_object_unref(warp);
  gst_object_unref(filter);
  gst_object_unref(bin);
}
