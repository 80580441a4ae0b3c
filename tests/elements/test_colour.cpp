// Colour signalling through the stages (gst/colour_caps.h): the transfer,
// primaries and HDR metadata of the input reach the output caps of every
// layout that keeps the picture's colours, in 4:2:0 and in R'G'B'; the
// input is not relabelled on its way in; an anaglyph of HDR input is
// refused with a message.
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

#include <string>

#include "element_helpers.h"

using namespace p3d::test;

namespace {

struct Signal {
  const char *colorimetry;
  GstVideoTransferFunction transfer;
  GstVideoColorPrimaries primaries;
};

const Signal kSignals[] = {
    {"bt2100-pq", GST_VIDEO_TRANSFER_SMPTE2084, GST_VIDEO_COLOR_PRIMARIES_BT2020},
    {"bt2100-hlg", GST_VIDEO_TRANSFER_ARIB_STD_B67, GST_VIDEO_COLOR_PRIMARIES_BT2020},
    {"bt2020", GST_VIDEO_TRANSFER_BT2020_12, GST_VIDEO_COLOR_PRIMARIES_BT2020},
    {"bt709", GST_VIDEO_TRANSFER_BT709, GST_VIDEO_COLOR_PRIMARIES_BT709},
};

const char kMastering[] = "34000:16000:13250:34500:7500:3000:15635:16450:10000000:1";
const char kLightLevel[] = "1000:400";

// A source of `frames` frames in `format` stating `colorimetry` and the HDR fields.
std::string hdr_source(const char *format, const char *colorimetry, int frames = 2) {
  return std::string("videotestsrc num-buffers=") + std::to_string(frames) + " pattern=smpte ! video/x-raw,format=" +
         format + ",width=64,height=48,framerate=25/1,colorimetry=" + colorimetry +
         ",mastering-display-info=(string)" + kMastering + ",content-light-level=(string)" + kLightLevel + " ! ";
}

// The current caps of a pad of an element anywhere inside `bin`.
GstCaps *caps_of(GstElement *bin, const char *element, const char *pad_name) {
  GstElement *e = gst_bin_get_by_name(GST_BIN(bin), element);
  if (!e) return nullptr;
  GstPad *pad = gst_element_get_static_pad(e, pad_name);
  GstCaps *caps = pad ? gst_pad_get_current_caps(pad) : nullptr;
  if (pad) gst_object_unref(pad);
  gst_object_unref(e);
  return caps;
}

// The output's colorimetry: the input's exactly in Y'CbCr; in R'G'B' its
// transfer and primaries with the RGB matrix and full range. The HDR
// fields are the input's.
void expect_signal_kept(GstCaps *caps, const Signal &s, const std::string &what) {
  ASSERT_NE(caps, nullptr) << what;
  GstVideoInfo info;
  ASSERT_TRUE(gst_video_info_from_caps(&info, caps)) << what;
  if (GST_VIDEO_INFO_IS_YUV(&info)) {
    gchar *text = gst_video_colorimetry_to_string(&info.colorimetry);
    EXPECT_STREQ(text, s.colorimetry) << what;
    g_free(text);
  } else {
    EXPECT_EQ(info.colorimetry.matrix, GST_VIDEO_COLOR_MATRIX_RGB) << what;
    EXPECT_EQ(info.colorimetry.range, GST_VIDEO_COLOR_RANGE_0_255) << what;
  }
  EXPECT_EQ(info.colorimetry.transfer, s.transfer) << what;
  EXPECT_EQ(info.colorimetry.primaries, s.primaries) << what;
  const GstStructure *st = gst_caps_get_structure(caps, 0);
  const gchar *mastering = gst_structure_get_string(st, "mastering-display-info");
  const gchar *light = gst_structure_get_string(st, "content-light-level");
  EXPECT_STREQ(mastering, kMastering) << what;
  EXPECT_STREQ(light, kLightLevel) << what;
}

}  // namespace

// Every signal, through the bin in two layouts and both output families,
// from 8 and 10 bits through videoconvert: the output states the input's
// colours, and the 2D input reaches the depth stage as it was. The input
// caps say nothing of multiview, as a decoder's do: such caps intersect
// the output's, which upstream must not be offered first (it would label
// 2D video as a pair and convert it to the output's colorimetry).
TEST(ColourCaps, EverySignalPassesTheBin) {
  for (const Signal &s : kSignals)
    for (const char *layout : {"side-by-side-half", "top-bottom"})
      for (const char *out : {"I420", "RGBA", "NV12"})
        for (const char *in : {"I420", "I420_10LE"}) {
          const std::string what = std::string(s.colorimetry) + " " + layout + " " + in + " to " + out;
          GstHarness *h = gst_harness_new_parse((std::string("videoconvert ! pseudo3dconvert processing=cpu layout=") +
                                                 layout + " ! capsfilter caps=video/x-raw,format=" + out)
                                                    .c_str());
          const std::string caps = std::string("video/x-raw,format=") + in +
                                   ",width=64,height=48,framerate=25/1,pixel-aspect-ratio=1/1,colorimetry=" +
                                   s.colorimetry + ",mastering-display-info=(string)" + kMastering +
                                   ",content-light-level=(string)" + kLightLevel;
          gst_harness_set_src_caps_str(h, caps.c_str());
          GstVideoInfo in_info;
          GstCaps *in_caps = gst_caps_from_string(caps.c_str());
          ASSERT_TRUE(gst_video_info_from_caps(&in_info, in_caps)) << what;
          gst_caps_unref(in_caps);
          GstBuffer *frame = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&in_info), nullptr);
          gst_buffer_memset(frame, 0, 0, GST_VIDEO_INFO_SIZE(&in_info));
          GstBuffer *result = gst_harness_push_and_pull(h, frame);
          EXPECT_NE(result, nullptr) << what;
          if (result) gst_buffer_unref(result);
          GstCaps *output = gst_pad_get_current_caps(h->sinkpad);
          expect_signal_kept(output, s, what + ": output");
          if (output) gst_caps_unref(output);
          GstCaps *depth_in = caps_of(h->element, "depth", "sink");
          EXPECT_NE(depth_in, nullptr) << what;
          GstVideoInfo info;
          if (depth_in && gst_video_info_from_caps(&info, depth_in)) {
            gchar *text = gst_video_colorimetry_to_string(&info.colorimetry);
            EXPECT_STREQ(text, s.colorimetry) << what << ": the depth stage's input";
            g_free(text);
            const GstVideoMultiviewMode mode = GST_VIDEO_INFO_MULTIVIEW_MODE(&info);
            EXPECT_TRUE(mode == GST_VIDEO_MULTIVIEW_MODE_NONE || mode == GST_VIDEO_MULTIVIEW_MODE_MONO)
                << what << ": 2D input relabelled as " << gst_video_multiview_mode_to_caps_string(mode);
          }
          if (depth_in) gst_caps_unref(depth_in);
          gst_harness_teardown(h);
        }
}

// pseudo3dpack writing 4:2:0 from an R'G'B' pair: the pair's transfer and
// primaries with the matrix of those primaries (bt2100-pq from PQ BT.2020).
TEST(ColourCaps, ThePackStatesThePairsColours) {
  for (const Signal &s : kSignals) {
    const std::string what = std::string(s.colorimetry) + " pair";
    const std::string launch =
        hdr_source("I420", s.colorimetry) +
        "pseudo3ddepth processing=cpu ! pseudo3dfilter processing=cpu ! pseudo3dwarp processing=cpu ! "
        "capsfilter caps=video/x-raw,format=RGBA ! pseudo3dpack processing=cpu layout=side-by-side-half ! "
        "capsfilter caps=video/x-raw,format=I420 ! fakesink name=sink";
    const std::string error = run_to_eos(launch, 60, [&](GstElement *pipeline) {
      GstCaps *output = caps_of(pipeline, "sink", "sink");
      expect_signal_kept(output, s, what);
      if (output) gst_caps_unref(output);
    });
    EXPECT_EQ(error, "") << what;
  }
}

// An anaglyph mixes the views' colours as SDR code values: HDR input
// (PQ, HLG) is refused by the bin, the warp and the pack with a message
// that says so and what to do; SDR BT.2020 is mixed.
TEST(ColourCaps, AnaglyphOfHdrIsRefusedWithAMessage) {
  const std::string warp_chain = "pseudo3ddepth processing=cpu ! pseudo3dfilter processing=cpu ! pseudo3dwarp processing=cpu";
  for (const Signal &s : kSignals) {
    const bool hdr = s.transfer == GST_VIDEO_TRANSFER_SMPTE2084 || s.transfer == GST_VIDEO_TRANSFER_ARIB_STD_B67;
    for (const std::string &chain :
         {std::string("pseudo3dconvert processing=cpu layout=anaglyph"), warp_chain + " layout=anaglyph",
          warp_chain + " ! pseudo3dpack processing=cpu layout=anaglyph"}) {
      const std::string what = std::string(s.colorimetry) + ": " + chain;
      const std::string error = run_to_eos(hdr_source("I420", s.colorimetry) + chain + " ! fakesink", 60);
      if (hdr) {
        EXPECT_NE(error.find("An anaglyph needs SDR video"), std::string::npos) << what << ": " << error;
        EXPECT_NE(error.find("choose another layout"), std::string::npos) << what << ": " << error;
      } else {
        EXPECT_EQ(error, "") << what;
      }
    }
  }
}

// An anaglyph asked for while PQ video plays: the value is refused with one
// warning that says why, the layout goes back to the one in force, and the
// stream goes on.
TEST(ColourCaps, AnaglyphAskedWhilePlayingHdrIsRefusedLive) {
  GstHarness *h = gst_harness_new_parse("pseudo3dconvert name=c processing=cpu layout=side-by-side-half");
  BusMessages bus(h->element);
  const std::string caps = std::string("video/x-raw,format=I420,width=64,height=48,framerate=25/1,colorimetry=bt2100-pq");
  gst_harness_set_src_caps_str(h, caps.c_str());
  GstVideoInfo info;
  GstCaps *c = gst_caps_from_string(caps.c_str());
  ASSERT_TRUE(gst_video_info_from_caps(&info, c));
  gst_caps_unref(c);
  auto push = [&]() {
    GstBuffer *frame = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&info), nullptr);
    gst_buffer_memset(frame, 0, 100, GST_VIDEO_INFO_SIZE(&info));
    return gst_harness_push_and_pull(h, frame);
  };
  GstBuffer *first = push();
  ASSERT_NE(first, nullptr);
  gst_buffer_unref(first);
  GstElement *bin = gst_bin_get_by_name(GST_BIN(h->element), "c");
  if (!bin) bin = GST_ELEMENT(gst_object_ref(h->element));
  gst_util_set_object_arg(G_OBJECT(bin), "layout", "anaglyph");
  GstBuffer *second = push();
  EXPECT_NE(second, nullptr) << "the stream goes on";
  if (second) gst_buffer_unref(second);
  const std::vector<std::string> warnings = bus.take(GST_MESSAGE_WARNING);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("An anaglyph needs SDR video"), std::string::npos) << warnings[0];
  EXPECT_TRUE(bus.take(GST_MESSAGE_ERROR).empty());
  gint layout = -1;
  g_object_get(bin, "layout", &layout, NULL);
  GEnumValue *v = g_enum_get_value(static_cast<GEnumClass *>(g_type_class_peek(G_PARAM_SPEC_VALUE_TYPE(
                                       g_object_class_find_property(G_OBJECT_GET_CLASS(bin), "layout")))),
                                   layout);
  EXPECT_STREQ(v ? v->value_nick : "", "side-by-side-half") << "the layout in force";
  GstCaps *out = gst_pad_get_current_caps(h->sinkpad);
  ASSERT_NE(out, nullptr);
  EXPECT_STREQ(gst_structure_get_string(gst_caps_get_structure(out, 0), "multiview-mode"), "side-by-side");
  gst_caps_unref(out);
  gst_object_unref(bin);
  gst_harness_teardown(h);
}

// Input that leaves its transfer and primaries unknown (jpegdec's 1:4:0:0)
// has nothing to carry: 4:2:0 output is labelled BT.709, as without the
// colour signalling, not "unknown".
TEST(ColourCaps, UnknownTransferAndPrimariesAreNotCarried) {
  GstHarness *h = gst_harness_new_parse(
      "pseudo3dconvert processing=cpu layout=side-by-side-half ! capsfilter caps=video/x-raw,format=I420");
  gst_harness_set_src_caps_str(h, "video/x-raw,format=I420,width=64,height=48,framerate=25/1,colorimetry=1:4:0:0");
  GstVideoInfo info;
  gst_video_info_set_format(&info, GST_VIDEO_FORMAT_I420, 64, 48);
  GstBuffer *frame = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&info), nullptr);
  gst_buffer_memset(frame, 0, 90, GST_VIDEO_INFO_SIZE(&info));
  GstBuffer *out = gst_harness_push_and_pull(h, frame);
  ASSERT_NE(out, nullptr);
  gst_buffer_unref(out);
  GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
  ASSERT_NE(caps, nullptr);
  EXPECT_STREQ(gst_structure_get_string(gst_caps_get_structure(caps, 0), "colorimetry"), "bt709");
  gst_caps_unref(caps);
  gst_harness_teardown(h);
}
