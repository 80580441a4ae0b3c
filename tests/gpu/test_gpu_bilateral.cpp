// GPU cross-bilateral filter against the CPU reference.
//
// Tolerance: none. The kernel runs the CPU's own per-pixel code
// (bilateral_pixel) on the same host-computed weight tables, in the same
// summation order, with the same guide luma (load_luma), and nvcc builds it
// with -fmad=false while common/ uses -ffp-contract=off; IEEE float +, *, /
// then round identically on both sides, so every output must be
// bit-identical (max |diff| == 0). Outputs are poisoned with NaN first, so
// an unwritten pixel counts as non-finite and fails.
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "bilateral_gpu.h"
#include "gpu_util.h"
#include "test_data.h"

namespace p3d {
namespace {

using test::DeviceDepth;
using test::DeviceFrame;
using test::cell_constant;

uint32_t fresh_seed() { return std::random_device{}(); }

cv::Mat random_depth(int w, int h, uint32_t seed) {
  cv::Mat d(h, w, CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(d, cv::RNG::UNIFORM, 0.0, 1.0);
  return d;
}

HostFrame random_guide(PixelFormat f, int w, int h, uint32_t seed) {
  HostFrame g(f, w, h, 3);
  g.fill_random(seed);
  return g;
}

struct Result {
  long long differing = 0;   // outputs not bit-identical to the CPU's
  long long nonfinite = 0;   // includes never-written (poisoned) outputs
  double max_abs = 0;
};

Result compare_exact(const cv::Mat &gpu, const cv::Mat &cpu) {
  Result r;
  for (int y = 0; y < cpu.rows; ++y)
    for (int x = 0; x < cpu.cols; ++x) {
      const float g = gpu.at<float>(y, x), c = cpu.at<float>(y, x);
      if (!std::isfinite(g) || !std::isfinite(c)) {
        ++r.nonfinite;
        continue;
      }
      if (std::memcmp(&g, &c, sizeof g) != 0) ++r.differing;
      r.max_abs = std::max(r.max_abs, double(std::fabs(g - c)));
    }
  return r;
}

cv::Mat run_cpu(const BilateralParams &p, const HostFrame &guide, const cv::Mat &depth) {
  cv::Mat out(depth.size(), CV_32FC1);
  bilateral_filter_cpu(p, guide.view(), depth_view_of(depth), depth_view_of(out));
  return out;
}

// in_shift: the depth handed in on a grid of 2^in_shift-pixel cells (the
// estimator's blocks; `depth` must be constant over them, as
// cell_constant() makes it); grid_out: the output on the filter's own cell
// grid (bilateral_grid_shift()), as the elements hand them on on CUDA
// memory. The result comes back full-size either way.
cv::Mat run_gpu_on(BilateralFilterGpu &filter, const BilateralParams &p, const DeviceFrame &g, const cv::Mat &depth,
                   cudaStream_t stream = nullptr, int in_shift = 0, bool grid_out = false) {
  const DeviceDepth in = DeviceDepth::upload_grid(depth, in_shift);
  const int out_shift = grid_out ? bilateral_grid_shift(bilateral_sanitize(p), depth.cols, depth.rows) : 0;
  DeviceDepth out(depth.cols, depth.rows, out_shift);  // NaN-poisoned
  test::check_cuda(filter.run(p, g.view(), as_const(in.grid()), out.grid(), stream));
  return out.download();
}

// GPU vs CPU on one input, the guide in device memory as `device_guide`
// holds it; `what` names the case in failures.
void expect_identical_on(BilateralFilterGpu &filter, const BilateralParams &p, const HostFrame &guide,
                         const DeviceFrame &device_guide, const cv::Mat &depth, const std::string &what,
                         int in_shift = 0, bool grid_out = false) {
  SCOPED_TRACE(what + " " + test::format_name(guide.format()) + " " + std::to_string(depth.cols) + "x" +
               std::to_string(depth.rows) + " r=" + std::to_string(p.radius) +
               " ss=" + std::to_string(p.sigma_space) + " sr=" + std::to_string(p.sigma_range));
  const cv::Mat gpu = run_gpu_on(filter, p, device_guide, depth, nullptr, in_shift, grid_out);
  const cv::Mat cpu = run_cpu(p, guide, depth);
  const Result r = compare_exact(gpu, cpu);
  EXPECT_EQ(r.nonfinite, 0);
  EXPECT_EQ(r.differing, 0) << "max |diff| " << r.max_abs;
}
void expect_identical(BilateralFilterGpu &filter, const BilateralParams &p, const HostFrame &guide,
                      const cv::Mat &depth, const std::string &what) {
  expect_identical_on(filter, p, guide, DeviceFrame::upload(guide), depth, what);
}

TEST(GpuBilateral, RandomDepthRandomGuide) {
  BilateralFilterGpu filter;
  for (int i = 0; i < 3; ++i) {
    const uint32_t seed = fresh_seed();
    SCOPED_TRACE("seed " + std::to_string(seed));
    for (PixelFormat f : {PixelFormat::NV12, PixelFormat::RGBA})
      expect_identical(filter, {5, 3.f, 12.f}, random_guide(f, 257, 131, seed), random_depth(257, 131, seed + 1),
                       "random");
  }
}

// A real picture guiding a piecewise-constant depth (the depth estimator's
// coarse output looks like this): the filter's intended use.
TEST(GpuBilateral, AloeGuideBlockyDepth) {
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  cv::Mat small = random_depth((aloe.cols + 15) / 16, (aloe.rows + 15) / 16, fresh_seed()), depth;
  cv::resize(small, depth, cv::Size(small.cols * 16, small.rows * 16), 0, 0, cv::INTER_NEAREST);
  depth = depth(cv::Rect(0, 0, aloe.cols, aloe.rows)).clone();
  BilateralFilterGpu filter;
  for (PixelFormat f : test::kAllFormats)
    for (const BilateralParams p : {BilateralParams{5, 3.f, 12.f}, BilateralParams{9, 5.f, 25.f}})
      for (BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable}) {
        BilateralParams pm = p;
        pm.mode = mode;
        expect_identical(filter, pm, HostFrame::from_bgr(aloe, f, 5), depth, "aloe");
      }
}

class GpuBilateralFormats : public ::testing::TestWithParam<PixelFormat> {};

TEST_P(GpuBilateralFormats, OddSizesAndRadii) {
  BilateralFilterGpu filter;
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (const cv::Size sz : {cv::Size(1, 1), cv::Size(3, 2), cv::Size(2, 3), cv::Size(33, 17), cv::Size(1001, 7),
                            cv::Size(7, 301), cv::Size(161, 83)})
    for (int r : {0, 1, 5, 16})
      expect_identical(filter, {r, 0.7f * r + 0.5f, 20.f}, random_guide(GetParam(), sz.width, sz.height, seed),
                       random_depth(sz.width, sz.height, seed ^ 0x9e3779b9u), "odd");
}

// The Separable mode: two 1-D passes in one tiled kernel, the CPU's
// bilateral_pass_pixel on the same tables, so bit-identical too; odd sizes
// clip both passes, and 161x83 has unclipped blocks up to radius 16.
TEST_P(GpuBilateralFormats, SeparableOddSizesAndRadii) {
  BilateralFilterGpu filter;
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (const cv::Size sz : {cv::Size(1, 1), cv::Size(3, 2), cv::Size(33, 17), cv::Size(1001, 7), cv::Size(161, 83)})
    for (int r : {0, 1, 5, 16}) {
      BilateralParams p{r, 0.7f * r + 0.5f, 20.f};
      p.mode = BilateralMode::Separable;
      expect_identical(filter, p, random_guide(GetParam(), sz.width, sz.height, seed),
                       random_depth(sz.width, sz.height, seed ^ 0x85ebca6bu), "separable");
    }
}

INSTANTIATE_TEST_SUITE_P(GpuBilateral, GpuBilateralFormats, ::testing::ValuesIn(test::kAllFormats),
                         [](const auto &info) { return std::string(test::format_name(info.param)); });

// Each radius has its own kernel instantiation per mode; 203x97 has both
// interior (unrolled) and border (clipped) blocks at every radius.
TEST(GpuBilateral, EveryRadius) {
  BilateralFilterGpu filter;
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const HostFrame guide = random_guide(PixelFormat::RGBx, 203, 97, seed);
  const cv::Mat depth = random_depth(203, 97, seed + 5);
  for (int r = 0; r <= kMaxBilateralRadius; ++r)
    for (BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable}) {
      BilateralParams p{r, 0.5f * r + 0.3f, 18.f};
      p.mode = mode;
      expect_identical(filter, p, guide, depth, "radius");
    }
}

TEST(GpuBilateral, DegenerateParameters) {
  BilateralFilterGpu filter;
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const HostFrame guide = random_guide(PixelFormat::BGRx, 95, 47, seed);
  const cv::Mat depth = random_depth(95, 47, seed + 7);
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  for (float sr : {0.f, 1e-30f, 1e30f, inf, nan, -4.f})
    expect_identical(filter, {5, 3.f, sr}, guide, depth, "sigma_range");
  for (float ss : {0.f, 1e-30f, 1e30f, nan, -1.f}) expect_identical(filter, {5, ss, 12.f}, guide, depth, "sigma_space");
  for (int r : {-3, 17, 1000}) expect_identical(filter, {r, 4.f, 12.f}, guide, depth, "radius");
}

// One instance, changing parameters back and forth: stale tables would show.
TEST(GpuBilateral, ParameterChangesReuploadTables) {
  BilateralFilterGpu filter;
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const HostFrame guide = random_guide(PixelFormat::I420, 120, 66, seed);
  const cv::Mat depth = random_depth(120, 66, seed + 1);
  const BilateralParams a{5, 3.f, 12.f}, b{5, 3.f, 40.f}, c{2, 1.f, 12.f}, d{16, 8.f, 5.f};
  for (const BilateralParams &p : {a, b, a, c, d, c, a, a}) expect_identical(filter, p, guide, depth, "sequence");
}

// The output view is narrower than its allocation and has a pitch unlike the
// input's: the kernel must write exactly the view's pixels.
// The filter into a view narrower and shorter than its buffer: the view
// holds the CPU's result, and nothing right of it or below it is written.
void expect_writes_only_the_view(const BilateralParams &p) {
  const int w = 77, h = 29, pad = 19;
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed) + " scale " + std::to_string(p.scale));
  const HostFrame guide = random_guide(PixelFormat::NV12, w, h, seed);
  const cv::Mat depth = random_depth(w, h, seed + 3);
  const DeviceFrame g = DeviceFrame::upload(guide);
  const DeviceDepth in = DeviceDepth::upload(depth);
  DeviceDepth wide(w + pad, h + 1);
  ImageView<float> out = wide.view();
  out.width = w;
  out.height = h;
  BilateralFilterGpu filter;
  test::check_cuda(filter.run(p, g.view(), as_const(in.view()), out, nullptr));
  const cv::Mat all = wide.download();
  const Result r = compare_exact(all(cv::Rect(0, 0, w, h)).clone(), run_cpu(p, guide, depth));
  EXPECT_EQ(r.nonfinite, 0);
  EXPECT_EQ(r.differing, 0);
  EXPECT_EQ(cv::countNonZero(all(cv::Rect(w, 0, pad, h + 1)) == all(cv::Rect(w, 0, pad, h + 1))), 0)
      << "pixels right of the view were written";
  EXPECT_EQ(cv::countNonZero(all(cv::Rect(0, h, w, 1)) == all(cv::Rect(0, h, w, 1))), 0)
      << "the row below the view was written";
}

TEST(GpuBilateral, WritesOnlyTheOutputView) { expect_writes_only_the_view({4, 2.f, 15.f}); }

TEST(GpuBilateral, RejectsBadArguments) {
  const DeviceFrame g(PixelFormat::RGBA, 16, 8);
  DeviceDepth a(16, 8), b(16, 9);
  BilateralFilterGpu filter;
  EXPECT_EQ(filter.run({}, g.view(), as_const(a.view()), a.view(), nullptr).code, cudaErrorInvalidValue);
  EXPECT_EQ(filter.run({}, g.view(), as_const(b.view()), a.view(), nullptr).code, cudaErrorInvalidValue);
  EXPECT_EQ(filter.run({}, g.view(), as_const(a.view()), b.view(), nullptr).code, cudaErrorInvalidValue);
  ImageView<float> empty = a.view();
  empty.width = empty.height = 0;
  FrameView none = g.view();
  none.width = none.height = 0;
  EXPECT_TRUE(filter.run({}, none, as_const(empty), empty, nullptr).ok());
  EXPECT_EQ(cudaSuccess, cudaDeviceSynchronize());
}

// Large frames: full CPU comparison (16 cores make it a few seconds). Speed
// is pseudo3d-bench's job, not a test's.
void large_frame(int w, int h, const BilateralParams &p) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const cv::Mat aloe = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  cv::Mat big;
  cv::resize(aloe, big, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  cv::Mat small = random_depth(w / 32 + 1, h / 32 + 1, seed), depth;
  cv::resize(small, depth, cv::Size(w, h), 0, 0, cv::INTER_NEAREST);
  BilateralFilterGpu filter;
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::BGRx}) {
    const HostFrame guide = HostFrame::from_bgr(big, f);
    expect_identical(filter, p, guide, depth, "large");
  }
}

TEST(GpuBilateral, Uhd3840x2160) { large_frame(3840, 2160, {5, 3.f, 12.f}); }
TEST(GpuBilateral, Uhd3840x2160Radius16) { large_frame(3840, 2160, {16, 8.f, 12.f}); }
TEST(GpuBilateral, Uhd7680x4320) { large_frame(7680, 4320, {5, 3.f, 12.f}); }

// ---- the coarse grid (BilateralParams::scale): the kernels stage cells and
// write each result over its cell; bit-identical to the CPU's composition.

BilateralParams with_scale(BilateralParams p, BilateralMode mode, int scale) {
  p.mode = mode;
  p.scale = scale;
  return p;
}

// Random inputs: steps that divide the size and steps that leave partial
// cells, frames smaller than a cell, odd radii, every format family.
TEST_P(GpuBilateralFormats, CoarseGridOddSizesAndSteps) {
  BilateralFilterGpu filter;
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (const cv::Size sz : {cv::Size(1, 1), cv::Size(3, 2), cv::Size(33, 17), cv::Size(1001, 7), cv::Size(161, 83),
                            cv::Size(256, 128)})
    for (const int scale : {2, 3, 4, 8})
      for (const int r : {1, 5, 16})
        for (const BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable})
          expect_identical(filter, with_scale({r, 0.6f * r + 0.5f, 15.f}, mode, scale),
                           random_guide(GetParam(), sz.width, sz.height, seed + r),
                           random_depth(sz.width, sz.height, seed + 7 * r + scale),
                           "scale " + std::to_string(scale) + " mode " + std::to_string(static_cast<int>(mode)));
}

// The depth in on the estimator's block grid and the output on the filter's
// cell grid (what the elements hand on on CUDA memory): the CPU's result
// on the same maps at full size. Every step (3 has no grid: its output is
// full-size), blocks finer and coarser than the cells, partial cells and
// blocks at the edges, both modes.
TEST_P(GpuBilateralFormats, DepthGridsInAndOut) {
  BilateralFilterGpu filter;
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (const cv::Size sz : {cv::Size(1, 1), cv::Size(3, 2), cv::Size(33, 17), cv::Size(161, 83), cv::Size(256, 128)})
    for (const int in_shift : {1, 2, 3}) {
      const HostFrame guide = random_guide(GetParam(), sz.width, sz.height, seed + in_shift);
      const DeviceFrame device_guide = DeviceFrame::upload(guide);
      const cv::Mat depth = cell_constant(random_depth(sz.width, sz.height, seed + 11 * in_shift), in_shift);
      for (const int scale : {1, 2, 3, 4, 8})
        for (const int r : {1, 5})
          for (const BilateralMode mode : {BilateralMode::Exact, BilateralMode::Separable})
            for (const bool grid_out : {false, true})
              expect_identical_on(filter, with_scale({r, 0.6f * r + 0.5f, 15.f}, mode, scale), guide, device_guide,
                                  depth,
                                  "blocks of " + std::to_string(1 << in_shift) + " scale " + std::to_string(scale) +
                                      " mode " + std::to_string(static_cast<int>(mode)) +
                                      (grid_out ? " grid out" : " full out"),
                                  in_shift, grid_out);
    }
}

// An output grid of another shift than the filter's cells is refused
// before anything is queued.
TEST(GpuBilateral, DepthGridOfAnotherShiftIsRefused) {
  const DeviceFrame g(PixelFormat::RGBA, 64, 32);
  const DeviceDepth in(64, 32, 2), out1(64, 32, 1), out2(64, 32, 2);
  BilateralFilterGpu filter;
  const BilateralParams at4 = with_scale({5, 3.f, 12.f}, BilateralMode::Separable, 4);
  EXPECT_EQ(filter.run(at4, g.view(), as_const(in.grid()), out1.grid(), nullptr).code, cudaErrorInvalidValue);
  const BilateralParams at1 = with_scale({5, 3.f, 12.f}, BilateralMode::Separable, 1);
  EXPECT_EQ(filter.run(at1, g.view(), as_const(in.grid()), out2.grid(), nullptr).code, cudaErrorInvalidValue);
  DepthGrid<const float> short_in = as_const(in.grid());
  short_in.cells.height -= 1;
  EXPECT_EQ(filter.run(at4, g.view(), short_in, out2.grid(), nullptr).code, cudaErrorInvalidValue);
  EXPECT_TRUE(filter.run(at4, g.view(), as_const(in.grid()), out2.grid(), nullptr).ok());
  EXPECT_EQ(cudaSuccess, cudaDeviceSynchronize());
}

// Guides whose rows do not start 2- or 4-byte aligned (odd plane offsets
// and strides) take the cells' byte loads; aligned ones (every other test)
// their 16- and 32-bit loads. Both must give the CPU's result.
TEST(GpuBilateral, CoarseGridUnalignedGuideRows) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  BilateralFilterGpu filter;
  const cv::Mat depth = random_depth(250, 66, seed);
  // Plane offset and extra stride bytes; {0, 6} leaves NV12's luma rows 4-byte aligned.
  const int layouts[][2] = {{1, 1}, {0, 3}, {2, 2}, {3, 0}, {0, 6}};
  for (PixelFormat fmt : {PixelFormat::NV12, PixelFormat::I420})
    for (const auto &l : layouts)
      for (const int scale : {2, 4}) {
        const HostFrame guide = random_guide(fmt, 250, 66, seed + scale);
        expect_identical_on(filter, with_scale({5, 3.f, 12.f}, BilateralMode::Separable, scale), guide,
                            DeviceFrame::upload_at(guide, l[0], l[1]), depth,
                            "scale " + std::to_string(scale) + " offset " + std::to_string(l[0]) + " stride+" +
                                std::to_string(l[1]));
      }
}

// The defaults at 4K and 8K (the automatic step 4) on a real picture
// guiding the estimator-like blocky depth, and the exact mode at step 2.
TEST(GpuBilateral, CoarseGridAutomaticAtUhdAnd8K) {
  large_frame(3840, 2160, default_filter_params());
  large_frame(3840, 2160, with_scale({5, 3.f, 12.f}, BilateralMode::Exact, 2));
  large_frame(7680, 4320, default_filter_params());
}

// Cells at the view's right and bottom edges are cut to the view: nothing
// beside or below it is written, at a step whose float2 stores straddle it.
TEST(GpuBilateral, CoarseGridWritesOnlyTheOutputView) {
  for (const int scale : {2, 3})
    expect_writes_only_the_view(with_scale({4, 2.f, 15.f}, BilateralMode::Separable, scale));
}

// Steps and parameters changing from call to call on one instance: the
// tables follow the grid's radius and sigma, not the parameters as given.
TEST(GpuBilateral, CoarseGridStepChangesReuploadTables) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const HostFrame guide = random_guide(PixelFormat::I420, 203, 97, seed);
  const cv::Mat depth = random_depth(203, 97, seed + 1);
  BilateralFilterGpu filter;
  const BilateralParams a{5, 3.f, 12.f};
  for (const int scale : {1, 2, 1, 3, 3, 2, 8, 1})
    for (const BilateralMode mode : {BilateralMode::Separable, BilateralMode::Exact})
      expect_identical(filter, with_scale(a, mode, scale), guide, depth, "sequence scale " + std::to_string(scale));
}

}  // namespace
}  // namespace p3d
