// GPU depth estimation against the CPU reference (common/depth_estimate.h).
//
// Tolerances: labels, temporal decisions and the mean difference must be
// identical (integer sums, a connected-components result defined by the
// smallest index, a fixed-point difference sum). Block depth and full depth
// are allowed 1e-6: both sides run the same P3D_HD functions in the same
// operation order (no FMA contraction on either side, IEEE division and
// sqrtf), so they are expected bitwise equal; 1e-6 (about 8 ulp at 1.0) only
// forgives a compiler reassociating a float expression, while the smallest
// real error (one hypothesis quantum, 1/65535 = 1.5e-5, or a block in the
// wrong region) is far larger. Every output starts poisoned with NaN, so an
// unwritten pixel counts as non-finite and fails.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "depth_estimate_gpu.h"
#include "gpu_util.h"
#include "test_data.h"
#include "warp_reduce_check.h"

namespace p3d {
namespace {

using test::check_cuda;
using test::DeviceDepth;
using test::DeviceFrame;
using test::format_name;
using test::kAllFormats;

constexpr double kDepthTolerance = 1e-6;  // see the file comment

uint32_t fresh_seed() { return std::random_device{}(); }

struct Result {
  cv::Mat depth;
  std::vector<int> labels;
  std::vector<float> block_depth;
  std::vector<float> smoothed;  // step 2's smoothed features
  TemporalDecision decision = TemporalDecision::Cut;
  float diff = -1.f;
};

Result run_cpu(DepthEstimatorCpu &est, const DepthParams &p, const HostFrame &f) {
  Result r;
  r.depth = cv::Mat(f.height(), f.width(), CV_32FC1, cv::Scalar(NAN));
  r.decision = est.estimate(p, f.view(), depth_view_of(r.depth));
  r.labels = est.labels();
  r.block_depth = est.block_depth();
  r.smoothed = est.smoothed_features();
  r.diff = est.last_diff();
  return r;
}

// block_grid: the estimate goes into the grid of the blocks' own cells
// (block_grid_shift(), what pseudo3ddepth hands on on CUDA memory) and is
// copied out to the pixels here, so every comparison with the CPU's
// full-size map holds for it too.
class GpuRunner {
 public:
  explicit GpuRunner(bool block_grid = false) : block_grid_(block_grid) {
    EXPECT_EQ(cudaSuccess, cudaStreamCreate(&stream_));
  }
  ~GpuRunner() { cudaStreamDestroy(stream_); }
  GpuRunner(const GpuRunner &) = delete;
  GpuRunner &operator=(const GpuRunner &) = delete;

  Result run(const DepthParams &p, const HostFrame &f) { return run_on(p, DeviceFrame::upload(f)); }
  Result run_on(const DepthParams &p, const DeviceFrame &frame) {
    Result r;
    const int w = frame.view().width, h = frame.view().height;
    DeviceDepth depth(w, h, block_grid_ ? block_grid_shift(p, w, h) : 0);  // NaN-poisoned
    check_cuda(est_.estimate(p, frame.view(), depth.grid(), stream_));
    check_cuda(est_.download_labels(r.labels, stream_));
    check_cuda(est_.download_block_depth(r.block_depth, stream_));
    check_cuda(est_.download_smoothed_features(r.smoothed, stream_));
    check_cuda(est_.last_decision(&r.decision, stream_));
    check_cuda(est_.last_diff(&r.diff, stream_));
    r.depth = depth.download();
    return r;
  }
  DepthEstimatorGpu &estimator() { return est_; }
  cudaStream_t stream() const { return stream_; }

 private:
  DepthEstimatorGpu est_;
  cudaStream_t stream_ = nullptr;
  bool block_grid_;
};

void expect_same(const Result &cpu, const Result &gpu, const std::string &what) {
  // The smoothed features decide the labels: one shared P3D_HD formula, bit for bit.
  ASSERT_EQ(cpu.smoothed.size(), gpu.smoothed.size()) << what;
  EXPECT_EQ(std::memcmp(cpu.smoothed.data(), gpu.smoothed.data(), cpu.smoothed.size() * sizeof(float)), 0)
      << what << ": smoothed features differ";
  ASSERT_EQ(cpu.labels.size(), gpu.labels.size()) << what;
  long long label_mismatch = 0;
  size_t first = 0;
  for (size_t k = 0; k < cpu.labels.size(); ++k)
    if (cpu.labels[k] != gpu.labels[k] && label_mismatch++ == 0) first = k;
  EXPECT_EQ(label_mismatch, 0) << what << ": first at block " << first << " cpu " << cpu.labels[first] << " gpu "
                               << gpu.labels[first];
  ASSERT_EQ(cpu.block_depth.size(), gpu.block_depth.size()) << what;
  double block_max = 0;
  long long block_nonfinite = 0;
  for (size_t k = 0; k < cpu.block_depth.size(); ++k) {
    if (!std::isfinite(gpu.block_depth[k])) ++block_nonfinite;
    else block_max = std::max(block_max, double(std::fabs(cpu.block_depth[k] - gpu.block_depth[k])));
  }
  EXPECT_EQ(block_nonfinite, 0) << what;
  EXPECT_LE(block_max, kDepthTolerance) << what;
  const test::FloatDiff d = test::compare_f32(cpu.depth, gpu.depth);
  EXPECT_EQ(d.nonfinite, 0) << what;
  EXPECT_LE(d.max_abs, kDepthTolerance) << what;
  EXPECT_EQ(cpu.decision, gpu.decision) << what;
  EXPECT_EQ(cpu.diff, gpu.diff) << what;
}

// One fresh CPU and GPU estimator on one frame, the GPU's map full-size
// and on the blocks' grid.
void compare_one(const DepthParams &p, const HostFrame &f, const std::string &what) {
  DepthEstimatorCpu cpu;
  GpuRunner gpu, gpu_grid(true);
  const Result c = run_cpu(cpu, p, f);
  expect_same(c, gpu.run(p, f), what);
  expect_same(c, gpu_grid.run(p, f), what + " (block grid)");
}

std::string describe(const HostFrame &f, const DepthParams &p) {
  return std::string(format_name(f.format())) + " " + std::to_string(f.width()) + "x" + std::to_string(f.height()) +
         " B=" + std::to_string(p.block_size) + " thr=" + std::to_string(p.edge_threshold) +
         " hyp=" + std::to_string(static_cast<int>(p.hypothesis));
}

// A picture of cell x cell squares, each one of two colours with probability
// near the site-percolation threshold: regions that sprawl across many tiles
// of the GPU union-find, with long and branching shapes.
cv::Mat percolation_picture(int w, int h, int cell, uint32_t seed) {
  std::mt19937 rng(seed);
  cv::Mat bgr(h, w, CV_8UC3);
  for (int y = 0; y < h; y += cell)
    for (int x = 0; x < w; x += cell) {
      const bool a = rng() % 1000 < 593;
      bgr(cv::Rect(x, y, std::min(cell, w - x), std::min(cell, h - y)))
          .setTo(a ? cv::Scalar(30, 60, 200) : cv::Scalar(220, 200, 40));
    }
  return bgr;
}

// One region shaped as a serpentine of `cell`-high stripes: the longest
// union-find chains a frame can make, winding through every tile.
cv::Mat serpentine_picture(int w, int h, int cell) {
  cv::Mat bgr(h, w, CV_8UC3, cv::Scalar(0, 0, 0));
  for (int r = 0; r * cell < h; r += 2) {
    bgr(cv::Rect(0, r * cell, w, std::min(cell, h - r * cell))).setTo(cv::Scalar(255, 255, 255));
    const int link_y = (r + 1) * cell;
    if (link_y >= h) break;
    const int link_x = (r / 2) % 2 == 0 ? w - cell : 0;
    bgr(cv::Rect(link_x, link_y, cell, std::min(cell, h - link_y))).setTo(cv::Scalar(255, 255, 255));
  }
  return bgr;
}

TEST(GpuDepth, RandomFramesAllFormatsAndBlockSizes) {
  std::mt19937 rng(fresh_seed());
  const int sizes[][2] = {{33, 17}, {640, 360}, {1001, 97}};
  for (PixelFormat fmt : kAllFormats)
    for (const auto &s : sizes)
      for (int B : {2, 3, 4, 7, 16, 64})
        for (float thr : {8.f, 24.f, 60.f}) {
          HostFrame f(fmt, s[0], s[1], 3);
          f.fill_random(rng());
          DepthParams p;
          p.block_size = B;
          p.edge_threshold = thr;
          p.hypothesis = static_cast<Hypothesis>(rng() % 4);
          compare_one(p, f, describe(f, p));
        }
}

TEST(GpuDepth, SmoothRandomFrames) {
  // Blurred noise: gradients make regions of every size, not just noise specks.
  std::mt19937 rng(fresh_seed());
  for (PixelFormat fmt : kAllFormats) {
    cv::Mat bgr(480, 700, CV_8UC3);
    cv::randu(bgr, 0, 256);
    cv::GaussianBlur(bgr, bgr, cv::Size(0, 0), 6);
    cv::normalize(bgr, bgr, 0, 255, cv::NORM_MINMAX);
    const HostFrame f = HostFrame::from_bgr(bgr, fmt, 1);
    for (int B : {2, 4, 8}) {
      DepthParams p;
      p.block_size = B;
      p.edge_threshold = 2.f + rng() % 12;
      compare_one(p, f, describe(f, p));
    }
  }
}

TEST(GpuDepth, PercolationMazes) {
  std::mt19937 rng(fresh_seed());
  const int sizes[][2] = {{500, 300}, {1920, 1080}};
  for (const auto &s : sizes)
    for (int B : {2, 4}) {
      const HostFrame f = HostFrame::from_bgr(percolation_picture(s[0], s[1], B, rng()), PixelFormat::RGBA);
      DepthParams p;
      p.block_size = B;
      compare_one(p, f, "percolation " + describe(f, p));
    }
}

TEST(GpuDepth, SerpentineRegion) {
  for (int B : {2, 4}) {
    const HostFrame f = HostFrame::from_bgr(serpentine_picture(3840, 2160, B), PixelFormat::BGRx);
    DepthParams p;
    p.block_size = B;
    DepthEstimatorCpu cpu;
    GpuRunner gpu;
    const Result c = run_cpu(cpu, p, f), g = gpu.run(p, f);
    expect_same(c, g, "serpentine " + describe(f, p));
    // White block rows are the even ones, all one snake through block 0.
    const int bx = cpu.blocks_x(), last_white = (cpu.blocks_y() - 1) & ~1;
    EXPECT_EQ(c.labels[static_cast<size_t>(last_white) * bx], 0);
    EXPECT_EQ(c.labels[static_cast<size_t>(last_white) * bx + bx - 1], 0);
  }
}

TEST(GpuDepth, AloeAllFormats) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  for (PixelFormat fmt : kAllFormats) {
    const HostFrame f = HostFrame::from_bgr(aloe, fmt, 7);
    for (int h = 0; h < 4; ++h)
      for (int B : {2, 4, 9}) {
        DepthParams p;
        p.hypothesis = static_cast<Hypothesis>(h);
        p.block_size = B;
        compare_one(p, f, "aloe " + describe(f, p));
      }
  }
}

TEST(GpuDepth, OddSizes) {
  std::mt19937 rng(fresh_seed());
  const int sizes[][2] = {{1, 1}, {3, 2}, {2, 3}, {33, 17}, {1001, 7}, {7, 1001}, {65, 65}};
  for (PixelFormat fmt : kAllFormats)
    for (const auto &s : sizes)
      for (int B : {2, 4, 5, 64}) {
        HostFrame f(fmt, s[0], s[1], 1);
        f.fill_random(rng());
        DepthParams p;
        p.block_size = B;
        p.edge_threshold = 40.f;
        compare_one(p, f, describe(f, p));
      }
}

// A grid whose cells are not the blocks (another shift, a block that is no
// power of two, cells of another size) is refused before anything is
// queued; the blocks' own grid is taken.
TEST(GpuDepth, BlockGridOfAnotherShiftIsRefused) {
  HostFrame f(PixelFormat::NV12, 64, 48, 2);
  f.fill_random(fresh_seed());
  const DeviceFrame df = DeviceFrame::upload(f);
  DepthEstimatorGpu est;
  DepthParams p;
  p.block_size = 4;
  const DeviceDepth two(64, 48, 1), four(64, 48, 2), eight(64, 48, 3);
  EXPECT_EQ(est.estimate(p, df.view(), two.grid(), nullptr).code, cudaErrorInvalidValue);
  EXPECT_EQ(est.estimate(p, df.view(), eight.grid(), nullptr).code, cudaErrorInvalidValue);
  DepthGrid<float> narrow = four.grid();
  narrow.cells.width -= 1;
  EXPECT_EQ(est.estimate(p, df.view(), narrow, nullptr).code, cudaErrorInvalidValue);
  DepthGrid<float> other_picture = four.grid();
  other_picture.width = 62;  // its cells fit (16 a row), its picture is not the frame's
  EXPECT_EQ(est.estimate(p, df.view(), other_picture, nullptr).code, cudaErrorInvalidValue);
  p.block_size = 6;
  EXPECT_EQ(block_grid_shift(p, 64, 48), 0);
  EXPECT_EQ(est.estimate(p, df.view(), two.grid(), nullptr).code, cudaErrorInvalidValue);
  p.block_size = 4;
  DepthGrid<float> no_cells = four.grid();
  no_cells.cells.data = nullptr;
  EXPECT_EQ(est.estimate(p, df.view(), no_cells, nullptr).code, cudaErrorInvalidValue);
  const DeviceDepth full(64, 48);
  DepthGrid<float> full_short = full.grid();  // a full-size map whose cells miss a row
  full_short.cells.height -= 1;
  EXPECT_EQ(est.estimate(p, df.view(), full_short, nullptr).code, cudaErrorInvalidValue);
  EXPECT_TRUE(est.estimate(p, df.view(), four.grid(), nullptr).ok());
  EXPECT_EQ(cudaSuccess, cudaDeviceSynchronize());
}

// 4:2:0 frames whose device rows do not start 4-byte aligned (an odd
// plane offset or stride, as a frame mapped from another allocator may
// have) take the features kernel's byte loads; aligned ones (every other
// test) its 32-bit loads. Both must give the CPU's result.
TEST(GpuDepth, UnalignedRowsMatchCpu) {
  std::mt19937 rng(fresh_seed());
  // Plane offset and extra stride bytes; {0, 6} leaves NV12's rows aligned.
  const int layouts[][2] = {{1, 1}, {0, 3}, {2, 2}, {3, 0}, {0, 6}};
  for (PixelFormat fmt : {PixelFormat::NV12, PixelFormat::I420})
    for (const auto &l : layouts)
      for (int B : {2, 4, 8}) {
        HostFrame f(fmt, 250, 66, 1);
        f.fill_random(rng());
        DepthParams p;
        p.block_size = B;
        p.edge_threshold = 30.f;
        const std::string what = describe(f, p) + " offset " + std::to_string(l[0]) + " stride+" + std::to_string(l[1]);
        DepthEstimatorCpu cpu;
        const Result want = run_cpu(cpu, p, f);
        GpuRunner gpu;
        expect_same(want, gpu.run_on(p, DeviceFrame::upload_at(f, l[0], l[1])), what);
      }
}

TEST(GpuDepth, Size3840x2160) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  cv::Mat big;
  cv::resize(aloe, big, cv::Size(3840, 2160), 0, 0, cv::INTER_LINEAR);
  for (PixelFormat fmt : {PixelFormat::NV12, PixelFormat::RGBA}) {
    const HostFrame f = HostFrame::from_bgr(big, fmt);
    for (int B : {2, 4, 8}) {
      DepthParams p;
      p.block_size = B;
      compare_one(p, f, "aloe " + describe(f, p));
    }
    HostFrame r(fmt, 3840, 2160);
    r.fill_random(fresh_seed());
    DepthParams p;
    p.edge_threshold = 60.f;
    compare_one(p, r, "random " + describe(r, p));
  }
}

TEST(GpuDepth, Size7680x4320) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  cv::Mat big;
  cv::resize(aloe, big, cv::Size(7680, 4320), 0, 0, cv::INTER_LINEAR);
  for (PixelFormat fmt : {PixelFormat::I420, PixelFormat::BGRx}) {
    const HostFrame f = HostFrame::from_bgr(big, fmt);
    for (int B : {2, 4}) {
      DepthParams p;
      p.block_size = B;
      compare_one(p, f, "aloe " + describe(f, p));
    }
  }
  HostFrame r(PixelFormat::NV12, 7680, 4320);
  r.fill_random(fresh_seed());
  DepthParams p;
  p.block_size = 2;
  p.edge_threshold = 90.f;
  compare_one(p, r, "random " + describe(r, p));
}

// Brightness shifted by `delta` levels (saturating).
cv::Mat shifted(const cv::Mat &bgr, int delta) {
  cv::Mat out;
  bgr.convertTo(out, -1, 1.0, delta);
  return out;
}

TEST(GpuDepth, TemporalSequenceMatches) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  cv::Mat inverted = cv::Scalar(255, 255, 255) - aloe;
  cv::Mat cropped = aloe(cv::Rect(0, 0, 600, 500)).clone();
  struct Step {
    cv::Mat picture;
    Hypothesis hypothesis;
    TemporalDecision expected;
  };
  const std::vector<Step> steps = {
      {aloe, Hypothesis::TopBottom, TemporalDecision::Cut},                 // first frame
      {aloe, Hypothesis::LeftRight, TemporalDecision::Reuse},               // static (new params ignored)
      {shifted(aloe, 6), Hypothesis::LeftRight, TemporalDecision::Smooth},  // small change
      {shifted(aloe, 6), Hypothesis::LeftRight, TemporalDecision::Reuse},
      {shifted(aloe, 12), Hypothesis::CenterNear, TemporalDecision::Smooth},
      {inverted, Hypothesis::CenterNear, TemporalDecision::Cut},            // scene cut
      {shifted(inverted, -5), Hypothesis::TopBottom, TemporalDecision::Smooth},
      {cropped, Hypothesis::TopBottom, TemporalDecision::Cut},              // size change
      {cropped, Hypothesis::TopBottom, TemporalDecision::Reuse},
  };
  for (PixelFormat fmt : kAllFormats) {
    DepthEstimatorCpu cpu;
    GpuRunner gpu, gpu_grid(true);  // the grid's Reuse frames write the kept block depths
    for (size_t i = 0; i < steps.size(); ++i) {
      const HostFrame f = HostFrame::from_bgr(steps[i].picture, fmt, 2);
      DepthParams p;
      p.hypothesis = steps[i].hypothesis;
      const std::string what = std::string(format_name(fmt)) + " step " + std::to_string(i);
      const Result c = run_cpu(cpu, p, f), g = gpu.run(p, f);
      EXPECT_EQ(c.decision, steps[i].expected) << what << " (cpu diff " << c.diff << ")";
      expect_same(c, g, what);
      expect_same(c, gpu_grid.run(p, f), what + " (block grid)");
    }
  }
}

// Step 2's feature smoothing over a stream: Aloe with fresh noise of a few
// levels in every frame (what flips edges on a static background), a square
// that moves (blocks past the motion gate take their new feature at once), a
// repeated frame (reused, smoothing still moves) and a scene cut. The
// automatic block size (2 here) and two smoothing weights; the test also
// checks that the smoothing changed the labels somewhere, so that it proves
// something about the smoothing.
TEST(GpuDepth, FeatureSmoothingSequenceMatches) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  std::mt19937 rng(fresh_seed());
  std::vector<cv::Mat> pictures;
  for (int i = 0; i < 10; ++i) {
    cv::Mat noise(aloe.size(), CV_16SC3), frame;
    cv::randu(noise, cv::Scalar::all(-3), cv::Scalar::all(4));
    aloe.convertTo(frame, CV_16SC3);
    frame += noise;
    frame.convertTo(frame, CV_8UC3);
    cv::rectangle(frame, cv::Rect(100 + 40 * i, 300, 120, 120), cv::Scalar(20, 240, 250), cv::FILLED);
    pictures.push_back(frame);
  }
  pictures.insert(pictures.begin() + 5, pictures[4]);              // reused
  pictures.push_back(cv::Scalar(255, 255, 255) - pictures.back());  // cut
  int smoothing_mattered = 0;
  for (PixelFormat fmt : {PixelFormat::I420, PixelFormat::NV12, PixelFormat::RGBA})
    for (const float w : {0.9f, 0.5f}) {
      DepthEstimatorCpu cpu;
      GpuRunner gpu;
      DepthParams p;
      p.feature_smoothing = w;
      for (size_t i = 0; i < pictures.size(); ++i) {
        const HostFrame f = HostFrame::from_bgr(pictures[i], fmt, 3);
        const std::string what =
            std::string(format_name(fmt)) + " smoothing " + std::to_string(w) + " frame " + std::to_string(i);
        const Result c = run_cpu(cpu, p, f);
        expect_same(c, gpu.run(p, f), what);
        std::vector<float> raw;
        std::vector<int> raw_labels;
        block_features_cpu(f.view(), effective_block_size(p, f.width(), f.height()), raw);
        region_labels_cpu(raw, cpu.blocks_x(), cpu.blocks_y(), p.edge_threshold, !is_packed_rgb(fmt), raw_labels);
        smoothing_mattered += raw_labels != c.labels;
        if (i == 5 || i + 1 == pictures.size()) {
          EXPECT_EQ(c.decision, i == 5 ? TemporalDecision::Reuse : TemporalDecision::Cut) << what;
        }
      }
    }
  EXPECT_GT(smoothing_mattered, 0) << "no frame where smoothing changed the regions: the test proves nothing";
}

TEST(GpuDepth, TemporalRandomSequenceAndReset) {
  std::mt19937 rng(fresh_seed());
  for (PixelFormat fmt : {PixelFormat::NV12, PixelFormat::RGBx}) {
    DepthEstimatorCpu cpu;
    GpuRunner gpu;
    const uint32_t base_seed = rng();
    DepthParams p;
    p.block_size = 3;
    p.static_threshold = 0.5f;
    p.cut_threshold = 8.f;
    for (int i = 0; i < 12; ++i) {
      // Change a random share of the bytes: diff lands anywhere around the thresholds.
      HostFrame f(fmt, 321, 203, 3);  // not a copy of a base frame: a HostFrame copy shares the planes
      f.fill_random(base_seed);
      const FrameView v = f.view();
      std::uniform_int_distribution<int> row(0, v.height - 1);
      const int changes = rng() % 20000;
      for (int k = 0; k < changes; ++k) v.plane[0][static_cast<size_t>(row(rng)) * v.stride[0] + rng() % v.width] ^= 0x40;
      if (i == 6) {
        cpu.reset();
        gpu.estimator().reset();
      }
      expect_same(run_cpu(cpu, p, f), gpu.run(p, f), std::string(format_name(fmt)) + " frame " + std::to_string(i));
    }
  }
}

TEST(GpuDepth, DepthFromGreyMatchesCpu) {
  std::mt19937 rng(fresh_seed());
  const int sizes[][2] = {{1, 1}, {3, 2}, {33, 17}, {1001, 7}, {3840, 2160}};
  cudaStream_t stream;
  ASSERT_EQ(cudaSuccess, cudaStreamCreate(&stream));
  for (PixelFormat fmt : kAllFormats)
    for (const auto &s : sizes) {
      HostFrame f(fmt, s[0], s[1], 5);
      f.fill_random(rng());
      const YuvToRgb m = yuv_to_rgb_params(0.2126, 0.0722, rng() % 2 == 0);
      cv::Mat want(s[1], s[0], CV_32FC1, cv::Scalar(NAN));
      depth_from_grey_cpu(f.view(), m, depth_view_of(want));
      const DeviceFrame df = DeviceFrame::upload(f);
      DeviceDepth dd(s[0], s[1]);
      check_cuda(depth_from_grey_gpu(df.view(), m, dd.view(), stream));
      ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream));
      const test::FloatDiff d = test::compare_f32(want, dd.download());
      const std::string what = std::string(format_name(fmt)) + " " + std::to_string(s[0]) + "x" + std::to_string(s[1]);
      EXPECT_EQ(d.nonfinite, 0) << what;
      EXPECT_LE(d.max_abs, kDepthTolerance) << what;  // one shared P3D_HD function
    }
  cudaStreamDestroy(stream);
}

// 4K and 8K frames, as a stream: the estimator keeps giving the CPU's answer
// with its buffers reused. (Speed is pseudo3d-bench's job, not a test's.)
TEST(GpuDepth, LargeFramesMatchCpu) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  struct Case {
    int w, h, block;
    PixelFormat fmt;
  };
  const Case cases[] = {{3840, 2160, 4, PixelFormat::NV12},
                        {3840, 2160, 4, PixelFormat::RGBA},
                        {7680, 4320, 2, PixelFormat::NV12}};
  for (const Case &k : cases) {
    cv::Mat big;
    cv::resize(aloe, big, cv::Size(k.w, k.h));
    const HostFrame f = HostFrame::from_bgr(big, k.fmt);
    const DeviceFrame frame = DeviceFrame::upload(f);
    DeviceDepth depth(f.width(), f.height());
    GpuRunner gpu;
    DepthParams p;
    p.block_size = k.block;
    p.static_threshold = -1.f;  // never reuse: the full computation every frame
    for (int i = 0; i < 3; ++i) check_cuda(gpu.estimator().estimate(p, frame.view(), depth.view(), gpu.stream()));
    const std::string name = std::to_string(k.w) + "x" + std::to_string(k.h) + "_" + format_name(k.fmt) + "_B" +
                             std::to_string(k.block);
    DepthEstimatorCpu cpu;
    const Result c = run_cpu(cpu, p, f);
    std::vector<int> labels;
    check_cuda(gpu.estimator().download_labels(labels, gpu.stream()));
    EXPECT_EQ(labels, c.labels) << name;
    const test::FloatDiff d = test::compare_f32(c.depth, depth.download());
    EXPECT_EQ(d.nonfinite, 0) << name;
    EXPECT_LE(d.max_abs, kDepthTolerance) << name;
  }
}

// The region reductions' warp sums and maxima: the shuffle form that Turing
// (sm_75) runs gives the very bits of the hardware instructions this GPU
// runs, and both the CPU's; random values over the whole range (sums wrap
// mod 2^32 alike) and the kernel's own range (at most 65535 a lane).
TEST(GpuDepth, WarpReductionsFallbackMatchesHardware) {
  std::mt19937 rng(fresh_seed());
  for (uint32_t top : {0xffffffffu, 65535u, 1u}) {
    std::vector<uint32_t> in(32 * 4096);
    for (uint32_t &v : in) v = static_cast<uint32_t>(rng()) % (top == 0xffffffffu ? top : top + 1);
    for (int k = 0; k < 32; ++k) in[32 * 7 + k] = top;  // a warp of equal lanes
    std::vector<uint32_t> out;
    check_cuda(test::warp_reductions_gpu(in, &out));
    for (size_t w = 0; w < in.size() / 32; ++w) {
      uint32_t sum = 0, mx = 0;
      for (int k = 0; k < 32; ++k) {
        sum += in[32 * w + k];
        mx = std::max(mx, in[32 * w + k]);
      }
      ASSERT_EQ(out[4 * w + 0], sum) << "warp " << w << ", top " << top;
      ASSERT_EQ(out[4 * w + 1], sum) << "warp " << w << ", top " << top;
      ASSERT_EQ(out[4 * w + 2], mx) << "warp " << w << ", top " << top;
      ASSERT_EQ(out[4 * w + 3], mx) << "warp " << w << ", top " << top;
    }
  }
}

}  // namespace
}  // namespace p3d
