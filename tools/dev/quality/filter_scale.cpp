// The cross-bilateral filter on a coarser grid (BilateralParams::scale,
// common/bilateral.h) against every pixel's filter, where it matters: at 4K
// and 8K, whose automatic step is 4. No stereo pair with ground
// truth that large ships with the test data, so Aloe stands in for them
// enlarged 2x (2564 x 2220, automatic step 4, the estimator's automatic
// block 4 as at 4K) and 4x (5128 x 4440, step 4, block 8 as at 8K): both
// views bicubic, the ground-truth depth nearest, the disparity the same
// share of the width. As shipped (1282 x 1110) the automatic step is 1; the
// coarser steps there show what forcing them costs. For every size and
// step, with the element's other defaults (separable, radius 5, sigma 3 and
// 12, background-smooth fill):
//   - view synthesis: the ground-truth depth filtered, the right view
//     rendered, PSNR and SSIM against aloeR (the synthesis study's measure);
//   - depth rank: the estimator's depth filtered, Spearman's rho against
//     aloeGT over depth_rank.cpp's sample, read at each sampled pixel's
//     first pixel of the enlarged picture;
//   - the filtered map's difference from step 1 (depth units) and the CPU
//     filter's time.
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "metrics.h"
#include "quality.h"

namespace p3d::quality {
namespace {

// Aloe enlarged `factor` times: what render_right and the studies here read
// (the views, the RGBA frame, the ground-truth depth, the warp), not the
// ground truth in pixels, whose disparities would overflow 8 bits.
Aloe enlarged(const Aloe &a, int factor) {
  if (factor == 1) return a;
  Aloe e;
  e.scale = factor;
  const cv::Size size(a.left.cols * factor, a.left.rows * factor);
  cv::resize(a.left, e.left, size, 0, 0, cv::INTER_CUBIC);
  cv::resize(a.right, e.right, size, 0, 0, cv::INTER_CUBIC);
  cv::resize(a.gt_depth, e.gt_depth, size, 0, 0, cv::INTER_NEAREST);
  e.left_frame = HostFrame::from_bgr(e.left, PixelFormat::RGBA);
  e.max_gt = a.max_gt * factor;
  e.warp = a.warp;  // max-disparity is a share of the width: the same
  return e;
}

// The depth map at the shipped picture's sampled pixels (indices into the
// 1x picture) of a map `factor` times larger.
std::vector<double> sampled(const cv::Mat &depth, const std::vector<int> &sample, int width_1x, int factor) {
  std::vector<double> v(sample.size());
  for (size_t i = 0; i < sample.size(); ++i) {
    const int x = sample[i] % width_1x, y = sample[i] / width_1x;
    v[i] = depth.at<float>(y * factor, x * factor);
  }
  return v;
}

}  // namespace

void measure_filter_scale(Writer &w, const Aloe &a, int runs) {
  const std::vector<int> sample = rank_sample(a.gt);
  std::vector<double> gt_values(sample.size());
  for (size_t i = 0; i < sample.size(); ++i) gt_values[i] = a.gt.ptr<uint8_t>()[sample[i]];
  for (const int factor : {1, 2, 4}) {
    const Aloe e = enlarged(a, factor);
    const FrameView guide = e.left_frame.view();
    const cv::Mat estimated = estimated_depth(DepthParams(), guide);
    const int automatic = bilateral_auto_scale(e.left.cols, e.left.rows);
    const std::vector<int> steps = {1, 2, 3, 4};
    std::vector<cv::Mat> gt_filtered(steps.size()), est_filtered(steps.size());
    std::vector<std::function<void()>> jobs;
    for (size_t k = 0; k < steps.size(); ++k)
      jobs.push_back([&, k] {
        BilateralParams p = default_filter_params();
        p.scale = steps[k];
        gt_filtered[k] = filter_depth(p, guide, e.gt_depth);
        est_filtered[k] = filter_depth(p, guide, estimated);
      });
    const std::vector<Timing> t = time_interleaved(runs, jobs);  // both maps: twice one filter's time
    HostFrame out(PixelFormat::BGRA, 2 * e.left.cols, e.left.rows);
    for (size_t k = 0; k < steps.size(); ++k) {
      render_right(e, gt_filtered[k], HoleFill::BackgroundSmooth, out);
      const cv::Mat synth = right_half_bgr(out);
      const double rho = spearman(sampled(est_filtered[k], sample, a.left.cols, factor), gt_values);
      const MapError gt_err = map_error(gt_filtered[0], gt_filtered[k]);
      const MapError est_err = map_error(est_filtered[0], est_filtered[k]);
      const double filter_ms = t[k].median_ms() / 2;
      JsonLine j;
      j.str("kind", "filter_scale").integer("enlarged", factor).integer("width", e.left.cols);
      j.integer("height", e.left.rows).integer("scale", steps[k]).integer("automatic_scale", automatic);
      j.integer("block_size", effective_block_size(DepthParams(), e.left.cols, e.left.rows));
      j.num("synth_psnr", psnr(synth, e.right)).num("synth_ssim", ssim(synth, e.right)).num("spearman", rho);
      j.num("gt_mean_abs_vs_scale1", gt_err.mean_abs).num("gt_max_abs_vs_scale1", gt_err.max_abs);
      j.num("estimated_mean_abs_vs_scale1", est_err.mean_abs);
      j.num("estimated_max_abs_vs_scale1", est_err.max_abs);
      j.num("filter_ms", filter_ms).num("filter_min_ms", t[k].min_ms() / 2);
      w.emit(j);
      std::printf("scale      %4dx%-4d step %d%s  PSNR %6.2f dB  SSIM %.4f  rho %+.4f  |d| mean %.5f  %8.1f ms\n",
                  e.left.cols, e.left.rows, steps[k], steps[k] == automatic ? " (auto)" : "       ",
                  psnr(synth, e.right), ssim(synth, e.right), rho, gt_err.mean_abs, filter_ms);
      std::fflush(stdout);
    }
  }
}

}  // namespace p3d::quality
