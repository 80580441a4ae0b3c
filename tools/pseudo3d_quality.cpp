// pseudo3d-quality: error against run time on real data, with the CPU
// reference code (common/). Writes one JSON line per measurement (the first
// line describes the run); scripts/quality-report.sh turns them into
// docs/quality.md and docs/img/quality-vs-time.png.
//
// Measurements (kind=...):
//   synthesis       Aloe's right view rendered from aloeL plus its ground-truth
//                   disparity, as tests/elements/test_aloe.cpp does (depth =
//                   GT / max(GT), view=right, convergence 0, max-disparity =
//                   100 max(GT) / W), for every hole fill and with the depth
//                   as is or cross-bilateral filtered (guide aloeL): PSNR and
//                   SSIM against aloeR, and the time of filter + warp.
//   baseline        aloeL itself against aloeR (what no warp at all scores).
//   filter_variant  the exact windowed filter against faster approximations
//                   implemented here (stride-2 taps; separable rows-then-
//                   columns): error against the exact result, and time.
//   depth_rank      DepthEstimatorCpu + default filter on aloeL: Spearman rank
//                   correlation with aloeGT over known-GT pixels.
//   flicker         depth change between consecutive frames of vtest.avi on
//                   its static background, with and without temporal smoothing.
// Times are medians of --runs runs on this machine's CPU (cv::getNumThreads()
// worker threads, recorded in the run line).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "bilateral.h"
#include "depth_estimate.h"
#include "host_frame.h"
#include "metrics.h"
#include "warp.h"
#include "json_line.h"

namespace p3d::quality {
namespace {

constexpr int kExitUsage = 64;
constexpr uint32_t kSampleSeed = 20261121u;  // fixed: the subsample is the same in every run
constexpr int kRankSamples = 50000;
constexpr double kStaticLumaStd = 2.0;  // 8-bit levels: the flicker mask
constexpr int kHistogramBins = 100000;  // |depth change| in [0, 1]: p95 to 1e-5

struct Options {
  std::string data_dir = "data";
  std::string out_path = "quality.jsonl";
  int runs = 5;
  int frames = 200;
  int threads = -1;  // -1: OpenCV's default
  std::set<std::string> parts = {"synthesis", "filter", "depth", "flicker"};
  std::string argv;
};

// ---- command line ---------------------------------------------------------------

void print_usage(std::ostream &os) {
  os << "Usage: pseudo3d-quality [options]\n"
        "  --data DIR      aloeL.jpg, aloeR.jpg, aloeGT.png, vtest.avi (default data)\n"
        "  --out FILE      JSON lines written here (default quality.jsonl; truncated)\n"
        "  --runs N        timed runs per measurement, median reported (default 5)\n"
        "  --frames N      vtest.avi frames for the flicker measurement (default 200)\n"
        "  --only LIST     comma separated subset of synthesis,filter,depth,flicker\n"
        "  --threads N     OpenCV worker threads (default: OpenCV's choice)\n"
        "  --quick         smoke test: --runs 1 --frames 20\n"
        "Exit status: 0 ok, 1 missing data or I/O error, 64 bad usage.\n";
}

[[noreturn]] void usage_error(const std::string &msg) {
  std::cerr << "pseudo3d-quality: " << msg << "\n";
  print_usage(std::cerr);
  std::exit(kExitUsage);
}

int parse_int(const std::string &opt, const std::string &v, int lo, int hi) {
  char *end = nullptr;
  const long n = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || n < lo || n > hi)
    usage_error(opt + " wants an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got '" + v + "'");
  return static_cast<int>(n);
}

std::set<std::string> parse_parts(const std::string &v) {
  static const std::set<std::string> known = {"synthesis", "filter", "depth", "flicker"};
  std::set<std::string> parts;
  std::stringstream ss(v);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!known.count(item)) usage_error("unknown part '" + item + "' in --only");
    parts.insert(item);
  }
  if (parts.empty()) usage_error("--only wants at least one part");
  return parts;
}

Options parse_args(int argc, char **argv) {
  Options o;
  bool quick = false, runs_given = false, frames_given = false;
  for (int i = 0; i < argc; ++i) o.argv += (i ? " " : "") + std::string(argv[i]);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      print_usage(std::cout);
      std::exit(0);
    }
    if (a == "--quick") {
      quick = true;
      continue;
    }
    if (i + 1 >= argc) usage_error("missing value after " + a);
    const std::string v = argv[++i];
    if (a == "--data") {
      o.data_dir = v;
    } else if (a == "--out") {
      o.out_path = v;
    } else if (a == "--runs") {
      o.runs = parse_int(a, v, 1, 1000);
      runs_given = true;
    } else if (a == "--frames") {
      o.frames = parse_int(a, v, 2, 100000);
      frames_given = true;
    } else if (a == "--threads") {
      o.threads = parse_int(a, v, 1, 1024);
    } else if (a == "--only") {
      o.parts = parse_parts(v);
    } else {
      usage_error("unknown option " + a);
    }
  }
  if (quick) {
    if (!runs_given) o.runs = 1;
    if (!frames_given) o.frames = 20;
  }
  return o;
}

// ---- output ---------------------------------------------------------------------

using p3d::tools::json_escape;
using p3d::tools::JsonLine;

class Writer {
 public:
  explicit Writer(std::ofstream &out) : out_(out) {}
  void emit(const JsonLine &j) { out_ << j.text() << "\n" << std::flush; }
  void error(const std::string &kind, const std::string &msg) {
    std::fprintf(stderr, "pseudo3d-quality: %s: %s\n", kind.c_str(), msg.c_str());
    emit(JsonLine().str("kind", kind).str("error", msg));
  }

 private:
  std::ofstream &out_;
};

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

// ---- timing and statistics --------------------------------------------------------

double elapsed_ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Wall times of one measured configuration.
struct Timing {
  std::vector<double> ms;
  double median_ms() const { return median(ms); }
  double min_ms() const {
    return ms.empty() ? std::numeric_limits<double>::quiet_NaN() : *std::min_element(ms.begin(), ms.end());
  }
};

// Times every job `runs` times, round-robin (run i of every job before run
// i+1 of any): the machine is shared, and a burst of someone else's load
// then slows all configurations alike instead of one of them.
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

double spearman(const std::vector<double> &a, const std::vector<double> &b) {
  return pearson(average_ranks(a), average_ranks(b));
}

// ---- Aloe -------------------------------------------------------------------------

struct Aloe {
  cv::Mat left, right;  // BGR, cropped to an even width like the Aloe test
  cv::Mat gt;           // CV_8UC1 disparity in left-view pixels, 0 = unknown
  double max_gt = 0;
  HostFrame left_frame;  // RGBA, the warp's source and the filter's guide
  cv::Mat gt_depth;      // CV_32FC1, GT / max(GT) through a grey picture (RGBD input)
  WarpParams warp;       // view=right, convergence 0, max-disparity = max(GT)
  cv::Mat mask;          // right-view pixels with a known correspondence (CV_8UC1)
};

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

bool load_aloe(const std::string &dir, Aloe &a, std::string &err) {
  const cv::Mat left = read_image(dir + "/aloeL.jpg", cv::IMREAD_COLOR);
  const cv::Mat right = read_image(dir + "/aloeR.jpg", cv::IMREAD_COLOR);
  const cv::Mat gt = read_image(dir + "/aloeGT.png", cv::IMREAD_GRAYSCALE);
  if (left.empty() || right.empty() || gt.empty()) {
    err = "cannot read aloeL.jpg, aloeR.jpg or aloeGT.png in " + dir + " (scripts/get-test-data.sh)";
    return false;
  }
  if (left.size() != right.size() || left.size() != gt.size()) {
    err = "Aloe images differ in size";
    return false;
  }
  const cv::Rect crop(0, 0, left.cols & ~1, left.rows);  // YUV-friendly even width, as the test
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

// Renders the right view (BGR) from the left view and `depth` with `fill`.
// `out` is the 2W x H stereo scratch frame. Returns the warp's hole count.
long long render_right(const Aloe &a, const cv::Mat &depth, HoleFill fill, HostFrame &out) {
  WarpParams p = a.warp;
  p.fill = fill;
  return warp_render_cpu(p, a.left_frame.view(), YuvToRgb(), depth_view_of(depth), out.view());
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

// Filter settings of the study: sigma_space = 0.6 radius, so that the window
// always spans the same +-1.67 sigma and radius 5 is the element's default
// (sigma_space 3); sigma_range is the default 12.
BilateralParams study_filter(int radius) {
  BilateralParams bp;
  bp.radius = radius;
  bp.sigma_space = 0.6f * static_cast<float>(radius);
  bp.sigma_range = 12.f;
  return bp;
}

const char *fill_name(HoleFill f) {
  switch (f) {
    case HoleFill::Background: return "background";
    case HoleFill::NeighborAverage: return "neighbor-average";
    case HoleFill::BackgroundSmooth: return "background-smooth";
    default: return "none";
  }
}

void measure_baseline(Writer &w, const Aloe &a) {
  JsonLine j;
  j.str("kind", "baseline").str("what", "left view as is");
  j.num("psnr", psnr(a.left, a.right)).num("ssim", ssim(a.left, a.right));
  j.num("psnr_masked", psnr(a.left, a.right, a.mask));
  w.emit(j);
}

struct SynthCase {
  int radius;
  HoleFill fill;
};

void measure_synthesis(Writer &w, const Aloe &a, int runs) {
  const std::vector<int> radii = {0, 2, 5, 10};  // 0: the GT depth as is
  std::vector<SynthCase> cases;
  for (const int radius : radii)
    for (const HoleFill fill : {HoleFill::BackgroundSmooth, HoleFill::Background, HoleFill::NeighborAverage, HoleFill::None})
      cases.push_back({radius, fill});
  HostFrame out(PixelFormat::BGRA, 2 * a.left.cols, a.left.rows);
  // The filter and the warp are timed apart (their sum is the case's time);
  // one filter run per radius and round serves the three fills.
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
  for (size_t i = 0; i < cases.size(); ++i) {
    const SynthCase &c = cases[i];
    const BilateralParams bp = study_filter(c.radius);
    const Timing &ft = filter_t[radius_index(c.radius)];
    const long long holes = render_right(a, filtered[radius_index(c.radius)], c.fill, out);
    const cv::Mat synth = right_half_bgr(out);
    const double full = psnr(synth, a.right), structural = ssim(synth, a.right);
    const double masked = psnr(synth, a.right, a.mask);
    const double filter_ms = c.radius > 0 ? ft.median_ms() : 0.0;
    const double filter_min = c.radius > 0 ? ft.min_ms() : 0.0;
    JsonLine j;
    j.str("kind", "synthesis").str("fill", fill_name(c.fill)).integer("radius", c.radius);
    j.num("sigma_space", c.radius > 0 ? bp.sigma_space : 0.0).num("sigma_range", c.radius > 0 ? bp.sigma_range : 0.0);
    j.integer("width", a.left.cols).integer("height", a.left.rows).num("max_disparity_percent", a.warp.max_disparity);
    j.num("psnr", full).num("ssim", structural).num("psnr_masked", masked).num("mask_fraction", mask_fraction);
    j.num("hole_fraction", static_cast<double>(holes) / static_cast<double>(a.mask.total()));
    j.num("time_ms", filter_ms + warp_t[i].median_ms()).num("min_ms", filter_min + warp_t[i].min_ms());
    j.num("filter_ms", filter_ms).num("warp_ms", warp_t[i].median_ms());
    w.emit(j);
    std::printf("synthesis  fill %-16s radius %2d  PSNR %6.2f dB  SSIM %.4f  masked %6.2f dB  %8.1f ms\n",
                fill_name(c.fill), c.radius, full, structural, masked, filter_ms + warp_t[i].median_ms());
    std::fflush(stdout);
  }
}

// ---- faster bilateral variants ------------------------------------------------------

struct FilterTables {
  BilateralParams p;
  std::vector<float> space, range;
  explicit FilterTables(const BilateralParams &params)
      : p(bilateral_sanitize(params)),
        space(bilateral_space_table_size(p.radius)),
        range(kBilateralRangeTableSize) {
    bilateral_tables(p, space.data(), range.data());
  }
  float space_at(int dx, int dy) const { return space[(dy + p.radius) * (2 * p.radius + 1) + (dx + p.radius)]; }
};

// Stride-2 window: only the taps with even dx and dy (about a quarter of
// them, the centre included so the weight sum stays >= 1). Same weights as
// the exact filter; a thin structure between two taps is what it can miss.
cv::Mat bilateral_stride2(const BilateralParams &params, const FrameView &guide, const cv::Mat &depth) {
  const FilterTables t(params);
  const cv::Mat luma = bilateral_guide_luma(guide);
  const int w = depth.cols, h = depth.rows, r = t.p.radius & ~1;  // the largest even offset
  cv::Mat out(depth.size(), CV_32FC1);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const uint8_t *gc = luma.ptr<uint8_t>(y);
      float *o = out.ptr<float>(y);
      for (int x = 0; x < w; ++x) {
        const int centre = gc[x];
        float sum_w = 0.f, sum_wd = 0.f;
        for (int dy = -r; dy <= r; dy += 2) {
          const int qy = y + dy;
          if (qy < 0 || qy >= h) continue;
          const uint8_t *g = luma.ptr<uint8_t>(qy);
          const float *d = depth.ptr<float>(qy);
          for (int dx = -r; dx <= r; dx += 2) {
            const int qx = x + dx;
            if (qx < 0 || qx >= w) continue;
            const int diff = static_cast<int>(g[qx]) - centre;
            bilateral_accumulate(t.space_at(dx, dy), t.range[diff < 0 ? -diff : diff], d[qx], sum_w, sum_wd);
          }
        }
        o[x] = sum_wd / sum_w;
      }
    }
  });
  return out;
}

// Separable approximation (Pham & van Vliet 2005): a 1D cross-bilateral pass
// along rows, then one along columns of its result, each with the 1D space
// weight and the range weight against the centre's guide. 2(2r+1) taps
// instead of (2r+1)^2; exact for the space part, approximate for the range
// part (a pixel can reach a similar one only through an L-shaped path).
cv::Mat bilateral_separable(const BilateralParams &params, const FrameView &guide, const cv::Mat &depth) {
  const FilterTables t(params);
  const cv::Mat luma = bilateral_guide_luma(guide);
  const int w = depth.cols, h = depth.rows, r = t.p.radius;
  cv::Mat across(depth.size(), CV_32FC1), out(depth.size(), CV_32FC1);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const uint8_t *g = luma.ptr<uint8_t>(y);
      const float *d = depth.ptr<float>(y);
      float *o = across.ptr<float>(y);
      for (int x = 0; x < w; ++x) {
        float sum_w = 0.f, sum_wd = 0.f;
        for (int qx = std::max(0, x - r); qx <= std::min(w - 1, x + r); ++qx) {
          const int diff = static_cast<int>(g[qx]) - static_cast<int>(g[x]);
          bilateral_accumulate(t.space_at(qx - x, 0), t.range[diff < 0 ? -diff : diff], d[qx], sum_w, sum_wd);
        }
        o[x] = sum_wd / sum_w;
      }
    }
  });
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const uint8_t *gc = luma.ptr<uint8_t>(y);
      float *o = out.ptr<float>(y);
      for (int x = 0; x < w; ++x) {
        float sum_w = 0.f, sum_wd = 0.f;
        for (int qy = std::max(0, y - r); qy <= std::min(h - 1, y + r); ++qy) {
          const int diff = static_cast<int>(luma.ptr<uint8_t>(qy)[x]) - static_cast<int>(gc[x]);
          bilateral_accumulate(t.space_at(0, qy - y), t.range[diff < 0 ? -diff : diff], across.ptr<float>(qy)[x],
                               sum_w, sum_wd);
        }
        o[x] = sum_wd / sum_w;
      }
    }
  });
  return out;
}

struct MapError {
  double max_abs = 0, mean_abs = 0, psnr = 0;
};

// Error of depth map b against a (depth units 0..1); PSNR of depth * 255
// with peak 255, i.e. 10 log10(1 / MSE).
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

cv::Mat estimated_depth(const DepthParams &dp, const FrameView &frame) {
  cv::Mat depth(frame.height, frame.width, CV_32FC1);
  DepthEstimatorCpu est;
  est.estimate(dp, frame, depth_view_of(depth));
  return depth;
}

void measure_filter_variants(Writer &w, const Aloe &a, int runs) {
  using Variant = std::function<cv::Mat(const BilateralParams &, const FrameView &, const cv::Mat &)>;
  const std::vector<std::pair<const char *, Variant>> variants = {
      {"exact", filter_depth}, {"stride2", bilateral_stride2}, {"separable", bilateral_separable}};
  const std::vector<std::pair<const char *, cv::Mat>> inputs = {
      {"estimated", estimated_depth(DepthParams(), a.left_frame.view())}, {"ground-truth", a.gt_depth}};
  const FrameView guide = a.left_frame.view();
  // One timing group for all of them, so that the speed-ups compare runs
  // taken side by side.
  struct Case {
    size_t input, variant;
    int radius;
  };
  std::vector<Case> cases;
  for (size_t i = 0; i < inputs.size(); ++i)
    for (const int radius : {5, 10})
      for (size_t v = 0; v < variants.size(); ++v) cases.push_back({i, v, radius});
  std::vector<cv::Mat> results(cases.size());
  std::vector<std::function<void()>> jobs;
  for (size_t k = 0; k < cases.size(); ++k)
    jobs.push_back([&, k] {
      // The element's default (sigma_space 3) at radius 5; 0.6 r at radius 10.
      const Case &c = cases[k];
      results[k] = variants[c.variant].second(study_filter(c.radius), guide, inputs[c.input].second);
    });
  const std::vector<Timing> t = time_interleaved(runs, jobs);

  HostFrame out(PixelFormat::BGRA, 2 * a.left.cols, a.left.rows);
  for (size_t k = 0; k < cases.size(); ++k) {
    const Case &c = cases[k];
    const char *variant = variants[c.variant].first, *input = inputs[c.input].first;
    const BilateralParams bp = study_filter(c.radius);
    const cv::Mat &exact = results[k - c.variant];  // variant 0 of the same input and radius
    const MapError e = map_error(exact, results[k]);
    JsonLine j;
    j.str("kind", "filter_variant").str("variant", variant).str("input", input).integer("radius", c.radius);
    j.num("sigma_space", bp.sigma_space).num("sigma_range", bp.sigma_range);
    j.num("time_ms", t[k].median_ms()).num("min_ms", t[k].min_ms());
    j.num("max_abs", e.max_abs).num("mean_abs", e.mean_abs).num("psnr_vs_exact", e.psnr);
    if (std::string(input) == "ground-truth") {
      render_right(a, results[k], HoleFill::Background, out);
      const cv::Mat synth = right_half_bgr(out);
      j.num("synth_psnr", psnr(synth, a.right)).num("synth_ssim", ssim(synth, a.right));
    }
    w.emit(j);
    std::printf("filter     %-9s %-12s radius %2d  %8.1f ms  max %.4f  mean %.5f  PSNR %6.2f dB\n", variant, input,
                c.radius, t[k].median_ms(), e.max_abs, e.mean_abs, e.psnr);
    std::fflush(stdout);
  }
}

// ---- depth estimator against ground truth ---------------------------------------------

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

const char *hypothesis_name(Hypothesis h) {
  switch (h) {
    case Hypothesis::TopBottom: return "top-bottom";
    case Hypothesis::LeftRight: return "left-right";
    case Hypothesis::CenterNear: return "center-near";
    default: return "flat";
  }
}

struct RankCase {
  DepthParams depth;
  int radius;  // 0: no filter
};

std::vector<RankCase> rank_cases() {
  std::vector<RankCase> cases;
  for (const Hypothesis h : {Hypothesis::TopBottom, Hypothesis::LeftRight, Hypothesis::CenterNear, Hypothesis::Flat}) {
    RankCase c{DepthParams(), 5};
    c.depth.hypothesis = h;
    cases.push_back(c);
  }
  cases.push_back({DepthParams(), 0});
  for (const float e : {0.f, 8.f, 48.f, 96.f}) {
    RankCase c{DepthParams(), 5};
    c.depth.edge_threshold = e;
    cases.push_back(c);
  }
  for (const float rw : {0.f, 0.5f, 1.f}) {
    RankCase c{DepthParams(), 5};
    c.depth.region_weight = rw;
    cases.push_back(c);
  }
  return cases;
}

void measure_depth_rank(Writer &w, const Aloe &a, int runs) {
  const std::vector<int> sample = rank_sample(a.gt);
  std::vector<double> gt_values(sample.size()), est_values(sample.size());
  for (size_t i = 0; i < sample.size(); ++i) gt_values[i] = a.gt.ptr<uint8_t>()[sample[i]];
  const FrameView frame = a.left_frame.view();
  const std::vector<RankCase> cases = rank_cases();
  std::vector<cv::Mat> depths(cases.size());
  std::vector<std::function<void()>> jobs;
  for (size_t k = 0; k < cases.size(); ++k)
    jobs.push_back([&, k] {
      depths[k] = estimated_depth(cases[k].depth, frame);
      if (cases[k].radius > 0) depths[k] = filter_depth(BilateralParams(), frame, depths[k]);  // element defaults
    });
  const std::vector<Timing> t = time_interleaved(runs, jobs);
  for (size_t k = 0; k < cases.size(); ++k) {
    const RankCase &c = cases[k];
    const cv::Mat &depth = depths[k];
    const double ms = t[k].median_ms();
    // The depth map is dense and continuous, so its element index is the
    // GT's (both W x H, continuous Mats).
    for (size_t i = 0; i < sample.size(); ++i) est_values[i] = depth.ptr<float>()[sample[i]];
    double lo = 0, hi = 0;
    cv::minMaxLoc(depth, &lo, &hi);
    // Flat (and any constant map) has no ranking; the filter's float
    // rounding would otherwise turn it into a random one.
    const double rho = hi - lo > 1e-4 ? spearman(est_values, gt_values) : std::numeric_limits<double>::quiet_NaN();
    JsonLine j;
    j.str("kind", "depth_rank").str("hypothesis", hypothesis_name(c.depth.hypothesis));
    j.integer("block_size", c.depth.block_size).num("edge_threshold", c.depth.edge_threshold);
    j.num("region_weight", c.depth.region_weight).integer("filter_radius", c.radius);
    j.integer("samples", static_cast<long long>(sample.size())).num("spearman", rho);
    j.num("time_ms", ms).num("min_ms", t[k].min_ms());
    w.emit(j);
    std::printf("depth      %-11s edge %5.1f region_weight %.2f radius %d  rho %+.4f  %8.1f ms\n",
                hypothesis_name(c.depth.hypothesis), c.depth.edge_threshold, c.depth.region_weight, c.radius, rho, ms);
    std::fflush(stdout);
  }
}

// ---- flicker on vtest.avi -------------------------------------------------------------

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

// Frame-to-frame |depth change| statistics of one estimator setting.
struct FlickerTrack {
  const char *stage;  // "estimate" (block depth) or "filtered" (what the warp gets)
  float temporal_smoothing;
  DepthEstimatorCpu estimator;
  cv::Mat prev;
  std::vector<double> frame_mean;      // mean |change| on the mask, per frame pair
  std::vector<double> frame_mean_all;  // over the whole frame
  std::vector<long long> histogram = std::vector<long long>(kHistogramBins + 1, 0);
  std::array<int, 3> decisions{};  // Cut, Smooth, Reuse
  std::vector<double> ms;

  void add(const cv::Mat &depth, const cv::Mat &mask) {
    if (!prev.empty()) {
      cv::Mat diff;
      cv::absdiff(depth, prev, diff);
      frame_mean.push_back(cv::mean(diff, mask)[0]);
      frame_mean_all.push_back(cv::mean(diff)[0]);
      for (int y = 0; y < diff.rows; ++y) {
        const float *d = diff.ptr<float>(y);
        const uint8_t *m = mask.ptr<uint8_t>(y);
        for (int x = 0; x < diff.cols; ++x)
          if (m[x]) ++histogram[std::min(kHistogramBins, static_cast<int>(d[x] * kHistogramBins))];
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

void measure_flicker(Writer &w, const std::string &path, int frames) {
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
  // Each smoothing setting runs one estimator; the filtered track filters
  // that same estimate, so both tracks of a setting share the estimator.
  std::vector<float> settings = {0.f, DepthParams().temporal_smoothing, 0.9f};
  std::vector<FlickerTrack> raw(settings.size()), filtered(settings.size());
  for (size_t s = 0; s < settings.size(); ++s) {
    raw[s].stage = "estimate";
    filtered[s].stage = "filtered";
    raw[s].temporal_smoothing = filtered[s].temporal_smoothing = settings[s];
  }
  cv::VideoCapture cap(path);
  const std::string backend = cap.isOpened() ? cap.getBackendName() : "";
  cv::Mat bgr;
  const BilateralParams bp;
  for (int f = 0; f < n && cap.read(bgr) && !bgr.empty(); ++f) {
    // Decoders hand GStreamer I420; the estimator groups regions in Y'UV then.
    const HostFrame frame = HostFrame::from_bgr(bgr, PixelFormat::I420);
    for (size_t s = 0; s < settings.size(); ++s) {
      DepthParams dp;
      dp.temporal_smoothing = settings[s];
      cv::Mat depth(bgr.size(), CV_32FC1);
      const auto t0 = std::chrono::steady_clock::now();
      const TemporalDecision d = raw[s].estimator.estimate(dp, frame.view(), depth_view_of(depth));
      raw[s].ms.push_back(elapsed_ms(t0));
      ++raw[s].decisions[static_cast<int>(d)];
      const auto t1 = std::chrono::steady_clock::now();
      const cv::Mat smooth = filter_depth(bp, frame.view(), depth);
      filtered[s].ms.push_back(elapsed_ms(t1));
      filtered[s].decisions = raw[s].decisions;
      raw[s].add(depth, mask);
      filtered[s].add(smooth, mask);
    }
  }
  for (const auto *tracks : {&raw, &filtered})
    for (const FlickerTrack &t : *tracks) {
      double mean = 0, worst = 0, mean_all = 0;
      for (const double v : t.frame_mean) {
        mean += v;
        worst = std::max(worst, v);
      }
      for (const double v : t.frame_mean_all) mean_all += v;
      const double pairs = static_cast<double>(t.frame_mean.size());
      JsonLine j;
      j.str("kind", "flicker").str("video", "vtest.avi").str("decoder", backend).str("stage", t.stage);
      j.num("temporal_smoothing", t.temporal_smoothing).integer("frames", n);
      j.num("static_std_levels", kStaticLumaStd).num("mask_fraction", mask_fraction);
      j.num("mean_abs", mean / pairs).num("p95_abs", t.quantile(0.95)).num("worst_frame_mean_abs", worst);
      // One 8-bit grey level: the smallest change a depth picture shows.
      j.num("share_over_1_level", t.share_at_least(1.0 / 255.0)).num("mean_abs_all_pixels", mean_all / pairs);
      j.integer("cuts", t.decisions[0]).integer("smoothed", t.decisions[1]).integer("reused", t.decisions[2]);
      j.num("time_ms", median(t.ms)).integer("width", mask.cols).integer("height", mask.rows);
      w.emit(j);
      std::printf("flicker    %-8s smoothing %.2f  mean %.5f  p95 %.5f  (all pixels %.5f)  %6.1f ms/frame\n", t.stage,
                  t.temporal_smoothing, mean / pairs, t.quantile(0.95), mean_all / pairs, median(t.ms));
      std::fflush(stdout);
    }
}

int run(const Options &o) {
  std::ofstream out(o.out_path, std::ios::trunc);
  if (!out) {
    std::cerr << "pseudo3d-quality: cannot write " << o.out_path << "\n";
    return 1;
  }
  Writer w(out);
  emit_run_line(w, o);
  int rc = 0;
  const bool need_aloe = o.parts.count("synthesis") || o.parts.count("filter") || o.parts.count("depth");
  Aloe aloe;
  std::string err;
  if (need_aloe && !load_aloe(o.data_dir, aloe, err)) {
    w.error("aloe", err);
    rc = 1;
  } else if (need_aloe) {
    if (o.parts.count("synthesis")) {
      measure_baseline(w, aloe);
      measure_synthesis(w, aloe, o.runs);
    }
    if (o.parts.count("filter")) measure_filter_variants(w, aloe, o.runs);
    if (o.parts.count("depth")) measure_depth_rank(w, aloe, o.runs);
  }
  if (o.parts.count("flicker")) measure_flicker(w, o.data_dir + "/vtest.avi", o.frames);
  return rc;
}

}  // namespace
}  // namespace p3d::quality

int main(int argc, char **argv) {
  const p3d::quality::Options o = p3d::quality::parse_args(argc, argv);
  if (o.threads > 0) cv::setNumThreads(o.threads);
  try {
    return p3d::quality::run(o);
  } catch (const cv::Exception &e) {
    std::cerr << "pseudo3d-quality: OpenCV error: " << e.what() << "\n";
    return 1;
  }
}
