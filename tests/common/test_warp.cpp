// DIBR warp (common/warp.h): known shifts (integer and sub-pixel), view
// directions, depth ordering, disocclusion filling from the background,
// NeighborAverage against a naive Jacobi written here, BackgroundSmooth
// against a brute-force reading of its specification, hole counts, every
// source and output format, edge sizes, extreme and invalid parameters.
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "test_data.h"
#include "warp.h"

namespace p3d {
namespace {

using test::warp_params;
using test::kAllFills;
using test::kAllViews;
using test::kAllFormats;
using test::kPackedFormats;


// Channels stay below 255, so a magenta pixel in an output is a hole.
HostFrame textured(PixelFormat f, int w, int h, uint32_t seed, int padding = 0) {
  std::mt19937 rng(seed);
  cv::Mat bgr(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(rng() % 200 + 20, rng() % 200 + 20, rng() % 200 + 20);
  return HostFrame::from_bgr(bgr, f, padding);
}

using DepthFn = std::function<float(int x, int y)>;
cv::Mat make_depth(int w, int h, const DepthFn &fn) {
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<float>(y, x) = fn(x, y);
  return d;
}
cv::Mat flat_depth(int w, int h, float v) {
  return make_depth(w, h, [v](int, int) { return v; });
}
cv::Mat noise_depth(int w, int h, uint32_t seed, bool binary) {
  std::mt19937 rng(seed);
  return make_depth(w, h, [&](int, int) {
    return binary ? static_cast<float>(rng() & 1) : std::uniform_real_distribution<float>(0.f, 1.f)(rng);
  });
}

struct Rendered {
  HostFrame out;
  long long holes = 0;
};

// Renders into a fresh 2W x H frame whose every byte starts as `poison`.
Rendered render(const WarpParams &p, const HostFrame &src, const cv::Mat &depth,
                PixelFormat out_format = PixelFormat::BGRA, uint8_t poison = 0xA5, int padding = 4) {
  Rendered r;
  r.out = HostFrame(out_format, 2 * src.width(), src.height(), padding);
  r.out.fill(poison);
  r.holes = warp_render_cpu(p, src.view(), YuvToRgb(), depth_view_of(depth), r.out.view());
  return r;
}

Rgba at(const HostFrame &f, int x, int y) { return load_rgba(f.view(), x, y, YuvToRgb()); }
// View pixel: eye 0 = left (columns [0, W)), eye 1 = right.
Rgba view_at(const HostFrame &out, int eye, int x, int y) { return at(out, eye * (out.width() / 2) + x, y); }

bool equal(Rgba a, Rgba b) { return a.r == b.r && a.g == b.g && a.b == b.b && a.a == b.a; }

::testing::AssertionResult same(Rgba got, Rgba want) {
  if (equal(got, want)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got (" << int(got.r) << "," << int(got.g) << "," << int(got.b) << ","
                                       << int(got.a) << ") want (" << int(want.r) << "," << int(want.g) << ","
                                       << int(want.b) << "," << int(want.a) << ")";
}

using PixelFn = std::function<Rgba(int x, int y)>;
// Every pixel of one view equals want(x, y).
::testing::AssertionResult view_is(const HostFrame &out, int eye, const PixelFn &want) {
  const int w = out.width() / 2;
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < w; ++x) {
      ::testing::AssertionResult r = same(view_at(out, eye, x, y), want(x, y));
      if (!r) return r << " at view " << eye << " (" << x << "," << y << ")";
    }
  return ::testing::AssertionSuccess();
}
PixelFn source_of(const HostFrame &src) {
  return [&src](int x, int y) { return at(src, x, y); };
}

// Exact reference of linear interpolation at a dyadic fraction: a + (b-a)*f
// is exact in float, then rounded half up.
Rgba lerp_exact(Rgba a, Rgba b, double f) {
  auto ch = [f](int p, int q) { return static_cast<uint8_t>(std::floor(p + (q - p) * f + 0.5)); };
  return Rgba{ch(a.r, b.r), ch(a.g, b.g), ch(a.b, b.b), ch(a.a, b.a)};
}

bool same_bytes(const HostFrame &a, const HostFrame &b) {
  const FrameView va = a.view(), vb = b.view();
  if (va.width != vb.width || va.height != vb.height || va.format != vb.format) return false;
  for (int y = 0; y < va.height; ++y)
    if (std::memcmp(va.plane[0] + y * va.stride[0], vb.plane[0] + y * vb.stride[0], 4 * va.width) != 0) return false;
  return true;
}

long long count_colour(const HostFrame &out, Rgba c) {
  long long n = 0;
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < out.width(); ++x) n += equal(at(out, x, y), c);
  return n;
}

// ---- known shifts -----------------------------------------------------------

// W = 100, max_disparity 8 % -> D = 8; depth 1, convergence 0.5 -> p = 4:
// view=both moves the left view right by 2 and the right view left by 2.
TEST(WarpShift, ConstantDepthIntegerDisparity) {
  const HostFrame src = textured(PixelFormat::BGRA, 100, 3, 1);
  const Rendered r = render(warp_params(8.f, 0.5f, StereoView::Both, HoleFill::Background), src, flat_depth(100, 3, 1.f));
  EXPECT_EQ(r.holes, 2 * 2 * 3);  // two columns uncovered at one edge of each view
  EXPECT_TRUE(view_is(r.out, 0, [&](int x, int y) { return at(src, x < 2 ? 0 : x - 2, y); }));
  EXPECT_TRUE(view_is(r.out, 1, [&](int x, int y) { return at(src, x > 97 ? 99 : x + 2, y); }));
}

// D = 1, depth 1, convergence 0.5: p = 0.5, shifts +-0.25 px; the target X
// takes the colour at u = X -+ 0.25, interpolated between its neighbours.
TEST(WarpShift, SubPixelShiftInterpolates) {
  const HostFrame src = textured(PixelFormat::RGBA, 100, 2, 2);
  const Rendered r = render(warp_params(1.f, 0.5f, StereoView::Both, HoleFill::None), src, flat_depth(100, 2, 1.f));
  EXPECT_EQ(r.holes, 0);
  EXPECT_TRUE(view_is(r.out, 0, [&](int x, int y) {
    return x == 0 ? at(src, 0, y) : lerp_exact(at(src, x - 1, y), at(src, x, y), 0.75);
  }));
  EXPECT_TRUE(view_is(r.out, 1, [&](int x, int y) {
    return x == 99 ? at(src, 99, y) : lerp_exact(at(src, x, y), at(src, x + 1, y), 0.25);
  }));
}

// view=right: the left view is the source; the right takes x - p with
// p = 1.5 * (1 - 0.5) = 0.75.
TEST(WarpShift, SubPixelShiftSingleView) {
  const HostFrame src = textured(PixelFormat::RGBx, 100, 2, 3);
  const Rendered r = render(warp_params(1.5f, 0.5f, StereoView::Right, HoleFill::None), src, flat_depth(100, 2, 1.f));
  // Column 99 is uncovered: t(99) = 98.25 and only t(x) - 0.5 <= X < t(x) + 0.5 reaches past t(99).
  EXPECT_EQ(r.holes, 2);
  EXPECT_TRUE(view_is(r.out, 0, source_of(src)));
  EXPECT_TRUE(view_is(r.out, 1, [&](int x, int y) {
    return x == 99 ? kHoleColour : lerp_exact(at(src, x, y), at(src, x + 1, y), 0.75);
  }));
}

// ---- view directions --------------------------------------------------------

// p = 8 * (1 - 0.5) = 4 (in front of the screen): the left view moves right,
// the right view left; view=left/right warp one eye by the whole p.
TEST(WarpViews, DirectionsInFrontOfScreen) {
  const HostFrame src = textured(PixelFormat::BGRA, 100, 2, 4);
  const cv::Mat near = flat_depth(100, 2, 1.f);
  const Rendered both = render(warp_params(8.f, 0.5f, StereoView::Both, HoleFill::None), src, near);
  const Rendered left = render(warp_params(8.f, 0.5f, StereoView::Left, HoleFill::None), src, near);
  const Rendered right = render(warp_params(8.f, 0.5f, StereoView::Right, HoleFill::None), src, near);
  auto or_hole = [&](int by) {
    return [&src, by](int x, int y) { return x - by < 0 || x - by > 99 ? kHoleColour : at(src, x - by, y); };
  };
  EXPECT_TRUE(view_is(both.out, 0, or_hole(2)));
  EXPECT_TRUE(view_is(both.out, 1, or_hole(-2)));
  EXPECT_TRUE(view_is(left.out, 0, or_hole(4)));
  EXPECT_TRUE(view_is(left.out, 1, source_of(src)));
  EXPECT_TRUE(view_is(right.out, 0, source_of(src)));
  EXPECT_TRUE(view_is(right.out, 1, or_hole(-4)));
  EXPECT_EQ(both.holes, 2 * 2 * 2);
  EXPECT_EQ(left.holes, 4 * 2);
  EXPECT_EQ(right.holes, 4 * 2);
}

// Behind the screen (depth 0 < convergence 0.5, p = -4) everything mirrors.
TEST(WarpViews, DirectionsBehindScreen) {
  const HostFrame src = textured(PixelFormat::BGRA, 100, 2, 5);
  const Rendered both = render(warp_params(8.f, 0.5f, StereoView::Both, HoleFill::Background), src, flat_depth(100, 2, 0.f));
  EXPECT_TRUE(view_is(both.out, 0, [&](int x, int y) { return at(src, x > 97 ? 99 : x + 2, y); }));
  EXPECT_TRUE(view_is(both.out, 1, [&](int x, int y) { return at(src, x < 2 ? 0 : x - 2, y); }));
}

// ---- zero disparity ---------------------------------------------------------

TEST(WarpZero, NoDisparityGivesTheSourceInEveryFormat) {
  for (PixelFormat f : kAllFormats) {
    SCOPED_TRACE(test::format_name(f));
    const HostFrame src = textured(f, 37, 11, 6, 3);
    const cv::Mat depth = noise_depth(37, 11, 7, false);
    for (StereoView v : kAllViews) {
      const Rendered zero = render(warp_params(0.f, 0.5f, v, HoleFill::None), src, depth);
      EXPECT_EQ(zero.holes, 0);
      EXPECT_TRUE(view_is(zero.out, 0, source_of(src)));
      EXPECT_TRUE(view_is(zero.out, 1, source_of(src)));
      // Depth on the screen plane everywhere: p = 0 whatever D is.
      const Rendered plane = render(warp_params(20.f, 0.3f, v, HoleFill::None), src, flat_depth(37, 11, 0.3f));
      EXPECT_EQ(plane.holes, 0);
      EXPECT_TRUE(view_is(plane.out, 0, source_of(src)));
      EXPECT_TRUE(view_is(plane.out, 1, source_of(src)));
    }
  }
}

// ---- depth ordering ---------------------------------------------------------

// Convergence 0 keeps the far background (depth 0) in place; a near pixel
// (depth 1, p = D = 4) at x = 10 lands on the background pixel 6 in the right
// view and must win there. Its own place becomes a hole between two equally
// far, equally distant neighbours: filled from the left one.
TEST(WarpOrder, NearerPixelWins) {
  const HostFrame src = textured(PixelFormat::BGRA, 100, 1, 8);
  const cv::Mat depth = make_depth(100, 1, [](int x, int) { return x == 10 ? 1.f : 0.f; });
  const Rendered r = render(warp_params(4.f, 0.f, StereoView::Right, HoleFill::Background), src, depth);
  EXPECT_EQ(r.holes, 1);
  EXPECT_TRUE(view_is(r.out, 0, source_of(src)));
  EXPECT_TRUE(view_is(r.out, 1, [&](int x, int y) { return at(src, x == 6 ? 10 : (x == 10 ? 9 : x), y); }));
  // Mirrored: view=left moves it right onto pixel 14.
  const Rendered l = render(warp_params(4.f, 0.f, StereoView::Left, HoleFill::Background), src, depth);
  EXPECT_EQ(l.holes, 1);
  EXPECT_TRUE(view_is(l.out, 0, [&](int x, int y) { return at(src, x == 14 ? 10 : (x == 10 ? 9 : x), y); }));
}

// Two near pixels land on one target: pixel 20 at depth 1 (p = 8) and pixel
// 16 at depth 0.5 (p = 4) both reach X = 12 in the right view; the nearer
// one (20) wins whichever way the row is walked.
TEST(WarpOrder, NearestOfSeveralWins) {
  const HostFrame src = textured(PixelFormat::BGRA, 64, 1, 9);
  const cv::Mat depth = make_depth(64, 1, [](int x, int) { return x == 20 ? 1.f : (x == 16 ? 0.5f : 0.f); });
  const Rendered r = render(warp_params(12.5f, 0.f, StereoView::Right, HoleFill::None), src, depth);
  EXPECT_TRUE(same(view_at(r.out, 1, 12, 0), at(src, 20, 0)));
  // Mirrored geometry in the left view: both reach X = 28 from 20 and 24.
  const cv::Mat mirrored = make_depth(64, 1, [](int x, int) { return x == 20 ? 1.f : (x == 24 ? 0.5f : 0.f); });
  const Rendered l = render(warp_params(12.5f, 0.f, StereoView::Left, HoleFill::None), src, mirrored);
  EXPECT_TRUE(same(view_at(l.out, 0, 28, 0), at(src, 20, 0)));
}

// ---- stretching ---------------------------------------------------------------

// Depth 0.25 on columns 20..29, 0 elsewhere, D = 8, convergence 0, right
// view: the step 29 -> 30 opens a gap of 1 + 8 * d. At d = 0.25 (gap 3 =
// 1 + kMaxStretch) the surface is stretched over X = 27..29 with
// u = 29 + (X - 27) / 3, kept in 1/256 steps: 29 + 85/256 and 29 + 171/256.
// At d = 0.3125 (gap 3.5) it tears: X = 27..29 are holes.
TEST(WarpStretch, GapUpToMaxStretchIsInterpolatedWiderIsAHole) {
  const HostFrame src = textured(PixelFormat::BGRA, 64, 2, 28);
  auto step = [](float d) { return make_depth(64, 2, [d](int x, int) { return x >= 20 && x <= 29 ? d : 0.f; }); };
  const WarpParams p = warp_params(12.5f, 0.f, StereoView::Right, HoleFill::None);
  const Rendered stretched = render(p, src, step(0.25f));
  EXPECT_EQ(stretched.holes, 0);
  for (int y = 0; y < 2; ++y) {
    EXPECT_TRUE(same(view_at(stretched.out, 1, 27, y), at(src, 29, y)));
    EXPECT_TRUE(same(view_at(stretched.out, 1, 28, y), lerp_exact(at(src, 29, y), at(src, 30, y), 85 / 256.)));
    EXPECT_TRUE(same(view_at(stretched.out, 1, 29, y), lerp_exact(at(src, 29, y), at(src, 30, y), 171 / 256.)));
    EXPECT_TRUE(same(view_at(stretched.out, 1, 30, y), at(src, 30, y)));
  }
  const Rendered torn = render(p, src, step(0.3125f));
  EXPECT_EQ(torn.holes, 3 * 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 27; x <= 29; ++x) EXPECT_TRUE(same(view_at(torn.out, 1, x, y), kHoleColour)) << x;
}

// The render (fill none) against the z-buffer read literally off the
// header: every target X of a row keeps the largest key of the source
// pixels whose covered run holds it (warp_span(), warp_hit_at()), each
// pixel placed by warp_source(), and shows sample_row() at the winner's u.
// (warp_span(), not warp_covers(): in float, t + 0.5 can round up to the
// next integer, so warp_covers() can miss a target whose t - 0.5 <= X <
// t + 0.5 holds exactly; warp_span() is what both devices render.) The renderer
// computes spans and the first two hits of many pixels at once
// (span_keys_vector in common/warp.cpp), so rows of every width from 1 to
// 70 (all remainders of the vector width), with depths that stretch,
// fold, jump, leave [0, 1] or are NaN, and subnormal depths beside 1 at
// convergence 0 with D = 2 (a subnormal gap: an infinite 1 / gap), for
// every view.
TEST(WarpScatter, RenderIsTheLiteralZBuffer) {
  const uint32_t seed = std::random_device{}();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 175; ++trial) {
    const int w = 1 + trial % 70, h = 3;
    const HostFrame src = textured(PixelFormat::RGBA, w, h, rng());
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    const int kind = trial % 5;
    const cv::Mat depth = make_depth(w, h, [&](int x, int) {
      switch (kind) {
        case 0: return unit(rng);                                         // noise: folds and holes
        case 1: return 0.3f + 0.4f * std::sin(0.37f * x) + 0.05f * unit(rng);  // smooth: stretches
        case 2: return (x / 7) % 2 ? 0.95f : 0.05f;                        // steps
        case 4: {
          const float v[] = {0.f, 1e-40f, 1.f, 0.5f, 3e-39f};
          return v[rng() % 5];
        }
        default: {
          const float v = unit(rng);
          return v < 0.1f ? std::nanf("") : 3.f * v - 1.f;                 // outside [0, 1], NaN
        }
      }
    });
    const WarpParams p = kind == 4 ? warp_params(std::min(25.f, 200.f / w), 0.f, kAllViews[trial % 3], HoleFill::None)
                                   : warp_params(5.f + 20.f * unit(rng), unit(rng), kAllViews[trial % 3], HoleFill::None);
    const Rendered got = render(p, src, depth, PixelFormat::RGBA);
    const WarpParams sp = warp_sanitize(p);
    const float D = disparity_scale(sp, w);
    for (int eye = 0; eye < 2; ++eye) {
      const float shift = warp_eye_shift(sp, D, eye);
      for (int y = 0; y < h; ++y) {
        std::vector<Rgba> row(w);
        for (int x = 0; x < w; ++x) row[x] = at(src, x, y);
        for (int X = 0; X < w; ++X) {
          Rgba want = row[X];
          if (shift != 0.f) {
            WideKeys::Word best = 0;
            for (int x = 0; x < w; ++x) {
              const WarpSource s = warp_source(depth.ptr<float>(y), x, w, shift, D, sp.convergence);
              const WarpSpan span = warp_span(s, w);
              if (span.first <= X && X <= span.last) best = std::max(best, WideKeys::key(warp_hit_at(s, X, w), X));
            }
            want = best ? sample_row(row.data(), w, WideKeys::u(best, X)) : kHoleColour;
          }
          ASSERT_TRUE(same(view_at(got.out, eye, X, y), want))
              << "width " << w << " depth kind " << kind << " eye " << eye << " at (" << X << "," << y << ")";
        }
      }
    }
  }
}

// The shared helpers on the stretched step above: pixel 29 (depth 0.25,
// t = 27) connected to pixel 30 (depth 0, t = 30).
TEST(WarpHelpers, StretchedSpanKeys) {
  float depth[64];
  for (int x = 0; x < 64; ++x) depth[x] = x >= 20 && x <= 29 ? 0.25f : 0.f;
  const WarpSource s = warp_source(depth, 29, 64, -1.f, 8.f, 0.f);
  EXPECT_TRUE(s.connected);
  EXPECT_EQ(s.t0, 27.f);
  EXPECT_EQ(s.t1, 30.f);
  const WarpSpan span = warp_span(s, 64);
  EXPECT_EQ(span.first, 27);
  EXPECT_EQ(span.last, 29);
  // Footprint target 27: u = 29, depth 0.25. Span targets: depth runs
  // linearly from 0.25 to 0 with u (1/6 and 1/12 at u = 29 1/3, 29 2/3).
  EXPECT_EQ(warp_u_of(warp_hit_at(s, 27, 64).u), 29.f);
  EXPECT_EQ(warp_hit_at(s, 27, 64).depth, warp_depth_code(0.25f));
  EXPECT_EQ(warp_u_of(warp_hit_at(s, 28, 64).u), 29.f + 85.f / 256.f);
  EXPECT_NEAR(warp_hit_at(s, 28, 64).depth, 65535 / 6., 0.5);  // 10922.5: either
  EXPECT_EQ(warp_hit_at(s, 29, 64).depth, 5461u);             // round(65535 / 12)
  // The clipped span at the view's edges.
  const WarpSpan left_edge = warp_span(warp_source(depth, 0, 64, -1.f, 8.f, 0.f), 64);
  EXPECT_EQ(left_edge.first, 0);
  EXPECT_EQ(left_edge.last, 0);
  const WarpSpan out = warp_span(warp_source(depth, 25, 64, -1.f, 80.f, 0.f), 64);  // t = 5
  EXPECT_EQ(out.first, 5);
}

// sample_row interpolates in integers; the specification is the float
// to_u8(a + (b - a) * f) at f = k / 256. Every channel pair and every
// 1/256 step must agree, or the CPU and GPU would both drift from it alike.
TEST(WarpHelpers, IntegerSamplingEqualsTheFloatFormulaEverywhere) {
  long long mismatches = 0;
  for (int a = 0; a < 256; ++a)
    for (int b = 0; b < 256; ++b)
      for (int k = 0; k < 256; ++k) {
        const float f = static_cast<float>(k) / 256.f;
        const int want = to_u8(static_cast<float>(a) + (static_cast<float>(b) - static_cast<float>(a)) * f);
        if (sample_channel(a, b, k) != want) ++mismatches;
      }
  EXPECT_EQ(mismatches, 0);
  // Whole pixels through keys, the row's last pixel included (u = W - 1).
  const Rgba row[3] = {{0, 255, 10, 255}, {255, 0, 200, 255}, {7, 9, 11, 13}};
  for (int q = 0; q <= 2 * 256; ++q) {
    const float u = static_cast<float>(q) / 256.f;
    const int x0 = static_cast<int>(std::floor(u)), x1 = x0 + 1 < 3 ? x0 + 1 : x0;
    const float f = u - static_cast<float>(x0);
    const Rgba got = sample_row(row, 3, warp_u_code(u));
    auto lerp = [f](uint8_t a, uint8_t b) { return to_u8(a + (static_cast<float>(b) - a) * f); };
    EXPECT_EQ(got.r, lerp(row[x0].r, row[x1].r)) << "q " << q;
    EXPECT_EQ(got.g, lerp(row[x0].g, row[x1].g)) << "q " << q;
    EXPECT_EQ(got.b, lerp(row[x0].b, row[x1].b)) << "q " << q;
    EXPECT_EQ(got.a, lerp(row[x0].a, row[x1].a)) << "q " << q;
  }
}

// sample_word (the CPU's and the GPU's resolve loops) is sample_row on
// rgba_word() words: every channel value pair at every fraction k, four
// pairs per word, plus the row's last pixel and the round trip of words.
TEST(WarpHelpers, SampleWordIsSampleRow) {
  std::mt19937 rng(31);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int a = 0; a < 256; ++a)
    for (int b = 0; b < 256; ++b) {
      const Rgba ca{static_cast<uint8_t>(a), static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(b),
                    static_cast<uint8_t>(byte(rng))};
      const Rgba cb{static_cast<uint8_t>(b), static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(a),
                    static_cast<uint8_t>(byte(rng))};
      const Rgba row[3] = {ca, cb, ca};
      const uint32_t words[3] = {rgba_word(ca), rgba_word(cb), rgba_word(ca)};
      ASSERT_TRUE(equal(word_rgba(words[1]), cb));
      for (int k = 0; k < 256; k += (a + b) % 7 + 1) {
        const unsigned key = warp_u_code(static_cast<float>(k) / 256.f);
        ASSERT_EQ(sample_word(words, 3, key), rgba_word(sample_row(row, 3, key))) << a << " " << b << " " << k;
      }
      const unsigned last = warp_u_code(2.f);
      ASSERT_EQ(sample_word(words, 3, last), rgba_word(sample_row(row, 3, last)));
    }
}

// warp_span is a closed form of "the run of targets warp_covers() accepts,
// starting at the footprint": compare it with walking warp_covers() for
// random, integer and half-integer targets, connected or not.
TEST(WarpHelpers, SpanIsTheRunOfCoveredTargets) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> pos(-20.f, 120.f), gap(-1.f, 4.5f);
  const int width = 100;
  for (int i = 0; i < 200000; ++i) {
    float t0 = pos(rng), t1 = t0 + gap(rng);
    if (i % 4 == 1) t0 = std::round(t0 * 2.f) / 2.f;  // half-integers and integers
    if (i % 4 == 2) t1 = std::round(t1 * 2.f) / 2.f;
    const float d = 0.5f;
    const WarpSource s = warp_link(40, d, t0, d, t1, i % 7 != 0);
    int X = static_cast<int>(std::ceil(t0 - 0.5f));
    ASSERT_TRUE(warp_covers(s, X));
    while (warp_covers(s, X + 1)) ++X;
    const int first = std::max(0, static_cast<int>(std::ceil(t0 - 0.5f))), last = std::min(width - 1, X);
    const WarpSpan span = warp_span(s, width);
    if (first > last) {
      EXPECT_GT(span.first, span.last) << t0 << " " << t1;
    } else {
      EXPECT_EQ(span.first, first) << t0 << " " << t1;
      EXPECT_EQ(span.last, last) << t0 << " " << t1;
    }
  }
}

// warp_span rounds with ceil_to_int, which the host computes without
// ceilf: it must give ceilf's integer for every value a target can take.
// Random values over the widest targets (8192-pixel rows, 25 % disparity),
// the integers and half-integers there with their float neighbours, signed
// zeros and the ends of the int-exact float range.
TEST(WarpHelpers, CeilToIntIsCeilf) {
  auto expect_ceil = [](float v) { ASSERT_EQ(ceil_to_int(v), static_cast<int>(std::ceil(v))) << v; };
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> wide(-12000.f, 12000.f), unit(-2.f, 2.f);
  for (int i = 0; i < 1000000; ++i) {
    expect_ceil(wide(rng));
    expect_ceil(unit(rng));
  }
  for (int k = -24000; k <= 24000; ++k) {
    const float v = static_cast<float>(k) / 2.f;
    expect_ceil(v);
    expect_ceil(std::nextafter(v, -1e9f));
    expect_ceil(std::nextafter(v, 1e9f));
  }
  for (float v : {0.f, -0.f, 1e-30f, -1e-30f, 8388607.5f, -8388607.5f, 16777216.f, -16777216.f, 2.1e9f, -2.1e9f})
    expect_ceil(v);
}

TEST(WarpHelpers, KeysOrderByDepthThenPosition) {
  auto hit = [](float d, float u) { return WarpHit{warp_depth_code(d), warp_u_code(u)}; };
  EXPECT_GT(WideKeys::key(hit(0.5f, 3.f), 0), WideKeys::key(hit(0.25f, 60.f), 0));
  EXPECT_GT(WideKeys::key(hit(0.5f, 3.5f), 0), WideKeys::key(hit(0.5f, 3.f), 0));
  EXPECT_GT(WideKeys::key(hit(0.f, 0.f), 0), 0ull);  // 0 stays "hole"
  EXPECT_EQ(warp_depth_code(-1.f), 0u);
  EXPECT_EQ(warp_depth_code(2.f), 65535u);
  EXPECT_EQ(warp_depth_code(1.f), 65535u);
  EXPECT_EQ(warp_depth_code(0.5f), 32768u);
  // Nearer than 1/65535 apart: one depth code, ordered by u.
  EXPECT_GT(WideKeys::key(hit(0.50000f, 3.5f), 0), WideKeys::key(hit(0.500005f, 3.f), 0));
  EXPECT_EQ(warp_u_of(WideKeys::u(WideKeys::key(hit(0.7f, 1234.5f), 0), 0)), 1234.5f);
  EXPECT_EQ(WideKeys::depth(WideKeys::key(hit(0.7f, 1234.5f), 0)), warp_depth_code(0.7f));
}

// NarrowKeys are WideKeys in 32 bits for hits within 127 pixels of their
// target: the same order at every target, the same depth and u codes back,
// never 0. Every u code within 32767 of 256 X (the bound of
// warp_narrow_keys_fit) at a few targets and depths, compared pairwise with
// its neighbours and with random others.
TEST(WarpHelpers, NarrowKeysOrderAsWideKeysNearTheTarget) {
  std::mt19937 rng(41);
  for (int X : {0, 1, 127, 128, 300, 4095, 7679, 65535}) {
    const unsigned lo = 256u * X > 32767u ? 256u * X - 32767u : 1u, hi = 256u * X + 32767u;
    std::uniform_int_distribution<unsigned> any_u(lo, hi), any_d(0u, 65535u);
    for (unsigned d : {0u, 1u, 32768u, 65534u, 65535u})
      for (unsigned u = lo; u <= hi; ++u) {
        const WarpHit h{d, u};
        const NarrowKeys::Word n = NarrowKeys::key(h, X);
        ASSERT_NE(n, 0u) << X << " " << u;
        ASSERT_EQ(NarrowKeys::u(n, X), u) << X;
        ASSERT_EQ(NarrowKeys::depth(n), d);
        const WarpHit o{any_d(rng), any_u(rng)};
        ASSERT_EQ(n < NarrowKeys::key(o, X), WideKeys::key(h, X) < WideKeys::key(o, X)) << X << " " << u;
        if (u > lo) {
          ASSERT_GT(n, NarrowKeys::key(WarpHit{d, u - 1}, X));
        }
      }
  }
}

// warp_narrow_keys_fit's bound holds: with random depth rows at parameters
// it accepts (up to its limit) every covered target's u code lies within
// 32767 of 256 X, and it refuses the parameters past that limit.
TEST(WarpHelpers, NarrowKeysFitBoundsEveryHit) {
  std::mt19937 rng(43);
  std::uniform_real_distribution<float> u01(0.f, 1.f);
  const int w = 4000;
  std::vector<float> depth(w);
  long long hits = 0, max_off = 0;
  for (int round = 0; round < 60; ++round) {
    const float convergence = round % 3 == 0 ? 0.f : round % 3 == 1 ? 1.f : u01(rng);
    const float c = std::max(convergence, 1.f - convergence), shift = round % 2 ? 1.f : -0.5f;
    float D = 120.f / (std::fabs(shift) * c);  // at the limit: the largest D it accepts
    while (!warp_narrow_keys_fit(shift, 0.f, D, convergence)) D = std::nextafter(D, 0.f);
    ASSERT_GT(D, 0.9999f * 120.f / (std::fabs(shift) * c));
    ASSERT_FALSE(warp_narrow_keys_fit(0.f, shift, D * 1.01f, convergence));
    for (int x = 0; x < w; ++x) depth[x] = round % 4 == 0 ? static_cast<float>(rng() & 1) : u01(rng);
    for (int x = 0; x < w; ++x) {
      const WarpSource s = warp_source(depth.data(), x, w, shift, D, convergence);
      const WarpSpan span = warp_span(s, w);
      for (int X = span.first; X <= span.last; ++X, ++hits) {
        const long long off = std::llabs(static_cast<long long>(warp_hit_at(s, X, w).u) - 256ll * X);
        ASSERT_LE(off, 32767) << x << " " << X;
        max_off = std::max(max_off, off);
      }
    }
  }
  EXPECT_GT(hits, 60 * w / 2);
  EXPECT_GT(max_off, 256 * 120) << "the rows reach the limit";  // so the bound is tested where it binds
}

TEST(WarpHelpers, BackgroundSourcePicksFartherThenCloserThenLeft) {
  const unsigned far = warp_depth_code(0.1f), near = warp_depth_code(0.9f);
  EXPECT_EQ(background_source(10, 5, far, 11, near), 5);
  EXPECT_EQ(background_source(10, 9, near, 20, far), 20);
  EXPECT_EQ(background_source(10, 7, far, 12, far), 12);  // equal depth: closer
  EXPECT_EQ(background_source(10, 8, far, 12, far), 8);   // equal distance too: left
  EXPECT_EQ(background_source(10, -1, 0, 12, near), 12);
  EXPECT_EQ(background_source(10, 3, near, -1, 0), 3);
  EXPECT_EQ(background_source(10, -1, 0, -1, 0), -1);
}

TEST(WarpHelpers, SanitizeAndDepth) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(warp_depth(nan), 0.f);
  EXPECT_EQ(warp_depth(-0.5f), 0.f);
  EXPECT_EQ(warp_depth(1.5f), 1.f);
  EXPECT_EQ(warp_depth(0.375f), 0.375f);
  WarpParams p = warp_params(nan, nan, StereoView::Left, HoleFill::None);
  EXPECT_EQ(warp_sanitize(p).max_disparity, 0.f);
  EXPECT_EQ(warp_sanitize(p).convergence, 0.f);
  p = warp_params(30.f, 2.f, StereoView::Left, HoleFill::None);
  EXPECT_EQ(warp_sanitize(p).max_disparity, kMaxDisparityPercent);
  EXPECT_EQ(warp_sanitize(p).convergence, 1.f);
  EXPECT_EQ(warp_sanitize(p).view, StereoView::Left);
  EXPECT_EQ(warp_eye_shift(p, 0.f, 0), 0.f);
  EXPECT_EQ(warp_eye_shift(p, 2.f, 0), 1.f);
  EXPECT_EQ(warp_eye_shift(p, 2.f, 1), 0.f);
}

// ---- disocclusions ----------------------------------------------------------

// A near square (depth 1, columns 24..39, rows 2..5) over a far background
// (depth 0), convergence 0, D = 8: the square moves +4 in the left view
// (uncovering columns 24..27) and -4 in the right view (uncovering 36..39).
constexpr int kSceneW = 64, kSceneH = 8;
bool in_square(int x, int y) { return x >= 24 && x <= 39 && y >= 2 && y <= 5; }
cv::Mat square_depth() {
  return make_depth(kSceneW, kSceneH, [](int x, int y) { return in_square(x, y) ? 1.f : 0.f; });
}
HostFrame two_colour_scene(Rgba bg, Rgba fg) {
  HostFrame f(PixelFormat::BGRA, kSceneW, kSceneH);
  for (int y = 0; y < kSceneH; ++y)
    for (int x = 0; x < kSceneW; ++x) store_rgba(f.view(), x, y, in_square(x, y) ? fg : bg);
  return f;
}
const WarpParams kSceneParams = warp_params(12.5f, 0.f, StereoView::Both, HoleFill::Background);
bool left_hole(int x, int y) { return x >= 24 && x <= 27 && y >= 2 && y <= 5; }
bool right_hole(int x, int y) { return x >= 36 && x <= 39 && y >= 2 && y <= 5; }

TEST(WarpFill, BackgroundFillsDisocclusionWithBackground) {
  const Rgba bg{20, 180, 40, 255}, fg{220, 30, 10, 255};
  const Rendered r = render(kSceneParams, two_colour_scene(bg, fg), square_depth());
  EXPECT_EQ(r.holes, 2 * 4 * 4);
  EXPECT_TRUE(view_is(r.out, 0, [&](int x, int y) { return in_square(x - 4, y) ? fg : bg; }));
  EXPECT_TRUE(view_is(r.out, 1, [&](int x, int y) { return in_square(x + 4, y) ? fg : bg; }));
}

// Textured: the hole copies the nearest background pixel, which sits left of
// the hole in the left view (column 23) and right of it in the right view
// (column 40, while the foreground is on its left).
TEST(WarpFill, BackgroundTakesTheFartherSide) {
  const HostFrame src = textured(PixelFormat::BGRA, kSceneW, kSceneH, 10);
  const Rendered r = render(kSceneParams, src, square_depth());
  EXPECT_EQ(r.holes, 2 * 4 * 4);
  EXPECT_TRUE(view_is(r.out, 0, [&](int x, int y) {
    return left_hole(x, y) ? at(src, 23, y) : in_square(x - 4, y) ? at(src, x - 4, y) : at(src, x, y);
  }));
  EXPECT_TRUE(view_is(r.out, 1, [&](int x, int y) {
    return right_hole(x, y) ? at(src, 40, y) : in_square(x + 4, y) ? at(src, x + 4, y) : at(src, x, y);
  }));
}

TEST(WarpFill, NonePaintsHolesMagenta) {
  const HostFrame src = textured(PixelFormat::BGRA, kSceneW, kSceneH, 11);
  WarpParams p = kSceneParams;
  p.fill = HoleFill::None;
  const Rendered r = render(p, src, square_depth());
  EXPECT_EQ(r.holes, 2 * 4 * 4);
  EXPECT_EQ(count_colour(r.out, kHoleColour), r.holes);
  EXPECT_TRUE(view_is(r.out, 0, [&](int x, int y) {
    return left_hole(x, y) ? kHoleColour : in_square(x - 4, y) ? at(src, x - 4, y) : at(src, x, y);
  }));
  EXPECT_TRUE(view_is(r.out, 1, [&](int x, int y) {
    return right_hole(x, y) ? kHoleColour : in_square(x + 4, y) ? at(src, x + 4, y) : at(src, x, y);
  }));
}

// Independent NeighborAverage: from the None rendering (holes = magenta, the
// source never is), Jacobi steps over each view with a plain hole mask.
HostFrame naive_neighbour_average(const HostFrame &none_render) {
  HostFrame out(PixelFormat::BGRA, none_render.width(), none_render.height());
  const int w = none_render.width() / 2, h = none_render.height();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < 2 * w; ++x) store_rgba(out.view(), x, y, at(none_render, x, y));
  for (int eye = 0; eye < 2; ++eye) {
    std::vector<std::vector<bool>> hole(h, std::vector<bool>(w));
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) hole[y][x] = equal(view_at(none_render, eye, x, y), kHoleColour);
    for (bool changed = true; changed;) {
      changed = false;
      auto next = hole;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          if (!hole[y][x]) continue;
          int n = 0, s[4] = {0, 0, 0, 0};
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int xx = x + dx, yy = y + dy;
              if ((!dx && !dy) || xx < 0 || yy < 0 || xx >= w || yy >= h || hole[yy][xx]) continue;
              const Rgba c = view_at(out, eye, xx, yy);
              s[0] += c.r, s[1] += c.g, s[2] += c.b, s[3] += c.a, ++n;
            }
          if (n == 0) continue;
          auto mean = [n](int v) { return static_cast<uint8_t>((v + n / 2) / n); };
          store_rgba(out.view(), eye * w + x, y, Rgba{mean(s[0]), mean(s[1]), mean(s[2]), mean(s[3])});
          next[y][x] = false;
          changed = true;
        }
      hole = next;
    }
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (hole[y][x]) store_rgba(out.view(), eye * w + x, y, kFillBlack);
  }
  return out;
}

// A fill against its naive reference, which gets the fill=none rendering
// (holes magenta), the parameters and the depth.
using NaiveFill = std::function<HostFrame(const WarpParams &, const HostFrame &none_render, const cv::Mat &depth)>;
void expect_fill_matches_naive(HoleFill fill, const NaiveFill &naive, const WarpParams &base, const HostFrame &src,
                               const cv::Mat &depth) {
  WarpParams p = base;
  p.fill = HoleFill::None;
  const Rendered none = render(p, src, depth);
  p.fill = fill;
  const Rendered got = render(p, src, depth);
  EXPECT_EQ(got.holes, none.holes);
  EXPECT_GT(got.holes, 0);
  EXPECT_EQ(count_colour(got.out, kHoleColour), 0);
  const HostFrame want = naive(p, none.out, depth);
  for (int eye = 0; eye < 2; ++eye)
    EXPECT_TRUE(view_is(got.out, eye, [&](int x, int y) { return view_at(want, eye, x, y); }));
}

void expect_neighbour_average_matches_naive(const WarpParams &base, const HostFrame &src, const cv::Mat &depth) {
  expect_fill_matches_naive(HoleFill::NeighborAverage,
                            [](const WarpParams &, const HostFrame &none, const cv::Mat &) {
                              return naive_neighbour_average(none);
                            },
                            base, src, depth);
}

TEST(WarpFill, NeighborAverageFillsAllHoles) {
  expect_neighbour_average_matches_naive(kSceneParams, textured(PixelFormat::BGRA, kSceneW, kSceneH, 12),
                                         square_depth());
  const HostFrame src = textured(PixelFormat::I420, 61, 37, 13);
  expect_neighbour_average_matches_naive(warp_params(15.f, 0.4f, StereoView::Both, HoleFill::None), src,
                                         noise_depth(61, 37, 14, true));
  expect_neighbour_average_matches_naive(warp_params(25.f, 0.f, StereoView::Right, HoleFill::None), src,
                                         noise_depth(61, 37, 15, false));
}

TEST(WarpFill, NeighborAverageOfOneColourIsThatColour) {
  const Rgba c{90, 60, 30, 255};
  const Rendered r = render(warp_params(12.5f, 0.f, StereoView::Both, HoleFill::NeighborAverage), two_colour_scene(c, c),
                            square_depth());
  EXPECT_EQ(r.holes, 2 * 4 * 4);
  for (int eye = 0; eye < 2; ++eye) EXPECT_TRUE(view_is(r.out, eye, [&](int, int) { return c; }));
}

// ---- BackgroundSmooth ---------------------------------------------------------

// Keys of one rendered view, recomputed from the public helpers (the warp's
// scatter is tested above): what BackgroundSmooth's background pick reads.
std::vector<WideKeys::Word> view_keys(const WarpParams &params, const cv::Mat &depth, int eye) {
  const WarpParams p = warp_sanitize(params);
  const int w = depth.cols, h = depth.rows;
  const float D = disparity_scale(p, w), shift = warp_eye_shift(p, D, eye);
  std::vector<WideKeys::Word> keys(static_cast<size_t>(w) * h, 0ull);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const WarpSource s = warp_source(depth.ptr<float>(y), x, w, shift, D, p.convergence);
      const WarpSpan span = warp_span(s, w);
      for (int X = span.first; X <= span.last; ++X) {
        WideKeys::Word &k = keys[static_cast<size_t>(y) * w + X];
        k = std::max(k, WideKeys::key(warp_hit_at(s, X, w), X));
      }
    }
  return keys;
}

// Independent BackgroundSmooth, the header's rules read literally (brute
// force, no prefix sums): from the None rendering and the keys of each
// warped view.
HostFrame naive_background_smooth(const WarpParams &params, const HostFrame &none_render, const cv::Mat &depth) {
  HostFrame out(PixelFormat::BGRA, none_render.width(), none_render.height());
  const int w = none_render.width() / 2, h = none_render.height();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < 2 * w; ++x) store_rgba(out.view(), x, y, at(none_render, x, y));
  const WarpParams p = warp_sanitize(params);
  const float D = disparity_scale(p, w);
  for (int eye = 0; eye < 2; ++eye) {
    const float shift = warp_eye_shift(p, D, eye);
    if (shift == 0.f) continue;
    const std::vector<WideKeys::Word> keys = view_keys(params, depth, eye);
    auto hole = [&](int x, int y) { return keys[static_cast<size_t>(y) * w + x] == 0; };
    auto is_clean = [&](int x, int y) {
      for (int xx = x - kSmoothClean; xx <= x + kSmoothClean; ++xx)
        if (xx >= 0 && xx < w && hole(xx, y)) return false;
      return true;
    };
    // The anchor of a hole, or false when it has none.
    auto anchor = [&](int x, int y, Rgba *c) {
      int side[2];
      for (int dir = 0; dir < 2; ++dir) {
        int clean = -1, any = -1;
        for (int k = 1; k <= w; ++k) {
          const int xx = dir == 0 ? x - k : x + k;
          if (xx < 0 || xx >= w) break;
          if (!hole(xx, y) && any < 0) any = xx;
          if (is_clean(xx, y)) {
            clean = xx;
            break;
          }
        }
        side[dir] = clean >= 0 ? clean : any;
      }
      const int xl = side[0], xr = side[1];
      auto depth_at = [&](int xx) { return xx >= 0 ? WideKeys::depth(keys[static_cast<size_t>(y) * w + xx]) : 0u; };
      const int pick = background_source(x, xl, depth_at(xl), xr, depth_at(xr));
      if (pick < 0) return false;
      *c = view_at(none_render, eye, pick, y);
      return true;
    };
    const int R = 1 + static_cast<int>(std::fabs(shift) * D / 2.f), Rx = R / 4;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (!hole(x, y)) continue;
        long long sum[4] = {0, 0, 0, 0}, n = 0;
        // The row run of holes through (x, y) within Rx, then each column's run within R.
        for (int dir = -1; dir <= 1; dir += 2)
          for (int dx = dir < 0 ? 0 : 1; dx <= Rx; ++dx) {
            const int xx = x + dir * dx;
            if (xx < 0 || xx >= w || !hole(xx, y)) break;
            for (int vdir = -1; vdir <= 1; vdir += 2)
              for (int dy = vdir < 0 ? 0 : 1; dy <= R; ++dy) {
                const int yy = y + vdir * dy;
                if (yy < 0 || yy >= h || !hole(xx, yy)) break;
                Rgba c;
                if (!anchor(xx, yy, &c)) continue;
                sum[0] += c.r, sum[1] += c.g, sum[2] += c.b, sum[3] += c.a, ++n;
              }
          }
        Rgba c = kFillBlack;
        if (n > 0) {
          auto mean = [n](long long v) { return static_cast<uint8_t>((v + n / 2) / n); };
          c = Rgba{mean(sum[0]), mean(sum[1]), mean(sum[2]), mean(sum[3])};
        }
        store_rgba(out.view(), eye * w + x, y, c);
      }
  }
  return out;
}

void expect_background_smooth_matches_naive(const WarpParams &base, const HostFrame &src, const cv::Mat &depth) {
  expect_fill_matches_naive(HoleFill::BackgroundSmooth, naive_background_smooth, base, src, depth);
}

TEST(WarpFill, BackgroundSmoothMatchesTheSpecification) {
  expect_background_smooth_matches_naive(kSceneParams, textured(PixelFormat::BGRA, kSceneW, kSceneH, 40),
                                         square_depth());
  const HostFrame src = textured(PixelFormat::I420, 61, 37, 41);
  for (StereoView v : kAllViews) {
    SCOPED_TRACE(int(v));
    expect_background_smooth_matches_naive(warp_params(15.f, 0.4f, v, HoleFill::None), src,
                                           noise_depth(61, 37, 42, true));
    expect_background_smooth_matches_naive(warp_params(25.f, 0.f, v, HoleFill::None), src,
                                           noise_depth(61, 37, 43, false));
  }
  // Smooth depth with steps: long runs, so R and Rx clip (R = 7, Rx = 1 at D = 12.2).
  const cv::Mat steps = make_depth(97, 45, [](int x, int y) { return ((x / 13 + y / 9) % 3) / 2.f; });
  expect_background_smooth_matches_naive(warp_params(12.6f, 0.f, StereoView::Right, HoleFill::None),
                                         textured(PixelFormat::RGBA, 97, 45, 44), steps);
}

// A WarpCpuScratch carried from frame to frame (as pseudo3dwarp carries
// it) gives every frame what a fresh one gives: planes left over from a
// larger or a different frame, or from another fill, are never read as
// this frame's.
TEST(WarpFill, ReusedScratchGivesWhatAFreshOneGives) {
  struct Frame {
    int w, h;
    HoleFill fill;
    StereoView view;
  };
  const Frame frames[] = {{97, 61, HoleFill::BackgroundSmooth, StereoView::Both},
                          {61, 37, HoleFill::BackgroundSmooth, StereoView::Right},  // smaller: stale planes beyond it
                          {61, 37, HoleFill::Background, StereoView::Both},
                          {80, 50, HoleFill::BackgroundSmooth, StereoView::Left},
                          {80, 50, HoleFill::BackgroundSmooth, StereoView::Both}};
  WarpCpuScratch kept;
  uint32_t seed = 50;
  for (const Frame &f : frames) {
    SCOPED_TRACE(std::to_string(f.w) + "x" + std::to_string(f.h));
    const HostFrame src = textured(PixelFormat::BGRA, f.w, f.h, seed++);
    const cv::Mat depth = noise_depth(f.w, f.h, seed++, true);
    const WarpParams p = warp_params(20.f, 0.3f, f.view, f.fill);
    HostFrame with_kept(PixelFormat::BGRA, 2 * f.w, f.h), fresh(PixelFormat::BGRA, 2 * f.w, f.h);
    const long long a = warp_render_cpu(p, src.view(), YuvToRgb(), depth_view_of(depth), with_kept.view(), kept);
    const long long b = warp_render_cpu(p, src.view(), YuvToRgb(), depth_view_of(depth), fresh.view());
    EXPECT_GT(a, 0);
    EXPECT_EQ(a, b);
    EXPECT_TRUE(same_bytes(with_kept, fresh));
  }
}

// Pictures taller than the CPU's bands of rows (at least 32, at least 2R):
// column runs of holes (the border band, tall depth steps) cross the band
// boundaries, where a band starts its windows by looking up the run.
TEST(WarpFill, BackgroundSmoothMatchesTheSpecificationAcrossRowBands) {
  const cv::Mat columns = make_depth(150, 300, [](int x, int y) { return ((x / 17 + y / 70) % 3) / 2.f; });
  expect_background_smooth_matches_naive(warp_params(15.f, 0.f, StereoView::Both, HoleFill::None),
                                         textured(PixelFormat::BGRA, 150, 300, 45), columns);  // R = 6: bands of 32
  const cv::Mat tall = make_depth(240, 260, [](int x, int y) { return ((x / 50 + y / 90) % 2) ? 1.f : 0.2f; });
  expect_background_smooth_matches_naive(warp_params(25.f, 0.f, StereoView::Right, HoleFill::None),
                                         textured(PixelFormat::RGBA, 240, 260, 46), tall);  // R = 31: bands of 62
}

TEST(WarpFill, BackgroundSmoothOfOneColourIsThatColour) {
  const Rgba c{90, 60, 30, 255};
  const Rendered r = render(warp_params(12.5f, 0.f, StereoView::Both, HoleFill::BackgroundSmooth),
                            two_colour_scene(c, c), square_depth());
  EXPECT_EQ(r.holes, 2 * 4 * 4);
  for (int eye = 0; eye < 2; ++eye) EXPECT_TRUE(view_is(r.out, eye, [&](int, int) { return c; }));
}

// Two flat colours: every anchor of the disocclusion is background, so the
// holes are exactly the background colour, never a blend with the square.
TEST(WarpFill, BackgroundSmoothFillsDisocclusionWithBackground) {
  const Rgba bg{20, 180, 40, 255}, fg{220, 30, 10, 255};
  WarpParams p = kSceneParams;
  p.fill = HoleFill::BackgroundSmooth;
  const Rendered r = render(p, two_colour_scene(bg, fg), square_depth());
  EXPECT_EQ(r.holes, 2 * 4 * 4);
  EXPECT_TRUE(view_is(r.out, 0, [&](int x, int y) { return in_square(x - 4, y) ? fg : bg; }));
  EXPECT_TRUE(view_is(r.out, 1, [&](int x, int y) { return in_square(x + 4, y) ? fg : bg; }));
}

// The averaging, by hand: background rows of grey level 10 y, a flat
// foreground square (rows 2..5). D = 8, shift 1/2: R = 1 + 4 / 2 = 3 rows,
// Rx = 0. The hole's column run is rows 2..5, every anchor is the
// background of its row (10 y), so hole (X, y) = the rounded mean of 10 y'
// over max(2, y - 3) .. min(5, y + 3). The pixels beside the hole, which the
// warp sampled across the depth edge, never leak in.
TEST(WarpFill, BackgroundSmoothAveragesDownTheColumn) {
  HostFrame src(PixelFormat::BGRA, kSceneW, kSceneH);
  for (int y = 0; y < kSceneH; ++y)
    for (int x = 0; x < kSceneW; ++x) {
      const uint8_t g = static_cast<uint8_t>(10 * y);
      store_rgba(src.view(), x, y, in_square(x, y) ? Rgba{250, 250, 250, 255} : Rgba{g, g, g, 255});
    }
  WarpParams p = kSceneParams;
  p.fill = HoleFill::BackgroundSmooth;
  const Rendered r = render(p, src, square_depth());
  ASSERT_EQ(r.holes, 2 * 4 * 4);
  auto expected = [](int y) {
    int sum = 0, n = 0;
    for (int t = std::max(2, y - 3); t <= std::min(5, y + 3); ++t) sum += 10 * t, ++n;
    const uint8_t g = static_cast<uint8_t>((sum + n / 2) / n);
    return Rgba{g, g, g, 255};
  };
  for (int y = 2; y <= 5; ++y)
    for (int x = 24; x <= 27; ++x) EXPECT_TRUE(same(view_at(r.out, 0, x, y), expected(y))) << x << "," << y;
  for (int y = 2; y <= 5; ++y)
    for (int x = 36; x <= 39; ++x) EXPECT_TRUE(same(view_at(r.out, 1, x, y), expected(y))) << x << "," << y;
}

// Integer sums: the result does not depend on how the rows and columns are
// split between threads.
TEST(WarpFill, BackgroundSmoothIsIndependentOfThreadCount) {
  const HostFrame src = textured(PixelFormat::BGRA, 211, 67, 45);
  const cv::Mat depth = noise_depth(211, 67, 46, false);
  const WarpParams p = warp_params(20.f, 0.3f, StereoView::Both, HoleFill::BackgroundSmooth);
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const Rendered one = render(p, src, depth);
  cv::setNumThreads(threads);
  const Rendered many = render(p, src, depth);
  EXPECT_EQ(one.holes, many.holes);
  EXPECT_TRUE(same_bytes(one.out, many.out));
}

TEST(WarpHelpers, BackgroundSmoothHelpers) {
  EXPECT_EQ(smooth_fill_radius(-1.f, 0.f), 1);
  EXPECT_EQ(smooth_fill_radius(-1.f, 211.f), 106);
  EXPECT_EQ(smooth_fill_radius(0.5f, 8.f), 3);
  EXPECT_EQ(smooth_fill_radius(-0.5f, 3.9f), 1);  // floor(0.975)
  EXPECT_EQ(smooth_fill_radius(1.f, 0.25f * 8192.f), 1025);
  EXPECT_EQ(smooth_fill_radius_x(106), 26);
  EXPECT_EQ(smooth_fill_radius_x(3), 0);
  // Clean: not a hole and no hole within kSmoothClean (4) pixels of the row.
  static_assert(kSmoothClean == 4, "the row below is laid out for 4");
  const uint8_t row[12] = {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
  EXPECT_FALSE(smooth_is_clean(row, 0, 12));  // a hole
  EXPECT_FALSE(smooth_is_clean(row, 4, 12));  // 4 from the hole at 0
  EXPECT_TRUE(smooth_is_clean(row, 5, 12));
  EXPECT_TRUE(smooth_is_clean(row, 6, 12));
  EXPECT_FALSE(smooth_is_clean(row, 7, 12));  // 4 from the hole at 11
  EXPECT_TRUE(smooth_is_clean(row, 7, 11));   // a row 11 wide ends before that hole
  const uint8_t one[1] = {0}, one_hole[1] = {1};
  EXPECT_TRUE(smooth_is_clean(one, 0, 1));
  EXPECT_FALSE(smooth_is_clean(one_hole, 0, 1));
  EXPECT_EQ(smooth_side(3, 5), 3);
  EXPECT_EQ(smooth_side(-1, 5), 5);
  EXPECT_EQ(smooth_side(-1, -1), -1);
  // Rounded mean, halves up; empty -> black.
  EXPECT_TRUE(same(smooth_mean(SmoothSum{0, 0, 0, 0, 0}), kFillBlack));
  EXPECT_TRUE(same(smooth_mean(SmoothSum{3, 1, 2, 510, 2}), Rgba{2, 1, 1, 255}));
  SmoothSum s{0, 0, 0, 0, 0};
  smooth_add(s, Rgba{255, 1, 2, 3});
  smooth_add(s, Rgba{255, 2, 2, 4});
  smooth_add(s, Rgba{254, 2, 3, 4});
  EXPECT_TRUE(same(smooth_mean(s), Rgba{255, 2, 2, 4}));
  const SmoothSum w = smooth_window(SmoothSum{10, 20, 30, 40, 5}, SmoothSum{1, 2, 3, 4, 2});
  EXPECT_EQ(w.r, 9u);
  EXPECT_EQ(w.n, 3u);
}

// ---- hole counts ------------------------------------------------------------

// The returned count is the number of pixels None paints magenta, in every
// view mode, on random depth.
TEST(WarpHoles, CountEqualsPaintedHoles) {
  const HostFrame src = textured(PixelFormat::NV12, 83, 29, 16);
  for (StereoView v : kAllViews)
    for (bool binary : {false, true}) {
      const Rendered r = render(warp_params(10.f, 0.5f, v, HoleFill::None), src, noise_depth(83, 29, 17, binary));
      EXPECT_GT(r.holes, 0);
      EXPECT_EQ(count_colour(r.out, kHoleColour), r.holes);
    }
}

// ---- formats and sizes ------------------------------------------------------

// The warp reads the source through load_rgba only, so every format gives
// the rendering of its own BGRA conversion; every packed output format
// holds the same colours.
TEST(WarpFormats, EverySourceAndOutputFormat) {
  const cv::Mat depth = noise_depth(45, 21, 18, false);
  for (PixelFormat f : kAllFormats) {
    SCOPED_TRACE(test::format_name(f));
    const HostFrame src = textured(f, 45, 21, 19, 5);
    const cv::Mat bgra = src.to_bgra();
    const HostFrame as_bgra = HostFrame::from_bgr(bgra, PixelFormat::BGRA);
    for (HoleFill fill : kAllFills) {
      const WarpParams p = warp_params(12.f, 0.5f, StereoView::Both, fill);
      const Rendered want = render(p, as_bgra, depth);
      for (PixelFormat of : kPackedFormats) {
        SCOPED_TRACE(test::format_name(of));
        const Rendered got = render(p, src, depth, of);
        EXPECT_EQ(got.holes, want.holes);
        for (int eye = 0; eye < 2; ++eye)
          EXPECT_TRUE(view_is(got.out, eye, [&](int x, int y) { return view_at(want.out, eye, x, y); }));
      }
    }
  }
}

// 1x1: D = 0.25, the only pixel moves by at most 0.25 and stays covered.
TEST(WarpSizes, OneByOne) {
  for (PixelFormat f : kAllFormats) {
    const HostFrame src = textured(f, 1, 1, 20);
    for (StereoView v : kAllViews)
      for (float d : {0.f, 1.f}) {
        const Rendered r = render(warp_params(25.f, 1.f - d, v, HoleFill::None), src, flat_depth(1, 1, d));
        EXPECT_EQ(r.holes, 0);
        EXPECT_TRUE(view_is(r.out, 0, source_of(src)));
        EXPECT_TRUE(view_is(r.out, 1, source_of(src)));
      }
  }
}

// Every pixel is written: two renderings into outputs poisoned differently
// give the same bytes (alpha/padding byte included).
void expect_fully_written(const WarpParams &p, const HostFrame &src, const cv::Mat &depth) {
  const Rendered a = render(p, src, depth, PixelFormat::RGBx, 0x00);
  const Rendered b = render(p, src, depth, PixelFormat::RGBx, 0xFF);
  EXPECT_GE(a.holes, 0);
  EXPECT_EQ(a.holes, b.holes);
  EXPECT_TRUE(same_bytes(a.out, b.out));
  EXPECT_EQ(count_colour(a.out, kHoleColour), p.fill == HoleFill::None ? a.holes : 0);
}

TEST(WarpSizes, OddSizesEveryModeFullyWritten) {
  const int sizes[][2] = {{1, 1}, {3, 2}, {2, 3}, {33, 17}, {1001, 7}};
  for (const auto &s : sizes) {
    SCOPED_TRACE(::testing::Message() << s[0] << "x" << s[1]);
    const HostFrame src = textured(PixelFormat::I420, s[0], s[1], 21);
    const cv::Mat depth = noise_depth(s[0], s[1], 22, true);
    for (StereoView v : kAllViews)
      for (HoleFill fill : kAllFills) expect_fully_written(warp_params(25.f, 0.5f, v, fill), src, depth);
  }
}

// max_disparity 25 % with depth at 0/1 extremes and convergence at both ends.
TEST(WarpExtremes, FullDisparityBinaryDepth) {
  const HostFrame src = textured(PixelFormat::BGRx, 97, 31, 23);
  const cv::Mat depth = noise_depth(97, 31, 24, true);
  for (float c : {0.f, 0.5f, 1.f})
    for (StereoView v : kAllViews)
      for (HoleFill fill : kAllFills) expect_fully_written(warp_params(25.f, c, v, fill), src, depth);
}

// Out-of-range parameters are clamped; NaN depth reads as 0 and depth
// outside 0..1 is clamped.
TEST(WarpExtremes, InvalidParametersAndDepthAreClamped) {
  const HostFrame src = textured(PixelFormat::BGRA, 57, 9, 25);
  const cv::Mat depth = noise_depth(57, 9, 26, false);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  auto same_render = [&](const WarpParams &a, const cv::Mat &da, const WarpParams &b, const cv::Mat &db) {
    const Rendered ra = render(a, src, da), rb = render(b, src, db);
    EXPECT_EQ(ra.holes, rb.holes);
    EXPECT_TRUE(same_bytes(ra.out, rb.out));
  };
  const StereoView v = StereoView::Both;
  const HoleFill f = HoleFill::Background;
  same_render(warp_params(80.f, 0.5f, v, f), depth, warp_params(25.f, 0.5f, v, f), depth);
  same_render(warp_params(inf, 0.5f, v, f), depth, warp_params(25.f, 0.5f, v, f), depth);
  same_render(warp_params(-3.f, 0.5f, v, f), depth, warp_params(0.f, 0.5f, v, f), depth);
  same_render(warp_params(nan, 0.5f, v, f), depth, warp_params(0.f, 0.5f, v, f), depth);
  same_render(warp_params(10.f, nan, v, f), depth, warp_params(10.f, 0.f, v, f), depth);
  same_render(warp_params(10.f, 7.f, v, f), depth, warp_params(10.f, 1.f, v, f), depth);
  same_render(warp_params(10.f, -1.f, v, f), depth, warp_params(10.f, 0.f, v, f), depth);
  same_render(warp_params(10.f, 0.5f, v, f), flat_depth(57, 9, nan), warp_params(10.f, 0.5f, v, f), flat_depth(57, 9, 0.f));
  same_render(warp_params(10.f, 0.5f, v, f), flat_depth(57, 9, -inf), warp_params(10.f, 0.5f, v, f), flat_depth(57, 9, 0.f));
  same_render(warp_params(10.f, 0.5f, v, f), flat_depth(57, 9, 3.f), warp_params(10.f, 0.5f, v, f), flat_depth(57, 9, 1.f));
  // Max disparity 0 is the source even with NaN depth.
  const Rendered zero = render(warp_params(0.f, 0.5f, v, f), src, flat_depth(57, 9, nan));
  EXPECT_EQ(zero.holes, 0);
  EXPECT_TRUE(view_is(zero.out, 0, source_of(src)));
}

TEST(WarpFrames, MismatchedFramesAreRefused) {
  const HostFrame src = textured(PixelFormat::BGRA, 8, 4, 27);
  const cv::Mat depth = flat_depth(8, 4, 1.f);
  HostFrame narrow(PixelFormat::BGRA, 8, 4);
  narrow.fill(0x5A);
  EXPECT_EQ(warp_render_cpu(WarpParams(), src.view(), YuvToRgb(), depth_view_of(depth), narrow.view()), -1);
  EXPECT_EQ(count_colour(narrow, Rgba{0x5A, 0x5A, 0x5A, 0x5A}), 8 * 4);  // untouched
  HostFrame yuv_out(PixelFormat::NV12, 16, 4);
  EXPECT_EQ(warp_render_cpu(WarpParams(), src.view(), YuvToRgb(), depth_view_of(depth), yuv_out.view()), -1);
  HostFrame out(PixelFormat::BGRA, 16, 4);
  const cv::Mat small = flat_depth(7, 4, 1.f);
  EXPECT_EQ(warp_render_cpu(WarpParams(), src.view(), YuvToRgb(), depth_view_of(small), out.view()), -1);
}

}  // namespace
}  // namespace p3d
