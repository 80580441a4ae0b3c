// What the quality studies share: output, timing, statistics, the Aloe data.
#include <algorithm>
#include <cstdio>
#include <cmath>
#include <ctime>
#include <limits>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "quality.h"

namespace p3d::quality {

// ---- output -----------------------------------------------------------------------

void Writer::emit(const JsonLine &j) { out_ << j.text() << "\n" << std::flush; }

void Writer::error(const std::string &kind, const std::string &msg) {
  std::fprintf(stderr, "pseudo3d-quality: %s: %s\n", kind.c_str(), msg.c_str());
  emit(JsonLine().str("kind", kind).str("error", msg));
}

namespace {

std::string command_output(const char *cmd) {
  std::string s;
  if (FILE *p = popen(cmd, "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, p)) s += buf;
    pclose(p);
  }
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  return "";
}

}  // namespace

void emit_run_line(Writer &w, const Options &o) {
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  JsonLine j;
  j.str("kind", "run").str("date", date);
  j.str("git", command_output("git describe --always --dirty --abbrev=12 2>/dev/null"));
  j.str("args", o.argv).str("cpu", cpu_model()).integer("cpu_threads", cv::getNumThreads());
  j.str("opencv", CV_VERSION).integer("runs", o.runs);
  w.emit(j);
}

// ---- timing and statistics ----------------------------------------------------------

double elapsed_ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double Timing::min_ms() const {
  return ms.empty() ? std::numeric_limits<double>::quiet_NaN() : *std::min_element(ms.begin(), ms.end());
}

std::vector<Timing> time_interleaved(int runs, const std::vector<std::function<void()>> &jobs) {
  std::vector<Timing> t(jobs.size());
  for (int i = 0; i < runs; ++i)
    for (size_t j = 0; j < jobs.size(); ++j) {
      const auto t0 = std::chrono::steady_clock::now();
      jobs[j]();
      t[j].ms.push_back(elapsed_ms(t0));
    }
  return t;
}

namespace {

// Ranks 1..n with ties given their average rank (Spearman's convention).
std::vector<double> average_ranks(const std::vector<double> &v) {
  std::vector<size_t> order(v.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&v](size_t a, size_t b) { return v[a] < v[b]; });
  std::vector<double> rank(v.size());
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    while (j + 1 < order.size() && v[order[j + 1]] == v[order[i]]) ++j;
    const double r = 0.5 * static_cast<double>(i + j) + 1.0;
    for (size_t k = i; k <= j; ++k) rank[order[k]] = r;
    i = j + 1;
  }
  return rank;
}

// Pearson correlation; NaN when either side is constant (no ranking at all).
double pearson(const std::vector<double> &a, const std::vector<double> &b) {
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= n;
  mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  if (saa == 0 || sbb == 0) return std::numeric_limits<double>::quiet_NaN();
  return sab / std::sqrt(saa * sbb);
}

}  // namespace

double spearman(const std::vector<double> &a, const std::vector<double> &b) {
  return pearson(average_ranks(a), average_ranks(b));
}

// ---- Aloe ---------------------------------------------------------------------------

namespace {

cv::Mat read_image(const std::string &path, int flags) {
  try {
    return cv::imread(path, flags);
  } catch (const cv::Exception &) {
    return cv::Mat();
  }
}

// The depth the RGBD path gives the warp: GT scaled to 0..255 as an 8-bit
// grey picture, read back by depth_from_grey_cpu (tests/elements/test_aloe.cpp).
cv::Mat depth_from_gt(const cv::Mat &gt, double max_gt) {
  cv::Mat grey, grey_bgr;
  gt.convertTo(grey, CV_8U, 255.0 / max_gt);
  cv::cvtColor(grey, grey_bgr, cv::COLOR_GRAY2BGR);
  const HostFrame frame = HostFrame::from_bgr(grey_bgr, PixelFormat::RGBA);
  cv::Mat depth(gt.size(), CV_32FC1);
  depth_from_grey_cpu(frame.view(), YuvToRgb(), depth_view_of(depth));
  return depth;
}

// Right-view pixels that some known-GT left pixel x lands on (x - GT(x),
// rounded), with one-pixel gaps closed: integer GT makes x - GT(x) skip a
// column where the disparity steps down by one along a row. Excludes the
// disocclusions, the band at the right border the left view never saw and
// the unknown-GT areas; what is left scores the warp, not the fill.
cv::Mat correspondence_mask(const cv::Mat &gt) {
  cv::Mat mask = cv::Mat::zeros(gt.size(), CV_8UC1);
  for (int y = 0; y < gt.rows; ++y) {
    const uint8_t *g = gt.ptr<uint8_t>(y);
    uint8_t *m = mask.ptr<uint8_t>(y);
    for (int x = 0; x < gt.cols; ++x) {
      const int X = x - g[x];
      if (g[x] > 0 && X >= 0) m[X] = 255;
    }
    for (int X = 1; X + 1 < gt.cols; ++X)
      if (!m[X] && m[X - 1] && m[X + 1]) m[X] = 255;
  }
  return mask;
}

}  // namespace

bool load_aloe(const std::string &dir, double scale, Aloe &a, std::string &err) {
  cv::Mat left = read_image(dir + "/aloeL.jpg", cv::IMREAD_COLOR);
  cv::Mat right = read_image(dir + "/aloeR.jpg", cv::IMREAD_COLOR);
  cv::Mat gt = read_image(dir + "/aloeGT.png", cv::IMREAD_GRAYSCALE);
  if (left.empty() || right.empty() || gt.empty()) {
    err = "cannot read aloeL.jpg, aloeR.jpg or aloeGT.png in " + dir + " (scripts/get-test-data.sh)";
    return false;
  }
  if (left.size() != right.size() || left.size() != gt.size()) {
    err = "Aloe images differ in size";
    return false;
  }
  if (scale != 1.0) {
    // Pixels average (INTER_AREA); the disparity is sampled (nearest, so no
    // unknown = 0 value leaks into its neighbours) and scaled with the picture.
    cv::resize(left, left, cv::Size(), scale, scale, cv::INTER_AREA);
    cv::resize(right, right, left.size(), 0, 0, cv::INTER_AREA);
    cv::Mat g;
    cv::resize(gt, g, left.size(), 0, 0, cv::INTER_NEAREST);
    g.convertTo(gt, CV_8U, scale);
  }
  const cv::Rect crop(0, 0, left.cols & ~1, left.rows);  // YUV-friendly even width, as the test
  a.scale = scale;
  a.left = left(crop).clone();
  a.right = right(crop).clone();
  a.gt = gt(crop).clone();
  cv::minMaxLoc(a.gt, nullptr, &a.max_gt);
  if (a.max_gt <= 0) {
    err = "aloeGT.png has no known disparity";
    return false;
  }
  a.left_frame = HostFrame::from_bgr(a.left, PixelFormat::RGBA);
  a.gt_depth = depth_from_gt(a.gt, a.max_gt);
  a.warp.view = StereoView::Right;
  a.warp.convergence = 0.f;
  a.warp.max_disparity = static_cast<float>(100.0 * a.max_gt / a.left.cols);
  a.mask = correspondence_mask(a.gt);
  return true;
}

long long render_right(const Aloe &a, const cv::Mat &depth, HoleFill fill, HostFrame &out) {
  WarpParams p = a.warp;
  p.fill = fill;
  // Kept between renders, as pseudo3dwarp keeps it between frames; one per
  // thread, so that renders from parallel jobs never share the planes.
  thread_local WarpCpuScratch scratch;
  return warp_render_cpu(p, a.left_frame.view(), YuvToRgb(), depth_view_of(depth), out.view(), scratch);
}

cv::Mat right_half_bgr(const HostFrame &out) {
  const cv::Mat bgra = out.to_bgra();
  cv::Mat bgr;
  cv::cvtColor(bgra(cv::Rect(bgra.cols / 2, 0, bgra.cols / 2, bgra.rows)), bgr, cv::COLOR_BGRA2BGR);
  return bgr;
}

cv::Mat filter_depth(const BilateralParams &bp, const FrameView &guide, const cv::Mat &depth) {
  cv::Mat out(depth.size(), CV_32FC1);
  bilateral_filter_cpu(bp, guide, depth_view_of(depth), depth_view_of(out));
  return out;
}

MapError map_error(const cv::Mat &a, const cv::Mat &b) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  MapError e;
  cv::minMaxLoc(diff, nullptr, &e.max_abs);
  e.mean_abs = cv::mean(diff)[0];
  const double mse = cv::norm(diff, cv::NORM_L2SQR) / static_cast<double>(diff.total());
  e.psnr = mse > 0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
  return e;
}

BilateralParams study_filter(int radius, BilateralMode mode) {
  BilateralParams bp;
  bp.radius = radius;
  bp.sigma_space = 0.6f * static_cast<float>(radius);
  bp.sigma_range = 12.f;
  bp.mode = mode;
  return bp;
}

cv::Mat estimated_depth(const DepthParams &dp, const FrameView &frame) {
  cv::Mat depth(frame.height, frame.width, CV_32FC1);
  DepthEstimatorCpu est;
  est.estimate(dp, frame, depth_view_of(depth));
  return depth;
}

const char *fill_name(HoleFill f) { return enum_nick(kHoleFillNames, f); }

const char *hypothesis_name(Hypothesis h) { return enum_nick(kHypothesisNames, h); }

}  // namespace p3d::quality
