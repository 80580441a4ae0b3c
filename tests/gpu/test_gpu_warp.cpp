// WarpRendererGpu against warp_render_cpu. Tolerance: none. Every
// per-pixel decision (targets, coverage, keys, bilinear colour, background
// pick, neighbour mean) is one P3D_HD helper of common/warp.h compiled
// without contraction on both sides (-ffp-contract=off / -fmad=false); the
// z-buffer is a max (order independent, so atomicMax = sequential max) and
// NeighborAverage is a Jacobi iteration (order independent), so every byte
// of the output, the 4th byte of X formats included, and the hole count
// must match.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gpu_util.h"
#include "pack.h"
#include "test_data.h"
#include "warp.h"
#include "warp_gpu.h"

namespace p3d {
namespace {

using test::warp_params;
using test::kAllFills;
using test::kAllViews;
using test::kAllFormats;
using test::kPackedFormats;
using test::cell_constant;
using test::kAllGlasses;
using test::kAllLayouts;
using test::kAllMethods;
using test::pack_params;

constexpr uint8_t kCpuPoison = 0x5A;  // DeviceFrame poisons with 0xA5: unwritten bytes differ

constexpr double kPi = 3.14159265358979323846;

uint32_t fresh_seed() { return std::random_device{}(); }

enum class DepthKind { Smooth, Noise, Binary };

// Smooth: two random sinusoids (a surface with slopes and occlusions);
// Noise: uniform per pixel; Binary: 0/1 per pixel (the depth extremes).
cv::Mat random_depth(int w, int h, DepthKind kind, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  cv::Mat d(h, w, CV_32FC1);
  const double lx = 8 + 200 * u01(rng), ly = 8 + 200 * u01(rng), px = u01(rng), py = u01(rng);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double v = 0;
      if (kind == DepthKind::Smooth)
        v = 0.5 + 0.25 * std::sin(2 * kPi * (x / lx + px)) + 0.25 * std::sin(2 * kPi * (y / ly + py));
      else if (kind == DepthKind::Noise)
        v = u01(rng);
      else
        v = static_cast<double>(rng() & 1);
      d.at<float>(y, x) = static_cast<float>(v);
    }
  return d;
}

const char *kind_name(DepthKind k) {
  return k == DepthKind::Smooth ? "smooth" : k == DepthKind::Noise ? "noise" : "binary";
}

std::string describe(const WarpParams &p, PixelFormat src, PixelFormat out, int w, int h) {
  std::ostringstream s;
  s << test::format_name(src) << "->" << test::format_name(out) << " " << w << "x" << h << " max_disparity "
    << p.max_disparity << " convergence " << p.convergence << " view " << int(p.view) << " fill " << int(p.fill);
  return s.str();
}

// First differing byte of two packed frames of one size, or "".
std::string first_difference(const HostFrame &want, const HostFrame &got) {
  const FrameView a = want.view(), b = got.view();
  long long differing = 0;
  std::ostringstream first;
  for (int y = 0; y < a.height; ++y)
    for (int i = 0; i < 4 * a.width; ++i) {
      const int va = a.plane[0][static_cast<size_t>(y) * a.stride[0] + i];
      const int vb = b.plane[0][static_cast<size_t>(y) * b.stride[0] + i];
      if (va == vb) continue;
      if (differing++ == 0)
        first << "first at pixel (" << i / 4 << "," << y << ") byte " << i % 4 << ": cpu " << va << " gpu " << vb;
    }
  if (differing == 0) return "";
  return std::to_string(differing) + " bytes differ, " + first.str();
}

// The same for frames of any format: every luma and chroma sample of a
// 4:2:0 frame, the pixels of a packed one.
std::string frame_difference(const HostFrame &want, const HostFrame &got) {
  if (is_packed_rgb(want.format())) return first_difference(want, got);
  const FrameView a = want.view(), b = got.view();
  long long differing = 0;
  std::ostringstream first;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      int ua = 0, va = 0, ub = 0, vb = 0;
      load_chroma(a, x, y, &ua, &va);
      load_chroma(b, x, y, &ub, &vb);
      const bool same = load_luma(a, x, y) == load_luma(b, x, y) && ua == ub && va == vb;
      if (!same && differing++ == 0) first << "first at pixel (" << x << "," << y << ")";
    }
  if (differing == 0) return "";
  return std::to_string(differing) + " pixels differ, " + first.str();
}

std::string describe(const PackParams &p, PixelFormat out) {
  std::ostringstream s;
  s << "layout " << int(p.layout) << " glasses " << int(p.glasses) << " method " << int(p.method) << " swap "
    << p.swap_eyes << " into " << test::format_name(out);
  return s.str();
}

// Whether this GPU resolves the rows of a group together where the tests
// below expect it (Hopper: RowsTogether blocks at their widths), so that
// render_packed fuses the anaglyph there.
bool fuses_on_this_gpu() {
  int dev = 0, major = 0;
  cudaGetDevice(&dev);
  cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, dev);
  return major == 9;
}

class GpuWarpTest : public ::testing::Test {
 public:
  void SetUp() override { test::check_cuda(CudaStatus{cudaStreamCreate(&stream_), "cudaStreamCreate", __FILE__, __LINE__}); }
  void TearDown() override {
    if (stream_) cudaStreamDestroy(stream_);
  }

  // Renders on both sides and asserts identical bytes and hole counts.
  // depth_shift: the GPU reads the depth on a grid of 2^depth_shift-pixel
  // cells (the filter's cells, as the elements hand them on on CUDA
  // memory); `depth` must then be constant over them (cell_constant).
  void expect_same(const WarpParams &p, const HostFrame &src, const cv::Mat &depth,
                   PixelFormat out_format = PixelFormat::RGBA, const YuvToRgb &m = YuvToRgb(), int depth_shift = 0) {
    const int w = src.width(), h = src.height();
    SCOPED_TRACE(describe(p, src.format(), out_format, w, h));
    HostFrame cpu(out_format, 2 * w, h, 12);
    cpu.fill(kCpuPoison);
    const long long cpu_holes = warp_render_cpu(p, src.view(), m, depth_view_of(depth), cpu.view());
    ASSERT_GE(cpu_holes, 0);

    const test::DeviceFrame dsrc = test::DeviceFrame::upload(src);
    const test::DeviceDepth ddepth = test::DeviceDepth::upload_grid(depth, depth_shift);
    const test::DeviceFrame dout(out_format, 2 * w, h);  // poisoned
    long long gpu_holes = -7;
    test::check_cuda(renderer_.render(p, dsrc.view(), m, as_const(ddepth.grid()), dout.view(), stream_, &gpu_holes));
    ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
    EXPECT_EQ(gpu_holes, cpu_holes);
    EXPECT_EQ(first_difference(cpu, dout.download()), "");
  }

  // render_packed against warp_render_cpu, then pack_cpu of its pair (in
  // the output's packed format, RGBA for 4:2:0), every visible byte.
  // Returns whether the GPU fused the pack into the warp.
  bool expect_packed_same(const WarpParams &w, const PackParams &pp, const HostFrame &src, const cv::Mat &depth,
                          int depth_shift, PixelFormat out_format) {
    const int sw = src.width(), sh = src.height();
    SCOPED_TRACE(describe(w, src.format(), out_format, sw, sh) + " " + describe(pp, out_format));
    int pw = 0, ph = 0;
    pack_size(pp.layout, sw, sh, &pw, &ph);
    HostFrame pair(is_packed_rgb(out_format) ? out_format : PixelFormat::RGBA, 2 * sw, sh, 4);
    HostFrame cpu(out_format, pw, ph, 12);
    cpu.fill(kCpuPoison);
    EXPECT_GE(warp_render_cpu(w, src.view(), YuvToRgb(), depth_view_of(depth), pair.view()), 0);
    pack_cpu(pp, pair.view(), cpu.view());

    const test::DeviceFrame dsrc = test::DeviceFrame::upload(src);
    const test::DeviceDepth ddepth = test::DeviceDepth::upload_grid(depth, depth_shift);
    const test::DeviceFrame dout(out_format, pw, ph);  // poisoned
    bool fused = false;
    test::check_cuda(
        renderer_.render_packed(w, pp, dsrc.view(), YuvToRgb(), as_const(ddepth.grid()), dout.view(), stream_, &fused));
    EXPECT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
    EXPECT_EQ(frame_difference(cpu, dout.download()), "");
    return fused;
  }

  // A random NV12 frame of w x h on depth cells of 2, 4 and 8 rows, both
  // eyes warped (the only case with row groups), every fill.
  void expect_row_groups(int w, int h, float max_disparity, PixelFormat out_format) {
    const uint32_t seed = fresh_seed();
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    std::mt19937 rng(seed);
    HostFrame src(PixelFormat::NV12, w, h, 2);
    src.fill_random(rng());
    for (const int shift : {1, 2, 3}) {
      SCOPED_TRACE(::testing::Message() << "cells of " << (1 << shift));
      const cv::Mat depth = cell_constant(random_depth(w, h, DepthKind::Smooth, rng()), shift);
      for (HoleFill f : kAllFills)
        expect_same(warp_params(max_disparity, 0.5f, StereoView::Both, f), src, depth, out_format, YuvToRgb(), shift);
    }
  }

  WarpRendererGpu renderer_;
  cudaStream_t stream_ = nullptr;
};

using GpuWarp = GpuWarpTest;
using GpuWarpLarge = GpuWarpTest;

// Every fill x view on random depth of three kinds, random parameters.
TEST_F(GpuWarp, AllModesRandomDepth) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.f, 1.f);
  for (DepthKind kind : {DepthKind::Smooth, DepthKind::Noise, DepthKind::Binary}) {
    SCOPED_TRACE(kind_name(kind));
    HostFrame src(kind == DepthKind::Noise ? PixelFormat::NV12 : PixelFormat::RGBA, 257, 131, 6);
    src.fill_random(rng());
    const cv::Mat depth = random_depth(257, 131, kind, rng());
    for (StereoView v : kAllViews)
      for (HoleFill f : kAllFills) expect_same(warp_params(1.f + 24.f * u01(rng), u01(rng), v, f), src, depth);
  }
}

// The depth read in place on the filter's cell grid (what the elements
// hand on on CUDA memory): the CPU's render of the same map at full size,
// every fill and view, cells cut at the right and bottom edges, and cells
// out of range or NaN (the warp's clamping happens per read, on both
// sides).
TEST_F(GpuWarp, DepthOnCellGrids) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.f, 1.f);
  const int sizes[][2] = {{257, 131}, {33, 17}, {3, 2}};
  for (const int shift : {1, 2, 3})
    for (const auto &s : sizes)
      for (DepthKind kind : {DepthKind::Smooth, DepthKind::Noise}) {
        SCOPED_TRACE(::testing::Message() << "cells of " << (1 << shift) << " " << kind_name(kind));
        HostFrame src(PixelFormat::NV12, s[0], s[1], 6);
        src.fill_random(rng());
        cv::Mat depth = random_depth(s[0], s[1], kind, rng());
        const float specials[] = {NAN, -0.5f, 1.5f, 0.f, 1.f};
        for (const float v : specials) depth.at<float>(rng() % s[1], rng() % s[0]) = v;
        depth = cell_constant(depth, shift);
        for (StereoView v : kAllViews)
          for (HoleFill f : kAllFills)
            expect_same(warp_params(1.f + 24.f * u01(rng), u01(rng), v, f), src, depth, PixelFormat::RGBA, YuvToRgb(),
                        shift);
      }
}

// Rows that share their depth cells share one scatter (cuda/warp_plan.h,
// choose_row_kernels): at the widths above, on Hopper, in RowsTogether
// blocks (a source row buffer for each row); here, 6000 pixels, in
// WideGroup blocks (rows one after another), where neither a RowsTogether
// block nor a row's block with both z-buffers keeps as many threads
// resident (on Hopper: two WideGroup blocks an SM against three of a
// row's size). Which kernel a width gets depends on the GPU's shared
// memory; the 4K chain tests (test_gpu_extremes.cpp) run 3840-pixel rows
// on the automatic grid. 67 rows leave a last group short at every cell
// size; both eyes are warped (the only case with groups), every fill.
TEST_F(GpuWarp, RowGroupsInWideRows) { expect_row_groups(6000, 67, 2.f, PixelFormat::BGRx); }

// More row groups than the GPU holds blocks of at once, not a whole number
// of waves of them (cuda/warp_plan.h, group_tail_y0): the groups that fill
// whole waves go first, the rows after them a block each (at these widths,
// RowsTogether blocks on Hopper, a block for each eye of each row). 1363
// rows are 341 groups of 4 (the last of 3 rows), more than the 264
// resident blocks of a 132-SM Hopper card at these widths and not a
// multiple of them, so the tail starts inside the frame and ends at a
// short group's rows; cells of 2 rows give groups of 2 (682 of them),
// cells of 8 groups of 4 again (at most 4 rows a group). 402 pixels is not
// a multiple of 4: the second eye's z-buffer then starts off 16-byte
// alignment. The 8K
// chain tests (test_gpu_extremes.cpp) meet the tail of WideGroup blocks.
TEST_F(GpuWarp, RowGroupsThenSingleRowsPastTheLastWholeWave) {
  expect_row_groups(400, 1363, 6.f, PixelFormat::RGBA);
  expect_row_groups(402, 1363, 6.f, PixelFormat::RGBA);
}

// Frames queued back to back with no host sync between them, as the
// elements queue them: every frame's kernels are chained to the last
// frame's (cuda/chained_launch.cuh), and BackgroundSmooth's tile marks
// and count are cleared every frame by a kernel of their own (the list is
// read up to the count; cuda/warp.cu), so a frame that read the last
// one's counters or tiles would show as a wrong frame here. Noise depth lists every tile, smooth
// depth a few; sizes alternate (buffers reused), on cells of 4 rows (row
// groups and their one-row tail) and full-size depth; each output is its
// own frame, checked against the CPU once all are queued.
TEST_F(GpuWarp, BackgroundSmoothFramesQueuedBackToBack) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  struct Frame {
    HostFrame src;
    cv::Mat depth;
    int shift;
  };
  std::vector<Frame> frames;
  const int sizes[][2] = {{1283, 1091}, {640, 360}};
  for (int k = 0; k < 8; ++k) {
    const int w = sizes[k % 2][0], h = sizes[k % 2][1], shift = k % 4 < 2 ? 2 : 0;
    HostFrame src(PixelFormat::NV12, w, h, 2);
    src.fill_random(rng());
    const DepthKind kind = k % 3 == 0 ? DepthKind::Noise : DepthKind::Smooth;
    frames.push_back(Frame{std::move(src), cell_constant(random_depth(w, h, kind, rng()), shift), shift});
  }
  const WarpParams p = warp_params(4.f, 0.5f, StereoView::Both, HoleFill::BackgroundSmooth);
  std::vector<test::DeviceFrame> srcs, outs;
  std::vector<test::DeviceDepth> depths;
  for (const Frame &f : frames) {
    srcs.push_back(test::DeviceFrame::upload(f.src));
    depths.push_back(test::DeviceDepth::upload_grid(f.depth, f.shift));
    outs.emplace_back(PixelFormat::RGBA, 2 * f.src.width(), f.src.height());
  }
  ASSERT_EQ(cudaSuccess, cudaDeviceSynchronize());
  for (size_t k = 0; k < frames.size(); ++k)
    test::check_cuda(
        renderer_.render(p, srcs[k].view(), YuvToRgb(), as_const(depths[k].grid()), outs[k].view(), stream_));
  ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
  for (size_t k = 0; k < frames.size(); ++k) {
    SCOPED_TRACE(::testing::Message() << "frame " << k);
    const Frame &f = frames[k];
    HostFrame cpu(PixelFormat::RGBA, 2 * f.src.width(), f.src.height(), 12);
    cpu.fill(kCpuPoison);
    ASSERT_GE(warp_render_cpu(p, f.src.view(), YuvToRgb(), depth_view_of(f.depth), cpu.view()), 0);
    EXPECT_EQ(first_difference(cpu, outs[k].download()), "");
  }
}

// The pack fused into the warp (render_packed): an anaglyph on gamma
// values with BackgroundSmooth, where the rows of a group are resolved
// together. The row kernel writes the anaglyph where neither eye has a
// hole, the rest goes through the pair: the sums kernel's fill, then a
// kernel that mixes the holes of the listed tiles and the tail rows (whose
// blocks render one eye each). Every method but dubois-linear, all glasses,
// either eye first, three output formats; groups of 2 and 4 rows; smooth
// depth (a few tiles listed) and noise (every tile); 1363 rows leave a
// tail past the last whole wave (RowGroupsThenSingleRowsPastTheLastWholeWave),
// at a width that is a multiple of 4 and one that is not; an RGBA source
// with random alpha, either eye first; and the Aloe image with its true
// depth on cells of 4. Each is byte for byte
// warp_render_cpu then pack_cpu, and on Hopper each ran fused.
TEST_F(GpuWarp, PackFusedIntoTheWarp) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  const bool hopper = fuses_on_this_gpu();
  const PixelFormat formats[] = {PixelFormat::RGBA, PixelFormat::BGRx, PixelFormat::BGRA};
  const WarpParams w = warp_params(6.f, 0.5f, StereoView::Both, HoleFill::BackgroundSmooth);
  {
    HostFrame src(PixelFormat::NV12, 400, 1363, 2);
    src.fill_random(rng());
    const cv::Mat depth = cell_constant(random_depth(400, 1363, DepthKind::Smooth, rng()), 2);
    int k = 0;
    for (AnaglyphGlasses g : kAllGlasses)
      for (AnaglyphMethod m : kAllMethods) {
        if (m == AnaglyphMethod::DuboisLinear) continue;
        const bool fused = expect_packed_same(w, pack_params(PackLayout::Anaglyph, g, m, k % 2 == 1), src, depth, 2,
                                              formats[k % 3]);
        if (hopper) {
          EXPECT_TRUE(fused);
        }
        ++k;
      }
  }
  const int sizes[][2] = {{402, 1363}, {1283, 531}};
  for (const auto &size : sizes)
    for (const int shift : {1, 2})
      for (DepthKind kind : {DepthKind::Smooth, DepthKind::Noise}) {
        SCOPED_TRACE(::testing::Message() << "cells of " << (1 << shift) << " " << kind_name(kind));
        HostFrame src(PixelFormat::BGRx, size[0], size[1], 3);
        src.fill_random(rng());
        const cv::Mat depth = cell_constant(random_depth(size[0], size[1], kind, rng()), shift);
        const PackParams pp = pack_params(PackLayout::Anaglyph, AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois,
                                          shift == 1);
        const bool fused = expect_packed_same(w, pp, src, depth, shift, formats[shift]);
        if (hopper) {
          EXPECT_TRUE(fused);
        }
      }
  // A source with its own alpha (random), either eye first: the anaglyph's
  // alpha is the left view's as shown, the swapped eye's with swap-eyes.
  for (const bool swap : {false, true})
    for (const PixelFormat out : {PixelFormat::RGBA, PixelFormat::BGRA}) {
      HostFrame src(PixelFormat::RGBA, 402, 203, 1);
      src.fill_random(rng());
      const cv::Mat depth = cell_constant(random_depth(402, 203, DepthKind::Smooth, rng()), 2);
      const bool fused = expect_packed_same(
          w, pack_params(PackLayout::Anaglyph, AnaglyphGlasses::GreenMagenta, AnaglyphMethod::Dubois, swap), src,
          depth, 2, out);
      if (hopper) {
        EXPECT_TRUE(fused);
      }
    }
  const cv::Mat bgr = test::load_data_image("aloeL.jpg"), gt = test::load_data_image("aloeGT.png");
  ASSERT_FALSE(bgr.empty());
  ASSERT_FALSE(gt.empty());
  cv::Mat gt1 = gt, depth;
  if (gt.channels() > 1) cv::extractChannel(gt, gt1, 0);
  gt1.convertTo(depth, CV_32FC1, 1.0 / 255);
  const HostFrame aloe = HostFrame::from_bgr(bgr, PixelFormat::NV12);
  const bool fused = expect_packed_same(warp_params(5.f, 0.5f, StereoView::Both, HoleFill::BackgroundSmooth),
                                        PackParams(), aloe, cell_constant(depth, 2), 2, PixelFormat::RGBA);
  if (hopper) {
    EXPECT_TRUE(fused);
  }
}

// What render_packed does not fuse renders the pair into its scratch, then
// packs it: every other layout, dubois-linear, 4:2:0 outputs, the other
// fills, one eye warped, full-size depth (no row groups), and a
// side-by-side output (rendered in place). Each is byte for byte
// warp_render_cpu then pack_cpu, and none ran fused.
TEST_F(GpuWarp, PackedOutputsThatAreNotFused) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  HostFrame src(PixelFormat::NV12, 258, 131, 2);
  src.fill_random(rng());
  const cv::Mat depth = cell_constant(random_depth(258, 131, DepthKind::Smooth, rng()), 2);
  const WarpParams smooth = warp_params(8.f, 0.5f, StereoView::Both, HoleFill::BackgroundSmooth);
  for (PackLayout l : kAllLayouts) {
    if (l == PackLayout::Anaglyph) continue;
    for (const bool swap : {false, true})
      EXPECT_FALSE(expect_packed_same(smooth, pack_params(l, AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois, swap),
                                      src, depth, 2, PixelFormat::RGBx));
  }
  const PackParams anaglyph;
  EXPECT_FALSE(expect_packed_same(
      smooth, pack_params(PackLayout::Anaglyph, AnaglyphGlasses::AmberBlue, AnaglyphMethod::DuboisLinear, false), src,
      depth, 2, PixelFormat::RGBA));
  for (PixelFormat yuv : {PixelFormat::NV12, PixelFormat::I420}) {
    EXPECT_FALSE(expect_packed_same(smooth, anaglyph, src, depth, 2, yuv));
    EXPECT_FALSE(expect_packed_same(
        smooth, pack_params(PackLayout::SideBySideHalf, AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois, false), src,
        depth, 2, yuv));
  }
  for (HoleFill f : kAllFills) {
    if (f == HoleFill::BackgroundSmooth) continue;
    EXPECT_FALSE(expect_packed_same(warp_params(8.f, 0.5f, StereoView::Both, f), anaglyph, src, depth, 2,
                                    PixelFormat::BGRA));
  }
  EXPECT_FALSE(expect_packed_same(warp_params(8.f, 0.5f, StereoView::Right, HoleFill::BackgroundSmooth), anaglyph,
                                  src, depth, 2, PixelFormat::RGBA));
  EXPECT_FALSE(expect_packed_same(smooth, anaglyph, src, depth, 0, PixelFormat::RGBA));
}

// Fused and unfused frames queued back to back with no host sync, sizes
// alternating (the pair scratch reused, its contents from the last frame):
// each output checked against the CPU once all are queued, and on Hopper
// every anaglyph frame fused.
TEST_F(GpuWarp, PackedFramesQueuedBackToBack) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  const int sizes[][2] = {{1283, 1091}, {640, 360}};
  const WarpParams w = warp_params(4.f, 0.5f, StereoView::Both, HoleFill::BackgroundSmooth);
  std::vector<HostFrame> srcs, cpus;
  std::vector<cv::Mat> depths;
  std::vector<PackParams> packs;
  std::vector<test::DeviceFrame> dsrcs, douts;
  std::vector<test::DeviceDepth> ddepths;
  for (int k = 0; k < 6; ++k) {
    const int sw = sizes[k % 2][0], sh = sizes[k % 2][1];
    srcs.emplace_back(PixelFormat::NV12, sw, sh, 2);
    srcs.back().fill_random(rng());
    depths.push_back(cell_constant(random_depth(sw, sh, k % 3 == 0 ? DepthKind::Noise : DepthKind::Smooth, rng()), 2));
    packs.push_back(pack_params(k % 4 == 3 ? PackLayout::TopBottomHalf : PackLayout::Anaglyph,
                                AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois, k % 2 == 0));
    int pw = 0, ph = 0;
    pack_size(packs.back().layout, sw, sh, &pw, &ph);
    HostFrame pair(PixelFormat::RGBA, 2 * sw, sh);
    ASSERT_GE(warp_render_cpu(w, srcs.back().view(), YuvToRgb(), depth_view_of(std::as_const(depths.back())),
                              pair.view()),
              0);
    cpus.emplace_back(PixelFormat::RGBA, pw, ph);
    pack_cpu(packs.back(), pair.view(), cpus.back().view());
    dsrcs.push_back(test::DeviceFrame::upload(srcs.back()));
    ddepths.push_back(test::DeviceDepth::upload_grid(depths.back(), 2));
    douts.emplace_back(PixelFormat::RGBA, pw, ph);
  }
  ASSERT_EQ(cudaSuccess, cudaDeviceSynchronize());
  bool fused[6] = {};
  for (size_t k = 0; k < srcs.size(); ++k)
    test::check_cuda(renderer_.render_packed(w, packs[k], dsrcs[k].view(), YuvToRgb(), as_const(ddepths[k].grid()),
                                             douts[k].view(), stream_, &fused[k]));
  ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
  for (size_t k = 0; k < srcs.size(); ++k) {
    SCOPED_TRACE(::testing::Message() << "frame " << k);
    EXPECT_EQ(first_difference(cpus[k], douts[k].download()), "");
    if (fuses_on_this_gpu()) {
      EXPECT_EQ(fused[k], packs[k].layout == PackLayout::Anaglyph);
    }
  }
}

// A depth grid whose cells do not fit its picture is refused.
TEST_F(GpuWarp, DepthGridThatDoesNotFitIsRefused) {
  const test::DeviceFrame src(PixelFormat::NV12, 64, 32), out(PixelFormat::RGBA, 128, 32);
  const test::DeviceDepth cells(64, 32, 2);
  DepthGrid<const float> g = as_const(cells.grid());
  g.cells.width -= 1;
  EXPECT_EQ(renderer_.render(WarpParams(), src.view(), YuvToRgb(), g, out.view(), stream_).code, cudaErrorInvalidValue);
  g = as_const(cells.grid());
  g.shift = 1;
  EXPECT_EQ(renderer_.render(WarpParams(), src.view(), YuvToRgb(), g, out.view(), stream_).code, cudaErrorInvalidValue);
  EXPECT_TRUE(renderer_.render(WarpParams(), src.view(), YuvToRgb(), as_const(cells.grid()), out.view(), stream_).ok());
  EXPECT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
}

// Every source format into every packed output format; BT.709 full range for
// the YUV ones, so the conversion parameters travel too.
TEST_F(GpuWarp, EveryFormat) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  const cv::Mat depth = random_depth(101, 37, DepthKind::Smooth, rng());
  const YuvToRgb bt709 = yuv_to_rgb_params(0.2126, 0.0722, true);
  for (PixelFormat f : kAllFormats) {
    HostFrame src(f, 101, 37, 7);
    src.fill_random(rng());
    for (PixelFormat of : kPackedFormats)
      for (HoleFill fill : kAllFills) expect_same(warp_params(12.f, 0.4f, StereoView::Both, fill), src, depth, of, bt709);
  }
}

TEST_F(GpuWarp, OddSizes) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  const int sizes[][2] = {{1, 1}, {3, 2}, {2, 3}, {33, 17}, {1001, 7}};
  for (const auto &s : sizes) {
    HostFrame src(PixelFormat::I420, s[0], s[1], 3);
    src.fill_random(rng());
    for (DepthKind kind : {DepthKind::Noise, DepthKind::Binary}) {
      const cv::Mat depth = random_depth(s[0], s[1], kind, rng());
      for (StereoView v : kAllViews)
        for (HoleFill f : kAllFills) expect_same(warp_params(25.f, 0.5f, v, f), src, depth, PixelFormat::BGRx);
    }
  }
}

// The row kernel stores whole 32-bit pixels where the output rows are
// 4-byte aligned and byte by byte where they are not (a start or a stride
// off by 1, 2 or 3 bytes); both give the CPU's pixels and write nothing
// outside the frame (row padding, guard band).
TEST_F(GpuWarp, UnalignedOutputRows) {
  std::mt19937 rng(fresh_seed());
  const int w = 45, h = 9;
  HostFrame src(PixelFormat::NV12, w, h);
  src.fill_random(rng());
  const test::DeviceFrame dsrc = test::DeviceFrame::upload(src);
  const size_t tight = 4 * static_cast<size_t>(2 * w);
  const size_t layouts[][2] = {{tight, 0}, {tight + 4, 4}, {tight, 1}, {tight + 1, 0}, {tight + 6, 3}};
  // Full-size depth (a row a block) and cells of 4 rows (row groups, whose
  // blocks store to several rows).
  for (const int shift : {0, 2})
  for (PixelFormat f : {PixelFormat::RGBA, PixelFormat::BGRx})
    for (HoleFill fill : kAllFills)
      for (const auto &l : layouts) {
        const cv::Mat depth = cell_constant(random_depth(w, h, DepthKind::Binary, rng()), shift);
        const test::DeviceDepth ddepth = test::DeviceDepth::upload_grid(depth, shift);
        const WarpParams p = warp_params(20.f, 0.5f, StereoView::Both, fill);
        SCOPED_TRACE(describe(p, src.format(), f, w, h) + " stride " + std::to_string(l[0]) + " offset " +
                     std::to_string(l[1]) + " depth shift " + std::to_string(shift));
        HostFrame cpu(f, 2 * w, h);
        const long long cpu_holes = warp_render_cpu(p, src.view(), YuvToRgb(), depth_view_of(depth), cpu.view());
        ASSERT_GT(cpu_holes, 0);
        test::DeviceOutput out(f, 2 * w, h, l[0], l[1], 0x5A);
        long long gpu_holes = -7;
        test::check_cuda(renderer_.render(p, dsrc.view(), YuvToRgb(), as_const(ddepth.grid()), out.view(), stream_,
                                          &gpu_holes));
        ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
        EXPECT_EQ(gpu_holes, cpu_holes);
        const test::DeviceOutput::Result got = out.download();
        EXPECT_EQ(first_difference(cpu, got.frame), "");
        EXPECT_EQ(got.writes_outside, 0);
      }
}

// Rows too wide for a z-buffer in shared memory (about 28000 pixels on
// Hopper with 32-bit keys, as here) take the global-memory z-buffer of
// 64-bit keys; both must agree with the CPU.
TEST_F(GpuWarp, VeryWideRowsUseGlobalKeys) {
  std::mt19937 rng(fresh_seed());
  HostFrame src(PixelFormat::BGRA, 40001, 3);
  src.fill_random(rng());
  for (DepthKind kind : {DepthKind::Smooth, DepthKind::Binary}) {
    const cv::Mat depth = random_depth(40001, 3, kind, rng());
    for (HoleFill f : kAllFills) expect_same(warp_params(0.5f, 0.5f, StereoView::Both, f), src, depth);
  }
}

// The row kernel keeps 32-bit keys (NarrowKeys: u relative to the target)
// where warp_narrow_keys_fit() says every hit lies within 127 pixels of its
// target, and 64-bit keys past that; both must give the CPU's bytes on
// either side of the limit: both views at convergence 0.5 (|s| D c = D / 4)
// and one view at convergence 0 (|s| D c = D), on noise and binary depth
// (the widest hits: every pixel at the far or near end).
TEST_F(GpuWarp, NarrowAndWideKeysAtTheLimit) {
  std::mt19937 rng(fresh_seed());
  const int w = 2000, h = 9;
  HostFrame src(PixelFormat::NV12, w, h);
  src.fill_random(rng());
  struct Case {
    float percent, convergence;
    StereoView view;
    bool narrow;
  };
  // D = percent * 20: both views 480 * 0.25 = 120 (the limit), one view 120 * 1.
  const Case cases[] = {{23.9f, 0.5f, StereoView::Both, true},  {24.1f, 0.5f, StereoView::Both, false},
                        {5.95f, 0.f, StereoView::Right, true},  {6.05f, 0.f, StereoView::Right, false},
                        {5.95f, 1.f, StereoView::Left, true},   {6.05f, 1.f, StereoView::Left, false}};
  for (const Case &c : cases) {
    const WarpParams p = warp_sanitize(warp_params(c.percent, c.convergence, c.view, HoleFill::BackgroundSmooth));
    const float D = disparity_scale(p, w);
    ASSERT_EQ(warp_narrow_keys_fit(warp_eye_shift(p, D, 0), warp_eye_shift(p, D, 1), D, p.convergence), c.narrow)
        << c.percent;
    for (DepthKind kind : {DepthKind::Noise, DepthKind::Binary}) {
      const cv::Mat depth = random_depth(w, h, kind, rng());
      for (HoleFill f : kAllFills) expect_same(warp_params(c.percent, c.convergence, c.view, f), src, depth);
    }
  }
}

// A kernel's shared-memory limit is the kernel's, shared by every renderer
// of the process, and the 48 KiB a block gets without opting in count the
// kernel's static shared memory too. Two renderers taking turns on rows of
// different widths must both launch (7680 and 6000 pixels: 61 and 48 KB
// with 32-bit keys), and so must rows whose dynamic bytes lie just under
// 48 KiB (5956 pixels with 32-bit keys, 4011 with 64-bit ones at 25 %:
// 49144 and 49140 bytes, plus the row kernel's 16 static ones). Those two
// come first: a kernel opted in by an earlier launch of the process no
// longer shows the second fault (run the test alone for that).
TEST_F(GpuWarp, SharedMemoryLimitsAcrossRenderersAndAt48KiB) {
  std::mt19937 rng(fresh_seed());
  WarpRendererGpu other;
  struct Run {
    int w;
    float percent;
    bool own;  // this fixture's renderer, else `other`
  };
  const Run runs[] = {{5956, 3.f, true},  {4011, 25.f, false}, {7680, 3.f, true},
                      {6000, 3.f, false}, {7680, 3.f, true},   {5957, 3.f, false}};
  for (const Run &r : runs) {
    SCOPED_TRACE(r.w);
    HostFrame src(PixelFormat::NV12, r.w, 3);
    src.fill_random(rng());
    const cv::Mat depth = random_depth(r.w, 3, DepthKind::Binary, rng());
    const WarpParams p = warp_params(r.percent, 0.5f, StereoView::Both, HoleFill::BackgroundSmooth);
    HostFrame cpu(PixelFormat::RGBA, 2 * r.w, 3);
    const long long cpu_holes = warp_render_cpu(p, src.view(), YuvToRgb(), depth_view_of(depth), cpu.view());
    const test::DeviceFrame dsrc = test::DeviceFrame::upload(src);
    const test::DeviceDepth ddepth = test::DeviceDepth::upload(depth);
    const test::DeviceFrame dout(PixelFormat::RGBA, 2 * r.w, 3);
    long long gpu_holes = -7;
    WarpRendererGpu &renderer = r.own ? renderer_ : other;
    test::check_cuda(
        renderer.render(p, dsrc.view(), YuvToRgb(), as_const(ddepth.view()), dout.view(), stream_, &gpu_holes));
    ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
    EXPECT_EQ(gpu_holes, cpu_holes);
    EXPECT_EQ(first_difference(cpu, dout.download()), "");
  }
}

// BackgroundSmooth windows too tall for the sums kernel's shared-memory
// copy (25 % of 3001 pixels: R = 188 rows for both views, 376 for one) read
// the states and anchors from global memory instead; the result is the same.
TEST_F(GpuWarp, BackgroundSmoothWideWindowsReadGlobalMemory) {
  std::mt19937 rng(fresh_seed());
  HostFrame src(PixelFormat::RGBA, 3001, 41);
  src.fill_random(rng());
  for (DepthKind kind : {DepthKind::Noise, DepthKind::Binary}) {
    const cv::Mat depth = random_depth(3001, 41, kind, rng());
    for (StereoView v : kAllViews) expect_same(warp_params(25.f, 0.3f, v, HoleFill::BackgroundSmooth), src, depth);
  }
}

// The sums kernel keeps V in 16 bits a channel up to R = 128, where a
// column window holds 257 anchors (255 * 257 = 65535), and in 32 bits
// above. A white picture at constant depth leaves border bands that are
// holes in all 300 rows, so windows fill up with 255s: R = 128 reaches the
// 16-bit limit exactly, R = 129 and 130 (V in 32 bits, still copied into
// shared memory) would pass it.
TEST_F(GpuWarp, BackgroundSmoothSumsAtTheNarrowLimit) {
  for (const int W : {2032, 2048, 2064}) {  // 25 %, both views: R = 128, 129, 130
    SCOPED_TRACE(W);
    const HostFrame src = HostFrame::from_bgr(cv::Mat(300, W, CV_8UC3, cv::Scalar(255, 255, 255)), PixelFormat::RGBA);
    const cv::Mat depth(300, W, CV_32FC1, cv::Scalar(1.f));
    expect_same(warp_params(25.f, 0.5f, StereoView::Both, HoleFill::BackgroundSmooth), src, depth);
  }
}

// Zero disparity and out-of-range parameters / depth (NaN, +-inf, > 1).
TEST_F(GpuWarp, ZeroDisparityAndInvalidValues) {
  HostFrame src(PixelFormat::BGRA, 64, 9);
  src.fill_random(fresh_seed());
  cv::Mat depth = random_depth(64, 9, DepthKind::Noise, fresh_seed());
  depth.at<float>(0, 3) = NAN;
  depth.at<float>(1, 5) = INFINITY;
  depth.at<float>(2, 7) = -INFINITY;
  depth.at<float>(3, 9) = 4.f;
  depth.at<float>(4, 11) = -2.f;
  for (HoleFill f : kAllFills) {
    expect_same(warp_params(0.f, 0.5f, StereoView::Both, f), src, depth);
    expect_same(warp_params(NAN, NAN, StereoView::Right, f), src, depth);
    expect_same(warp_params(90.f, 3.f, StereoView::Left, f), src, depth);
    expect_same(warp_params(25.f, -1.f, StereoView::Both, f), src, depth);
  }
}

// Aloe (Middlebury): the left image and its ground-truth disparity as depth.
TEST_F(GpuWarp, Aloe) {
  const cv::Mat bgr = test::load_data_image("aloeL.jpg");
  const cv::Mat gt = test::load_data_image("aloeGT.png");
  ASSERT_FALSE(bgr.empty());
  ASSERT_FALSE(gt.empty());
  cv::Mat gt1 = gt;
  if (gt.channels() > 1) cv::extractChannel(gt, gt1, 0);
  double maxv = 0;
  cv::minMaxLoc(gt1, nullptr, &maxv);
  ASSERT_GT(maxv, 0);
  cv::Mat depth;
  gt1.convertTo(depth, CV_32FC1, 1.0 / maxv);
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::BGRx}) {
    const HostFrame src = HostFrame::from_bgr(bgr, f, 5);
    for (StereoView v : kAllViews)
      for (HoleFill fill : kAllFills) expect_same(warp_params(5.f, 0.5f, v, fill), src, depth);
  }
}

// One renderer over frames of changing size: buffers grown, then reused
// with stale contents from the larger frame.
TEST_F(GpuWarp, BufferReuseAcrossSizes) {
  std::mt19937 rng(fresh_seed());
  const int sizes[][2] = {{320, 96}, {33, 17}, {320, 96}, {500, 40}, {7, 300}};
  for (const auto &s : sizes) {
    HostFrame src(PixelFormat::RGBx, s[0], s[1]);
    src.fill_random(rng());
    const cv::Mat depth = random_depth(s[0], s[1], DepthKind::Binary, rng());
    for (HoleFill f : kAllFills) expect_same(warp_params(10.f, 0.3f, StereoView::Both, f), src, depth);
  }
}

// Without holes_out nothing is read back, and the output is the same.
TEST_F(GpuWarp, HoleCountIsOptional) {
  HostFrame src(PixelFormat::RGBA, 70, 20);
  src.fill_random(fresh_seed());
  const cv::Mat depth = random_depth(70, 20, DepthKind::Binary, fresh_seed());
  for (HoleFill f : kAllFills) {
    const WarpParams p = warp_params(20.f, 0.5f, StereoView::Both, f);
    HostFrame cpu(PixelFormat::RGBA, 140, 20);
    warp_render_cpu(p, src.view(), YuvToRgb(), depth_view_of(depth), cpu.view());
    const test::DeviceFrame dsrc = test::DeviceFrame::upload(src);
    const test::DeviceDepth ddepth = test::DeviceDepth::upload(depth);
    const test::DeviceFrame dout(PixelFormat::RGBA, 140, 20);
    test::check_cuda(renderer_.render(p, dsrc.view(), YuvToRgb(), as_const(ddepth.view()), dout.view(), stream_));
    ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
    EXPECT_EQ(first_difference(cpu, dout.download()), "");
  }
}

TEST_F(GpuWarp, MismatchedFramesAreRefused) {
  const test::DeviceFrame src(PixelFormat::RGBA, 16, 8);
  const test::DeviceDepth depth(16, 8);
  const test::DeviceFrame narrow(PixelFormat::RGBA, 16, 8), yuv(PixelFormat::NV12, 32, 8);
  long long holes = -7;
  EXPECT_EQ(renderer_.render(WarpParams(), src.view(), YuvToRgb(), as_const(depth.view()), narrow.view(), stream_, &holes)
                .code,
            cudaErrorInvalidValue);
  EXPECT_EQ(renderer_.render(WarpParams(), src.view(), YuvToRgb(), as_const(depth.view()), yuv.view(), stream_).code,
            cudaErrorInvalidValue);
  EXPECT_EQ(holes, -7);
}

// 4K and 8K: every fill on a smooth surface with noise-level detail, and a
// timing line for the default path (information only).
void large_case(GpuWarpTest &t, int w, int h, const std::initializer_list<HoleFill> &fills) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  HostFrame src(PixelFormat::NV12, w, h);
  src.fill_random(rng());
  cv::Mat depth = random_depth(w, h, DepthKind::Smooth, rng());
  const cv::Mat noise = random_depth(w, h, DepthKind::Noise, rng());
  depth = depth * 0.9 + noise * 0.1;
  for (HoleFill f : fills) t.expect_same(warp_params(3.f, 0.5f, StereoView::Both, f), src, depth);
}

TEST_F(GpuWarpLarge, Uhd4k) {
  large_case(*this, 3840, 2160,
             {HoleFill::BackgroundSmooth, HoleFill::Background, HoleFill::NeighborAverage, HoleFill::None});
}
TEST_F(GpuWarpLarge, Uhd8k) {
  large_case(*this, 7680, 4320,
             {HoleFill::BackgroundSmooth, HoleFill::Background, HoleFill::NeighborAverage, HoleFill::None});
}

}  // namespace
}  // namespace p3d
