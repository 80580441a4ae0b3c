// Stiff and extreme cases on the GPU: every stage alone and the whole chain
// on the device (DepthEstimatorGpu -> BilateralFilterGpu -> WarpRendererGpu
// -> pack_gpu) against the CPU references, on constant, black, white,
// 1-pixel stripe and checkerboard frames, a max-contrast checkerboard and
// noise; depth all 0, all 1, noise, 0/1 noise and non-finite; parameters at
// and past their limits; sizes 1x1, 3x2, 1001x7, 3840x2160 and 7680x4320
// (8K: a constant and a checkerboard frame only).
//
// Tolerance: none, for every output. Each stage runs the CPU's own P3D_HD
// per-pixel code in the same operation order, without contraction on either
// side (-ffp-contract=off / -fmad=false), with integer or order-independent
// reductions (depth sums, z-buffer max, Jacobi fill), so depth must be
// bit-identical and frames byte-identical, hole counts and labels equal.
// (test_gpu_depth allows depth 1e-6 against a reassociating compiler; these
// inputs are meant to show such a difference, not to forgive it.)
// Outputs are poisoned: device depth with NaN, CPU depth with NaN too (both
// must be finite, in [0, 1]), device frames with 0xA5 and CPU frames with
// 0x5A, so a value either side leaves unwritten can never match.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "bilateral_gpu.h"
#include "depth_estimate_gpu.h"
#include "gpu_util.h"
#include "pack_gpu.h"
#include "stiff_frames.h"
#include "test_data.h"
#include "warp_gpu.h"

namespace p3d {
namespace {

using test::pack_params;
using test::warp_params;
using test::bilateral_params;
using test::check_cuda;
using test::DeviceDepth;
using test::DeviceFrame;
using test::format_name;
using test::kAllFormats;
using test::kAllGlasses;
using test::kAllLayouts;
using test::kAllMethods;
using test::kPackedFormats;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr uint8_t kCpuPoison = 0x5A;  // DeviceFrame poisons with 0xA5

uint32_t fresh_seed() { return std::random_device{}(); }

struct Size {
  int w, h;
};
constexpr Size kSmallSizes[] = {{1, 1}, {3, 2}, {1001, 7}};
constexpr Size k4K = {3840, 2160}, k8K = {7680, 4320};

std::string size_name(Size s) { return std::to_string(s.w) + "x" + std::to_string(s.h); }

using test::kAllPatterns;
using test::make_frame;
using test::Pattern;
using test::pattern_level;
using test::pattern_name;

enum class DepthKind { Zero, One, Half, Noise, Binary, Aligned, NonFinite };

const char *depth_name(DepthKind k) {
  switch (k) {
    case DepthKind::Zero: return "depth 0";
    case DepthKind::One: return "depth 1";
    case DepthKind::Half: return "depth 0.5";
    case DepthKind::Noise: return "depth noise";
    case DepthKind::Binary: return "depth 0/1 noise";
    case DepthKind::Aligned: return "depth 0/1 on the 8px checker";
    default: return "depth with NaN/Inf/-1/2";
  }
}

// NonFinite only goes to the warp, which defines what it reads for those.
cv::Mat make_depth(DepthKind k, int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.f, 1.f);
  const float odd[] = {kNaN, kInf, -kInf, -1.f, 2.f, 0.f, 1.f};
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y) {
    float *row = d.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      switch (k) {
        case DepthKind::Zero: row[x] = 0.f; break;
        case DepthKind::One: row[x] = 1.f; break;
        case DepthKind::Half: row[x] = 0.5f; break;
        case DepthKind::Binary: row[x] = static_cast<float>(rng() & 1); break;
        case DepthKind::Aligned: row[x] = pattern_level(Pattern::Checker8, x, y) == 255 ? 1.f : 0.f; break;
        case DepthKind::Noise: row[x] = rng() % 8 == 0 ? static_cast<float>(rng() & 1) : u01(rng); break;
        default: row[x] = rng() % 3 == 0 ? odd[rng() % 7] : u01(rng); break;
      }
    }
  }
  return d;
}

cv::Mat nan_depth(int w, int h) { return cv::Mat(h, w, CV_32FC1, cv::Scalar(kNaN)); }

// "" when both maps are finite, in [0, 1] and bit-identical; else counts and
// the first offender.
std::string depth_mismatch(const cv::Mat &cpu, const cv::Mat &gpu) {
  if (cpu.size() != gpu.size()) return "depth sizes differ";
  long long bad_cpu = 0, bad_gpu = 0, differing = 0;
  double max_abs = 0;
  std::ostringstream first;
  auto ok = [](float v) { return std::isfinite(v) && v >= 0.f && v <= 1.f; };
  for (int y = 0; y < cpu.rows; ++y) {
    const float *c = cpu.ptr<float>(y), *g = gpu.ptr<float>(y);
    for (int x = 0; x < cpu.cols; ++x) {
      const bool cok = ok(c[x]), gok = ok(g[x]);
      bad_cpu += !cok;
      bad_gpu += !gok;
      if (std::memcmp(&c[x], &g[x], sizeof(float)) == 0 && cok) continue;
      if (cok && gok) max_abs = std::max(max_abs, double(std::fabs(c[x] - g[x])));
      if (differing++ == 0) first << "first at (" << x << "," << y << "): cpu " << c[x] << " gpu " << g[x];
    }
  }
  if (differing == 0) return "";
  std::ostringstream s;
  s << differing << " values differ or are bad (cpu non-finite/out of [0,1]/unwritten: " << bad_cpu
    << ", gpu: " << bad_gpu << ", max |diff| of finite pairs " << max_abs << "); " << first.str();
  return s.str();
}

// "" when the row bytes of every plane agree; else the count and the first.
std::string frame_mismatch(const HostFrame &cpu, const HostFrame &gpu) {
  if (cpu.format() != gpu.format() || cpu.width() != gpu.width() || cpu.height() != gpu.height())
    return "frames differ in shape";
  const FrameView a = cpu.view(), b = gpu.view();
  long long differing = 0;
  std::ostringstream first;
  for (int i = 0; i < frame_plane_count(cpu.format()); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(cpu.format(), cpu.width(), cpu.height(), i, &row_bytes, &rows);
    for (int y = 0; y < rows; ++y) {
      const uint8_t *ra = a.plane[i] + static_cast<size_t>(y) * a.stride[i];
      const uint8_t *rb = b.plane[i] + static_cast<size_t>(y) * b.stride[i];
      if (std::memcmp(ra, rb, row_bytes) == 0) continue;
      for (int k = 0; k < row_bytes; ++k)
        if (ra[k] != rb[k] && differing++ == 0)
          first << "first at plane " << i << " row " << y << " byte " << k << ": cpu " << int(ra[k]) << " gpu "
                << int(rb[k]);
    }
  }
  return differing == 0 ? "" : std::to_string(differing) + " bytes differ, " + first.str();
}

PixelFormat warp_output_format(PixelFormat src) { return is_packed_rgb(src) ? src : PixelFormat::RGBA; }

DepthParams depth_params(Hypothesis h, int block, float edge_threshold, float region_weight) {
  DepthParams p;
  p.hypothesis = h;
  p.block_size = block;
  p.edge_threshold = edge_threshold;
  p.region_weight = region_weight;
  return p;
}

std::string describe(const DepthParams &p) {
  std::ostringstream s;
  s << "depth(hyp " << int(p.hypothesis) << " block " << p.block_size << " edge " << p.edge_threshold << " weight "
    << p.region_weight << ")";
  return s.str();
}
std::string describe(const BilateralParams &p) {
  std::ostringstream s;
  s << "filter(r " << p.radius << " ss " << p.sigma_space << " sr " << p.sigma_range << ")";
  return s.str();
}
std::string describe(const WarpParams &p) {
  std::ostringstream s;
  s << "warp(max " << p.max_disparity << " conv " << p.convergence << " view " << int(p.view) << " fill "
    << int(p.fill) << ")";
  return s.str();
}
std::string describe(const PackParams &p) {
  std::ostringstream s;
  s << "pack(layout " << int(p.layout) << " glasses " << int(p.glasses) << " method " << int(p.method) << " swap "
    << p.swap_eyes << ")";
  return s.str();
}

// Depth, filter, warp and pack parameters run as one chain.
struct ChainParams {
  const char *name;
  DepthParams depth;
  BilateralParams filter;
  WarpParams warp;
  PackParams pack;
};

// The chain's extremes; `big` caps the filter radius at 5 so that the CPU
// reference stays affordable at 4K/8K (radius 16 is covered at small sizes
// and once at 4K by the filter test).
std::vector<ChainParams> chain_params(bool big) {
  const int r_max = big ? 5 : kMaxBilateralRadius;
  std::vector<ChainParams> all;
  all.push_back({"defaults", DepthParams(), BilateralParams(), WarpParams(), PackParams()});
  all.push_back({"stiff", depth_params(Hypothesis::TopBottom, 2, 0.f, 0.f), bilateral_params(r_max, 1e30f, 0.f),
                 warp_params(25.f, 0.f, StereoView::Both, big ? HoleFill::Background : HoleFill::NeighborAverage),
                 pack_params(PackLayout::SideBySideHalf)});
  all.push_back({"soft", depth_params(Hypothesis::CenterNear, 64, kInf, 1.f), bilateral_params(r_max, 1e-30f, kInf),
                 warp_params(25.f, 1.f, StereoView::Left, HoleFill::None),
                 pack_params(PackLayout::Anaglyph, AnaglyphGlasses::GreenMagenta, AnaglyphMethod::Gray, true)});
  if (big) return all;
  all.push_back({"off", depth_params(Hypothesis::Flat, 4, 24.f, 0.75f), bilateral_params(0, 3.f, 12.f),
                 warp_params(0.f, 0.5f, StereoView::Right, HoleFill::None), pack_params(PackLayout::TopBottom)});
  all.push_back({"out of range", depth_params(Hypothesis::LeftRight, 1000, 1e-30f, 0.5f),
                 bilateral_params(5, 3.f, 1e-30f), warp_params(1e6f, -1.f, StereoView::Both, HoleFill::Background),
                 pack_params(PackLayout::Checkerboard)});
  return all;
}

// ---- the fixture: one GPU instance of every stage, one stream ---------------------

class GpuExtreme : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(cudaSuccess, cudaStreamCreate(&stream_)); }
  void TearDown() override {
    if (stream_) cudaStreamDestroy(stream_);
  }

  void sync() { ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_)); }

  // Depth of one frame from fresh state on both sides: labels, block depth,
  // decision and the depth map identical.
  void check_depth(const DepthParams &p, const HostFrame &f, const DeviceFrame &df, const std::string &what) {
    SCOPED_TRACE(what + " " + describe(p));
    DepthEstimatorCpu cpu;
    cv::Mat cd = nan_depth(f.width(), f.height());
    const TemporalDecision cdec = cpu.estimate(p, f.view(), depth_view_of(cd));

    DeviceDepth dd(f.width(), f.height());  // NaN-poisoned
    depth_.reset();
    check_cuda(depth_.estimate(p, df.view(), dd.view(), stream_));
    std::vector<int> labels;
    std::vector<float> blocks;
    TemporalDecision gdec = TemporalDecision::Reuse;
    check_cuda(depth_.download_labels(labels, stream_));
    check_cuda(depth_.download_block_depth(blocks, stream_));
    check_cuda(depth_.last_decision(&gdec, stream_));
    sync();
    EXPECT_EQ(cdec, gdec);
    EXPECT_TRUE(labels == cpu.labels()) << "region labels differ";
    ASSERT_EQ(blocks.size(), cpu.block_depth().size());
    EXPECT_EQ(std::memcmp(blocks.data(), cpu.block_depth().data(), blocks.size() * sizeof(float)), 0)
        << "block depth differs";
    EXPECT_EQ(depth_mismatch(cd, dd.download()), "");
  }

  // Filter on both sides; the device input is uploaded once by the caller.
  void check_filter(const BilateralParams &p, const HostFrame &guide, const DeviceFrame &dguide, const cv::Mat &depth,
                    const DeviceDepth &ddepth, DeviceDepth &dout, const std::string &what) {
    SCOPED_TRACE(what + " " + describe(p));
    cv::Mat cd = nan_depth(depth.cols, depth.rows);
    bilateral_filter_cpu(p, guide.view(), depth_view_of(depth), depth_view_of(cd));
    dout.poison();
    check_cuda(filter_.run(p, dguide.view(), as_const(ddepth.view()), dout.view(), stream_));
    sync();
    EXPECT_EQ(depth_mismatch(cd, dout.download()), "");
  }

  // Warp on both sides: bytes of both views and the hole count identical.
  void check_warp(const WarpParams &p, const HostFrame &src, const DeviceFrame &dsrc, const cv::Mat &depth,
                  const DeviceDepth &ddepth, const std::string &what) {
    SCOPED_TRACE(what + " " + describe(p));
    const PixelFormat of = warp_output_format(src.format());
    HostFrame cpu(of, 2 * src.width(), src.height(), 6);
    cpu.fill(kCpuPoison);
    const long long cpu_holes = warp_render_cpu(p, src.view(), YuvToRgb(), depth_view_of(depth), cpu.view());
    EXPECT_GE(cpu_holes, 0);
    const DeviceFrame dout(of, 2 * src.width(), src.height());  // 0xA5
    long long gpu_holes = -7;
    check_cuda(warp_.render(p, dsrc.view(), YuvToRgb(), as_const(ddepth.view()), dout.view(), stream_, &gpu_holes));
    sync();
    EXPECT_EQ(cpu_holes, gpu_holes);
    EXPECT_EQ(frame_mismatch(cpu, dout.download()), "");
  }

  // Pack on both sides, byte for byte.
  void check_pack(const PackParams &p, const HostFrame &pair, const DeviceFrame &dpair, const std::string &what) {
    SCOPED_TRACE(what + " " + describe(p));
    int w = 0, h = 0;
    pack_size(p.layout, pair.width() / 2, pair.height(), &w, &h);
    HostFrame cpu(pair.format(), w, h, 5);
    cpu.fill(kCpuPoison);
    pack_cpu(p, pair.view(), cpu.view());
    const DeviceFrame dout(pair.format(), w, h);  // 0xA5
    check_cuda(pack_gpu(p, dpair.view(), dout.view(), stream_));
    sync();
    EXPECT_EQ(frame_mismatch(cpu, dout.download()), "");
  }

  // The chain on the CPU and, stage to stage on the device, on the GPU;
  // every intermediate result compared.
  void check_chain(const ChainParams &cp, const HostFrame &src, const std::string &what) {
    SCOPED_TRACE(what + " chain " + cp.name + " " + describe(cp.depth) + " " + describe(cp.filter) + " " +
                 describe(cp.warp) + " " + describe(cp.pack));
    const int w = src.width(), h = src.height();
    const PixelFormat of = warp_output_format(src.format());
    int pw = 0, ph = 0;
    pack_size(cp.pack.layout, w, h, &pw, &ph);

    DepthEstimatorCpu est;
    cv::Mat c_depth = nan_depth(w, h), c_filtered = nan_depth(w, h);
    est.estimate(cp.depth, src.view(), depth_view_of(c_depth));
    bilateral_filter_cpu(cp.filter, src.view(), as_const(depth_view_of(c_depth)), depth_view_of(c_filtered));
    HostFrame c_warped(of, 2 * w, h, 6), c_packed(of, pw, ph, 5);
    c_warped.fill(kCpuPoison);
    c_packed.fill(kCpuPoison);
    const long long c_holes = warp_render_cpu(cp.warp, src.view(), YuvToRgb(), as_const(depth_view_of(c_filtered)),
                                              c_warped.view());
    pack_cpu(cp.pack, c_warped.view(), c_packed.view());

    const DeviceFrame d_src = DeviceFrame::upload(src);
    DeviceDepth d_depth(w, h), d_filtered(w, h);  // NaN-poisoned
    const DeviceFrame d_warped(of, 2 * w, h), d_packed(of, pw, ph);  // 0xA5
    long long g_holes = -7;
    depth_.reset();
    check_cuda(depth_.estimate(cp.depth, d_src.view(), d_depth.view(), stream_));
    check_cuda(filter_.run(cp.filter, d_src.view(), as_const(d_depth.view()), d_filtered.view(), stream_));
    check_cuda(warp_.render(cp.warp, d_src.view(), YuvToRgb(), as_const(d_filtered.view()), d_warped.view(), stream_,
                            &g_holes));
    check_cuda(pack_gpu(cp.pack, d_warped.view(), d_packed.view(), stream_));
    sync();

    EXPECT_EQ(depth_mismatch(c_depth, d_depth.download()), "") << "depth stage";
    EXPECT_EQ(depth_mismatch(c_filtered, d_filtered.download()), "") << "filter stage";
    EXPECT_EQ(c_holes, g_holes) << "warp stage";
    EXPECT_EQ(frame_mismatch(c_warped, d_warped.download()), "") << "warp stage";
    EXPECT_EQ(frame_mismatch(c_packed, d_packed.download()), "") << "pack stage";

    // Again with the depth handed on as the elements do on CUDA memory: on
    // the estimator's block grid and the filter's cell grid (p3d_defs.h
    // DepthGrid; full-size where a block or step is no power of two).
    DeviceDepth grid_depth(w, h, block_grid_shift(cp.depth, w, h)),
        grid_filtered(w, h, bilateral_grid_shift(bilateral_sanitize(cp.filter), w, h));
    const DeviceFrame grid_warped(of, 2 * w, h);  // 0xA5
    long long grid_holes = -7;
    depth_.reset();
    check_cuda(depth_.estimate(cp.depth, d_src.view(), grid_depth.grid(), stream_));
    check_cuda(filter_.run(cp.filter, d_src.view(), as_const(grid_depth.grid()), grid_filtered.grid(), stream_));
    check_cuda(warp_.render(cp.warp, d_src.view(), YuvToRgb(), as_const(grid_filtered.grid()), grid_warped.view(),
                            stream_, &grid_holes));
    sync();
    EXPECT_EQ(depth_mismatch(c_depth, grid_depth.download()), "") << "depth stage, block grid";
    EXPECT_EQ(depth_mismatch(c_filtered, grid_filtered.download()), "") << "filter stage, cell grid";
    EXPECT_EQ(c_holes, grid_holes) << "warp stage, cell grid";
    EXPECT_EQ(frame_mismatch(c_warped, grid_warped.download()), "") << "warp stage, cell grid";
  }

  DepthEstimatorGpu depth_;
  BilateralFilterGpu filter_;
  WarpRendererGpu warp_;
  cudaStream_t stream_ = nullptr;
};

using GpuExtremeDepth = GpuExtreme;
using GpuExtremeBilateral = GpuExtreme;
using GpuExtremeWarp = GpuExtreme;
using GpuExtremePack = GpuExtreme;
using GpuExtremeChain = GpuExtreme;

std::string frame_name(Pattern p, PixelFormat f, Size s) {
  return std::string(pattern_name(p)) + " " + format_name(f) + " " + size_name(s);
}

// ==== depth =========================================================================

std::vector<DepthParams> depth_extremes() {
  return {DepthParams(),
          depth_params(Hypothesis::TopBottom, 1, 0.f, 0.f),          // block clamps to 2, every block its own region
          depth_params(Hypothesis::CenterNear, 1000, kInf, 1.f),     // block clamps to 64, one region
          depth_params(Hypothesis::Flat, 64, 1e30f, 0.75f),
          depth_params(Hypothesis::LeftRight, 3, 1e-30f, 1.f)};
}

TEST_F(GpuExtremeDepth, StiffFramesSmallSizes) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (PixelFormat f : kAllFormats)
    for (Pattern pat : kAllPatterns)
      for (Size s : kSmallSizes) {
        const HostFrame frame = make_frame(pat, f, s.w, s.h, seed + s.w);
        const DeviceFrame dframe = DeviceFrame::upload(frame);
        for (const DepthParams &p : depth_extremes()) {
          check_depth(p, frame, dframe, frame_name(pat, f, s));
          if (HasFailure()) return;  // one precise report beats hundreds
        }
      }
}

TEST_F(GpuExtremeDepth, StiffFrames4K) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  int i = 0;
  for (Pattern pat : kAllPatterns) {
    const PixelFormat f = kAllFormats[i++ % 6];
    const HostFrame frame = make_frame(pat, f, k4K.w, k4K.h, seed);
    const DeviceFrame dframe = DeviceFrame::upload(frame);
    for (const DepthParams &p : depth_extremes()) {
      check_depth(p, frame, dframe, frame_name(pat, f, k4K));
      if (HasFailure()) return;
    }
  }
}

// 8K: one constant and one checkerboard frame; block 2 with threshold 0 on
// the checkerboard makes 8.3 million one-block regions, block 4 on the
// constant frame one region of 2 million blocks.
TEST_F(GpuExtremeDepth, Frames8K) {
  for (Pattern pat : {Pattern::Colour, Pattern::Checker8}) {
    const HostFrame frame = make_frame(pat, PixelFormat::NV12, k8K.w, k8K.h);
    const DeviceFrame dframe = DeviceFrame::upload(frame);
    for (const DepthParams &p : {DepthParams(), depth_params(Hypothesis::TopBottom, 2, 0.f, 0.f),
                                 depth_params(Hypothesis::CenterNear, 4, kInf, 1.f)}) {
      check_depth(p, frame, dframe, frame_name(pat, PixelFormat::NV12, k8K));
      if (HasFailure()) return;
    }
  }
}

// The temporal step at its extremes, one estimator per side across frames:
// reuse of an unchanged frame (static_threshold 0), a black -> white cut,
// smoothing with cut_threshold +Inf, reuse forever with static_threshold
// +Inf, a cut on any change with cut_threshold 0; decisions, differences and
// depth identical at every step.
TEST_F(GpuExtremeDepth, TemporalExtremes) {
  const Size s{1001, 7};
  const HostFrame black = make_frame(Pattern::Black, PixelFormat::I420, s.w, s.h);
  const HostFrame white = make_frame(Pattern::White, PixelFormat::I420, s.w, s.h);
  const HostFrame noise = make_frame(Pattern::Noise, PixelFormat::I420, s.w, s.h, fresh_seed());
  for (float smoothing : {0.f, 0.99f}) {
    SCOPED_TRACE("temporal_smoothing " + std::to_string(smoothing));
    DepthEstimatorCpu cpu;
    depth_.reset();
    DepthParams p;
    p.temporal_smoothing = smoothing;
    struct Step {
      const HostFrame *frame;
      float static_threshold, cut_threshold;
      TemporalDecision expected;
    };
    const Step steps[] = {{&black, 0.f, 30.f, TemporalDecision::Cut},    {&black, 0.f, 30.f, TemporalDecision::Reuse},
                          {&white, 0.f, 30.f, TemporalDecision::Cut},    {&noise, 0.f, kInf, TemporalDecision::Smooth},
                          {&black, kInf, kInf, TemporalDecision::Reuse}, {&white, 0.f, 0.f, TemporalDecision::Cut}};
    int n = 0;
    for (const Step &st : steps) {
      SCOPED_TRACE("step " + std::to_string(n++));
      p.static_threshold = st.static_threshold;
      p.cut_threshold = st.cut_threshold;
      cv::Mat cd = nan_depth(s.w, s.h);
      const TemporalDecision cdec = cpu.estimate(p, st.frame->view(), depth_view_of(cd));
      const DeviceFrame dframe = DeviceFrame::upload(*st.frame);
      DeviceDepth dd(s.w, s.h);
      check_cuda(depth_.estimate(p, dframe.view(), dd.view(), stream_));
      TemporalDecision gdec = TemporalDecision::Cut;
      float gdiff = -1.f;
      check_cuda(depth_.last_decision(&gdec, stream_));
      check_cuda(depth_.last_diff(&gdiff, stream_));
      sync();
      EXPECT_EQ(cdec, st.expected);
      EXPECT_EQ(gdec, cdec);
      EXPECT_EQ(gdiff, cpu.last_diff());
      EXPECT_EQ(depth_mismatch(cd, dd.download()), "");
    }
  }
}

// ==== bilateral filter ================================================================

std::vector<BilateralParams> bilateral_extremes() {
  return {bilateral_params(0, 3.f, 12.f),                       // identity
          bilateral_params(-5, 3.f, 12.f),                      // -> radius 0
          bilateral_params(16, 0.f, 12.f),                      // sigma_space 0 -> identity
          bilateral_params(16, kNaN, kInf),                     // sigma_space NaN -> identity
          bilateral_params(kMaxBilateralRadius, 1e-30f, 0.f),   // space and range -> 0: centre only
          bilateral_params(kMaxBilateralRadius, kInf, kInf),    // plain box
          bilateral_params(kMaxBilateralRadius, 1e30f, 1e-30f), // box over the exact guide matches
          bilateral_params(1, 1e-20f, 1e30f),
          bilateral_params(1000, 3.f, 12.f),                    // radius clamps to 16
          bilateral_params(5, 3.f, kNaN),                       // sigma_range NaN -> 0
          bilateral_params(5, 3.f, 1e19f)};                     // range weight rounds to 1
}

TEST_F(GpuExtremeBilateral, StiffInputsSmallSizes) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420, PixelFormat::RGBA, PixelFormat::BGRx})
    for (Pattern pat : kAllPatterns)
      for (Size s : kSmallSizes) {
        const HostFrame guide = make_frame(pat, f, s.w, s.h, seed ^ static_cast<uint32_t>(s.w));
        const DeviceFrame dguide = DeviceFrame::upload(guide);
        DeviceDepth dout(s.w, s.h);
        for (DepthKind k : {DepthKind::Zero, DepthKind::One, DepthKind::Half, DepthKind::Noise, DepthKind::Binary,
                            DepthKind::Aligned}) {
          const cv::Mat depth = make_depth(k, s.w, s.h, seed + 1);
          const DeviceDepth ddepth = DeviceDepth::upload(depth);
          for (const BilateralParams &p : bilateral_extremes()) {
            check_filter(p, guide, dguide, depth, ddepth, dout, frame_name(pat, f, s) + " " + depth_name(k));
            if (HasFailure()) return;
          }
        }
      }
}

// 4K: the maximum radius with sigma_range 0 once (the CPU reference is
// costly), then radius 5 at the sigma extremes and radius 0.
TEST_F(GpuExtremeBilateral, StiffInputs4K) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  struct Case {
    Pattern guide;
    PixelFormat format;
    DepthKind depth;
    BilateralParams params;
  };
  const Case cases[] = {
      {Pattern::Checker1, PixelFormat::NV12, DepthKind::Aligned, bilateral_params(kMaxBilateralRadius, 3.f, 0.f)},
      {Pattern::Checker8, PixelFormat::RGBA, DepthKind::Noise, bilateral_params(5, 3.f, kInf)},
      {Pattern::Checker8, PixelFormat::I420, DepthKind::Aligned, bilateral_params(5, 1e30f, 1e-30f)},
      {Pattern::Noise, PixelFormat::BGRx, DepthKind::Noise, BilateralParams()},
      {Pattern::White, PixelFormat::RGBx, DepthKind::One, bilateral_params(1, 1e-30f, 12.f)},
      {Pattern::VStripes, PixelFormat::NV12, DepthKind::Binary, bilateral_params(0, 3.f, 12.f)}};
  for (const Case &c : cases) {
    const HostFrame guide = make_frame(c.guide, c.format, k4K.w, k4K.h, seed);
    const DeviceFrame dguide = DeviceFrame::upload(guide);
    const cv::Mat depth = make_depth(c.depth, k4K.w, k4K.h, seed + 2);
    const DeviceDepth ddepth = DeviceDepth::upload(depth);
    DeviceDepth dout(k4K.w, k4K.h);
    check_filter(c.params, guide, dguide, depth, ddepth, dout, frame_name(c.guide, c.format, k4K) + " " +
                                                                  depth_name(c.depth));
    if (HasFailure()) return;
  }
}

// ==== warp ========================================================================

std::vector<WarpParams> warp_extremes() {
  return {warp_params(0.f, 0.f, StereoView::Both, HoleFill::Background),
          warp_params(25.f, 0.f, StereoView::Both, HoleFill::NeighborAverage),
          warp_params(25.f, 1.f, StereoView::Both, HoleFill::None),
          warp_params(25.f, 0.f, StereoView::Left, HoleFill::Background),
          warp_params(25.f, 1.f, StereoView::Right, HoleFill::NeighborAverage),
          warp_params(1e9f, 0.f, StereoView::Right, HoleFill::None),          // max_disparity clamps to 25
          warp_params(kNaN, 0.5f, StereoView::Both, HoleFill::Background),   // -> 0: copies
          warp_params(25.f, kNaN, StereoView::Left, HoleFill::None),         // convergence -> 0
          warp_params(-1.f, 1.f, StereoView::Both, HoleFill::NeighborAverage),
          warp_params(25.f, 0.5f, StereoView::Both, HoleFill::Background),
          warp_params(25.f, 0.f, StereoView::Both, HoleFill::None),
          warp_params(25.f, 1.f, StereoView::Left, HoleFill::NeighborAverage)};
}

TEST_F(GpuExtremeWarp, StiffInputsSmallSizes) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420, PixelFormat::RGBA, PixelFormat::BGRx})
    for (Pattern pat : {Pattern::Black, Pattern::Checker1, Pattern::Noise})
      for (Size s : kSmallSizes) {
        const HostFrame src = make_frame(pat, f, s.w, s.h, seed);
        const DeviceFrame dsrc = DeviceFrame::upload(src);
        for (DepthKind k : {DepthKind::Zero, DepthKind::One, DepthKind::Half, DepthKind::Noise, DepthKind::Binary,
                            DepthKind::NonFinite}) {
          const cv::Mat depth = make_depth(k, s.w, s.h, seed + 3);
          const DeviceDepth ddepth = DeviceDepth::upload(depth);
          for (const WarpParams &p : warp_extremes()) {
            check_warp(p, src, dsrc, depth, ddepth, frame_name(pat, f, s) + " " + depth_name(k));
            if (HasFailure()) return;
          }
        }
      }
}

// 4K: the largest disparity with the nearest and farthest depth and with
// noise; NeighborAverage only at 1 % (D = 38.4), where the Jacobi fill of the
// CPU reference needs some 20 steps, not hundreds.
TEST_F(GpuExtremeWarp, StiffInputs4K) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const WarpParams params[] = {warp_params(25.f, 0.f, StereoView::Both, HoleFill::Background),
                               warp_params(25.f, 1.f, StereoView::Left, HoleFill::None),
                               warp_params(1.f, 0.f, StereoView::Both, HoleFill::NeighborAverage)};
  int i = 0;
  for (Pattern pat : {Pattern::Checker1, Pattern::Noise}) {
    const PixelFormat f = i++ % 2 ? PixelFormat::RGBA : PixelFormat::NV12;
    const HostFrame src = make_frame(pat, f, k4K.w, k4K.h, seed);
    const DeviceFrame dsrc = DeviceFrame::upload(src);
    for (DepthKind k : {DepthKind::One, DepthKind::Zero, DepthKind::Noise, DepthKind::Binary}) {
      const cv::Mat depth = make_depth(k, k4K.w, k4K.h, seed + 4);
      const DeviceDepth ddepth = DeviceDepth::upload(depth);
      for (const WarpParams &p : params) {
        check_warp(p, src, dsrc, depth, ddepth, frame_name(pat, f, k4K) + " " + depth_name(k));
        if (HasFailure()) return;
      }
    }
  }
}

// ==== pack ==========================================================================

HostFrame pair_of(const HostFrame &l, const HostFrame &r) {
  HostFrame pair(l.format(), 2 * l.width(), l.height(), 3);
  const YuvToRgb m;
  for (int y = 0; y < l.height(); ++y)
    for (int x = 0; x < l.width(); ++x) {
      store_rgba(pair.view(), x, y, load_rgba(l.view(), x, y, m));
      store_rgba(pair.view(), l.width() + x, y, load_rgba(r.view(), x, y, m));
    }
  return pair;
}

// Every layout x swap, and every glasses x method for the anaglyphs.
std::vector<PackParams> every_pack_params() {
  std::vector<PackParams> all;
  for (PackLayout l : kAllLayouts)
    for (bool swap : {false, true}) {
      if (l != PackLayout::Anaglyph) {
        all.push_back(pack_params(l, AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois, swap));
        continue;
      }
      for (AnaglyphGlasses g : kAllGlasses)
        for (AnaglyphMethod m : kAllMethods) all.push_back(pack_params(l, g, m, swap));
    }
  return all;
}

TEST_F(GpuExtremePack, StiffPairsSmallSizes) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (PixelFormat f : kPackedFormats)
    for (Size s : kSmallSizes) {
      const HostFrame noise = make_frame(Pattern::Noise, f, s.w, s.h, seed);
      const HostFrame pairs[] = {
          pair_of(make_frame(Pattern::Black, f, s.w, s.h), make_frame(Pattern::White, f, s.w, s.h)),
          pair_of(make_frame(Pattern::Checker1, f, s.w, s.h), make_frame(Pattern::VStripes, f, s.w, s.h)),
          pair_of(noise, make_frame(Pattern::Noise, f, s.w, s.h, seed + 1)), pair_of(noise, noise)};
      const char *names[] = {"black|white", "checker|stripes", "noise|noise", "identical noise"};
      for (int i = 0; i < 4; ++i) {
        const DeviceFrame dpair = DeviceFrame::upload(pairs[i]);
        for (const PackParams &p : every_pack_params()) {
          check_pack(p, pairs[i], dpair, std::string(names[i]) + " " + format_name(f) + " view " + size_name(s));
          if (HasFailure()) return;
        }
      }
    }
}

// 4K and 8K pairs (black | white, checkerboard | inverted checkerboard) in
// the layouts that read differently: anaglyphs, the half formats, checkerboard.
TEST_F(GpuExtremePack, Pairs4KAnd8K) {
  const PackParams params[] = {pack_params(PackLayout::Anaglyph),
                               pack_params(PackLayout::Anaglyph, AnaglyphGlasses::AmberBlue, AnaglyphMethod::Gray, true),
                               pack_params(PackLayout::SideBySideHalf), pack_params(PackLayout::TopBottomHalf, {}, {}, true),
                               pack_params(PackLayout::Checkerboard)};
  for (Size s : {k4K, k8K}) {
    const PixelFormat f = s.w == k4K.w ? PixelFormat::BGRA : PixelFormat::RGBx;
    HostFrame checker(f, 2 * s.w, s.h, 3);
    const FrameView chv = checker.view();
    for (int y = 0; y < s.h; ++y)
      for (int x = 0; x < 2 * s.w; ++x) {
        const int parity = (((x % s.w) / 8) + (y / 8)) & 1;
        const bool white = x < s.w ? parity == 1 : parity == 0;  // the right view is the inverse
        const uint8_t l = white ? 255 : 0;
        store_rgba(chv, x, y, Rgba{l, l, l, 255});
      }
    HostFrame black_white(f, 2 * s.w, s.h, 3);
    const FrameView bw = black_white.view();
    for (int y = 0; y < s.h; ++y)
      for (int x = 0; x < 2 * s.w; ++x) {
        const uint8_t l = x < s.w ? 0 : 255;
        store_rgba(bw, x, y, Rgba{l, l, l, 255});
      }
    for (const HostFrame *pair : {&black_white, &checker}) {
      const DeviceFrame dpair = DeviceFrame::upload(*pair);
      for (const PackParams &p : params) {
        check_pack(p, *pair, dpair, std::string(pair == &checker ? "checker|inverted" : "black|white") + " view " +
                                        size_name(s));
        if (HasFailure()) return;
      }
    }
  }
}

// ==== the whole chain ===================================================================

TEST_F(GpuExtremeChain, StiffFramesSmallSizes) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (PixelFormat f : kAllFormats)
    for (Pattern pat : kAllPatterns)
      for (Size s : kSmallSizes) {
        const HostFrame src = make_frame(pat, f, s.w, s.h, seed);
        for (const ChainParams &cp : chain_params(false)) {
          check_chain(cp, src, frame_name(pat, f, s));
          if (HasFailure()) return;
        }
      }
}

TEST_F(GpuExtremeChain, StiffFrames4K) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  int i = 0;
  for (Pattern pat : {Pattern::Black, Pattern::White, Pattern::VStripes, Pattern::Checker1, Pattern::Checker8,
                      Pattern::Noise}) {
    const PixelFormat f = kAllFormats[i++ % 6];
    const HostFrame src = make_frame(pat, f, k4K.w, k4K.h, seed);
    for (const ChainParams &cp : chain_params(true)) {
      check_chain(cp, src, frame_name(pat, f, k4K));
      if (HasFailure()) return;
    }
  }
}

// 8K: a constant frame and a max-contrast checkerboard only.
TEST_F(GpuExtremeChain, Frames8K) {
  const std::vector<ChainParams> all = chain_params(true);
  for (Pattern pat : {Pattern::Colour, Pattern::Checker8}) {
    const PixelFormat f = pat == Pattern::Colour ? PixelFormat::NV12 : PixelFormat::RGBA;
    const HostFrame src = make_frame(pat, f, k8K.w, k8K.h);
    for (const ChainParams &cp : {all[0], all[1]}) {
      check_chain(cp, src, frame_name(pat, f, k8K));
      if (HasFailure()) return;
    }
  }
}

}  // namespace
}  // namespace p3d
