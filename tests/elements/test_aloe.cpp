// Real stereo data: Middlebury "Aloe" (from Debian's opencv-doc). The right
// view is synthesized from the left view plus its ground-truth disparity
// through the elements (RGBD input, view=right, convergence=0,
// max-disparity = 100 * max(GT) / width) and compared with the real right
// view. Floors are measured values less a margin (README, "Quality").
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

AloeResult synthesize_right(const char *fill, PixelFormat fmt) {
  AloeResult r;
  const cv::Mat left = load_data_image("aloeL.jpg"), right = load_data_image("aloeR.jpg");
  const cv::Mat gt = load_data_image("aloeGT.png");
  if (left.empty() || right.empty() || gt.empty()) return r;
  cv::Mat gt8;
  if (gt.channels() > 1)
    cv::cvtColor(gt, gt8, cv::COLOR_BGR2GRAY);
  else
    gt8 = gt;
  double max_gt = 0;
  cv::minMaxLoc(gt8, nullptr, &max_gt);
  // Depth as grey, normalised so that depth 1 = max disparity.
  cv::Mat grey;
  gt8.convertTo(grey, CV_8U, 255.0 / max_gt);
  cv::Mat grey_bgr;
  cv::cvtColor(grey, grey_bgr, cv::COLOR_GRAY2BGR);
  // YUV halves must be even: crop to an even width.
  const int w = left.cols & ~1, h = left.rows;
  cv::Mat rgbd;
  cv::hconcat(left(cv::Rect(0, 0, w, h)), grey_bgr(cv::Rect(0, 0, w, h)), rgbd);
  const float max_disp = static_cast<float>(100.0 * max_gt / w);

  const std::string launch = "pseudo3ddepth method=rgbd ! pseudo3dwarp view=right convergence=0 max-disparity=" +
                             std::to_string(max_disp) + " fill=" + fill +
                             " ! pseudo3dpack layout=right ! capsfilter caps=video/x-raw,format=BGRA";
  GstHarness *hx = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(hx, raw_caps(fmt, 2 * w, h).c_str());
  GstBuffer *out = gst_harness_push_and_pull(hx, buffer_from_frame(HostFrame::from_bgr(rgbd, fmt)));
  if (!out) {
    ADD_FAILURE() << "no output";
    gst_harness_teardown(hx);
    return r;
  }
  GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
  cv::Mat synth_bgra = buffer_to_bgra(out, caps), synth;
  cv::cvtColor(synth_bgra, synth, cv::COLOR_BGRA2BGR);
  const cv::Mat ref = right(cv::Rect(0, 0, w, h)), src = left(cv::Rect(0, 0, w, h));
  r.psnr = psnr(synth, ref);
  r.ssim = ssim(synth, ref);
  r.baseline_psnr = psnr(src, ref);
  cv::imwrite(output_dir() + "/aloe-right-" + fill + "-" + format_name(fmt) + ".png", synth);
  gst_caps_unref(caps);
  gst_buffer_unref(out);
  gst_harness_teardown(hx);
  return r;
}

}  // namespace

// The best fill (background-smooth): the synthesized right view must be
// far closer to the real one than the left view itself is (the no-warp
// baseline).
TEST(Aloe, SynthesizedRightViewMatchesRealRightView) {
  const AloeResult r = synthesize_right("background-smooth", PixelFormat::RGBA);
  RecordProperty("psnr_db", std::to_string(r.psnr));
  RecordProperty("ssim", std::to_string(r.ssim));
  RecordProperty("baseline_psnr_db", std::to_string(r.baseline_psnr));
  std::printf("Aloe right view: PSNR %.2f dB, SSIM %.4f (left view as is: PSNR %.2f dB)\n", r.psnr, r.ssim,
              r.baseline_psnr);
  // Measured (2026-11-22, CPU): 24.56 dB, SSIM 0.805, baseline 14.96 dB.
  // What is left is disocclusions, the right border (content the left view
  // never saw) and pixels whose ground truth is unknown (0). SSIM: even the
  // real right view blurred (sigma 4) in the holes scores 0.823, so no
  // smooth fill reaches 0.83 (docs/quality.md).
  EXPECT_GE(r.psnr, 24.5);
  EXPECT_GT(r.psnr, r.baseline_psnr + 9.0);
  EXPECT_GT(r.ssim, 0.80);
}

// The other fills and a YUV input stay in their quality bands.
TEST(Aloe, OtherFillsAndYuvInput) {
  const AloeResult bg = synthesize_right("background", PixelFormat::RGBA);
  const AloeResult na = synthesize_right("neighbor-average", PixelFormat::RGBA);
  const AloeResult yuv = synthesize_right("background-smooth", PixelFormat::I420);
  std::printf("Aloe: background PSNR %.2f dB SSIM %.4f; neighbor-average PSNR %.2f dB SSIM %.4f; I420 input PSNR "
              "%.2f dB SSIM %.4f\n",
              bg.psnr, bg.ssim, na.psnr, na.ssim, yuv.psnr, yuv.ssim);
  // Measured: 22.97 dB / 0.790, 22.91 dB / 0.800, I420 24.45 dB / 0.798.
  EXPECT_GT(bg.psnr, 22.5);
  EXPECT_GT(bg.ssim, 0.77);
  EXPECT_GT(na.psnr, 22.5);
  EXPECT_GT(na.ssim, 0.77);
  EXPECT_GT(yuv.psnr, 24.3);  // 4:2:0 chroma and a colour round trip cost a little
  EXPECT_GT(yuv.ssim, 0.79);
}
