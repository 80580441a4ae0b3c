// pseudo3dpack as a stereo converter and its signalling, and pseudo3dwarp
// packing its own pair the same way (WarpLayout): the output caps of
// every layout with and without swap-eyes (GStreamer's multiview
// conventions), every input arrangement from the caps against a reference
// reconstruction computed in the test, declared input layouts, 2D input
// refused with a message that says what to do, passthrough, and 4:2:0
// output for encoders (format, colorimetry and samples).
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

#include <string>

#include <opencv2/imgproc.hpp>

#include "element_helpers.h"
#include "stereo_frames.h"
#include "test_data.h"

using namespace p3d;
using namespace p3d::test;

namespace {

// How a layout is signalled: mode, half-aspect, and whether swap-eyes makes it right-view-first.
struct LayoutSignal {
  const char *layout;
  int w_num, h_num;  // output size over one view, per axis
  GstVideoMultiviewMode mode, swapped_mode;
  bool half_aspect;
  bool swap_flags;  // swap-eyes sets right-view-first
};

const LayoutSignal kSignals[] = {
    {"anaglyph", 1, 1, GST_VIDEO_MULTIVIEW_MODE_MONO, GST_VIDEO_MULTIVIEW_MODE_MONO, false, false},
    {"side-by-side", 2, 1, GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, false, true},
    {"side-by-side-half", 1, 1, GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, true,
     true},
    {"top-bottom", 1, 2, GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM, GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM, false, true},
    {"top-bottom-half", 1, 1, GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM, GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM, true, true},
    {"row-interleaved", 1, 1, GST_VIDEO_MULTIVIEW_MODE_ROW_INTERLEAVED, GST_VIDEO_MULTIVIEW_MODE_ROW_INTERLEAVED, true,
     true},
    {"column-interleaved", 1, 1, GST_VIDEO_MULTIVIEW_MODE_COLUMN_INTERLEAVED,
     GST_VIDEO_MULTIVIEW_MODE_COLUMN_INTERLEAVED, true, true},
    {"checkerboard", 1, 1, GST_VIDEO_MULTIVIEW_MODE_CHECKERBOARD, GST_VIDEO_MULTIVIEW_MODE_CHECKERBOARD, true, true},
    {"left", 1, 1, GST_VIDEO_MULTIVIEW_MODE_LEFT, GST_VIDEO_MULTIVIEW_MODE_RIGHT, false, false},
    {"right", 1, 1, GST_VIDEO_MULTIVIEW_MODE_RIGHT, GST_VIDEO_MULTIVIEW_MODE_LEFT, false, false},
};

// Caps of a stereo input frame: multiview-mode and flags as GStreamer writes them.
std::string stereo_caps(int w, int h, const char *mode, guint flags, const char *par = "1/1") {
  char extra[256];
  snprintf(extra, sizeof extra,
           ",multiview-mode=%s,multiview-flags=(GstVideoMultiviewFlagsSet)%x:ffffffff,pixel-aspect-ratio=%s", mode,
           flags, par);
  return raw_caps(PixelFormat::RGBA, w, h, extra);
}

const char *mode_of(StereoInput in) {
  switch (in) {
    case StereoInput::SideBySide:
    case StereoInput::SideBySideHalf: return "side-by-side";
    case StereoInput::TopBottom:
    case StereoInput::TopBottomHalf: return "top-bottom";
    case StereoInput::RowInterleaved: return "row-interleaved";
    case StereoInput::ColumnInterleaved: return "column-interleaved";
    default: return "checkerboard";
  }
}
guint flags_of(StereoInput in, bool right_first) {
  const bool half = in != StereoInput::SideBySide && in != StereoInput::TopBottom;
  return (half ? GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT : 0) | (right_first ? GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_VIEW_FIRST : 0);
}

struct Packed {
  cv::Mat bgra;
  GstVideoInfo info;
  GstBuffer *in = nullptr, *out = nullptr;  // refs kept for identity checks
};

Packed push_one(const std::string &launch, const std::string &caps, const HostFrame &frame) {
  Packed r;
  GstHarness *h = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(h, caps.c_str());
  r.in = buffer_from_frame(frame);
  r.out = gst_harness_push_and_pull(h, gst_buffer_ref(r.in));
  if (r.out) {
    GstCaps *c = gst_pad_get_current_caps(h->sinkpad);
    gst_video_info_from_caps(&r.info, c);
    r.bgra = buffer_to_bgra(r.out, c);
    gst_caps_unref(c);
  }
  gst_harness_teardown(h);
  return r;
}

void release(Packed &p) {
  if (p.in) gst_buffer_unref(p.in);
  if (p.out) gst_buffer_unref(p.out);
  p.in = p.out = nullptr;
}

cv::Mat to_bgra(const HostFrame &f) { return f.to_bgra(); }

}  // namespace

// Every layout, with and without swap-eyes, from a left-first full pair with
// PAR 4/3: size per layout, multiview-mode, half-aspect on squeezed layouts
// only, the input's PAR unchanged, right-view-first exactly with swap-eyes.
TEST(StereoCaps, EveryLayoutFollowsGStreamerConventions) {
  const int w = 21, h = 10;
  HostFrame pair(PixelFormat::RGBA, 2 * w, h);
  pair.fill_random(3);
  for (const LayoutSignal &s : kSignals)
    for (bool swap : {false, true}) {
      const std::string what = std::string(s.layout) + (swap ? " swap-eyes" : "");
      Packed p = push_one(std::string("pseudo3dpack layout=") + s.layout + (swap ? " swap-eyes=true" : ""),
                          stereo_caps(2 * w, h, "side-by-side", 0, "4/3"), pair);
      ASSERT_NE(p.out, nullptr) << what;
      EXPECT_EQ(GST_VIDEO_INFO_WIDTH(&p.info), w * s.w_num) << what;
      EXPECT_EQ(GST_VIDEO_INFO_HEIGHT(&p.info), h * s.h_num) << what;
      EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_MODE(&p.info), swap ? s.swapped_mode : s.mode) << what;
      const guint flags = GST_VIDEO_INFO_MULTIVIEW_FLAGS(&p.info);
      EXPECT_EQ((flags & GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT) != 0, s.half_aspect) << what;
      EXPECT_EQ((flags & GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_VIEW_FIRST) != 0, swap && s.swap_flags) << what;
      EXPECT_EQ(GST_VIDEO_INFO_PAR_N(&p.info), 4) << what << ": the frame's pixel aspect ratio is kept";
      EXPECT_EQ(GST_VIDEO_INFO_PAR_D(&p.info), 3) << what;
      release(p);
    }
}

// A full side-by-side input is the warp's output: the caps string, not just
// the parsed info, carries PAR 1/1 and the half-aspect flag for half SBS
// (what x264enc turns into SAR 1:1 plus a frame-packing SEI).
TEST(StereoCaps, HalfSideBySideCapsString) {
  GstHarness *h = gst_harness_new_parse("pseudo3dpack layout=side-by-side-half");
  gst_harness_set_src_caps_str(h, stereo_caps(32, 8, "side-by-side", 0).c_str());
  HostFrame pair(PixelFormat::RGBA, 32, 8);
  pair.fill(9);
  GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(pair));
  ASSERT_NE(out, nullptr);
  const std::string caps = current_caps(h->sinkpad);
  EXPECT_NE(caps.find("pixel-aspect-ratio=(fraction)1/1"), std::string::npos) << caps;
  EXPECT_NE(caps.find("multiview-mode=(string)side-by-side"), std::string::npos) << caps;
  EXPECT_NE(caps.find("half-aspect"), std::string::npos) << caps;
  EXPECT_NE(caps.find("4000:"), std::string::npos) << "half-aspect flag set: " << caps;
  gst_buffer_unref(out);
  gst_harness_teardown(h);
}

// Every input arrangement, either eye first, read from the caps into a full
// side-by-side pair: the views are the reference reconstruction, byte for byte.
TEST(StereoInputs, EveryArrangementFromTheCaps) {
  HostFrame l(PixelFormat::RGBA, 17, 8), r(PixelFormat::RGBA, 17, 8);
  l.fill_random(11);
  r.fill_random(12);
  for (StereoInput in : kAllInputs)
    for (bool rf : {false, true}) {
      const HostFrame frame = arrange_pair(in, rf, l, r);
      const std::string what = std::string(mode_of(in)) + " flags " + std::to_string(flags_of(in, rf));
      Packed p = push_one("pseudo3dpack layout=side-by-side",
                          stereo_caps(frame.width(), frame.height(), mode_of(in), flags_of(in, rf)), frame);
      ASSERT_NE(p.out, nullptr) << what;
      cv::Mat want;
      cv::hconcat(to_bgra(reference_view(in, rf, frame, 0)), to_bgra(reference_view(in, rf, frame, 1)), want);
      ASSERT_EQ(p.bgra.size(), want.size()) << what;
      EXPECT_EQ(cv::norm(p.bgra, want, cv::NORM_INF), 0) << what;
      // A full input pair converts losslessly.
      if (in == StereoInput::SideBySide || in == StereoInput::TopBottom) {
        cv::Mat exact;
        cv::hconcat(to_bgra(l), to_bgra(r), exact);
        EXPECT_EQ(cv::norm(p.bgra, exact, cv::NORM_INF), 0) << what;
      }
      release(p);
    }
}

// Input whose caps say nothing (2D caps) with input-layout declared gives
// what the same frames signalled in the caps give.
TEST(StereoInputs, DeclaredLayoutEqualsSignalledOne) {
  HostFrame l(PixelFormat::RGBA, 12, 6), r(PixelFormat::RGBA, 12, 6);
  l.fill_random(21);
  r.fill_random(22);
  const struct {
    StereoInput in;
    const char *nick;
  } cases[] = {{StereoInput::TopBottomHalf, "top-bottom-half"}, {StereoInput::ColumnInterleaved, "column-interleaved"}};
  for (const auto &c : cases) {
    const HostFrame frame = arrange_pair(c.in, true, l, r);
    Packed signalled = push_one("pseudo3dpack layout=anaglyph",
                                stereo_caps(frame.width(), frame.height(), mode_of(c.in), flags_of(c.in, true)), frame);
    Packed declared = push_one(std::string("pseudo3dpack layout=anaglyph input-right-first=true input-layout=") + c.nick,
                               raw_caps(PixelFormat::RGBA, frame.width(), frame.height()), frame);
    ASSERT_NE(signalled.out, nullptr) << c.nick;
    ASSERT_NE(declared.out, nullptr) << c.nick;
    EXPECT_EQ(cv::norm(signalled.bgra, declared.bgra, cv::NORM_INF), 0) << c.nick;
    release(signalled);
    release(declared);
  }
}

// 2D input (no multiview-mode, mono, or a single view) is refused with one
// error that names input-layout; nothing is packed as if it were a pair.
TEST(StereoInputs, TwoDimensionalInputIsRefusedWithAMessage) {
  const std::string inputs[] = {raw_caps(PixelFormat::RGBA, 16, 8), stereo_caps(16, 8, "mono", 0),
                                stereo_caps(16, 8, "left", 0)};
  for (const std::string &caps : inputs) {
    GstHarness *h = gst_harness_new_parse("pseudo3dpack layout=anaglyph");
    BusMessages bus(h->element);
    gst_harness_set_src_caps_str(h, caps.c_str());
    HostFrame frame(PixelFormat::RGBA, 16, 8);
    frame.fill(5);
    for (int i = 0; i < 3; ++i) EXPECT_NE(gst_harness_push(h, buffer_from_frame(frame)), GST_FLOW_OK) << caps;
    const std::vector<std::string> errors = bus.take(GST_MESSAGE_ERROR);
    ASSERT_EQ(errors.size(), 1u) << caps << ": one error for one failure, however many buffers arrive";
    EXPECT_NE(errors[0].find("needs a stereo pair"), std::string::npos) << errors[0];
    EXPECT_NE(errors[0].find("input-layout=side-by-side"), std::string::npos) << errors[0];
    EXPECT_EQ(gst_harness_buffers_received(h), 0u);
    gst_harness_teardown(h);
  }
}

// An odd-width "full side-by-side" frame holds no pair: the element's own
// reason, once.
TEST(StereoInputs, OddFullSideBySideIsRefused) {
  GstHarness *h = gst_harness_new_parse("pseudo3dpack layout=left");
  BusMessages bus(h->element);
  gst_harness_set_src_caps_str(h, stereo_caps(15, 4, "side-by-side", 0).c_str());
  HostFrame frame(PixelFormat::RGBA, 15, 4);
  frame.fill(1);
  EXPECT_NE(gst_harness_push(h, buffer_from_frame(frame)), GST_FLOW_OK);
  EXPECT_NE(gst_harness_push(h, buffer_from_frame(frame)), GST_FLOW_OK);
  const std::vector<std::string> errors = bus.take(GST_MESSAGE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("even width"), std::string::npos) << errors[0];
  gst_harness_teardown(h);
}

// The input's own arrangement and eye order: the very buffer passes; the
// other eye order is a real conversion.
TEST(StereoInputs, SameArrangementPassesThrough) {
  HostFrame frame(PixelFormat::RGBA, 16, 8);
  frame.fill_random(4);
  const guint half_rf = GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT | GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_VIEW_FIRST;
  Packed same = push_one("pseudo3dpack layout=side-by-side-half swap-eyes=true", stereo_caps(16, 8, "side-by-side", half_rf),
                         frame);
  EXPECT_EQ(same.out, same.in);
  release(same);
  Packed swapped = push_one("pseudo3dpack layout=side-by-side-half", stereo_caps(16, 8, "side-by-side", half_rf), frame);
  ASSERT_NE(swapped.out, nullptr);
  EXPECT_NE(swapped.out, swapped.in);
  EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_FLAGS(&swapped.info) & GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_VIEW_FIRST, 0u);
  release(swapped);
}

namespace {

// Samples of every plane of a mapped output buffer that differ from `want`.
long long yuv_diff(const Packed &p, const HostFrame &want) {
  GstVideoInfo info = p.info;
  GstVideoFrame vf;
  if (!gst_video_frame_map(&vf, &info, p.out, GST_MAP_READ)) return -1;
  long long n = 0;
  for (int i = 0; i < frame_plane_count(want.format()); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(want.format(), want.width(), want.height(), i, &row_bytes, &rows);
    for (int y = 0; y < rows; ++y) {
      const auto *got = static_cast<const uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&vf, i)) +
                        static_cast<size_t>(y) * GST_VIDEO_FRAME_PLANE_STRIDE(&vf, i);
      const uint8_t *exp = want.view().plane[i] + static_cast<size_t>(y) * want.view().stride[i];
      for (int x = 0; x < row_bytes; ++x) n += got[x] != exp[x];
    }
  }
  gst_video_frame_unmap(&vf);
  return n;
}

// The half side-by-side pair of `frame` (a full side-by-side pair) as the
// test computes it: packed, then converted with the given matrix.
HostFrame half_sbs_yuv(const HostFrame &frame, PixelFormat f, double kr, double kb, bool full) {
  PackParams params;
  params.layout = PackLayout::SideBySideHalf;
  params.yuv = rgb_to_yuv_params(kr, kb, full);
  HostFrame out(f, frame.width() / 2, frame.height());
  pack_cpu(params, frame.view(), out.view());
  return out;
}

}  // namespace

// An encoder's 4:2:0 caps after pseudo3dpack: the pair is packed and
// converted by the pack itself, in BT.709 limited range unless downstream
// names another colorimetry, chroma-site jpeg, the multiview signal as for
// RGB output; without such caps the output stays in the input's format.
TEST(StereoYuvOutput, EncoderFormatsAreWrittenByThePack) {
  HostFrame frame(PixelFormat::RGBA, 2 * 19, 11);
  frame.fill_random(21);
  const std::string in_caps = stereo_caps(38, 11, "side-by-side", 0);

  Packed i420 = push_one("pseudo3dpack layout=side-by-side-half ! capsfilter caps=video/x-raw,format=I420", in_caps, frame);
  ASSERT_NE(i420.out, nullptr);
  EXPECT_EQ(GST_VIDEO_INFO_FORMAT(&i420.info), GST_VIDEO_FORMAT_I420);
  gchar *colorimetry = gst_video_colorimetry_to_string(&i420.info.colorimetry);
  EXPECT_STREQ(colorimetry, "bt709");
  g_free(colorimetry);
  EXPECT_EQ(i420.info.chroma_site, GST_VIDEO_CHROMA_SITE_JPEG);
  EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_MODE(&i420.info), GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE);
  EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_FLAGS(&i420.info), GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT);
  EXPECT_EQ(yuv_diff(i420, half_sbs_yuv(frame, PixelFormat::I420, 0.2126, 0.0722, false)), 0);
  release(i420);

  Packed nv12 = push_one("pseudo3dpack layout=side-by-side-half ! capsfilter caps=\"video/x-raw,format=NV12,colorimetry=bt601\"", in_caps,
                         frame);
  ASSERT_NE(nv12.out, nullptr);
  EXPECT_EQ(GST_VIDEO_INFO_FORMAT(&nv12.info), GST_VIDEO_FORMAT_NV12);
  EXPECT_EQ(yuv_diff(nv12, half_sbs_yuv(frame, PixelFormat::NV12, 0.299, 0.114, false)), 0);
  release(nv12);

  Packed rgb = push_one("pseudo3dpack layout=side-by-side-half", in_caps, frame);
  ASSERT_NE(rgb.out, nullptr);
  EXPECT_EQ(GST_VIDEO_INFO_FORMAT(&rgb.info), GST_VIDEO_FORMAT_RGBA);
  release(rgb);
}

// The input's own arrangement into 4:2:0 is a conversion, not passthrough.
TEST(StereoYuvOutput, SameArrangementInAnotherFormatIsConverted) {
  HostFrame frame(PixelFormat::RGBA, 16, 8);
  frame.fill_random(5);
  Packed p = push_one("pseudo3dpack layout=side-by-side ! capsfilter caps=video/x-raw,format=I420",
                      stereo_caps(16, 8, "side-by-side", 0), frame);
  ASSERT_NE(p.out, nullptr);
  EXPECT_NE(p.out, p.in);
  EXPECT_EQ(GST_VIDEO_INFO_FORMAT(&p.info), GST_VIDEO_FORMAT_I420);
  PackParams params;
  params.layout = PackLayout::SideBySide;
  params.yuv = rgb_to_yuv_params(0.2126, 0.0722, false);
  HostFrame want(PixelFormat::I420, 16, 8);
  pack_cpu(params, frame.view(), want.view());
  EXPECT_EQ(yuv_diff(p, want), 0);
  release(p);
}

// ---- pseudo3dwarp with a layout: the warp packs its own pair --------------

namespace {

constexpr const char *kDepthStages =
    "pseudo3ddepth processing=cpu temporal-smoothing=0 ! pseudo3dfilter processing=cpu ! ";

// The Aloe view, small, as 4:2:0 input.
HostFrame small_aloe(int w, int h) {
  const cv::Mat bgr = load_data_image("aloeL.jpg");
  if (bgr.empty()) return HostFrame();
  cv::Mat small;
  cv::resize(bgr, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  return HostFrame::from_bgr(small, PixelFormat::NV12);
}

std::string warp_props(const char *layout, bool swap) {
  return std::string(" layout=") + layout + (swap ? " swap-eyes=true" : "") + " anaglyph-method=dubois-ffmpeg";
}

// Same caps (size, multiview mode and flags, PAR, format) and same pixels.
void expect_same_output(const Packed &got, const Packed &want, const std::string &what) {
  ASSERT_NE(got.out, nullptr) << what;
  ASSERT_NE(want.out, nullptr) << what;
  EXPECT_EQ(GST_VIDEO_INFO_FORMAT(&got.info), GST_VIDEO_INFO_FORMAT(&want.info)) << what;
  EXPECT_EQ(GST_VIDEO_INFO_WIDTH(&got.info), GST_VIDEO_INFO_WIDTH(&want.info)) << what;
  EXPECT_EQ(GST_VIDEO_INFO_HEIGHT(&got.info), GST_VIDEO_INFO_HEIGHT(&want.info)) << what;
  EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_MODE(&got.info), GST_VIDEO_INFO_MULTIVIEW_MODE(&want.info)) << what;
  EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_FLAGS(&got.info), GST_VIDEO_INFO_MULTIVIEW_FLAGS(&want.info)) << what;
  EXPECT_EQ(GST_VIDEO_INFO_PAR_N(&got.info), GST_VIDEO_INFO_PAR_N(&want.info)) << what;
  EXPECT_EQ(GST_VIDEO_INFO_PAR_D(&got.info), GST_VIDEO_INFO_PAR_D(&want.info)) << what;
  const DiffStats d = compare_u8(got.bgra, want.bgra, 0);
  EXPECT_EQ(d.max_abs, 0) << what << ": " << d.over_tolerance << " samples differ";
}

}  // namespace

// pseudo3dwarp layout=L is pseudo3dwarp ! pseudo3dpack layout=L: every
// layout with and without swap-eyes (and an anaglyph method, passed on),
// caps and bytes, from a real picture with a non-square PAR.
TEST(WarpLayout, EveryLayoutIsTheWarpThenThePack) {
  const HostFrame frame = small_aloe(96, 64);
  ASSERT_FALSE(frame.empty());
  const std::string caps = raw_caps(PixelFormat::NV12, 96, 64, ",pixel-aspect-ratio=4/3");
  for (const LayoutSignal &s : kSignals)
    for (bool swap : {false, true}) {
      const std::string props = warp_props(s.layout, swap);
      Packed got = push_one(std::string(kDepthStages) + "pseudo3dwarp processing=cpu" + props, caps, frame);
      Packed want = push_one(std::string(kDepthStages) + "pseudo3dwarp processing=cpu ! pseudo3dpack processing=cpu" +
                                 props,
                             caps, frame);
      expect_same_output(got, want, props);
      if (got.out) {
        EXPECT_EQ(GST_VIDEO_INFO_WIDTH(&got.info), 96 * s.w_num) << props;
      }
      release(got);
      release(want);
    }
}

// An encoder's 4:2:0 caps after the warp: packed and converted by the warp
// itself, in the colorimetry downstream names (BT.709 by default), as the
// pack writes them.
TEST(WarpLayout, EncoderFormatsAreWrittenByTheWarp) {
  const HostFrame frame = small_aloe(96, 64);
  ASSERT_FALSE(frame.empty());
  const std::string caps = raw_caps(PixelFormat::NV12, 96, 64);
  for (const char *tail : {" ! capsfilter caps=video/x-raw,format=I420",
                           " ! capsfilter caps=\"video/x-raw,format=NV12,colorimetry=bt601\""})
    for (const char *layout : {"side-by-side-half", "side-by-side"}) {
      const std::string props = warp_props(layout, false);
      Packed got = push_one(std::string(kDepthStages) + "pseudo3dwarp processing=cpu" + props + tail, caps, frame);
      Packed want = push_one(
          std::string(kDepthStages) + "pseudo3dwarp processing=cpu ! pseudo3dpack processing=cpu" + props + tail, caps,
          frame);
      expect_same_output(got, want, props + tail);
      if (got.out) {
        EXPECT_FALSE(GST_VIDEO_INFO_IS_RGB(&got.info)) << props + tail;
      }
      release(got);
      release(want);
    }
}

// layout and swap-eyes changed between frames of one stream: each frame
// comes out in the layout set before it (renegotiated where the caps
// change; swap-eyes of an anaglyph keeps them), as a fresh warp ! pack
// with those properties gives it.
TEST(WarpLayout, LayoutChangedWhilePlaying) {
  const HostFrame frame = small_aloe(96, 64);
  ASSERT_FALSE(frame.empty());
  const std::string caps = raw_caps(PixelFormat::NV12, 96, 64);
  GstHarness *h = gst_harness_new_parse((std::string(kDepthStages) + "pseudo3dwarp name=w processing=cpu").c_str());
  gst_harness_set_src_caps_str(h, caps.c_str());
  GstElement *warp = gst_bin_get_by_name(GST_BIN(h->element), "w");
  ASSERT_NE(warp, nullptr);
  const struct {
    const char *layout;
    bool swap;
  } steps[] = {{"side-by-side", false}, {"anaglyph", false}, {"anaglyph", true},
               {"top-bottom-half", true}, {"side-by-side", false}};
  for (const auto &st : steps) {
    gst_util_set_object_arg(G_OBJECT(warp), "layout", st.layout);
    g_object_set(warp, "swap-eyes", st.swap, NULL);
    GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(frame));
    ASSERT_NE(out, nullptr) << st.layout;
    Packed got;
    got.out = out;
    GstCaps *c = gst_pad_get_current_caps(h->sinkpad);
    gst_video_info_from_caps(&got.info, c);
    got.bgra = buffer_to_bgra(out, c);
    gst_caps_unref(c);
    const std::string props = std::string(" layout=") + st.layout + (st.swap ? " swap-eyes=true" : "");
    Packed want = push_one(std::string(kDepthStages) + "pseudo3dwarp processing=cpu ! pseudo3dpack processing=cpu" +
                               props,
                           caps, frame);
    expect_same_output(got, want, props);
    release(got);
    release(want);
  }
  gst_object_unref(warp);
  gst_harness_teardown(h);
}

// pseudo3dconvert keeps pseudo3dpack's defaults for the pack's properties
// that the warp takes (the warp's own layout default is the pair): with no
// property set it writes the anaglyph, as pseudo3ddepth ! pseudo3dfilter !
// pseudo3dwarp ! pseudo3dpack does, and says so through its property.
TEST(WarpLayout, TheBinDefaultsToTheAnaglyph) {
  const HostFrame frame = small_aloe(96, 64);
  ASSERT_FALSE(frame.empty());
  GstElement *bin = gst_element_factory_make("pseudo3dconvert", nullptr);
  ASSERT_NE(bin, nullptr);
  gint layout = -1;
  g_object_get(bin, "layout", &layout, NULL);
  EXPECT_EQ(layout, static_cast<gint>(PackLayout::Anaglyph));
  gst_object_unref(bin);
  const std::string caps = raw_caps(PixelFormat::NV12, 96, 64);
  Packed got = push_one("pseudo3dconvert processing=cpu", caps, frame);
  Packed want = push_one(std::string(kDepthStages) + "pseudo3dwarp processing=cpu ! pseudo3dpack processing=cpu", caps,
                         frame);
  expect_same_output(got, want, "pseudo3dconvert's defaults");
  if (got.out) {
    EXPECT_EQ(GST_VIDEO_INFO_WIDTH(&got.info), 96);
    EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_MODE(&got.info), GST_VIDEO_MULTIVIEW_MODE_MONO);
  }
  release(got);
  release(want);
}
