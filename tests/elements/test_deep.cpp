// P010_10LE, I420_10LE and RGBA64_LE through the elements on system
// memory: every layout of the warp into each deep output format, byte for
// byte the CPU references (common/warp.h, common/pack.h) on the depth the
// elements attached; pseudo3dpack on a 16-bit pair; adaptive work on a
// changing 10-bit sequence; the caps keeping the input's depth (and CUDA
// memory offering no RGBA64_LE).
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "element_helpers.h"
#include "host_frame.h"
#include "pack.h"
#include "test_data.h"
#include "warp.h"

using namespace p3d;
using namespace p3d::test;

namespace {

constexpr int kW = 96, kH = 64;

// Pushes one frame through `launch`; returns the output (new ref) and its caps.
GstBuffer *push_one(const std::string &launch, const HostFrame &frame, GstCaps **caps) {
  GstHarness *h = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(h, raw_caps(frame.format(), frame.width(), frame.height()).c_str());
  GstBuffer *in = buffer_from_frame(frame);
  GST_BUFFER_PTS(in) = 0;
  GstBuffer *out = gst_harness_push_and_pull(h, in);
  *caps = gst_pad_get_current_caps(h->sinkpad);
  gst_harness_teardown(h);
  return out;
}

// Fails where the buffer's pixels (as its caps describe them) differ from
// the frame's in any byte.
void expect_frame(GstBuffer *buf, GstCaps *caps, const HostFrame &want, const std::string &what) {
  GstVideoInfo info;
  ASSERT_TRUE(caps && gst_video_info_from_caps(&info, caps)) << what;
  ASSERT_EQ(GST_VIDEO_INFO_WIDTH(&info), want.width()) << what;
  ASSERT_EQ(GST_VIDEO_INFO_HEIGHT(&info), want.height()) << what;
  ASSERT_STREQ(GST_VIDEO_INFO_NAME(&info), format_name(want.format())) << what;
  GstVideoFrame f;
  ASSERT_TRUE(gst_video_frame_map(&f, &info, buf, GST_MAP_READ)) << what;
  const FrameView w = want.view();
  for (int p = 0; p < frame_plane_count(want.format()); ++p) {
    int row = 0, rows = 0;
    frame_plane_size(want.format(), want.width(), want.height(), p, &row, &rows);
    for (int y = 0; y < rows; ++y) {
      const uint8_t *got = static_cast<const uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&f, p)) +
                           static_cast<size_t>(y) * GST_VIDEO_FRAME_PLANE_STRIDE(&f, p);
      if (std::memcmp(got, w.plane[p] + static_cast<size_t>(y) * w.stride[p], row) != 0) {
        ADD_FAILURE() << what << ": plane " << p << " row " << y << " differs";
        gst_video_frame_unmap(&f);
        return;
      }
    }
  }
  gst_video_frame_unmap(&f);
}

// The 10-bit R'G'B' -> Y'CbCr conversion of negotiated caps (their
// matrix and range; the stage picks the matrix, see test_colour).
RgbToYuv yuv_of(GstCaps *caps) {
  GstVideoInfo info;
  gst_video_info_init(&info);
  gdouble kr = 0.2126, kb = 0.0722;
  if (caps && gst_video_info_from_caps(&info, caps))
    gst_video_color_matrix_get_Kr_Kb(info.colorimetry.matrix, &kr, &kb);
  return rgb_to_yuv_params(kr, kb, info.colorimetry.range == GST_VIDEO_COLOR_RANGE_0_255, 10);
}

const PixelFormat kDeepOutputs[] = {PixelFormat::RGBA64, PixelFormat::P010, PixelFormat::I420_10};

// depth ! filter ! warp layout=L into each deep output format: the output
// is warp_render_cpu() of the source and the depth the filter attached,
// packed by pack_cpu(), with the caps' colorimetry.
TEST(DeepElements, EveryLayoutIsTheCpuReference) {
  const YuvToRgb in_yuv = yuv_to_rgb_params(0.299, 0.114, false, 10);
  for (PixelFormat f : kDeepFormats) {
    const HostFrame src = HostFrame::from_bgr16(deep_picture(kW, kH, 1), f);
    GstCaps *depth_caps = nullptr;
    GstBuffer *with_depth = push_one("pseudo3ddepth ! pseudo3dfilter", src, &depth_caps);
    ASSERT_NE(with_depth, nullptr) << format_name(f);
    const cv::Mat depth = buffer_depth(with_depth);
    gst_buffer_unref(with_depth);
    gst_caps_unref(depth_caps);
    ASSERT_FALSE(depth.empty()) << format_name(f);
    HostFrame pair(PixelFormat::RGBA64, 2 * kW, kH);
    ASSERT_GT(warp_render_cpu(WarpParams{}, src.view(), in_yuv, depth_view_of(depth), pair.view()), 0);
    for (const PackLayout layout : kAllLayouts)
      for (const PixelFormat out_format : kDeepOutputs) {
        const std::string what = std::string(format_name(f)) + " " + enum_nick(kPackLayoutNames, layout) + " to " +
                                 format_name(out_format);
        const std::string caps = std::string("video/x-raw,format=") + format_name(out_format);
        GstCaps *out_caps = nullptr;
        GstBuffer *out = push_one(std::string("pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp layout=") +
                                      enum_nick(kPackLayoutNames, layout) + " ! capsfilter caps=\"" + caps + "\"",
                                  src, &out_caps);
        ASSERT_NE(out, nullptr) << what;
        PackParams p;
        p.layout = layout;
        p.yuv = yuv_of(out_caps);
        int ow = 0, oh = 0;
        pack_size(layout, kW, kH, &ow, &oh);
        HostFrame want(out_format, ow, oh);
        pack_cpu(p, pair.view(), want.view());
        expect_frame(out, out_caps, want, what);
        gst_buffer_unref(out);
        gst_caps_unref(out_caps);
      }
  }
}

// pseudo3dpack on a 16-bit side-by-side pair: pack_cpu's bytes, every layout.
TEST(DeepElements, PackIsTheCpuReference) {
  const HostFrame pair = HostFrame::from_bgr16(deep_picture(2 * kW, kH, 2), PixelFormat::RGBA64);
  for (const PackLayout layout : kAllLayouts) {
    const std::string name = enum_nick(kPackLayoutNames, layout);
    GstCaps *caps = nullptr;
    GstBuffer *out = push_one("pseudo3dpack input-layout=side-by-side layout=" + name, pair, &caps);
    ASSERT_NE(out, nullptr) << name;
    PackParams p;
    p.layout = layout;
    int ow = 0, oh = 0;
    pack_size(layout, kW, kH, &ow, &oh);
    HostFrame want(PixelFormat::RGBA64, ow, oh);
    pack_cpu(p, pair.view(), want.view());
    expect_frame(out, caps, want, name);
    gst_buffer_unref(out);
    gst_caps_unref(caps);
  }
}

// adaptive=true gives the bytes of adaptive=false on a 10-bit stream with
// unchanged, partly changed and cut frames.
TEST(DeepElements, AdaptiveChangesNoByte) {
  const std::vector<cv::Mat> frames = changing_sequence(kW, kH, 3);
  const std::string chain = "pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp layout=side-by-side-half";
  for (PixelFormat f : {PixelFormat::P010, PixelFormat::RGBA64}) {
    const auto on = output_bytes(with_adaptive(chain, true), f, frames);
    const auto off = output_bytes(with_adaptive(chain, false), f, frames);
    expect_same_bytes(on, off, format_name(f));
  }
}

// The output keeps the input's sample depth: an 8-bit output for 10-bit
// input (or the reverse) does not negotiate (the caps offer none).
TEST(DeepElements, OutputKeepsTheInputsDepth) {
  const std::string ok = run_to_eos(
      "videotestsrc num-buffers=2 ! video/x-raw,format=P010_10LE,width=64,height=48 ! pseudo3dconvert "
      "processing=cpu layout=side-by-side-half ! video/x-raw,format=I420_10LE ! fakesink");
  EXPECT_EQ(ok, "");
  for (const char *pair : {"P010_10LE ! pseudo3dconvert processing=cpu ! video/x-raw,format=NV12",
                           "NV12 ! pseudo3dconvert processing=cpu ! video/x-raw,format=P010_10LE"}) {
    const std::string err = run_to_eos(std::string("videotestsrc num-buffers=2 ! video/x-raw,width=64,height=48,format=") +
                                       pair + " ! fakesink");
    EXPECT_NE(err, "") << pair;
  }
}

// CUDA memory carries no RGBA64_LE (GStreamer 1.22's CUDA allocator aborts
// on it): no template of a stage offers it there, while system memory
// takes the deep formats. Without CUDA the templates have no CUDA
// structure, and this checks the system-memory side.
TEST(DeepElements, CudaMemoryTemplatesHaveNoRgba64) {
  for (const char *name : {"pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp", "pseudo3dpack"}) {
    GstElementFactory *factory = gst_element_factory_find(name);
    ASSERT_NE(factory, nullptr) << name;
    for (const GList *l = gst_element_factory_get_static_pad_templates(factory); l; l = l->next) {
      GstCaps *caps = gst_static_caps_get(&static_cast<GstStaticPadTemplate *>(l->data)->static_caps);
      bool system_deep = false;
      for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
        GstCaps *one = gst_caps_copy_nth(caps, i);
        GstCapsFeatures *features = gst_caps_get_features(caps, i);
        const bool cuda = features && gst_caps_features_contains(features, "memory:CUDAMemory");
        GstCaps *deep = gst_caps_from_string(cuda ? "video/x-raw, format=RGBA64_LE"
                                                  : "video/x-raw, format={ P010_10LE, I420_10LE, RGBA64_LE }");
        gst_caps_set_features(deep, 0, features ? gst_caps_features_copy(features) : nullptr);
        const bool has = gst_caps_can_intersect(one, deep);
        if (cuda) {
          gchar *text = gst_caps_to_string(one);
          EXPECT_FALSE(has) << name << ": " << text;
          g_free(text);
        }
        system_deep = system_deep || (!cuda && has);
        gst_caps_unref(deep);
        gst_caps_unref(one);
      }
      EXPECT_TRUE(system_deep) << name << ": system memory takes the deep formats";
      gst_caps_unref(caps);
    }
    gst_object_unref(factory);
  }
}

}  // namespace
