// pseudo3d-depthmap: writes the depth map the pipeline would compute for a
// still image, as an 8-bit grey PNG (white = near, black = far).
//
// It runs the same CPU code as the elements with their default settings:
// pseudo3ddepth (DepthEstimatorCpu on an RGBA frame; a single image is a
// first frame, so no temporal smoothing) followed by pseudo3dfilter
// (bilateral_filter_cpu guided by the same frame), so the picture shows what
// pseudo3dwarp receives.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "bilateral.h"
#include "depth_estimate.h"
#include "depth_grey.h"
#include "host_frame.h"

namespace {

struct Options {
  std::string in, out;
  p3d::DepthParams depth;
  p3d::BilateralParams filter = p3d::default_filter_params();
};

void usage(FILE *f) {
  std::fprintf(f,
               "usage: pseudo3d-depthmap IN OUT.png [--hypothesis %s] [--radius N]\n"
               "  Estimates depth from IN (any image OpenCV reads) as pseudo3ddepth ! pseudo3dfilter do with\n"
               "  their defaults, and writes it as 8-bit grey (white = near). --radius 0 skips the filter.\n",
               p3d::enum_nicks(p3d::kHypothesisNames, "|").c_str());
}

bool parse_hypothesis(const char *s, p3d::Hypothesis &h) { return p3d::enum_from_nick(p3d::kHypothesisNames, s, &h); }

bool parse_radius(const char *s, int &radius) {
  char *end = nullptr;
  const long v = std::strtol(s, &end, 10);
  if (end == s || *end != '\0' || v < 0 || v > p3d::kMaxBilateralRadius) return false;
  radius = static_cast<int>(v);
  return true;
}

// Returns 0 when parsed, otherwise the exit status to leave with.
int parse_args(int argc, char **argv, Options &o) {
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    const char *a = argv[i];
    if (std::strcmp(a, "-h") == 0 || std::strcmp(a, "--help") == 0) {
      usage(stdout);
      return -1;
    }
    if (std::strcmp(a, "--hypothesis") == 0 || std::strcmp(a, "--radius") == 0) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "pseudo3d-depthmap: %s needs a value\n", a);
        return 2;
      }
      const char *v = argv[++i];
      const bool ok = a[2] == 'h' ? parse_hypothesis(v, o.depth.hypothesis) : parse_radius(v, o.filter.radius);
      if (!ok) {
        std::fprintf(stderr, "pseudo3d-depthmap: invalid value '%s' for %s\n", v, a);
        return 2;
      }
    } else if (a[0] == '-' && a[1] != '\0') {
      std::fprintf(stderr, "pseudo3d-depthmap: unknown option '%s'\n", a);
      usage(stderr);
      return 2;
    } else if (positional == 0) {
      o.in = a;
      ++positional;
    } else if (positional == 1) {
      o.out = a;
      ++positional;
    } else {
      std::fprintf(stderr, "pseudo3d-depthmap: too many arguments\n");
      usage(stderr);
      return 2;
    }
  }
  if (positional != 2) {
    usage(stderr);
    return 2;
  }
  return 0;
}

cv::Mat estimate_depth(const cv::Mat &bgr, const Options &o) {
  const p3d::HostFrame frame = p3d::HostFrame::from_bgr(bgr, p3d::PixelFormat::RGBA);
  cv::Mat depth(bgr.rows, bgr.cols, CV_32FC1);
  p3d::DepthEstimatorCpu estimator;
  estimator.estimate(o.depth, frame.view(), p3d::depth_view_of(depth));
  if (o.filter.radius == 0) return depth;
  cv::Mat filtered(depth.size(), CV_32FC1);
  p3d::bilateral_filter_cpu(o.filter, frame.view(), p3d::depth_view_of(static_cast<const cv::Mat &>(depth)),
                            p3d::depth_view_of(filtered));
  return filtered;
}

cv::Mat to_grey8(const cv::Mat &depth) {
  cv::Mat grey(depth.size(), CV_8UC1);
  p3d::export_depth_cpu(p3d::ImageView<const float>{depth.ptr<float>(), depth.cols, depth.rows, depth.step}, 8,
                        p3d::ImageView<uint8_t>{grey.ptr<uint8_t>(), grey.cols, grey.rows, grey.step});
  return grey;
}

}  // namespace

int main(int argc, char **argv) {
  Options o;
  const int rc = parse_args(argc, argv, o);
  if (rc != 0) return rc < 0 ? 0 : rc;

  cv::Mat bgr;
  try {
    bgr = cv::imread(o.in, cv::IMREAD_COLOR);
  } catch (const cv::Exception &e) {
    std::fprintf(stderr, "pseudo3d-depthmap: cannot read '%s': %s\n", o.in.c_str(), e.what());
    return 1;
  }
  if (bgr.empty()) {
    std::fprintf(stderr, "pseudo3d-depthmap: cannot read '%s' as an image\n", o.in.c_str());
    return 1;
  }

  const cv::Mat grey = to_grey8(estimate_depth(bgr, o));
  bool written = false;
  try {
    written = cv::imwrite(o.out, grey);
  } catch (const cv::Exception &e) {
    std::fprintf(stderr, "pseudo3d-depthmap: cannot write '%s': %s\n", o.out.c_str(), e.what());
    return 1;
  }
  if (!written) {
    std::fprintf(stderr, "pseudo3d-depthmap: cannot write '%s'\n", o.out.c_str());
    return 1;
  }
  return 0;
}
