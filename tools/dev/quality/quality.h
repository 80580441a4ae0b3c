// pseudo3d-quality: error against run time on real data, with the CPU
// reference code (common/). One file per study, this header for what they
// share:
//   main.cpp             command line, the run line, which studies run
//   common.cpp           output, timing, statistics, the Aloe data set
//   synthesis.cpp        Aloe's right view for every hole fill and depth filter,
//                        and peers' inpainting in the same holes
//   filter_variants.cpp  exact cross-bilateral window against its faster variants
//   depth_rank.cpp       single-picture depth against Aloe's ground truth, per cue
//   filter_scale.cpp     the filter on a coarser grid, on Aloe enlarged to 4K and 8K sizes
//   flicker.cpp          depth change on vtest.avi's static background
// scripts/quality-report.sh turns the JSON lines into docs/quality.md and
// docs/img/quality-vs-time.png (scripts/plot_quality.py).
#pragma once

#include <chrono>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bilateral.h"
#include "depth_estimate.h"
#include "host_frame.h"
#include "json_line.h"
#include "warp.h"

namespace p3d::quality {

using p3d::tools::JsonLine;

struct Options {
  std::string data_dir = "data";
  std::string out_path = "quality.jsonl";
  int runs = 5;
  int frames = 200;
  int threads = -1;  // -1: OpenCV's default
  // "peers" (OpenCV's inpainting in the warp's holes, minutes on the CPU)
  // runs only when asked for (--only peers).
  std::set<std::string> parts = {"synthesis", "filter", "depth", "scale", "flicker"};
  // The cross-bilateral filter's mode in the depth and flicker studies
  // (what pseudo3dfilter runs; its other parameters are the defaults).
  BilateralMode filter_mode = kDefaultFilterMode;
  std::string argv;
};

// ---- output -----------------------------------------------------------------------

class Writer {
 public:
  explicit Writer(std::ofstream &out) : out_(out) {}
  void emit(const JsonLine &j);
  void error(const std::string &kind, const std::string &msg);

 private:
  std::ofstream &out_;
};

// The first line: date, commit, arguments, CPU, threads, OpenCV.
void emit_run_line(Writer &w, const Options &o);

// ---- timing and statistics ----------------------------------------------------------

double elapsed_ms(std::chrono::steady_clock::time_point t0);
double median(std::vector<double> v);

// Wall times of one measured configuration.
struct Timing {
  std::vector<double> ms;
  double median_ms() const { return median(ms); }
  double min_ms() const;
};

// Times every job `runs` times, round-robin (run i of every job before run
// i+1 of any): the machine is shared, and a burst of someone else's load
// then slows all configurations alike instead of one of them.
std::vector<Timing> time_interleaved(int runs, const std::vector<std::function<void()>> &jobs);

// Spearman rank correlation (ties get their average rank); NaN when either
// side is constant.
double spearman(const std::vector<double> &a, const std::vector<double> &b);

// Error of depth map b against a (CV_32FC1, depth units 0..1); PSNR of
// depth * 255 with peak 255, i.e. 10 log10(1 / MSE).
struct MapError {
  double max_abs = 0, mean_abs = 0, psnr = 0;
};
MapError map_error(const cv::Mat &a, const cv::Mat &b);

// ---- Aloe ---------------------------------------------------------------------------

struct Aloe {
  double scale = 1.0;   // 1: as shipped; 0.5: both views INTER_AREA-downscaled, GT nearest
  cv::Mat left, right;  // BGR, cropped to an even width like the Aloe test
  cv::Mat gt;           // CV_8UC1 disparity in this picture's pixels, 0 = unknown
  double max_gt = 0;
  HostFrame left_frame;  // RGBA, the warp's source and the filter's guide
  cv::Mat gt_depth;      // CV_32FC1, GT / max(GT) through a grey picture (RGBD input)
  WarpParams warp;       // view=right, convergence 0, max-disparity = max(GT)
  cv::Mat mask;          // right-view pixels with a known correspondence (CV_8UC1)
};

// Loads data/aloe{L,R,GT} at `scale` (1 or 0.5). False with a message in err.
bool load_aloe(const std::string &dir, double scale, Aloe &a, std::string &err);

// Renders the right view from the left view and `depth` with `fill` into
// `out` (a 2W x H scratch frame). Returns the warp's hole count.
long long render_right(const Aloe &a, const cv::Mat &depth, HoleFill fill, HostFrame &out);
cv::Mat right_half_bgr(const HostFrame &out);

cv::Mat filter_depth(const BilateralParams &bp, const FrameView &guide, const cv::Mat &depth);
// sigma_space = 0.6 radius (radius 5 is the element's default, sigma 3), sigma_range 12.
BilateralParams study_filter(int radius, BilateralMode mode = BilateralMode::Exact);
cv::Mat estimated_depth(const DepthParams &dp, const FrameView &frame);

const char *fill_name(HoleFill f);
const char *hypothesis_name(Hypothesis h);

// ---- the studies ----------------------------------------------------------------------

void measure_baseline(Writer &w, const Aloe &a);
void measure_synthesis(Writer &w, const Aloe &a, int runs);
// Peers' inpainting (OpenCV photo and xphoto) in the same warp's holes.
void measure_peer_fills(Writer &w, const Aloe &a);
void measure_filter_variants(Writer &w, const Aloe &a, int runs);
// full: Aloe as shipped; half: the same at half size (the cues must not
// depend on the picture's resolution).
void measure_depth_rank(Writer &w, const Aloe &full, const Aloe &half, int runs, BilateralMode filter_mode);
// The fixed random sample of known-GT pixels (indices into a continuous
// W x H map) that the depth ranks are taken over.
std::vector<int> rank_sample(const cv::Mat &gt);
// The filter's grid step (BilateralParams::scale) on Aloe as shipped and
// enlarged 2x and 4x (where the automatic step is 1, 4 and 4): view
// synthesis, depth rank and filter time against every pixel's filter.
void measure_filter_scale(Writer &w, const Aloe &a, int runs);
void measure_flicker(Writer &w, const std::string &path, int frames, BilateralMode filter_mode);

}  // namespace p3d::quality
