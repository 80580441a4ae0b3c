// Real stereo data: Middlebury "Aloe" (from Debian's opencv-doc). The right
// view is synthesized from the left view plus its ground-truth disparity
// through the elements (RGBD input, view=right, convergence=0,
// max-disparity = 100 * max(GT) / width) and compared with the real right
// view. Floors are measured values less a margin (docs/quality.md).
#include <gtest/gtest.h>

#include <gst/check/gstharness.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "element_helpers.h"
#include "metrics.h"
#include "test_data.h"

using namespace p3d;
using namespace p3d::test;

namespace {

struct AloeResult {
  double psnr = 0, ssim = 0, baseline_psnr = 0;
};

// Aloe's views and its ground truth as depth: grey, normalised so that
// depth 1 = the largest disparity; cropped to an even width (YUV halves).
struct AloeData {
  cv::Mat left, right, grey;
  int w = 0, h = 0;
  float max_disp = 0;
  bool ok() const { return !left.empty(); }
};

AloeData load_aloe() {
  AloeData d;
  const cv::Mat left = load_data_image("aloeL.jpg"), right = load_data_image("aloeR.jpg");
  const cv::Mat gt = load_data_image("aloeGT.png");
  if (left.empty() || right.empty() || gt.empty()) return d;
  cv::Mat gt8;
  if (gt.channels() > 1)
    cv::cvtColor(gt, gt8, cv::COLOR_BGR2GRAY);
  else
    gt8 = gt;
  double max_gt = 0;
  cv::minMaxLoc(gt8, nullptr, &max_gt);
  d.w = left.cols & ~1;
  d.h = left.rows;
  const cv::Rect crop(0, 0, d.w, d.h);
  gt8(crop).convertTo(d.grey, CV_8U, 255.0 / max_gt);
  d.left = left(crop).clone();
  d.right = right(crop).clone();
  d.max_disp = static_cast<float>(100.0 * max_gt / d.w);
  return d;
}

std::string warp_to_right(const AloeData &d, const char *fill) {
  return "pseudo3dwarp view=right convergence=0 max-disparity=" + std::to_string(d.max_disp) + " fill=" + fill +
         " ! pseudo3dpack layout=right ! capsfilter caps=video/x-raw,format=BGRA";
}

// Scores the synthesized view `out` (BGRA buffer) against the real right view.
AloeResult score(const AloeData &d, GstBuffer *out, GstPad *sinkpad, const std::string &name) {
  AloeResult r;
  GstCaps *caps = gst_pad_get_current_caps(sinkpad);
  cv::Mat synth_bgra = buffer_to_bgra(out, caps), synth;
  gst_caps_unref(caps);
  cv::cvtColor(synth_bgra, synth, cv::COLOR_BGRA2BGR);
  r.psnr = psnr(synth, d.right);
  r.ssim = ssim(synth, d.right);
  r.baseline_psnr = psnr(d.left, d.right);
  cv::imwrite(output_dir() + "/aloe-right-" + name + ".png", synth);
  return r;
}

AloeResult synthesize_right(const char *fill, PixelFormat fmt) {
  const AloeData d = load_aloe();
  if (!d.ok()) return AloeResult();
  cv::Mat grey_bgr, rgbd;
  cv::cvtColor(d.grey, grey_bgr, cv::COLOR_GRAY2BGR);
  cv::hconcat(d.left, grey_bgr, rgbd);
  GstHarness *hx = gst_harness_new_parse(("pseudo3ddepth method=rgbd ! " + warp_to_right(d, fill)).c_str());
  gst_harness_set_src_caps_str(hx, raw_caps(fmt, 2 * d.w, d.h).c_str());
  GstBuffer *out = gst_harness_push_and_pull(hx, buffer_from_frame(HostFrame::from_bgr(rgbd, fmt)));
  AloeResult r;
  if (out) {
    r = score(d, out, hx->sinkpad, std::string(fill) + "-" + format_name(fmt));
    gst_buffer_unref(out);
  } else {
    ADD_FAILURE() << "no output";
  }
  gst_harness_teardown(hx);
  return r;
}

// The same view with the ground truth brought in as a depth picture through
// pseudo3ddepthmux (GRAY8, white = near), `scale` times the frame's size
// (INTER_AREA, as a picture is made smaller), with `stages` between the mux
// and the warp.
AloeResult synthesize_right_external(const char *fill, double scale, const std::string &stages) {
  const AloeData d = load_aloe();
  if (!d.ok()) return AloeResult();
  cv::Mat depth = d.grey;
  if (scale != 1.0) cv::resize(d.grey, depth, cv::Size(), scale, scale, cv::INTER_AREA);
  GstElement *bin = gst_parse_bin_from_description(
      ("pseudo3ddepthmux name=m " + stages + warp_to_right(d, fill)).c_str(), FALSE, nullptr);
  GstElement *mux = gst_bin_get_by_name(GST_BIN(bin), "m");
  GstPad *video = gst_element_get_static_pad(mux, "video"), *depth_pad = gst_element_get_static_pad(mux, "depth");
  gst_element_add_pad(bin, gst_ghost_pad_new("video", video));
  gst_element_add_pad(bin, gst_ghost_pad_new("depth", depth_pad));
  GstPad *last = gst_bin_find_unlinked_pad(GST_BIN(bin), GST_PAD_SRC);
  gst_element_add_pad(bin, gst_ghost_pad_new("src", last));
  gst_object_unref(last);
  gst_object_unref(video);
  gst_object_unref(depth_pad);
  gst_object_unref(mux);
  GstHarness *hv = gst_harness_new_with_element(bin, "video", "src");
  GstHarness *hd = gst_harness_new_with_element(bin, "depth", nullptr);
  gst_harness_set_src_caps_str(hv, raw_caps(PixelFormat::RGBA, d.w, d.h).c_str());
  gst_harness_set_src_caps_str(hd, grey_caps(depth).c_str());
  gst_harness_push(hd, buffer_from_grey(depth));
  gst_harness_push_event(hd, gst_event_new_eos());
  GstBuffer *out = gst_harness_push_and_pull(hv, buffer_from_frame(HostFrame::from_bgr(d.left, PixelFormat::RGBA)));
  AloeResult r;
  if (out) {
    r = score(d, out, hv->sinkpad, std::string("depthmux-") + fill + (scale != 1.0 ? "-half" : ""));
    gst_buffer_unref(out);
  } else {
    ADD_FAILURE() << "no output";
  }
  gst_harness_teardown(hd);
  gst_harness_teardown(hv);
  gst_object_unref(bin);
  return r;
}


// The fill a fresh element starts with, by its nick.
std::string default_fill(const char *factory) {
  GstElement *e = gst_element_factory_make(factory, nullptr);
  if (!e) return "no " + std::string(factory);
  GParamSpec *spec = g_object_class_find_property(G_OBJECT_GET_CLASS(e), "fill");
  gint value = -1;
  g_object_get(e, "fill", &value, nullptr);
  const GEnumValue *v = spec ? g_enum_get_value(G_PARAM_SPEC_ENUM(spec)->enum_class, value) : nullptr;
  const std::string nick = v ? v->value_nick : "?";
  gst_object_unref(e);
  return nick;
}

}  // namespace

// The default fill (background-smooth): the synthesized
// right view must be far closer to the real one than the left view itself
// is (the no-warp baseline).
TEST(Aloe, SynthesizedRightViewMatchesRealRightView) {
  EXPECT_EQ(default_fill("pseudo3dwarp"), "background-smooth");
  EXPECT_EQ(default_fill("pseudo3dconvert"), "background-smooth");
  const AloeResult r = synthesize_right("background-smooth", PixelFormat::RGBA);
  RecordProperty("psnr_db", std::to_string(r.psnr));
  RecordProperty("ssim", std::to_string(r.ssim));
  RecordProperty("baseline_psnr_db", std::to_string(r.baseline_psnr));
  std::printf("Aloe right view: PSNR %.2f dB, SSIM %.4f (left view as is: PSNR %.2f dB)\n", r.psnr, r.ssim,
              r.baseline_psnr);
  // Measured (CPU, docs/quality.md): 24.54 dB, SSIM 0.804, baseline 14.96 dB.
  // What is left is disocclusions, the right border (content the left view
  // never saw) and pixels whose ground truth is unknown (0). SSIM: even the
  // real right view blurred (sigma 4) in the holes scores 0.823, so no
  // smooth fill reaches 0.83, and none of OpenCV's inpainting methods
  // (Telea, Navier-Stokes, shift-map, FSR) passes 0.803 in the same holes
  // (docs/quality.md).
  EXPECT_GE(r.psnr, 24.5);
  EXPECT_GT(r.psnr, r.baseline_psnr + 9.0);
  EXPECT_GE(r.ssim, 0.803);
}

// The other fills and a YUV input stay in their quality bands.
TEST(Aloe, OtherFillsAndYuvInput) {
  const AloeResult bg = synthesize_right("background", PixelFormat::RGBA);
  const AloeResult na = synthesize_right("neighbor-average", PixelFormat::RGBA);
  const AloeResult yuv = synthesize_right("background-smooth", PixelFormat::I420);
  std::printf("Aloe: background PSNR %.2f dB SSIM %.4f; neighbor-average PSNR %.2f dB SSIM %.4f; I420 input PSNR "
              "%.2f dB SSIM %.4f\n",
              bg.psnr, bg.ssim, na.psnr, na.ssim, yuv.psnr, yuv.ssim);
  // Measured: 22.97 dB / 0.790, 22.91 dB / 0.800, I420 24.43 dB / 0.797.
  EXPECT_GT(bg.psnr, 22.5);
  EXPECT_GT(bg.ssim, 0.77);
  EXPECT_GT(na.psnr, 22.5);
  EXPECT_GT(na.ssim, 0.77);
  EXPECT_GT(yuv.psnr, 24.3);  // 4:2:0 chroma and a colour round trip cost a little
  EXPECT_GT(yuv.ssim, 0.79);
}

// External depth (pseudo3ddepthmux): the ground truth as a grey picture
// scores as it does through the RGBD input; from a half-size picture
// (nearest-sample upsampling) it keeps at least 24.0 dB. Measured
// (docs/quality.md): 24.54 dB as RGBD; half size 24.20 dB / 0.793, and
// 23.43 dB with pseudo3dfilter's defaults after the mux (its smoothing
// costs more than its edge alignment gains on a true depth).
TEST(Aloe, ExternalDepthThroughDepthMux) {
  const AloeResult rgbd = synthesize_right("background-smooth", PixelFormat::RGBA);
  const AloeResult full = synthesize_right_external("background-smooth", 1.0, "! ");
  const AloeResult half = synthesize_right_external("background-smooth", 0.5, "! ");
  const AloeResult half_filtered = synthesize_right_external("background-smooth", 0.5, "! pseudo3dfilter ! ");
  std::printf("Aloe through pseudo3ddepthmux: full size PSNR %.2f dB SSIM %.4f (RGBD input %.2f dB); half size "
              "%.2f dB / %.4f, with pseudo3dfilter %.2f dB / %.4f\n",
              full.psnr, full.ssim, rgbd.psnr, half.psnr, half.ssim, half_filtered.psnr, half_filtered.ssim);
  EXPECT_NEAR(full.psnr, rgbd.psnr, 0.01);
  EXPECT_NEAR(full.ssim, rgbd.ssim, 0.001);
  EXPECT_GE(half.psnr, 24.0);
  EXPECT_GT(half_filtered.psnr, 23.0);
}
