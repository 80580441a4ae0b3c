// Flicker on vtest.avi (static camera, people walking): depth change between
// consecutive frames on the static background, for the defaults with and
// without temporal smoothing, the defaults before the ground-contact cue, and
// block size 2; `estimate` is the estimator's output, `filtered` what the
// warp receives (default cross-bilateral filter). depth_std, the spatial
// standard deviation of each depth map averaged over the frames, shows how
// much of the depth range a setting uses: a flat map cannot flicker.
#include <algorithm>
#include <array>
#include <cstdio>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "quality.h"

namespace p3d::quality {
namespace {

constexpr double kStaticLumaStd = 2.0;  // 8-bit levels: the flicker mask
constexpr int kHistogramBins = 100000;  // |depth change| in [0, 1]: p95 to 1e-5

// Pixels whose luma standard deviation over the first `frames` frames is
// under kStaticLumaStd: the static background. Returns the frames read.
int static_mask(const std::string &path, int frames, cv::Mat &mask, std::string &err) {
  cv::VideoCapture cap;
  try {
    cap.open(path);
  } catch (const cv::Exception &e) {
    err = e.what();
  }
  if (!cap.isOpened()) {
    if (err.empty()) err = "cv::VideoCapture cannot open " + path;
    return 0;
  }
  cv::Mat bgr, grey, g64, sum, sum_sq;
  int n = 0;
  while (n < frames && cap.read(bgr) && !bgr.empty()) {
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    grey.convertTo(g64, CV_64F);
    if (n == 0) {
      sum = cv::Mat::zeros(g64.size(), CV_64F);
      sum_sq = cv::Mat::zeros(g64.size(), CV_64F);
    } else if (g64.size() != sum.size()) {
      break;
    }
    sum += g64;
    sum_sq += g64.mul(g64);
    ++n;
  }
  if (n < 2) {
    err = "fewer than 2 frames decoded from " + path;
    return n;
  }
  const cv::Mat mean = sum / n;
  cv::Mat var = sum_sq / n - mean.mul(mean);
  var = cv::max(var, 0.0);
  mask = var < kStaticLumaStd * kStaticLumaStd;
  return n;
}

// Frame-to-frame |depth change| statistics of one depth track.
struct FlickerTrack {
  const char *stage = "";  // "estimate" (block depth) or "filtered" (what the warp gets)
  cv::Mat prev;
  std::vector<double> frame_mean;      // mean |change| on the mask, per frame pair
  std::vector<double> frame_mean_all;  // over the whole frame
  std::vector<double> spread;          // spatial standard deviation of each map
  std::vector<long long> histogram = std::vector<long long>(kHistogramBins + 1, 0);
  std::vector<double> ms;

  void add(const cv::Mat &depth, const cv::Mat &mask) {
    cv::Scalar m, s;
    cv::meanStdDev(depth, m, s);
    spread.push_back(s[0]);
    if (!prev.empty()) {
      cv::Mat diff;
      cv::absdiff(depth, prev, diff);
      frame_mean.push_back(cv::mean(diff, mask)[0]);
      frame_mean_all.push_back(cv::mean(diff)[0]);
      for (int y = 0; y < diff.rows; ++y) {
        const float *d = diff.ptr<float>(y);
        const uint8_t *k = mask.ptr<uint8_t>(y);
        for (int x = 0; x < diff.cols; ++x)
          if (k[x]) ++histogram[std::min(kHistogramBins, static_cast<int>(d[x] * kHistogramBins))];
      }
    }
    depth.copyTo(prev);
  }

  // Share of the counted changes of at least `level` (depth units).
  double share_at_least(double level) const {
    long long total = 0, over = 0;
    const int first = static_cast<int>(level * kHistogramBins);
    for (int i = 0; i <= kHistogramBins; ++i) {
      total += histogram[i];
      if (i >= first) over += histogram[i];
    }
    return total > 0 ? static_cast<double>(over) / static_cast<double>(total) : 0.0;
  }

  // Upper edge of the histogram bin where the cumulative count reaches q.
  double quantile(double q) const {
    long long total = 0;
    for (const long long c : histogram) total += c;
    const double target = q * static_cast<double>(total);
    long long acc = 0;
    for (int i = 0; i <= kHistogramBins; ++i) {
      acc += histogram[i];
      if (static_cast<double>(acc) >= target) return static_cast<double>(i + 1) / kHistogramBins;
    }
    return 1.0;
  }
};

// One estimator setting: its estimator and the estimate / filtered tracks.
struct Setting {
  const char *label;  // "defaults", or what differs from them (see settings())
  DepthParams params;
  DepthEstimatorCpu estimator;
  FlickerTrack raw, filtered;
  std::array<int, 3> decisions{};  // Cut, Smooth, Reuse
};

std::vector<Setting> settings() {
  std::vector<Setting> s;
  for (const float smoothing : {0.f, DepthParams().temporal_smoothing, 0.9f}) {
    Setting d;
    d.label = "defaults";
    d.params.temporal_smoothing = smoothing;
    s.push_back(std::move(d));
  }
  // Two alternatives to the defaults, named by what they set: 4-pixel blocks
  // without feature smoothing, then the same without the ground-contact cue
  // (scripts/plot_quality.py knows these labels).
  Setting before;
  before.label = "4-pixel blocks, no feature smoothing";
  before.params.block_size = 4;
  before.params.feature_smoothing = 0.f;
  Setting previous = before;
  previous.label = "4-pixel blocks, no feature smoothing, no ground contact";
  previous.params.ground_contact = 0.f;
  previous.params.region_weight = 0.75f;
  // The block size and the feature smoothing each moved alone.
  Setting fine = before;
  fine.label = "block_size 2, no feature smoothing";
  fine.params.block_size = 2;
  Setting coarse;
  coarse.label = "block_size 4";
  coarse.params.block_size = 4;
  Setting light;
  light.label = "feature_smoothing 0.5";
  light.params.feature_smoothing = 0.5f;
  for (Setting *x : {&before, &previous, &fine, &coarse, &light}) s.push_back(std::move(*x));
  return s;
}

void emit(Writer &w, const Setting &s, const FlickerTrack &t, int frames, double mask_fraction, const cv::Mat &mask,
          const std::string &backend, BilateralMode filter_mode) {
  double mean = 0, worst = 0, mean_all = 0, spread = 0;
  for (const double v : t.frame_mean) {
    mean += v;
    worst = std::max(worst, v);
  }
  for (const double v : t.frame_mean_all) mean_all += v;
  for (const double v : t.spread) spread += v;
  const double pairs = static_cast<double>(t.frame_mean.size());
  const DepthParams &p = s.params;
  JsonLine j;
  j.str("kind", "flicker").str("video", "vtest.avi").str("decoder", backend).str("stage", t.stage);
  j.str("setting", s.label).num("temporal_smoothing", p.temporal_smoothing).integer("block_size", p.block_size);
  j.integer("effective_block_size", effective_block_size(p, mask.cols, mask.rows));
  j.num("feature_smoothing", p.feature_smoothing);
  j.str("filter_mode", filter_mode == BilateralMode::Separable ? "separable" : "exact");
  j.num("region_weight", p.region_weight).num("ground_contact", p.ground_contact).integer("frames", frames);
  j.num("static_std_levels", kStaticLumaStd).num("mask_fraction", mask_fraction);
  j.num("mean_abs", mean / pairs).num("p95_abs", t.quantile(0.95)).num("worst_frame_mean_abs", worst);
  // One 8-bit grey level: the smallest change a depth picture shows.
  j.num("share_over_1_level", t.share_at_least(1.0 / 255.0)).num("mean_abs_all_pixels", mean_all / pairs);
  j.num("depth_std", spread / static_cast<double>(t.spread.size()));
  j.integer("cuts", s.decisions[0]).integer("smoothed", s.decisions[1]).integer("reused", s.decisions[2]);
  j.num("time_ms", median(t.ms)).integer("width", mask.cols).integer("height", mask.rows);
  w.emit(j);
  std::printf("flicker    %-34s %-8s smoothing %.2f  mean %.5f  p95 %.5f  >=1 level %.2f%%  std %.3f  %6.1f ms/frame\n",
              s.label, t.stage, p.temporal_smoothing, mean / pairs, t.quantile(0.95),
              100 * t.share_at_least(1.0 / 255.0), spread / static_cast<double>(t.spread.size()), median(t.ms));
  std::fflush(stdout);
}

}  // namespace

void measure_flicker(Writer &w, const std::string &path, int frames, BilateralMode filter_mode) {
  cv::Mat mask;
  std::string err;
  const int n = static_mask(path, frames, mask, err);
  if (n < 2) {
    w.error("flicker", err);
    return;
  }
  const double mask_fraction = static_cast<double>(cv::countNonZero(mask)) / static_cast<double>(mask.total());
  if (mask_fraction == 0) {
    w.error("flicker", "no static pixel in " + path);
    return;
  }
  std::vector<Setting> all = settings();
  for (Setting &s : all) {
    s.raw.stage = "estimate";
    s.filtered.stage = "filtered";
  }
  cv::VideoCapture cap(path);
  const std::string backend = cap.isOpened() ? cap.getBackendName() : "";
  cv::Mat bgr;
  BilateralParams bp;  // the element's defaults in the given mode
  bp.mode = filter_mode;
  for (int f = 0; f < n && cap.read(bgr) && !bgr.empty(); ++f) {
    // Decoders hand GStreamer I420; the estimator groups regions in Y'UV then.
    const HostFrame frame = HostFrame::from_bgr(bgr, PixelFormat::I420);
    for (Setting &s : all) {
      cv::Mat depth(bgr.size(), CV_32FC1);
      const auto t0 = std::chrono::steady_clock::now();
      const TemporalDecision d = s.estimator.estimate(s.params, frame.view(), depth_view_of(depth));
      s.raw.ms.push_back(elapsed_ms(t0));
      ++s.decisions[static_cast<int>(d)];
      const auto t1 = std::chrono::steady_clock::now();
      const cv::Mat smooth = filter_depth(bp, frame.view(), depth);
      s.filtered.ms.push_back(elapsed_ms(t1));
      s.raw.add(depth, mask);
      s.filtered.add(smooth, mask);
    }
  }
  for (const bool filtered : {false, true})
    for (const Setting &s : all) emit(w, s, filtered ? s.filtered : s.raw, n, mask_fraction, mask, backend, filter_mode);
}

}  // namespace p3d::quality
