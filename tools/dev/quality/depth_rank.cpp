// The single-picture depth estimate against Aloe's ground truth:
// DepthEstimatorCpu + the element's default filter on aloeL, Spearman rank
// correlation with aloeGT over a fixed random sample of known-GT pixels, at
// full and at half size. One case per cue setting, each moving one parameter
// away from the defaults (and the defaults before the ground-contact cue), so
// every cue's effect reads off one table.
#include <algorithm>
#include <cstdio>
#include <limits>
#include <random>

#include "quality.h"

namespace p3d::quality {
namespace {

constexpr uint32_t kSampleSeed = 20261121u;  // fixed: the subsample is the same in every run
constexpr int kRankSamples = 50000;

}  // namespace

// kRankSamples known-GT pixel indices drawn without replacement by a partial
// Fisher-Yates shuffle on mt19937 (whose output the standard fixes), so every
// build draws the same sample.
std::vector<int> rank_sample(const cv::Mat &gt) {
  std::vector<int> known;
  for (int y = 0; y < gt.rows; ++y)
    for (int x = 0; x < gt.cols; ++x)
      if (gt.ptr<uint8_t>(y)[x] > 0) known.push_back(y * gt.cols + x);
  std::mt19937 rng(kSampleSeed);
  const size_t n = std::min(known.size(), static_cast<size_t>(kRankSamples));
  for (size_t i = 0; i < n; ++i) {
    const size_t j = i + static_cast<size_t>(rng()) % (known.size() - i);
    std::swap(known[i], known[j]);
  }
  known.resize(n);
  return known;
}

namespace {

const char *pixel_format_name(PixelFormat f) {
  return f == PixelFormat::I420 ? "I420" : f == PixelFormat::NV12 ? "NV12" : "RGBA";
}

struct RankCase {
  const char *cue;  // what this case changes: "defaults", "no ground contact", a parameter name
  DepthParams depth;
  int radius;  // 0: no filter
  PixelFormat format = PixelFormat::RGBA;  // how the picture reaches the estimator and the filter
};

std::vector<RankCase> rank_cases() {
  std::vector<RankCase> cases;
  cases.push_back({"defaults", DepthParams(), 5});
  // Without the ground-contact cue, with 4-pixel blocks and region weight 0.75.
  RankCase previous{"no ground contact", DepthParams(), 5};
  previous.depth.block_size = 4;
  previous.depth.ground_contact = 0.f;
  previous.depth.region_weight = 0.75f;
  cases.push_back(previous);
  for (const Hypothesis h : {Hypothesis::LeftRight, Hypothesis::CenterNear, Hypothesis::Flat}) {
    RankCase c{"hypothesis", DepthParams(), 5};
    c.depth.hypothesis = h;
    cases.push_back(c);
  }
  cases.push_back({"filter_radius", DepthParams(), 0});
  for (const float g : {0.f, 0.5f, 0.75f}) {
    RankCase c{"ground_contact", DepthParams(), 5};
    c.depth.ground_contact = g;
    cases.push_back(c);
  }
  for (const float rw : {0.f, 0.5f, 0.75f, 1.f}) {
    RankCase c{"region_weight", DepthParams(), 5};
    c.depth.region_weight = rw;
    cases.push_back(c);
  }
  for (const int b : {2, 3, 4, 8}) {  // 4: the default before the automatic block size
    RankCase c{"block_size", DepthParams(), 5};
    c.depth.block_size = b;
    cases.push_back(c);
  }
  for (const float e : {0.f, 8.f, 16.f, 32.f, 48.f}) {
    RankCase c{"edge_threshold", DepthParams(), 5};
    c.depth.edge_threshold = e;
    cases.push_back(c);
  }
  // The picture as decoders deliver it (4:2:0 Y'CbCr, BT.601): the depth
  // should not depend on the format it arrives in.
  for (const PixelFormat f : {PixelFormat::I420, PixelFormat::NV12}) {
    RankCase c{"input_format", DepthParams(), 5};
    c.format = f;
    cases.push_back(c);
  }
  return cases;
}

void measure_scale(Writer &w, const Aloe &a, const char *scale, int runs, const BilateralParams &filter) {
  const std::vector<int> sample = rank_sample(a.gt);
  std::vector<double> gt_values(sample.size()), est_values(sample.size());
  for (size_t i = 0; i < sample.size(); ++i) gt_values[i] = a.gt.ptr<uint8_t>()[sample[i]];
  const std::vector<RankCase> cases = rank_cases();
  std::vector<HostFrame> frames;  // the picture in each case's format
  for (const RankCase &c : cases)
    frames.push_back(c.format == PixelFormat::RGBA ? a.left_frame : HostFrame::from_bgr(a.left, c.format));
  std::vector<cv::Mat> depths(cases.size());
  std::vector<std::function<void()>> jobs;
  for (size_t k = 0; k < cases.size(); ++k)
    jobs.push_back([&, k] {
      const FrameView frame = frames[k].view();
      depths[k] = estimated_depth(cases[k].depth, frame);
      if (cases[k].radius > 0) depths[k] = filter_depth(filter, frame, depths[k]);
    });
  const std::vector<Timing> t = time_interleaved(runs, jobs);
  for (size_t k = 0; k < cases.size(); ++k) {
    const RankCase &c = cases[k];
    const cv::Mat &depth = depths[k];
    // The depth map is dense and continuous, so its element index is the
    // GT's (both W x H, continuous Mats).
    for (size_t i = 0; i < sample.size(); ++i) est_values[i] = depth.ptr<float>()[sample[i]];
    double lo = 0, hi = 0;
    cv::minMaxLoc(depth, &lo, &hi);
    // Flat (and any constant map) has no ranking; the filter's float
    // rounding would otherwise turn it into a random one.
    const double rho = hi - lo > 1e-4 ? spearman(est_values, gt_values) : std::numeric_limits<double>::quiet_NaN();
    JsonLine j;
    j.str("kind", "depth_rank").str("scale", scale).str("cue", c.cue).str("format", pixel_format_name(c.format));
    j.integer("width", a.left.cols).integer("height", a.left.rows);
    j.str("hypothesis", hypothesis_name(c.depth.hypothesis)).integer("block_size", c.depth.block_size);
    j.integer("effective_block_size", effective_block_size(c.depth, a.left.cols, a.left.rows));
    j.num("edge_threshold", c.depth.edge_threshold).num("region_weight", c.depth.region_weight);
    j.num("ground_contact", c.depth.ground_contact).integer("filter_radius", c.radius);
    j.str("filter_mode", filter.mode == BilateralMode::Separable ? "separable" : "exact");
    j.integer("samples", static_cast<long long>(sample.size())).num("spearman", rho);
    j.num("time_ms", t[k].median_ms()).num("min_ms", t[k].min_ms());
    w.emit(j);
    std::printf("depth %-4s %-14s %-4s %-11s B %2d (%d) edge %4.1f rw %.2f gc %.2f radius %d  rho %+.4f  %7.1f ms\n",
                scale, c.cue, pixel_format_name(c.format), hypothesis_name(c.depth.hypothesis), c.depth.block_size,
                effective_block_size(c.depth, a.left.cols, a.left.rows), c.depth.edge_threshold,
                c.depth.region_weight, c.depth.ground_contact, c.radius, rho, t[k].median_ms());
    std::fflush(stdout);
  }
}

}  // namespace

void measure_depth_rank(Writer &w, const Aloe &full, const Aloe &half, int runs, BilateralMode filter_mode) {
  BilateralParams filter;  // the element's defaults in the given mode
  filter.mode = filter_mode;
  measure_scale(w, full, "full", runs, filter);
  measure_scale(w, half, "half", runs, filter);
}

}  // namespace p3d::quality
