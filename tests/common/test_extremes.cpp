// Stiff and extreme cases through every CPU reference, alone and chained
// (DepthEstimatorCpu -> bilateral_filter_cpu -> warp_render_cpu -> pack_cpu):
// constant, black, white, 1-pixel stripe and checkerboard frames, a
// max-contrast checkerboard, noise; depth all 0, all 1, noise, binary and
// non-finite; every parameter at and past its limits; sizes 1x1 to 8K.
//
// "Every value written" is asserted by poisoning outputs first: depth with
// NaN (an unwritten value fails the finite check), frames twice with two
// different byte patterns (0xA5, 0x5A) whose results must be byte-identical.
// Depth must be finite and inside [0, 1] after every stage. Known answers
// from the conventions (docs/architecture.md, the stage headers) are asserted
// where the input makes them exact.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "bilateral.h"
#include "depth_estimate.h"
#include "pack.h"
#include "stiff_frames.h"
#include "test_data.h"
#include "warp.h"

namespace p3d {
namespace {

using test::pack_params;
using test::warp_params;
using test::bilateral_params;
using test::kAllFills;
using test::kAllFormats;
using test::kAllGlasses;
using test::kAllLayouts;
using test::kAllMethods;
using test::kAllViews;
using test::kPackedFormats;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr uint8_t kPoisonA = 0xA5, kPoisonB = 0x5A;

struct Size {
  int w, h;
};
// The degenerate sizes the issue names, plus a small odd one with interior.
constexpr Size kEdgeSizes[] = {{1, 1}, {2, 1}, {1, 2}, {3, 2}, {4097, 3}, {37, 23}};

std::string size_name(Size s) { return std::to_string(s.w) + "x" + std::to_string(s.h); }

using test::kAllPatterns;
using test::make_frame;
using test::Pattern;
using test::pattern_level;
using test::pattern_name;

Rgba at(const HostFrame &f, int x, int y) { return load_rgba(f.view(), x, y, YuvToRgb()); }
bool equal(Rgba a, Rgba b) { return a.r == b.r && a.g == b.g && a.b == b.b && a.a == b.a; }

std::string str(Rgba c) {
  std::ostringstream s;
  s << "(" << int(c.r) << "," << int(c.g) << "," << int(c.b) << "," << int(c.a) << ")";
  return s.str();
}

// The row bytes of every plane of two frames of one format and size; "" when
// identical, else the count and the first difference.
std::string first_difference(const HostFrame &a, const HostFrame &b) {
  if (a.format() != b.format() || a.width() != b.width() || a.height() != b.height()) return "frames differ in shape";
  const FrameView va = a.view(), vb = b.view();
  long long differing = 0;
  std::ostringstream first;
  for (int i = 0; i < frame_plane_count(a.format()); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(a.format(), a.width(), a.height(), i, &row_bytes, &rows);
    for (int y = 0; y < rows; ++y)
      for (int k = 0; k < row_bytes; ++k) {
        const int pa = va.plane[i][static_cast<size_t>(y) * va.stride[i] + k];
        const int pb = vb.plane[i][static_cast<size_t>(y) * vb.stride[i] + k];
        if (pa != pb && differing++ == 0)
          first << "first at plane " << i << " row " << y << " byte " << k << ": " << pa << " vs " << pb;
      }
  }
  return differing == 0 ? "" : std::to_string(differing) + " bytes differ, " + first.str();
}

// ---- depth maps -----------------------------------------------------------------

enum class DepthKind { Zero, One, Half, Noise, Binary, NonFinite };

const char *depth_name(DepthKind k) {
  switch (k) {
    case DepthKind::Zero: return "depth 0";
    case DepthKind::One: return "depth 1";
    case DepthKind::Half: return "depth 0.5";
    case DepthKind::Noise: return "depth noise";
    case DepthKind::Binary: return "depth 0/1 noise";
    default: return "depth with NaN/Inf/-1/2";
  }
}

// Noise is uniform in [0, 1] with exact 0s and 1s mixed in; NonFinite is
// noise with NaN, +-Inf, -1 and 2 sprinkled over it (only the warp, which
// defines them, gets those).
cv::Mat make_depth(DepthKind k, int w, int h, uint32_t seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.f, 1.f);
  const float odd[] = {kNaN, kInf, -kInf, -1.f, 2.f, 0.f, 1.f};
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float v = 0.f;
      switch (k) {
        case DepthKind::Zero: v = 0.f; break;
        case DepthKind::One: v = 1.f; break;
        case DepthKind::Half: v = 0.5f; break;
        case DepthKind::Binary: v = static_cast<float>(rng() & 1); break;
        case DepthKind::Noise: v = rng() % 8 == 0 ? static_cast<float>(rng() & 1) : u01(rng); break;
        default: v = rng() % 3 == 0 ? odd[rng() % 7] : u01(rng); break;
      }
      d.at<float>(y, x) = v;
    }
  return d;
}

cv::Mat nan_depth(int w, int h) { return cv::Mat(h, w, CV_32FC1, cv::Scalar(kNaN)); }

// Every value finite and inside [0, 1] (NaN poison left behind fails too).
::testing::AssertionResult depth_ok(const cv::Mat &d) {
  long long bad = 0;
  std::ostringstream first;
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x) {
      const float v = d.at<float>(y, x);
      if (std::isfinite(v) && v >= 0.f && v <= 1.f) continue;
      if (bad++ == 0) first << " first at (" << x << "," << y << "): " << v;
    }
  if (bad == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << bad << " depth values NaN/Inf/unwritten or outside [0,1];" << first.str();
}

bool bitwise_equal(const cv::Mat &a, const cv::Mat &b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int y = 0; y < a.rows; ++y)
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0) return false;
  return true;
}

// ---- stage wrappers ---------------------------------------------------------------

struct DepthResult {
  cv::Mat depth;
  std::vector<int> labels;
  int bx = 0, by = 0;
};

DepthResult estimate(const DepthParams &p, const HostFrame &f) {
  DepthEstimatorCpu est;
  DepthResult r;
  r.depth = nan_depth(f.width(), f.height());
  est.estimate(p, f.view(), depth_view_of(r.depth));
  r.labels = est.labels();
  r.bx = est.blocks_x();
  r.by = est.blocks_y();
  return r;
}

cv::Mat filter(const BilateralParams &p, const HostFrame &guide, const cv::Mat &depth) {
  cv::Mat out = nan_depth(depth.cols, depth.rows);
  bilateral_filter_cpu(p, guide.view(), depth_view_of(depth), depth_view_of(out));
  return out;
}

struct Rendered {
  HostFrame out;
  long long holes = 0;
};

PixelFormat warp_output_format(PixelFormat src) { return is_packed_rgb(src) ? src : PixelFormat::RGBA; }

Rendered warp_once(const WarpParams &p, const HostFrame &src, const cv::Mat &depth, uint8_t poison) {
  Rendered r;
  r.out = HostFrame(warp_output_format(src.format()), 2 * src.width(), src.height(), 5);
  r.out.fill(poison);
  r.holes = warp_render_cpu(p, src.view(), YuvToRgb(), depth_view_of(depth), r.out.view());
  return r;
}

// Renders twice over two poisons and asserts the outputs agree byte for byte
// (so every byte was written) and the hole count is sane.
Rendered warp(const WarpParams &p, const HostFrame &src, const cv::Mat &depth) {
  Rendered a = warp_once(p, src, depth, kPoisonA);
  const Rendered b = warp_once(p, src, depth, kPoisonB);
  EXPECT_EQ(first_difference(a.out, b.out), "") << "warp left bytes unwritten";
  EXPECT_EQ(a.holes, b.holes);
  EXPECT_GE(a.holes, 0);
  EXPECT_LE(a.holes, 2LL * src.width() * src.height());
  return a;
}

HostFrame pack_once(const PackParams &p, const HostFrame &pair, uint8_t poison) {
  int w = 0, h = 0;
  pack_size(p.layout, pair.width() / 2, pair.height(), &w, &h);
  HostFrame out(pair.format(), w, h, 7);
  out.fill(poison);
  pack_cpu(p, pair.view(), out.view());
  return out;
}

HostFrame pack(const PackParams &p, const HostFrame &pair) {
  HostFrame a = pack_once(p, pair, kPoisonA);
  EXPECT_EQ(first_difference(a, pack_once(p, pair, kPoisonB)), "") << "pack left bytes unwritten";
  return a;
}

// View pixel of a warp output: eye 0 = left (columns [0, W)), eye 1 = right.
Rgba view_at(const HostFrame &out, int eye, int x, int y) { return at(out, eye * (out.width() / 2) + x, y); }

using PixelFn = std::function<Rgba(int x, int y)>;
// Every pixel of one view of a warp output equals want(x, y) where `where` holds.
::testing::AssertionResult view_is(const HostFrame &out, int eye, const PixelFn &want,
                                   const std::function<bool(int)> &where = [](int) { return true; }) {
  const int w = out.width() / 2;
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < w; ++x) {
      if (!where(x)) continue;
      const Rgba got = view_at(out, eye, x, y), exp = want(x, y);
      if (!equal(got, exp))
        return ::testing::AssertionFailure() << "view " << eye << " (" << x << "," << y << "): got " << str(got)
                                             << " want " << str(exp);
    }
  return ::testing::AssertionSuccess();
}

PixelFn source_of(const HostFrame &src) {
  return [&src](int x, int y) { return at(src, x, y); };
}

long long count_colour(const HostFrame &f, Rgba c) {
  long long n = 0;
  for (int y = 0; y < f.height(); ++y)
    for (int x = 0; x < f.width(); ++x) n += equal(at(f, x, y), c);
  return n;
}

// ==== depth estimation =========================================================

constexpr Hypothesis kAllHypotheses[] = {Hypothesis::TopBottom, Hypothesis::LeftRight, Hypothesis::CenterNear,
                                         Hypothesis::Flat};

// Block depths of a frame that is one region: every block gets
// region_weight * r + (1 - region_weight) * its own hq, r the ground-contact
// blend of the largest and the mean hq of all blocks.
std::vector<float> one_region_block_depth(const DepthParams &p, int w, int h) {
  const int B = effective_block_size(p, w, h), bx = blocks_along(w, B), by = blocks_along(h, B);
  std::vector<uint32_t> hq(static_cast<size_t>(bx) * by);
  uint64_t sum = 0;
  uint32_t max = 0;
  for (int j = 0; j < by; ++j)
    for (int i = 0; i < bx; ++i) {
      const uint32_t q = hq[static_cast<size_t>(j) * bx + i] = block_hypothesis_q(p.hypothesis, i, j, B, w, h);
      sum += q;
      max = std::max(max, q);
    }
  std::vector<float> out(hq.size());
  for (size_t k = 0; k < hq.size(); ++k)
    out[k] = block_depth_value(p, sum, static_cast<uint32_t>(hq.size()), max, hq[k]);
  return out;
}

// Every pixel of `depth` equals its block's value in `blocks` (bitwise).
::testing::AssertionResult depth_is_blocks(const cv::Mat &depth, const std::vector<float> &blocks, int B) {
  const int bx = blocks_along(depth.cols, B);
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) {
      const float got = depth.at<float>(y, x), want = blocks[static_cast<size_t>(y / B) * bx + x / B];
      if (std::memcmp(&got, &want, sizeof got) != 0)
        return ::testing::AssertionFailure() << "(" << x << "," << y << "): got " << got << " want " << want;
    }
  return ::testing::AssertionSuccess();
}

bool all_labels(const std::vector<int> &labels, int value) {
  return std::all_of(labels.begin(), labels.end(), [value](int l) { return l == value; });
}
bool labels_are_indices(const std::vector<int> &labels) {
  for (size_t k = 0; k < labels.size(); ++k)
    if (labels[k] != static_cast<int>(k)) return false;
  return true;
}

// A constant frame is one region (all blocks labelled 0), so a block's depth
// is the region mean of the hypothesis blended with its own; region_weight 1
// makes the whole map that one mean, and Flat makes it 0.5 up to the 16-bit
// quantisation (32768 / 65535). Out-of-range block sizes (1, 1000) clamp.
TEST(ExtremeDepth, ConstantFramesAreOneRegion) {
  for (PixelFormat f : kAllFormats)
    for (Pattern pat : {Pattern::Black, Pattern::White, Pattern::Colour})
      for (Size s : kEdgeSizes) {
        const HostFrame frame = make_frame(pat, f, s.w, s.h);
        for (Hypothesis hyp : kAllHypotheses)
          for (int block : {1, 4, 64, 1000})
            for (float rw : {0.f, 0.75f, 1.f}) {
              SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << pattern_name(pat) << " "
                                                << size_name(s) << " hypothesis " << int(hyp) << " block " << block
                                                << " region_weight " << rw);
              DepthParams p;
              p.hypothesis = hyp;
              p.block_size = block;
              p.region_weight = rw;
              const DepthResult r = estimate(p, frame);
              ASSERT_TRUE(depth_ok(r.depth));
              EXPECT_TRUE(all_labels(r.labels, 0));
              EXPECT_TRUE(depth_is_blocks(r.depth, one_region_block_depth(p, s.w, s.h), effective_block_size(p, s.w, s.h)));
              if (rw == 1.f) {
                double lo = 1, hi = 0;
                cv::minMaxLoc(r.depth, &lo, &hi);
                EXPECT_EQ(lo, hi) << "region_weight 1: one region, one depth";
              }
              if (hyp == Hypothesis::Flat) {
                for (int y = 0; y < s.h; ++y)
                  for (int x = 0; x < s.w; ++x)
                    ASSERT_NEAR(r.depth.at<float>(y, x), 32768.0 / 65535.0, 1e-6) << "flat hypothesis, flat depth";
              }
            }
      }
}

// 1-pixel stripes and checkerboards average to the same grey in every block
// of even size, so they are one region and give exactly the depth of a
// uniform frame.
TEST(ExtremeDepth, OnePixelPatternsAverageToOneRegion) {
  for (PixelFormat f : kAllFormats)
    for (Pattern pat : {Pattern::VStripes, Pattern::HStripes, Pattern::Checker1})
      for (int block : {2, 4, 8})
        for (Hypothesis hyp : kAllHypotheses) {
          SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << pattern_name(pat) << " block " << block
                                            << " hypothesis " << int(hyp));
          DepthParams p;
          p.hypothesis = hyp;
          p.block_size = block;
          const DepthResult r = estimate(p, make_frame(pat, f, 64, 40));
          ASSERT_TRUE(depth_ok(r.depth));
          EXPECT_TRUE(all_labels(r.labels, 0));
          EXPECT_TRUE(depth_is_blocks(r.depth, one_region_block_depth(p, 64, 40), block));
        }
}

// A black/white checkerboard whose cells are the blocks (8 px) has the
// largest contrast between every pair of neighbours: each block is its own
// region and its depth is its own quantised hypothesis, within 1e-6 of the
// spec's formula evaluated in double (plus half a 16-bit step). An infinite
// edge threshold joins everything again; threshold 0 separates even a
// constant frame.
TEST(ExtremeDepth, MaxContrastCheckerboardSeparatesEveryBlock) {
  for (PixelFormat f : kAllFormats)
    for (Size s : {Size{64, 48}, Size{67, 45}, Size{8, 8}, Size{9, 1}})
      for (Hypothesis hyp : {Hypothesis::TopBottom, Hypothesis::LeftRight})
        for (float rw : {0.f, 0.75f, 1.f}) {
          SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << size_name(s) << " hypothesis "
                                            << int(hyp) << " region_weight " << rw);
          DepthParams p;
          p.hypothesis = hyp;
          p.block_size = 8;
          p.region_weight = rw;
          const DepthResult r = estimate(p, make_frame(Pattern::Checker8, f, s.w, s.h));
          ASSERT_TRUE(depth_ok(r.depth));
          EXPECT_TRUE(labels_are_indices(r.labels));
          for (int y = 0; y < s.h; ++y)
            for (int x = 0; x < s.w; ++x) {
              const int b = hyp == Hypothesis::TopBottom ? y / 8 : x / 8, n = hyp == Hypothesis::TopBottom ? s.h : s.w;
              const double centre = (b * 8 + std::min(8, n - b * 8) / 2.0) / n;
              ASSERT_NEAR(r.depth.at<float>(y, x), centre, 0.5 / 65535 + 1e-6) << "(" << x << "," << y << ")";
            }

          p.edge_threshold = kInf;
          const DepthResult joined = estimate(p, make_frame(Pattern::Checker8, f, s.w, s.h));
          ASSERT_TRUE(depth_ok(joined.depth));
          EXPECT_TRUE(all_labels(joined.labels, 0));
          EXPECT_TRUE(depth_is_blocks(joined.depth, one_region_block_depth(p, s.w, s.h), 8));

          p.edge_threshold = 0.f;
          const DepthResult apart = estimate(p, make_frame(Pattern::White, f, s.w, s.h));
          ASSERT_TRUE(depth_ok(apart.depth));
          EXPECT_TRUE(labels_are_indices(apart.labels));
        }
}

// Pure noise frames (alpha and chroma random too), every hypothesis and the
// extreme thresholds and weights: depth finite, in [0, 1], every pixel written.
TEST(ExtremeDepth, NoiseFramesGiveFiniteDepth) {
  uint32_t seed = 11;
  for (PixelFormat f : kAllFormats)
    for (Size s : kEdgeSizes) {
      const HostFrame frame = make_frame(Pattern::Noise, f, s.w, s.h, ++seed);
      for (Hypothesis hyp : kAllHypotheses)
        for (float thr : {0.f, 1e-30f, 24.f, 1e30f, kInf})
          for (int block : {2, 64}) {
            SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << size_name(s) << " hypothesis "
                                              << int(hyp) << " edge_threshold " << thr << " block " << block);
            DepthParams p;
            p.hypothesis = hyp;
            p.edge_threshold = thr;
            p.block_size = block;
            p.region_weight = thr > 100.f ? 1.f : 0.5f;
            const DepthResult r = estimate(p, frame);
            EXPECT_TRUE(depth_ok(r.depth));
            EXPECT_EQ(r.labels.size(), static_cast<size_t>(r.bx) * r.by);
          }
    }
}

// The temporal step at its extremes: an unchanged frame is reused exactly
// (static_threshold 0), black -> white (mean difference 255) is a cut,
// smoothing 0 and 0.99 stay finite, static_threshold +Inf reuses whatever
// comes, cut_threshold 0 cuts on any change.
TEST(ExtremeDepth, TemporalExtremes) {
  const int w = 33, h = 17;
  const HostFrame black = make_frame(Pattern::Black, PixelFormat::RGBA, w, h);
  const HostFrame white = make_frame(Pattern::White, PixelFormat::RGBA, w, h);
  const HostFrame noise = make_frame(Pattern::Noise, PixelFormat::RGBA, w, h, 5);
  for (float smoothing : {0.f, 0.99f}) {
    SCOPED_TRACE(::testing::Message() << "temporal_smoothing " << smoothing);
    DepthParams p;
    p.temporal_smoothing = smoothing;
    p.static_threshold = 0.f;
    DepthEstimatorCpu est;
    std::vector<cv::Mat> out;
    auto step = [&](const HostFrame &f) {
      out.push_back(nan_depth(w, h));
      const TemporalDecision d = est.estimate(p, f.view(), depth_view_of(out.back()));
      EXPECT_TRUE(depth_ok(out.back()));
      return d;
    };
    EXPECT_EQ(step(black), TemporalDecision::Cut);
    EXPECT_EQ(step(black), TemporalDecision::Reuse);
    EXPECT_TRUE(bitwise_equal(out[0], out[1]));
    EXPECT_EQ(step(white), TemporalDecision::Cut);
    EXPECT_EQ(est.last_diff(), 255.f);
    p.cut_threshold = kInf;
    EXPECT_EQ(step(noise), TemporalDecision::Smooth);
    p.static_threshold = kInf;
    EXPECT_EQ(step(black), TemporalDecision::Reuse);
    EXPECT_TRUE(bitwise_equal(out[4], out[3]));
    p.static_threshold = 0.f;
    p.cut_threshold = 0.f;
    EXPECT_EQ(step(white), TemporalDecision::Cut);
  }
}

// One 8K frame (the largest size the plugin is meant for): a uniform grey is
// one region of 960 x 540 blocks (the automatic block size is 8 at 8K).
// TopBottom with region_weight 1 gives the mean of the block centres, 0.5
// (quantisation aside), everywhere with ground_contact 0 and the lowest block
// row's centre with ground_contact 1; with region_weight 0 every pixel gets
// its block row's centre.
TEST(ExtremeDepth, Frame8K) {
  const int W = 7680, H = 4320;
  HostFrame frame(PixelFormat::RGBA, W, H);
  frame.fill(128);
  DepthParams p;
  const int B = effective_block_size(p, W, H);
  ASSERT_EQ(B, 8);
  p.hypothesis = Hypothesis::TopBottom;
  p.region_weight = 1.f;
  p.ground_contact = 0.f;
  const DepthResult mean = estimate(p, frame);
  ASSERT_TRUE(depth_ok(mean.depth));
  EXPECT_TRUE(all_labels(mean.labels, 0));
  double lo = 0, hi = 0;
  cv::minMaxLoc(mean.depth, &lo, &hi);
  EXPECT_EQ(lo, hi);
  EXPECT_NEAR(lo, 0.5, 1e-5);

  p.ground_contact = 1.f;
  const DepthResult nearest = estimate(p, frame);
  cv::minMaxLoc(nearest.depth, &lo, &hi);
  EXPECT_EQ(lo, hi);
  EXPECT_NEAR(lo, (H - B / 2.0) / H, 0.5 / 65535 + 1e-6);

  p.region_weight = 0.f;
  const DepthResult own = estimate(p, frame);
  ASSERT_TRUE(depth_ok(own.depth));
  for (int y = 0; y < H; ++y) {
    const double centre = ((y / B) * B + B / 2.0) / H;
    const float *row = own.depth.ptr<float>(y);
    for (int x = 0; x < W; ++x) ASSERT_NEAR(row[x], centre, 0.5 / 65535 + 1e-6) << "(" << x << "," << y << ")";
  }
}

// ==== cross-bilateral filter ====================================================

// Radius 0, and every parameter that sanitises to it (negative radius,
// sigma_space 0, negative or NaN), is the identity: bit for bit.
TEST(ExtremeBilateral, RadiusZeroIsTheIdentity) {
  const BilateralParams identities[] = {bilateral_params(0, 3.f, 12.f), bilateral_params(-5, 3.f, 12.f),
                                        bilateral_params(16, 0.f, 12.f), bilateral_params(16, -1.f, 0.f),
                                        bilateral_params(16, kNaN, kInf), bilateral_params(0, kInf, kNaN)};
  for (Size s : kEdgeSizes)
    for (Pattern g : {Pattern::Checker1, Pattern::Noise, Pattern::White})
      for (DepthKind k : {DepthKind::Zero, DepthKind::One, DepthKind::Noise, DepthKind::Binary})
        for (const BilateralParams &bp : identities) {
          SCOPED_TRACE(::testing::Message() << size_name(s) << " guide " << pattern_name(g) << " " << depth_name(k)
                                            << " radius " << bp.radius << " sigma_space " << bp.sigma_space
                                            << " sigma_range " << bp.sigma_range);
          const cv::Mat depth = make_depth(k, s.w, s.h);
          const cv::Mat out = filter(bp, make_frame(g, PixelFormat::NV12, s.w, s.h), depth);
          ASSERT_TRUE(depth_ok(out));
          EXPECT_TRUE(bitwise_equal(out, depth));
        }
}

// A constant depth map comes back unchanged, bit for bit, whatever the
// guide and the sigmas (the taps sum differences from the centre's depth,
// all exactly 0), denormal weights included.
TEST(ExtremeBilateral, ConstantDepthIsUnchanged) {
  for (Size s : {Size{1, 1}, Size{3, 2}, Size{1, 2}, Size{37, 23}})
    for (Pattern g : {Pattern::Checker1, Pattern::Checker8, Pattern::Noise})
      for (int radius : {1, kMaxBilateralRadius})
        for (float ss : {1e-30f, 3.f, kInf})
          for (float sr : {0.f, 12.f, kInf}) {
            const HostFrame guide = make_frame(g, PixelFormat::RGBA, s.w, s.h, 3);
            for (DepthKind k : {DepthKind::Zero, DepthKind::One, DepthKind::Half}) {
              SCOPED_TRACE(::testing::Message() << size_name(s) << " guide " << pattern_name(g) << " " << depth_name(k)
                                                << " radius " << radius << " sigma_space " << ss << " sigma_range "
                                                << sr);
              const cv::Mat depth = make_depth(k, s.w, s.h);
              const cv::Mat out = filter(bilateral_params(radius, ss, sr), guide, depth);
              ASSERT_TRUE(depth_ok(out));
              EXPECT_TRUE(bitwise_equal(out, depth));
            }
          }
}

// Depth that follows a max-contrast checkerboard exactly (1 on white cells, 0
// on black, and inverted): with sigma_range 0, or so small that the range
// weight of a black/white difference is 0, every pixel averages only pixels
// of its own colour, which share its depth, so each depth step stays on its
// checker edge bit for bit, at every radius.
TEST(ExtremeBilateral, TinySigmaRangeKeepsCheckerAlignedSteps) {
  for (PixelFormat f : kAllFormats)
    for (Pattern g : {Pattern::Checker1, Pattern::Checker8})
      for (Size s : {Size{3, 2}, Size{37, 23}, Size{4097, 3}})
        for (bool inverted : {false, true}) {
          const HostFrame guide = make_frame(g, f, s.w, s.h);
          cv::Mat depth(s.h, s.w, CV_32FC1);
          for (int y = 0; y < s.h; ++y)
            for (int x = 0; x < s.w; ++x) depth.at<float>(y, x) = (pattern_level(g, x, y) == 255) != inverted ? 1.f : 0.f;
          for (int radius : {1, 5, kMaxBilateralRadius})
            for (float sr : {0.f, 1e-30f, 1e-20f, 1e-3f, 1.f})
              for (float ss : {3.f, kInf}) {
                SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << pattern_name(g) << " "
                                                  << size_name(s) << " inverted " << inverted << " radius " << radius
                                                  << " sigma_range " << sr << " sigma_space " << ss);
                const cv::Mat out = filter(bilateral_params(radius, ss, sr), guide, depth);
                ASSERT_TRUE(depth_ok(out));
                EXPECT_TRUE(bitwise_equal(out, depth));
              }
        }
}

// A huge sigma_range (1e19: the weight rounds to 1; 1e30 and +Inf: 2 sigma^2
// overflows, the weight is exactly 1) makes the filter blind to the guide:
// the same bits as with a uniform guide. On checker-aligned depth it then
// blurs across the edges (the output is not the input any more).
TEST(ExtremeBilateral, HugeSigmaRangeIgnoresTheGuide) {
  const int w = 37, h = 23;
  const HostFrame uniform = make_frame(Pattern::White, PixelFormat::BGRx, w, h);
  cv::Mat aligned(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) aligned.at<float>(y, x) = pattern_level(Pattern::Checker8, x, y) / 255.f;
  for (Pattern g : {Pattern::Checker1, Pattern::Checker8, Pattern::Noise})
    for (float sr : {1e19f, 1e30f, kInf})
      for (int radius : {1, 5, kMaxBilateralRadius})
        for (DepthKind k : {DepthKind::Noise, DepthKind::Binary}) {
          SCOPED_TRACE(::testing::Message() << pattern_name(g) << " sigma_range " << sr << " radius " << radius << " "
                                            << depth_name(k));
          const HostFrame guide = make_frame(g, PixelFormat::BGRx, w, h, 9);
          const BilateralParams bp = bilateral_params(radius, 3.f, sr);
          const cv::Mat depth = make_depth(k, w, h);
          const cv::Mat out = filter(bp, guide, depth);
          ASSERT_TRUE(depth_ok(out));
          EXPECT_TRUE(bitwise_equal(out, filter(bp, uniform, depth)));
          if (g == Pattern::Checker8) {
            const cv::Mat blurred = filter(bp, guide, aligned);
            ASSERT_TRUE(depth_ok(blurred));
            EXPECT_FALSE(bitwise_equal(blurred, aligned));
            EXPECT_TRUE(bitwise_equal(blurred, filter(bp, uniform, aligned)));
          }
        }
}

// Noise depth through every extreme combination: a weighted mean of values
// in [0, 1] stays in [0, 1] (and within the input's range), finite, every
// pixel written; filtering in place gives the same bits.
TEST(ExtremeBilateral, NoiseDepthStaysInRange) {
  const BilateralParams extremes[] = {
      bilateral_params(kMaxBilateralRadius, 1e-30f, 0.f), bilateral_params(kMaxBilateralRadius, kInf, kInf),
      bilateral_params(kMaxBilateralRadius, 1e30f, 1e-30f), bilateral_params(1, 1e-20f, 1e30f),
      bilateral_params(1000, 3.f, 12.f), bilateral_params(5, 3.f, kNaN)};
  uint32_t seed = 21;
  for (Size s : kEdgeSizes)
    for (Pattern g : kAllPatterns)
      for (DepthKind k : {DepthKind::Noise, DepthKind::Binary})
        for (const BilateralParams &bp : extremes) {
          SCOPED_TRACE(::testing::Message() << size_name(s) << " guide " << pattern_name(g) << " " << depth_name(k)
                                            << " radius " << bp.radius << " sigma_space " << bp.sigma_space
                                            << " sigma_range " << bp.sigma_range);
          const HostFrame guide = make_frame(g, PixelFormat::I420, s.w, s.h, ++seed);
          const cv::Mat depth = make_depth(k, s.w, s.h, ++seed);
          const cv::Mat out = filter(bp, guide, depth);
          ASSERT_TRUE(depth_ok(out));
          double in_lo = 0, in_hi = 0, lo = 0, hi = 0;
          cv::minMaxLoc(depth, &in_lo, &in_hi);
          cv::minMaxLoc(out, &lo, &hi);
          EXPECT_GE(lo, in_lo - 1e-6);  // a weighted mean, up to float rounding
          EXPECT_LE(hi, in_hi + 1e-6);
          cv::Mat in_place = depth.clone();
          bilateral_filter_cpu(bp, guide.view(), as_const(depth_view_of(in_place)), depth_view_of(in_place));
          EXPECT_TRUE(bitwise_equal(in_place, out));
        }
}

// ==== DIBR warp =================================================================

// Depth equal to the convergence everywhere puts every pixel on the screen
// plane (p = 0 exactly): both views are the source, for every view mode,
// fill, disparity (25 %, and 1e9 % clamped to it) and format, with no hole.
TEST(ExtremeWarp, DepthOnTheScreenPlaneCopiesTheSource) {
  int i = 0;
  for (PixelFormat f : kAllFormats)
    for (Pattern pat : {Pattern::Black, Pattern::White, Pattern::Checker1, Pattern::Noise})
      for (Size s : kEdgeSizes) {
        const HostFrame src = make_frame(pat, f, s.w, s.h, 3);
        for (float conv : {0.f, 0.5f, 1.f})
          for (StereoView v : kAllViews) {
            ++i;
            const WarpParams p = warp_params(i % 2 ? 25.f : 1e9f, conv, v, kAllFills[i % std::size(kAllFills)]);
            SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << pattern_name(pat) << " "
                                              << size_name(s) << " convergence " << conv << " view " << int(v)
                                              << " max_disparity " << p.max_disparity << " fill " << int(p.fill));
            const Rendered r = warp(p, src, cv::Mat(s.h, s.w, CV_32FC1, cv::Scalar(conv)));
            EXPECT_EQ(r.holes, 0);
            EXPECT_TRUE(view_is(r.out, 0, source_of(src)));
            EXPECT_TRUE(view_is(r.out, 1, source_of(src)));
          }
      }
}

// max_disparity 0 (and the values that sanitise to it: negative, NaN, -Inf)
// copies the source into both views whatever the depth, NaN included.
TEST(ExtremeWarp, ZeroDisparityCopiesTheSource) {
  for (PixelFormat f : kAllFormats)
    for (Size s : kEdgeSizes)
      for (float md : {0.f, -1.f, kNaN, -kInf})
        for (DepthKind k : {DepthKind::One, DepthKind::Binary, DepthKind::NonFinite})
          for (StereoView v : kAllViews) {
            SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << size_name(s) << " max_disparity "
                                              << md << " " << depth_name(k) << " view " << int(v));
            const HostFrame src = make_frame(Pattern::Checker1, f, s.w, s.h);
            const Rendered r = warp(warp_params(md, 0.f, v, HoleFill::None), src, make_depth(k, s.w, s.h));
            EXPECT_EQ(r.holes, 0);
            EXPECT_TRUE(view_is(r.out, 0, source_of(src)));
            EXPECT_TRUE(view_is(r.out, 1, source_of(src)));
          }
}

// Exact linear interpolation at a dyadic fraction, rounded half up.
Rgba lerp_exact(Rgba a, Rgba b, double frac) {
  auto ch = [frac](int p, int q) { return static_cast<uint8_t>(std::floor(p + (q - p) * frac + 0.5)); };
  return Rgba{ch(a.r, b.r), ch(a.g, b.g), ch(a.b, b.b), ch(a.a, b.a)};
}

// The source sampled at u (0 <= u <= W-1) along row y.
Rgba source_at(const HostFrame &src, double u, int y) {
  const int x0 = static_cast<int>(std::floor(u)), x1 = std::min(x0 + 1, src.width() - 1);
  return lerp_exact(at(src, x0, y), at(src, x1, y), u - x0);
}

// Uniform depth moves a whole view by one shift: view(X) = source at X - shift.
// Checked where X - shift is inside the source; at an integer shift the
// Background fill then repeats the edge column into the uncovered border.
// The covered targets are exactly -0.5 <= X - shift < W - 0.5 (the
// footprints' half-open ends), so fill=None paints the rest magenta.
void expect_uniform_shift(const HostFrame &out, int eye, const HostFrame &src, double shift, HoleFill fill) {
  const int w = src.width();
  auto inside = [w, shift](int X) { return X - shift >= 0 && X - shift <= w - 1; };
  EXPECT_TRUE(view_is(out, eye, [&](int X, int y) { return source_at(src, X - shift, y); }, inside));
  if (fill == HoleFill::Background && shift == std::floor(shift)) {
    EXPECT_TRUE(view_is(out, eye, [&](int X, int y) { return at(src, X - shift < 0 ? 0 : w - 1, y); },
                        [&](int X) { return !inside(X); }));
  }
  if (fill == HoleFill::None) {
    EXPECT_TRUE(view_is(out, eye, [](int, int) { return kHoleColour; },
                        [&](int X) { return X - shift < -0.5 || X - shift >= w - 0.5; }));
  }
}

// Depth all 1 with convergence 0 is the nearest possible scene: p = D, so the
// left view is the source moved right by D/2 and the right view moved left by
// D/2 (view=both); view=right keeps the left view and moves the right by D,
// view=left the mirror. Depth 0 with convergence 1 (p = -D) mirrors all of
// it. Widths and percentages give integer shifts (exact, borders included),
// the 25 % maximum, and dyadic sub-pixel shifts (exact interpolation).
TEST(ExtremeWarp, NearestDepthShiftsTheViewsApart) {
  struct Case {
    int w;
    float percent;
  };
  // D = 10 (shift 5), D = 16 (25 %, shift 8), D = 3 (shift 1.5), D = 1024.25 (25 % of 4097, shift 512.125).
  const Case cases[] = {{200, 5.f}, {64, 25.f}, {100, 3.f}, {4097, 25.f}};
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::RGBA, PixelFormat::BGRx})
    for (Pattern pat : {Pattern::Checker1, Pattern::Noise})
      for (const Case &c : cases)
        for (bool behind : {false, true})
          for (StereoView v : kAllViews)
            for (HoleFill fill : kAllFills) {
              SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << pattern_name(pat) << " width "
                                                << c.w << " max_disparity " << c.percent << " view " << int(v)
                                                << " fill " << int(fill) << (behind ? " depth 0 conv 1" : " depth 1 conv 0"));
              const HostFrame src = make_frame(pat, f, c.w, 3, 4);
              const double D = c.percent * c.w / 100.0, p = behind ? -D : D;
              const Rendered r = warp(warp_params(c.percent, behind ? 1.f : 0.f, v, fill), src,
                                      cv::Mat(3, c.w, CV_32FC1, cv::Scalar(behind ? 0.f : 1.f)));
              for (int eye = 0; eye < 2; ++eye) {
                const double shift = view_shift(v, eye) * p;
                if (shift == 0) {
                  EXPECT_TRUE(view_is(r.out, eye, source_of(src)));
                } else {
                  expect_uniform_shift(r.out, eye, src, shift, fill);
                }
              }
              const double moved = v == StereoView::Both ? D / 2 : D;
              if (moved == std::floor(moved)) {
                EXPECT_EQ(r.holes, static_cast<long long>((v == StereoView::Both ? 2 : 1) * moved * 3));
              }
            }
}

// A shift that is no dyadic fraction (W 333, 3 %: D = 9.99): every pixel
// away from the border lies between the two source pixels it comes from.
TEST(ExtremeWarp, NonDyadicShiftInterpolatesBetweenNeighbours) {
  const HostFrame src = make_frame(Pattern::Noise, PixelFormat::RGBA, 333, 4, 8);
  const Rendered r = warp(warp_params(3.f, 0.f, StereoView::Both, HoleFill::Background), src,
                          cv::Mat(4, 333, CV_32FC1, cv::Scalar(1.f)));
  const double half = 3.0 * 333 / 100 / 2;
  for (int eye = 0; eye < 2; ++eye)
    for (int y = 0; y < 4; ++y)
      for (int X = 8; X < 333 - 8; ++X) {
        const double u = eye == 0 ? X - half : X + half;
        const int x0 = static_cast<int>(std::floor(u));
        const Rgba a = at(src, x0, y), b = at(src, x0 + 1, y), got = view_at(r.out, eye, X, y);
        auto between = [](int v, int p, int q) { return v >= std::min(p, q) && v <= std::max(p, q); };
        ASSERT_TRUE(between(got.r, a.r, b.r) && between(got.g, a.g, b.g) && between(got.b, a.b, b.b) &&
                    between(got.a, a.a, b.a))
            << "eye " << eye << " (" << X << "," << y << ") got " << str(got) << " between " << str(a) << " and "
            << str(b);
      }
}

// Depth values the warp defines rather than receives (NaN, -Inf, -1 -> 0;
// +Inf, 2 -> 1) give exactly the output of the clamped map.
TEST(ExtremeWarp, NonFiniteDepthReadsAsClamped) {
  for (Size s : kEdgeSizes) {
    const cv::Mat wild = make_depth(DepthKind::NonFinite, s.w, s.h, 13);
    cv::Mat clamped = wild.clone();
    for (int y = 0; y < s.h; ++y)
      for (int x = 0; x < s.w; ++x) {
        float &v = clamped.at<float>(y, x);
        v = std::isnan(v) || v < 0.f ? 0.f : (v > 1.f ? 1.f : v);
      }
    const HostFrame src = make_frame(Pattern::Checker8, PixelFormat::I420, s.w, s.h);
    for (float conv : {0.f, 1.f})
      for (StereoView v : kAllViews)
        for (HoleFill fill : kAllFills) {
          SCOPED_TRACE(::testing::Message() << size_name(s) << " convergence " << conv << " view " << int(v)
                                            << " fill " << int(fill));
          const WarpParams p = warp_params(25.f, conv, v, fill);
          const Rendered a = warp(p, src, wild), b = warp(p, src, clamped);
          EXPECT_EQ(a.holes, b.holes);
          EXPECT_EQ(first_difference(a.out, b.out), "");
        }
  }
}

// Every mode over depth 0, 1, noise and 0/1 noise at the extreme disparities
// and convergences: every byte written, the hole count consistent with what
// is left visible: fill=None paints exactly `holes` pixels magenta, the fills
// leave none (the source, a grey checkerboard, has no magenta).
TEST(ExtremeWarp, EveryModeOnStiffDepthWritesEveryPixel) {
  for (Size s : kEdgeSizes)
    for (DepthKind k : {DepthKind::Zero, DepthKind::One, DepthKind::Noise, DepthKind::Binary}) {
      const cv::Mat depth = make_depth(k, s.w, s.h, 17);
      const HostFrame src = make_frame(Pattern::Checker1, PixelFormat::RGBx, s.w, s.h);
      for (float md : {0.f, 25.f})
        for (float conv : {0.f, 1.f})
          for (StereoView v : kAllViews)
            for (HoleFill fill : kAllFills) {
              SCOPED_TRACE(::testing::Message() << size_name(s) << " " << depth_name(k) << " max_disparity " << md
                                                << " convergence " << conv << " view " << int(v) << " fill "
                                                << int(fill));
              const Rendered r = warp(warp_params(md, conv, v, fill), src, depth);
              const long long magenta = count_colour(r.out, kHoleColour);
              EXPECT_EQ(magenta, fill == HoleFill::None ? r.holes : 0);
              if (md == 0.f) {
                EXPECT_EQ(r.holes, 0);
              }
            }
    }
}

// ==== packing ====================================================================

HostFrame pair_of(const HostFrame &l, const HostFrame &r) {
  HostFrame pair(l.format(), 2 * l.width(), l.height(), 3);
  for (int y = 0; y < l.height(); ++y)
    for (int x = 0; x < l.width(); ++x) {
      store_rgba(pair.view(), x, y, at(l, x, y));
      store_rgba(pair.view(), l.width() + x, y, at(r, x, y));
    }
  return pair;
}

// rgb_luma() of a pixel as the anaglyph mixes compute it: in 16.16 fixed
// point (common/pack.h, anaglyph_mix_word), the weights round(65536 w).
uint8_t fixed_point_luma(Rgba v) {
  const long q[3] = {std::lround(65536.0 * 0.299f), std::lround(65536.0 * 0.587f), std::lround(65536.0 * 0.114f)};
  const long s = (q[0] * v.r + q[1] * v.g + q[2] * v.b + 32768) >> 16;
  return static_cast<uint8_t>(s < 0 ? 0 : (s > 255 ? 255 : s));
}

// Identical views: the Gray anaglyph is grey (every eye's channels carry the
// same luma: R' = G' = B' = the luma in the mix's fixed point, alpha from
// the view) and the Color
// anaglyph is the view itself (the glasses' filters split R', G', B'
// between the eyes), for every glasses, swap and stiff view.
TEST(ExtremePack, IdenticalViewsGiveGreyGrayAndUnchangedColourAnaglyphs) {
  for (PixelFormat f : kPackedFormats)
    for (Size s : kEdgeSizes)
      for (Pattern pat : {Pattern::Black, Pattern::White, Pattern::Colour, Pattern::Checker1, Pattern::Noise}) {
        const HostFrame view = make_frame(pat, f, s.w, s.h, 6);
        const HostFrame pair = pair_of(view, view);
        for (AnaglyphGlasses g : kAllGlasses)
          for (bool swap : {false, true}) {
            SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << size_name(s) << " "
                                              << pattern_name(pat) << " glasses " << int(g) << " swap " << swap);
            const HostFrame grey = pack(pack_params(PackLayout::Anaglyph, g, AnaglyphMethod::Gray, swap), pair);
            const HostFrame colour = pack(pack_params(PackLayout::Anaglyph, g, AnaglyphMethod::Color, swap), pair);
            for (int y = 0; y < s.h; ++y)
              for (int x = 0; x < s.w; ++x) {
                const Rgba v = at(view, x, y), gr = at(grey, x, y);
                const uint8_t l = fixed_point_luma(v);
                ASSERT_LE(std::abs(l - to_u8(rgb_luma(v.r, v.g, v.b))), 1);  // the float luma within a code
                ASSERT_TRUE(equal(gr, Rgba{l, l, l, v.a})) << "(" << x << "," << y << ") " << str(gr) << " from " << str(v);
                ASSERT_TRUE(equal(at(colour, x, y), v)) << "(" << x << "," << y << ")";
              }
          }
      }
}

// Every layout and anaglyph on stiff pairs (black | white, checkerboard |
// inverted checkerboard, noise | noise) at the degenerate sizes: every byte
// written, and the layouts that copy a view copy it.
TEST(ExtremePack, EveryLayoutOnStiffPairsWritesEveryPixel) {
  for (PixelFormat f : kPackedFormats)
    for (Size s : kEdgeSizes) {
      const HostFrame pairs[] = {
          pair_of(make_frame(Pattern::Black, f, s.w, s.h), make_frame(Pattern::White, f, s.w, s.h)),
          pair_of(make_frame(Pattern::Checker1, f, s.w, s.h), make_frame(Pattern::VStripes, f, s.w, s.h)),
          pair_of(make_frame(Pattern::Noise, f, s.w, s.h, 1), make_frame(Pattern::Noise, f, s.w, s.h, 2))};
      for (const HostFrame &pair : pairs)
        for (PackLayout l : kAllLayouts)
          for (bool swap : {false, true})
            for (AnaglyphGlasses g : kAllGlasses)
              for (AnaglyphMethod m : kAllMethods) {
                if (l != PackLayout::Anaglyph && (g != AnaglyphGlasses::RedCyan || m != AnaglyphMethod::Dubois))
                  continue;
                SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << size_name(s) << " layout "
                                                  << int(l) << " swap " << swap << " glasses " << int(g) << " method "
                                                  << int(m));
                const HostFrame out = pack(pack_params(l, g, m, swap), pair);
                const int eye_l = swap ? 1 : 0;
                auto view_px = [&](int eye, int x, int y) { return at(pair, eye * s.w + x, y); };
                for (int y = 0; y < out.height(); ++y)
                  for (int x = 0; x < out.width(); ++x) {
                    Rgba want{};
                    if (l == PackLayout::SideBySide)
                      want = view_px(x < s.w ? eye_l : 1 - eye_l, x % s.w, y);
                    else if (l == PackLayout::TopBottom)
                      want = view_px(y < s.h ? eye_l : 1 - eye_l, x, y % s.h);
                    else if (l == PackLayout::Left || l == PackLayout::Right)
                      want = view_px(l == PackLayout::Left ? eye_l : 1 - eye_l, x, y);
                    else
                      continue;
                    ASSERT_TRUE(equal(at(out, x, y), want)) << "(" << x << "," << y << ")";
                  }
              }
    }
}

// One 8K pair (two 7680 x 4320 views, black | white): the Gray red-cyan
// anaglyph is (luma L, luma R, luma R) = (0, 255, 255) everywhere, and
// TopBottomHalf is black over white; the poison (0xA5) can pass neither.
TEST(ExtremePack, Pair8K) {
  const int W = 7680, H = 4320;
  HostFrame pair(PixelFormat::RGBA, 2 * W, H);
  {
    std::vector<uint8_t> row(static_cast<size_t>(8) * W);
    for (int x = 0; x < 2 * W; ++x) {
      const uint8_t v = x < W ? 0 : 255;
      row[4 * x] = row[4 * x + 1] = row[4 * x + 2] = v;
      row[4 * x + 3] = 255;
    }
    for (int y = 0; y < H; ++y) std::memcpy(pair.view().plane[0] + static_cast<size_t>(y) * pair.view().stride[0], row.data(), row.size());
  }
  auto uniform = [](const HostFrame &f, int y0, int y1, Rgba c) -> ::testing::AssertionResult {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < f.width(); ++x)
        if (!equal(at(f, x, y), c))
          return ::testing::AssertionFailure() << "(" << x << "," << y << ") " << str(at(f, x, y)) << " want " << str(c);
    return ::testing::AssertionSuccess();
  };
  const HostFrame grey = pack_once(pack_params(PackLayout::Anaglyph, AnaglyphGlasses::RedCyan, AnaglyphMethod::Gray),
                                   pair, kPoisonA);
  EXPECT_TRUE(uniform(grey, 0, H, Rgba{0, 255, 255, 255}));
  const HostFrame tb = pack_once(pack_params(PackLayout::TopBottomHalf), pair, kPoisonA);
  EXPECT_TRUE(uniform(tb, 0, H / 2, Rgba{0, 0, 0, 255}));
  EXPECT_TRUE(uniform(tb, H / 2, H, Rgba{255, 255, 255, 255}));
}

// ==== the whole chain =============================================================

struct ChainParams {
  const char *name;
  DepthParams depth;
  BilateralParams filter;
  WarpParams warp;
  PackParams pack;
};

std::vector<ChainParams> chain_params() {
  std::vector<ChainParams> all;
  all.push_back({"defaults", DepthParams(), BilateralParams(), WarpParams(), PackParams()});
  ChainParams stiff{"stiff", DepthParams(), bilateral_params(kMaxBilateralRadius, 1e30f, 0.f),
                    warp_params(25.f, 0.f, StereoView::Both, HoleFill::NeighborAverage),
                    pack_params(PackLayout::SideBySideHalf)};
  stiff.depth.block_size = 2;
  stiff.depth.edge_threshold = 0.f;
  stiff.depth.region_weight = 0.f;
  all.push_back(stiff);
  ChainParams soft{"soft", DepthParams(), bilateral_params(kMaxBilateralRadius, 1e-30f, kInf),
                   warp_params(25.f, 1.f, StereoView::Left, HoleFill::Background),
                   pack_params(PackLayout::Anaglyph, AnaglyphGlasses::GreenMagenta, AnaglyphMethod::Gray, true)};
  soft.depth.hypothesis = Hypothesis::CenterNear;
  soft.depth.block_size = 64;
  soft.depth.edge_threshold = kInf;
  soft.depth.region_weight = 1.f;
  all.push_back(soft);
  all.push_back({"off", DepthParams(), bilateral_params(0, 3.f, 12.f),
                 warp_params(0.f, 0.5f, StereoView::Right, HoleFill::None), pack_params(PackLayout::TopBottom)});
  ChainParams clamped{"out of range", DepthParams(), bilateral_params(5, 3.f, 1e-30f),
                      warp_params(1e6f, -1.f, StereoView::Both, HoleFill::None),
                      pack_params(PackLayout::Checkerboard)};
  clamped.depth.hypothesis = Hypothesis::LeftRight;
  clamped.depth.block_size = 1000;
  clamped.depth.edge_threshold = 1e-30f;
  all.push_back(clamped);
  return all;
}

// Every stiff frame in every format through depth -> filter -> warp -> pack
// with default, stiff, soft, switched-off and out-of-range parameters: depth
// finite and in [0, 1] after both depth stages, every frame byte written,
// and the stages that are switched off are identities.
TEST(ExtremeChain, StiffFramesThroughEveryStage) {
  const std::vector<ChainParams> all = chain_params();
  uint32_t seed = 31;
  for (PixelFormat f : kAllFormats)
    for (Pattern pat : kAllPatterns)
      for (Size s : kEdgeSizes) {
        const HostFrame src = make_frame(pat, f, s.w, s.h, ++seed);
        for (const ChainParams &cp : all) {
          SCOPED_TRACE(::testing::Message() << test::format_name(f) << " " << pattern_name(pat) << " "
                                            << size_name(s) << " params " << cp.name);
          const DepthResult d = estimate(cp.depth, src);
          ASSERT_TRUE(depth_ok(d.depth));
          const cv::Mat filtered = filter(cp.filter, src, d.depth);
          ASSERT_TRUE(depth_ok(filtered));
          if (bilateral_sanitize(cp.filter).radius == 0) {
            EXPECT_TRUE(bitwise_equal(filtered, d.depth));
          }
          const Rendered r = warp(cp.warp, src, filtered);
          if (warp_sanitize(cp.warp).max_disparity == 0.f) {
            EXPECT_EQ(r.holes, 0);
            EXPECT_TRUE(view_is(r.out, 0, source_of(src)));
            EXPECT_TRUE(view_is(r.out, 1, source_of(src)));
          }
          const HostFrame packed = pack(cp.pack, r.out);
          int pw = 0, ph = 0;
          pack_size(cp.pack.layout, s.w, s.h, &pw, &ph);
          EXPECT_EQ(packed.width(), pw);
          EXPECT_EQ(packed.height(), ph);
        }
      }
}

}  // namespace
}  // namespace p3d
