// View synthesis on Aloe: the right view rendered from aloeL plus its
// ground-truth disparity, as tests/elements/test_aloe.cpp does (depth =
// GT / max(GT), view=right, convergence 0, max-disparity = 100 max(GT) / W),
// for every hole fill and with the depth as is or cross-bilateral filtered
// (guide aloeL): PSNR and SSIM against aloeR, PSNR over the warp's holes
// alone, and the time of filter + warp. Plus what fills cannot beat: the
// holes given aloeR itself, sharp or blurred (kind synthesis_bound).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>

#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>
#include <opencv2/xphoto/inpainting.hpp>

#include "metrics.h"
#include "quality.h"

namespace p3d::quality {

void measure_baseline(Writer &w, const Aloe &a) {
  JsonLine j;
  j.str("kind", "baseline").str("what", "left view as is");
  j.num("psnr", psnr(a.left, a.right)).num("ssim", ssim(a.left, a.right));
  j.num("psnr_masked", psnr(a.left, a.right, a.mask));
  w.emit(j);
}

namespace {

struct SynthCase {
  int radius;
  HoleFill fill;
};

// The warp's holes (CV_8UC1): the pixels fill=none paints kHoleColour. The
// count is checked against the warp's own, so a magenta source pixel cannot
// pass for a hole unnoticed.
cv::Mat hole_mask(const Aloe &a, const cv::Mat &depth, HostFrame &out) {
  const long long holes = render_right(a, depth, HoleFill::None, out);
  const cv::Mat view = right_half_bgr(out);
  cv::Mat mask;
  cv::inRange(view, cv::Scalar(kHoleColour.b, kHoleColour.g, kHoleColour.r),
              cv::Scalar(kHoleColour.b, kHoleColour.g, kHoleColour.r), mask);
  CV_Assert(cv::countNonZero(mask) == holes);
  return mask;
}

// The bounds: the GT warp's holes (depth as is) filled with aloeR itself,
// sharp and Gaussian-blurred. A fill sees nothing of aloeR, so a smooth fill
// scores at best about the blurred rows; SSIM rewards only detail that
// matches the real view.
void measure_bounds(Writer &w, const Aloe &a) {
  HostFrame out(PixelFormat::BGRA, 2 * a.left.cols, a.left.rows);
  const cv::Mat holes = hole_mask(a, a.gt_depth, out);
  render_right(a, a.gt_depth, HoleFill::None, out);
  const cv::Mat view = right_half_bgr(out);
  for (const double sigma : {0.0, 2.0, 4.0, 8.0, 16.0}) {
    cv::Mat truth = a.right.clone();
    if (sigma > 0) cv::GaussianBlur(a.right, truth, cv::Size(), sigma);
    cv::Mat synth = view.clone();
    truth.copyTo(synth, holes);
    JsonLine j;
    j.str("kind", "synthesis_bound").num("blur_sigma", sigma);
    j.num("psnr", psnr(synth, a.right)).num("ssim", ssim(synth, a.right)).num("psnr_holes", psnr(synth, a.right, holes));
    w.emit(j);
    std::printf("bound      aloeR in the holes, blur sigma %4.1f  PSNR %6.2f dB  SSIM %.4f\n", sigma,
                psnr(synth, a.right), ssim(synth, a.right));
  }
}

}  // namespace

// Peers' inpainting on the same holes (the GT warp, depth as is): what the
// issue's peers and OpenCV's best single-image inpainting reach with this
// warp, at any cost. Each runs once (they take up to minutes on the CPU).
void measure_peer_fills(Writer &w, const Aloe &a) {
  HostFrame out(PixelFormat::BGRA, 2 * a.left.cols, a.left.rows);
  const cv::Mat holes = hole_mask(a, a.gt_depth, out);
  render_right(a, a.gt_depth, HoleFill::None, out);
  const cv::Mat view = right_half_bgr(out);
  cv::Mat valid;
  cv::bitwise_not(holes, valid);  // xphoto::inpaint marks the known pixels
  struct Peer {
    const char *name;
    std::function<void(cv::Mat &)> fill;
  };
  const std::vector<Peer> peers = {
      {"opencv-telea-r3", [&](cv::Mat &d) { cv::inpaint(view, holes, d, 3, cv::INPAINT_TELEA); }},
      {"opencv-ns-r3", [&](cv::Mat &d) { cv::inpaint(view, holes, d, 3, cv::INPAINT_NS); }},
      {"xphoto-shiftmap",
       [&](cv::Mat &d) {
         // Shift-map expects a Lab-like space (intensity first).
         cv::Mat lab, filled;
         cv::cvtColor(view, lab, cv::COLOR_BGR2Lab);
         cv::xphoto::inpaint(lab, valid, filled, cv::xphoto::INPAINT_SHIFTMAP);
         cv::cvtColor(filled, d, cv::COLOR_Lab2BGR);
         view.copyTo(d, valid);
       }},
      {"xphoto-fsr-fast", [&](cv::Mat &d) { cv::xphoto::inpaint(view, valid, d, cv::xphoto::INPAINT_FSR_FAST); }},
      {"xphoto-fsr-best", [&](cv::Mat &d) { cv::xphoto::inpaint(view, valid, d, cv::xphoto::INPAINT_FSR_BEST); }},
  };
  for (const Peer &p : peers) {
    cv::Mat synth;
    const auto t0 = std::chrono::steady_clock::now();
    p.fill(synth);
    const double ms = elapsed_ms(t0);
    JsonLine j;
    j.str("kind", "synthesis_peer").str("method", p.name);
    j.num("psnr", psnr(synth, a.right)).num("ssim", ssim(synth, a.right)).num("psnr_holes", psnr(synth, a.right, holes));
    j.num("time_ms", ms);
    w.emit(j);
    std::printf("peer       %-16s  PSNR %6.2f dB  SSIM %.4f  holes %6.2f dB  %10.1f ms\n", p.name,
                psnr(synth, a.right), ssim(synth, a.right), psnr(synth, a.right, holes), ms);
    std::fflush(stdout);
  }
}

void measure_synthesis(Writer &w, const Aloe &a, int runs) {
  const std::vector<int> radii = {0, 2, 5, 10};  // 0: the GT depth as is
  const std::vector<HoleFill> fills = {HoleFill::BackgroundSmooth, HoleFill::Background, HoleFill::NeighborAverage,
                                       HoleFill::None};
  std::vector<SynthCase> cases;
  for (const int radius : radii)
    for (const HoleFill fill : fills) cases.push_back({radius, fill});
  HostFrame out(PixelFormat::BGRA, 2 * a.left.cols, a.left.rows);
  // The filter and the warp are timed apart (their sum is the case's time);
  // one filter run per radius and round serves every fill.
  std::vector<cv::Mat> filtered(radii.size());
  std::vector<std::function<void()>> filter_jobs, warp_jobs;
  for (size_t r = 0; r < radii.size(); ++r)
    filter_jobs.push_back([&, r] {
      filtered[r] = radii[r] > 0 ? filter_depth(study_filter(radii[r]), a.left_frame.view(), a.gt_depth) : a.gt_depth;
    });
  const std::vector<Timing> filter_t = time_interleaved(runs, filter_jobs);
  auto radius_index = [&radii](int radius) {
    return static_cast<size_t>(std::find(radii.begin(), radii.end(), radius) - radii.begin());
  };
  for (const SynthCase &c : cases)
    warp_jobs.push_back([&, c] { render_right(a, filtered[radius_index(c.radius)], c.fill, out); });
  const std::vector<Timing> warp_t = time_interleaved(runs, warp_jobs);

  const double mask_fraction = static_cast<double>(cv::countNonZero(a.mask)) / static_cast<double>(a.mask.total());
  std::vector<cv::Mat> holes(radii.size());
  for (size_t r = 0; r < radii.size(); ++r) holes[r] = hole_mask(a, filtered[r], out);
  for (size_t i = 0; i < cases.size(); ++i) {
    const SynthCase &c = cases[i];
    const size_t r = radius_index(c.radius);
    const BilateralParams bp = study_filter(c.radius);
    const long long n_holes = render_right(a, filtered[r], c.fill, out);
    const cv::Mat synth = right_half_bgr(out);
    const double full = psnr(synth, a.right), structural = ssim(synth, a.right);
    const double masked = psnr(synth, a.right, a.mask), in_holes = psnr(synth, a.right, holes[r]);
    const double filter_ms = c.radius > 0 ? filter_t[r].median_ms() : 0.0;
    const double filter_min = c.radius > 0 ? filter_t[r].min_ms() : 0.0;
    JsonLine j;
    j.str("kind", "synthesis").str("fill", fill_name(c.fill)).integer("radius", c.radius);
    j.num("sigma_space", c.radius > 0 ? bp.sigma_space : 0.0).num("sigma_range", c.radius > 0 ? bp.sigma_range : 0.0);
    j.integer("width", a.left.cols).integer("height", a.left.rows).num("max_disparity_percent", a.warp.max_disparity);
    j.num("psnr", full).num("ssim", structural).num("psnr_masked", masked).num("mask_fraction", mask_fraction);
    j.num("psnr_holes", in_holes);
    j.num("hole_fraction", static_cast<double>(n_holes) / static_cast<double>(a.mask.total()));
    j.num("time_ms", filter_ms + warp_t[i].median_ms()).num("min_ms", filter_min + warp_t[i].min_ms());
    j.num("filter_ms", filter_ms).num("warp_ms", warp_t[i].median_ms());
    w.emit(j);
    std::printf("synthesis  fill %-17s radius %2d  PSNR %6.2f dB  SSIM %.4f  masked %6.2f dB  holes %6.2f dB  %8.1f ms\n",
                fill_name(c.fill), c.radius, full, structural, masked, in_holes, filter_ms + warp_t[i].median_ms());
    std::fflush(stdout);
  }
  measure_bounds(w, a);
}

}  // namespace p3d::quality
