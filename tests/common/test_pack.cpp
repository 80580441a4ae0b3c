// Stereo packing (common/pack.h): sizes, every layout on hand-made pairs with
// known answers, the anaglyph matrices, format independence, and that
// nothing is written outside the output rows; 4:2:0 output against an
// independent conversion and OpenCV's.
#include <cmath>
#include <cstring>
#include <functional>
#include <iterator>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "pack.h"
#include "stereo_frames.h"
#include "test_data.h"

namespace p3d {
namespace {

using test::kAllLayouts;
using test::kAllGlasses;
using test::kAllMethods;
using test::kPackedFormats;

constexpr uint8_t kPoison = 0xA5;

using PixelFn = std::function<Rgba(int x, int y)>;

// A W x H pair side by side (2W x H) with the given views.
HostFrame make_pair(PixelFormat f, int w, int h, const PixelFn &left, const PixelFn &right, int padding = 0) {
  HostFrame pair(f, 2 * w, h, padding);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      store_rgba(pair.view(), x, y, left(x, y));
      store_rgba(pair.view(), w + x, y, right(x, y));
    }
  return pair;
}

PixelFn solid(Rgba c) {
  return [c](int, int) { return c; };
}

// Packs `in` into a fresh output frame whose every byte (padding included)
// starts as kPoison.
HostFrame pack(const PackParams &p, const HostFrame &in, int padding = 0) {
  int w = 0, h = 0;
  pack_size(p.layout, in.width() / 2, in.height(), &w, &h);
  HostFrame out(in.format(), w, h, padding);
  out.fill(kPoison);
  pack_cpu(p, in.view(), out.view());
  return out;
}

PackParams layout_params(PackLayout l, bool swap = false) {
  PackParams p;
  p.layout = l;
  p.swap_eyes = swap;
  return p;
}
PackParams anaglyph_params(AnaglyphGlasses g, AnaglyphMethod m) {
  PackParams p;
  p.layout = PackLayout::Anaglyph;
  p.glasses = g;
  p.method = m;
  return p;
}

Rgba at(const HostFrame &f, int x, int y) { return load_rgba(f.view(), x, y, YuvToRgb()); }

::testing::AssertionResult same(Rgba got, Rgba want) {
  if (got.r == want.r && got.g == want.g && got.b == want.b && got.a == want.a) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got (" << int(got.r) << "," << int(got.g) << "," << int(got.b) << ","
                                       << int(got.a) << ") want (" << int(want.r) << "," << int(want.g) << ","
                                       << int(want.b) << "," << int(want.a) << ")";
}

// Every pixel of `f` equals want(x, y).
::testing::AssertionResult all_pixels(const HostFrame &f, const PixelFn &want) {
  for (int y = 0; y < f.height(); ++y)
    for (int x = 0; x < f.width(); ++x) {
      ::testing::AssertionResult r = same(at(f, x, y), want(x, y));
      if (!r) return r << " at (" << x << "," << y << ")";
    }
  return ::testing::AssertionSuccess();
}

bool equal_bgra(const cv::Mat &a, const cv::Mat &b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// ---- sizes ------------------------------------------------------------------

TEST(PackSize, EveryLayout) {
  const int sizes[][2] = {{1, 1}, {3, 2}, {641, 555}, {1920, 1080}};
  for (const auto &s : sizes) {
    const int w = s[0], h = s[1];
    for (PackLayout l : kAllLayouts) {
      int ow = -1, oh = -1;
      pack_size(l, w, h, &ow, &oh);
      EXPECT_EQ(ow, l == PackLayout::SideBySide ? 2 * w : w) << "layout " << int(l) << " view " << w << "x" << h;
      EXPECT_EQ(oh, l == PackLayout::TopBottom ? 2 * h : h) << "layout " << int(l) << " view " << w << "x" << h;
    }
  }
}

TEST(PackSize, HalfSplitKeepsTheOddColumnLeft) {
  EXPECT_EQ(half_split(1), 1);
  EXPECT_EQ(half_split(2), 1);
  EXPECT_EQ(half_split(5), 3);
  EXPECT_EQ(half_split(1920), 960);
}

// Every layout on 1x1 views: the output has the right size and every pixel
// comes from the expected view.
TEST(PackLayouts, OneByOneViews) {
  const Rgba a{200, 10, 20, 255}, b{5, 150, 250, 255};
  const HostFrame in = make_pair(PixelFormat::RGBA, 1, 1, solid(a), solid(b));
  for (PackLayout l : kAllLayouts) {
    if (l == PackLayout::Anaglyph) continue;
    const HostFrame out = pack(layout_params(l), in);
    int ow = 0, oh = 0;
    pack_size(l, 1, 1, &ow, &oh);
    ASSERT_EQ(out.width(), ow);
    ASSERT_EQ(out.height(), oh);
    EXPECT_TRUE(same(at(out, 0, 0), l == PackLayout::Right ? b : a)) << "layout " << int(l);
    if (ow == 2) {
      EXPECT_TRUE(same(at(out, 1, 0), b));
    }
    if (oh == 2) {
      EXPECT_TRUE(same(at(out, 0, 1), b));
    }
  }
}

// ---- geometric layouts --------------------------------------------------------

TEST(PackLayouts, SideBySideFullEqualsInput) {
  for (PixelFormat f : kPackedFormats) {
    HostFrame in(f, 2 * 33, 17, 12);
    in.fill_random(11);
    const HostFrame out = pack(layout_params(PackLayout::SideBySide), in, 4);
    EXPECT_TRUE(equal_bgra(out.to_bgra(), in.to_bgra())) << test::format_name(f);
  }
}

TEST(PackLayouts, SwapEyesSwapsTheViews) {
  HostFrame in(PixelFormat::RGBA, 2 * 7, 5);
  in.fill_random(12);
  const HostFrame sbs = pack(layout_params(PackLayout::SideBySide, true), in);
  EXPECT_TRUE(all_pixels(sbs, [&](int x, int y) { return at(in, (x + 7) % 14, y); }));
  const HostFrame left = pack(layout_params(PackLayout::Left, true), in);
  EXPECT_TRUE(all_pixels(left, [&](int x, int y) { return at(in, 7 + x, y); }));
  const HostFrame right = pack(layout_params(PackLayout::Right, true), in);
  EXPECT_TRUE(all_pixels(right, [&](int x, int y) { return at(in, x, y); }));
  const HostFrame tb = pack(layout_params(PackLayout::TopBottom, true), in);
  EXPECT_TRUE(all_pixels(tb, [&](int x, int y) { return y < 5 ? at(in, 7 + x, y) : at(in, x, y - 5); }));
}

TEST(PackLayouts, TopBottomFull) {
  HostFrame in(PixelFormat::BGRA, 2 * 3, 2);
  in.fill_random(13);
  const HostFrame out = pack(layout_params(PackLayout::TopBottom), in);
  ASSERT_EQ(out.width(), 3);
  ASSERT_EQ(out.height(), 4);
  EXPECT_TRUE(all_pixels(out, [&](int x, int y) { return y < 2 ? at(in, x, y) : at(in, 3 + x, y - 2); }));
}

// Sample values along the squeezed axis; the half formats must store the
// rounded means (a + b + 1) / 2 of pairs, hand-computed below.
const int kLeftRamp[5] = {10, 21, 30, 41, 50};
const int kRightRamp[5] = {100, 103, 0, 255, 7};
Rgba ramp_pixel(const int *ramp, int i, int other) {
  const int v = ramp[i];
  return Rgba{uint8_t(v), uint8_t(255 - v), uint8_t(20 * other), uint8_t(v / 2 + 1)};
}

TEST(PackLayouts, SideBySideHalfAveragesColumnPairs) {
  const HostFrame in = make_pair(
      PixelFormat::RGBA, 5, 3, [](int x, int y) { return ramp_pixel(kLeftRamp, x, y); },
      [](int x, int y) { return ramp_pixel(kRightRamp, x, y); });
  const HostFrame out = pack(layout_params(PackLayout::SideBySideHalf), in);
  ASSERT_EQ(out.width(), 5);
  ASSERT_EQ(out.height(), 3);
  for (int y = 0; y < 3; ++y) {
    const uint8_t b = uint8_t(20 * y);
    // Left: columns (0,1), (2,3), (4,4 clamped). Alphas are v/2+1: 6,11 ; 16,21 ; 26.
    EXPECT_TRUE(same(at(out, 0, y), Rgba{16, 240, b, 9}));
    EXPECT_TRUE(same(at(out, 1, y), Rgba{36, 220, b, 19}));
    EXPECT_TRUE(same(at(out, 2, y), Rgba{50, 205, b, 26}));
    // Right gets floor(5/2) = 2 columns: (0,1), (2,3); its column 4 is dropped.
    // Alphas: 51,52 ; 1,128.
    EXPECT_TRUE(same(at(out, 3, y), Rgba{102, 154, b, 52}));
    EXPECT_TRUE(same(at(out, 4, y), Rgba{128, 128, b, 65}));
  }
}

// pack_detail::mean2_word() is mean2() in every lane: all 65536 byte pairs in each lane
// of a word (the other lanes holding the extremes a borrow would reach),
// and 16-bit lanes on the extremes and random pairs.
TEST(PackLayouts, WordMeanIsTheMeanOfEveryLane) {
  for (int lane = 0; lane < 4; ++lane)
    for (uint32_t a = 0; a < 256; ++a)
      for (uint32_t b = 0; b < 256; ++b) {
        const uint32_t others = lane % 2 ? 0x00ff00ffu : 0xff00ff00u;
        const uint32_t wa = (others & ~(0xffu << 8 * lane)) | a << 8 * lane, wb = (~others & ~(0xffu << 8 * lane)) | b << 8 * lane;
        const uint32_t got = pack_detail::mean2_word(wa, wb);
        for (int l = 0; l < 4; ++l)
          ASSERT_EQ(got >> 8 * l & 0xff, pack_detail::mean2(uint8_t(wa >> 8 * l), uint8_t(wb >> 8 * l)))
              << "lane " << l << " of " << std::hex << wa << " and " << wb;
      }
  std::mt19937 rng(5);
  std::vector<uint16_t> samples = {0, 1, 2, 32767, 32768, 65534, 65535};
  for (int i = 0; i < 2000; ++i) samples.push_back(uint16_t(rng()));
  for (uint16_t a : samples)
    for (size_t k = 0; k < samples.size(); k += 7) {
      const uint16_t b = samples[(k + a) % samples.size()];
      const uint64_t wa = uint64_t(a) * 0x0001000100010001ull ^ 0xffff00000000ffffull;
      const uint64_t wb = uint64_t(b) * 0x0001000100010001ull;
      const uint64_t got = pack_detail::mean2_word(wa, wb);
      for (int l = 0; l < 4; ++l)
        ASSERT_EQ(got >> 16 * l & 0xffff, pack_detail::mean2(uint16_t(wa >> 16 * l), uint16_t(wb >> 16 * l)))
            << "lane " << l << " of " << std::hex << wa << " and " << wb;
    }
}

// pack_cpu runs side-by-side-half of a side-by-side pair into packed RGB a
// row at a time on stored words; every byte of its rows (an RGBx padding
// byte included, the poisoned bytes after each row untouched) must be what
// the per-pixel function stored through store_rgba() / store_rgba16()
// gives, for every packed format and RGBA64 (16-bit words), odd and even
// view widths (the odd view's last column pairs with itself), eye order
// and rows of padding.
TEST(PackLayouts, SideBySideHalfRowLoopEqualsThePerPixelFunction) {
  std::vector<PixelFormat> formats(std::begin(kPackedFormats), std::end(kPackedFormats));
  formats.push_back(PixelFormat::RGBA64);
  for (PixelFormat f : formats)
    for (int w : {1, 2, 3, 4, 5, 37, 38, 67})
      for (bool swap : {false, true}) {
        HostFrame in(f, 2 * w, 4, 12);
        in.fill_random(3 * w + static_cast<int>(f));
        PackParams p = layout_params(PackLayout::SideBySideHalf, swap);
        const AnaglyphMatrices am = anaglyph_matrices(p.glasses, p.method);
        const HostFrame out = pack(p, in, 8);
        HostFrame want(f, w, 4, 8);
        want.fill(kPoison);
        for (int y = 0; y < 4; ++y)
          for (int x = 0; x < w; ++x) {
            if (is_deep(f))
              store_rgba16(want.view(),
                           x, y, pack_detail::pack_pixel_for<StereoInput::SideBySide, Rgba16>(p, am, in.view(), x, y));
            else
              store_rgba(want.view(), x, y, pack_pixel(p, am, in.view(), x, y));
          }
        ASSERT_EQ(out.view().stride[0], want.view().stride[0]);
        for (int y = 0; y < 4; ++y)
          ASSERT_EQ(0, std::memcmp(out.view().plane[0] + static_cast<size_t>(y) * out.view().stride[0],
                                   want.view().plane[0] + static_cast<size_t>(y) * want.view().stride[0],
                                   static_cast<size_t>(out.view().stride[0])))
              << test::format_name(f) << " view width " << w << " swap " << swap << " row " << y;
      }
}

TEST(PackLayouts, TopBottomHalfAveragesRowPairs) {
  const HostFrame in = make_pair(
      PixelFormat::BGRx, 2, 5, [](int x, int y) { return ramp_pixel(kLeftRamp, y, x); },
      [](int x, int y) { return ramp_pixel(kRightRamp, y, x); });
  const HostFrame out = pack(layout_params(PackLayout::TopBottomHalf), in);
  ASSERT_EQ(out.width(), 2);
  ASSERT_EQ(out.height(), 5);
  for (int x = 0; x < 2; ++x) {
    const uint8_t b = uint8_t(20 * x);
    // BGRx has no alpha: 255 in, 255 out.
    EXPECT_TRUE(same(at(out, x, 0), Rgba{16, 240, b, 255}));
    EXPECT_TRUE(same(at(out, x, 1), Rgba{36, 220, b, 255}));
    EXPECT_TRUE(same(at(out, x, 2), Rgba{50, 205, b, 255}));
    EXPECT_TRUE(same(at(out, x, 3), Rgba{102, 154, b, 255}));
    EXPECT_TRUE(same(at(out, x, 4), Rgba{128, 128, b, 255}));
  }
}

TEST(PackLayouts, HalfFormatsOfOneSampleViews) {
  // One column (one row): the left view keeps it, averaged with itself; the
  // right view gets nothing.
  const Rgba a{201, 3, 77, 255}, b{9, 9, 9, 255};
  const HostFrame in = make_pair(PixelFormat::RGBx, 1, 3, solid(a), solid(b));
  EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::SideBySideHalf), in), solid(a)));
  const HostFrame row = make_pair(PixelFormat::RGBx, 3, 1, solid(a), solid(b));
  EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::TopBottomHalf), row), solid(a)));
}

// Views of one colour each, so every output pixel tells which view it came from.
TEST(PackLayouts, InterleavesPickTheRightView) {
  const Rgba a{200, 10, 20, 255}, b{5, 150, 250, 128};
  const int sizes[][2] = {{3, 2}, {4, 3}, {33, 17}};
  for (const auto &s : sizes)
    for (bool swap : {false, true}) {
      const HostFrame in = make_pair(PixelFormat::RGBA, s[0], s[1], solid(a), solid(b));
      const Rgba l = swap ? b : a, r = swap ? a : b;
      EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::RowInterleaved, swap), in),
                             [&](int, int y) { return y % 2 == 0 ? l : r; }));
      EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::ColumnInterleaved, swap), in),
                             [&](int x, int) { return x % 2 == 0 ? l : r; }));
      EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::Checkerboard, swap), in),
                             [&](int x, int y) { return (x + y) % 2 == 0 ? l : r; }));
      EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::Left, swap), in), solid(l)));
      EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::Right, swap), in), solid(r)));
    }
}

TEST(PackLayouts, LeftAndRightOfARandomPair) {
  HostFrame in(PixelFormat::RGBA, 2 * 9, 4, 8);
  in.fill_random(14);
  EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::Left), in), [&](int x, int y) { return at(in, x, y); }));
  EXPECT_TRUE(all_pixels(pack(layout_params(PackLayout::Right), in), [&](int x, int y) { return at(in, 9 + x, y); }));
}

// ---- anaglyphs ------------------------------------------------------------------

Rgba anaglyph_of(AnaglyphGlasses g, AnaglyphMethod m, Rgba l, Rgba r, PixelFormat f = PixelFormat::RGBA) {
  const HostFrame in = make_pair(f, 1, 1, solid(l), solid(r));
  return at(pack(anaglyph_params(g, m), in), 0, 0);
}

constexpr Rgba kWhite{255, 255, 255, 200}, kBlack{0, 0, 0, 100};

TEST(PackAnaglyph, ColorPassesEachEyesChannels) {
  // Alpha comes from the left view.
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::Color, kWhite, kBlack), Rgba{255, 0, 0, 200}));
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::Color, kBlack, kWhite), Rgba{0, 255, 255, 100}));
  EXPECT_TRUE(
      same(anaglyph_of(AnaglyphGlasses::GreenMagenta, AnaglyphMethod::Color, kWhite, kBlack), Rgba{0, 255, 0, 200}));
  EXPECT_TRUE(
      same(anaglyph_of(AnaglyphGlasses::GreenMagenta, AnaglyphMethod::Color, kBlack, kWhite), Rgba{255, 0, 255, 100}));
  EXPECT_TRUE(
      same(anaglyph_of(AnaglyphGlasses::AmberBlue, AnaglyphMethod::Color, kWhite, kBlack), Rgba{255, 255, 0, 200}));
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::AmberBlue, AnaglyphMethod::Color, kBlack, kWhite), Rgba{0, 0, 255, 100}));
  // Colour views pass unchanged through their channels.
  const Rgba l{200, 100, 50, 255}, r{10, 20, 30, 255};
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::Color, l, r), Rgba{200, 20, 30, 255}));
}

TEST(PackAnaglyph, GrayOfEqualViewsIsGrey) {
  // luma(200, 100, 50) = 59.8 + 58.7 + 5.7 = 124.2
  const Rgba c{200, 100, 50, 255};
  ASSERT_EQ(to_u8(rgb_luma(200, 100, 50)), 124);
  for (AnaglyphGlasses g : kAllGlasses)
    EXPECT_TRUE(same(anaglyph_of(g, AnaglyphMethod::Gray, c, c), Rgba{124, 124, 124, 255})) << "glasses " << int(g);
}

TEST(PackAnaglyph, HalfColorLumaBehindTheSingleColourFilter) {
  // luma(L) = 124.2, luma(R) = 2.99 + 11.74 + 3.42 = 18.15
  const Rgba l{200, 100, 50, 255}, r{10, 20, 30, 255};
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::HalfColor, l, r), Rgba{124, 20, 30, 255}));
  EXPECT_TRUE(
      same(anaglyph_of(AnaglyphGlasses::GreenMagenta, AnaglyphMethod::HalfColor, l, r), Rgba{10, 124, 30, 255}));
  // Amber-blue: the right eye looks through blue.
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::AmberBlue, AnaglyphMethod::HalfColor, l, r), Rgba{200, 100, 18, 255}));
}

TEST(PackAnaglyph, DuboisRedCyanHandComputed) {
  // Row sums of the red-cyan matrices: left (1.050, -0.148, -0.115), right
  // (-0.050, 1.147, 1.115). Grey L = 60, R = 180:
  //   R = 63.0 - 9.0 = 54,  G = -8.88 + 206.46 = 197.58,  B = -6.9 + 200.7 = 193.8
  const Rgba g60{60, 60, 60, 255}, g180{180, 180, 180, 255};
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois, g60, g180), Rgba{54, 198, 194, 255}));
  // Saturation at both ends: L = 0, R = 255: R = -12.75 -> 0, G = 292.5 -> 255, B = 284.3 -> 255.
  const Rgba g0{0, 0, 0, 255}, g255{255, 255, 255, 255};
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois, g0, g255), Rgba{0, 255, 255, 255}));
  // A colour pair, L = (200, 100, 50), R = (10, 20, 30):
  //   R = (87.4 + 44.9 + 8.2) + (-0.11 - 0.64 - 0.21) = 139.54
  //   G = (-12.4 - 6.2 - 1.2) + (3.77 + 15.22 + 0.27) = -0.54
  //   B = (-9.6 - 5.0 - 0.85) + (-0.26 - 1.86 + 37.02) = 19.45
  const Rgba l{200, 100, 50, 77}, r{10, 20, 30, 255};
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois, l, r), Rgba{140, 0, 19, 77}));
}

// The gamma mixes run in 16.16 fixed point (anaglyph_mix_word): the
// coefficients are round(65536 m), and every output code is within one of
// the float mix to_u8(Ml . L + Mr . R) (equal but where the float sum lies
// within about 2^-16 of a half), for every gamma method and glasses, on a
// million random pairs and on the extremes; the fixed-point sum stays far
// from int overflow.
TEST(PackAnaglyph, FixedPointMixIsTheFloatMixWithinOneCode) {
  std::mt19937 rng(20261126);
  for (AnaglyphGlasses g : kAllGlasses)
    for (AnaglyphMethod m : kAllMethods) {
      if (m == AnaglyphMethod::DuboisLinear) continue;
      const AnaglyphMatrices am = anaglyph_matrices(g, m);
      long long off_by_one = 0, sum_max = 0;
      for (int k = 0; k < 9; ++k) {
        EXPECT_EQ(am.left_q[k], std::lround(65536.0 * am.left[k]));
        EXPECT_EQ(am.right_q[k], std::lround(65536.0 * am.right[k]));
        sum_max += 255LL * (std::abs(am.left_q[k]) + std::abs(am.right_q[k]));
      }
      EXPECT_LT(sum_max + 32768, 1LL << 31) << "the fixed-point sums fit an int";
      for (int i = 0; i < 1000000 / 15; ++i) {
        const uint32_t lw = rng() | 0xff000000u, rw = rng();
        const Rgba l = word_rgba(lw), r = word_rgba(rw);
        const Rgba got = word_rgba(pack_detail::anaglyph_mix_word(am.left_q, am.right_q, lw, rw));
        const uint8_t c[3] = {got.r, got.g, got.b};
        for (int ch = 0; ch < 3; ++ch) {
          const float v =
              pack_detail::mat_row(am.left, ch, l.r, l.g, l.b) + pack_detail::mat_row(am.right, ch, r.r, r.g, r.b);
          const int want = to_u8(v);
          ASSERT_LE(std::abs(int(c[ch]) - want), 1) << "glasses " << int(g) << " method " << int(m) << " v " << v;
          off_by_one += c[ch] != want;
        }
        ASSERT_EQ(got.a, l.a);
      }
      EXPECT_LT(off_by_one, 1000) << "glasses " << int(g) << " method " << int(m) << ": a rare difference";
    }
}

TEST(PackAnaglyph, DuboisMatricesArePublishedOnes) {
  const AnaglyphMatrices rc = anaglyph_matrices(AnaglyphGlasses::RedCyan, AnaglyphMethod::Dubois);
  EXPECT_FLOAT_EQ(rc.left[0], 0.437f);
  EXPECT_FLOAT_EQ(rc.right[8], 1.234f);
  const AnaglyphMatrices gm = anaglyph_matrices(AnaglyphGlasses::GreenMagenta, AnaglyphMethod::Dubois);
  EXPECT_FLOAT_EQ(gm.left[4], 0.668f);
  EXPECT_FLOAT_EQ(gm.right[1], 0.705f);
  const AnaglyphMatrices ab = anaglyph_matrices(AnaglyphGlasses::AmberBlue, AnaglyphMethod::Dubois);
  EXPECT_FLOAT_EQ(ab.left[0], 1.062f);
  EXPECT_FLOAT_EQ(ab.right[8], 0.911f);
}

// Color/HalfColor/Gray: each output channel is fed by exactly one eye, and
// its row is either a unit vector or the luma weights.
TEST(PackAnaglyph, FilterMatricesFeedEachChannelFromOneEye) {
  for (AnaglyphGlasses g : kAllGlasses)
    for (AnaglyphMethod m : kAllMethods) {
      if (m == AnaglyphMethod::Dubois || m == AnaglyphMethod::DuboisFfmpeg || m == AnaglyphMethod::DuboisLinear)
        continue;
      const AnaglyphMatrices am = anaglyph_matrices(g, m);
      for (int c = 0; c < 3; ++c) {
        const float *rows[2] = {am.left + 3 * c, am.right + 3 * c};
        int fed = 0;
        for (const float *row : rows) {
          const float sum = row[0] + row[1] + row[2];
          if (sum == 0.f) continue;
          ++fed;
          const bool unit = row[c] == 1.f && sum == 1.f;
          const bool luma = row[0] == 0.299f && row[1] == 0.587f && row[2] == 0.114f;
          EXPECT_TRUE(unit || luma) << "glasses " << int(g) << " method " << int(m) << " channel " << c;
          EXPECT_TRUE(m != AnaglyphMethod::Gray || luma);
          EXPECT_TRUE(m != AnaglyphMethod::Color || unit);
        }
        EXPECT_EQ(fed, 1) << "glasses " << int(g) << " method " << int(m) << " channel " << c;
      }
    }
}

TEST(PackAnaglyph, MatricesFinite) {
  for (AnaglyphGlasses g : kAllGlasses)
    for (AnaglyphMethod m : kAllMethods) {
      const AnaglyphMatrices am = anaglyph_matrices(g, m);
      for (int i = 0; i < 9; ++i) {
        EXPECT_TRUE(std::isfinite(am.left[i]));
        EXPECT_TRUE(std::isfinite(am.right[i]));
      }
    }
}

// Both eyes of the real pair through red-cyan Color: R from aloeL, G and B
// from aloeR, pixel for pixel.
TEST(PackAnaglyph, ColorOfTheAloePair) {
  const cv::Mat l = test::load_data_image("aloeL.jpg"), r = test::load_data_image("aloeR.jpg");
  ASSERT_FALSE(l.empty());
  ASSERT_FALSE(r.empty());
  cv::Mat pair;
  cv::hconcat(l, r, pair);
  const HostFrame in = HostFrame::from_bgr(pair, PixelFormat::BGRx, 16);
  const HostFrame out = pack(anaglyph_params(AnaglyphGlasses::RedCyan, AnaglyphMethod::Color), in, 8);
  EXPECT_TRUE(all_pixels(out, [&](int x, int y) {
    const cv::Vec3b a = l.at<cv::Vec3b>(y, x), b = r.at<cv::Vec3b>(y, x);
    return Rgba{a[2], b[1], b[0], 255};
  }));
}

// ffmpeg's stereo3d ana_coeff (16.16), arcd: the fractions, entry for entry.
TEST(PackAnaglyph, DuboisFfmpegIsStereo3dsTable) {
  const AnaglyphMatrices rc = anaglyph_matrices(AnaglyphGlasses::RedCyan, AnaglyphMethod::DuboisFfmpeg);
  EXPECT_FLOAT_EQ(rc.left[0], 29891 / 65536.f);   // R out from left R
  EXPECT_FLOAT_EQ(rc.right[0], -2849 / 65536.f);  // R out from right R
  EXPECT_FLOAT_EQ(rc.right[4], 48080 / 65536.f);  // G out from right G
  EXPECT_FLOAT_EQ(rc.right[8], 80373 / 65536.f);  // B out from right B
  EXPECT_FALSE(rc.linear_light);
  const AnaglyphMatrices ab = anaglyph_matrices(AnaglyphGlasses::AmberBlue, AnaglyphMethod::DuboisFfmpeg);
  EXPECT_FLOAT_EQ(ab.left[0], 65535 / 65536.f);
  EXPECT_FLOAT_EQ(ab.right[8], 56217 / 65536.f);
  // Grey 100 on both eyes, red row: (29891 + 32800 + 11559 - 2849 - 5763 - 102) * 100 / 65536 = 100.0
  const Rgba g100{100, 100, 100, 255};
  EXPECT_EQ(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::DuboisFfmpeg, g100, g100).r, 100);
}

// Linear light: the tables are the sRGB transfer, and codes come back to
// themselves through them (the nearest code of a code's own linear value).
// pack_cpu runs the side-by-side anaglyph a row at a time (every method but
// DuboisLinear); it must give pack_pixel()'s pixel, the per-pixel
// definition the GPU kernels share, for every glasses, method, eye order
// and packed format, alpha included.
TEST(PackAnaglyph, RowLoopEqualsThePerPixelFunction) {
  for (PixelFormat f : kPackedFormats) {
    HostFrame in(f, 2 * 37, 5, 12);
    in.fill_random(7 + static_cast<int>(f));
    for (AnaglyphGlasses g : kAllGlasses)
      for (AnaglyphMethod m : kAllMethods)
        for (bool swap : {false, true})
          for (bool rf : {false, true}) {
            PackParams p = anaglyph_params(g, m);
            p.swap_eyes = swap;
            p.input_right_first = rf;
            const AnaglyphMatrices am = anaglyph_matrices(g, m);
            const HostFrame out = pack(p, in, 8);
            EXPECT_TRUE(all_pixels(out, [&](int x, int y) { return pack_pixel(p, am, in.view(), x, y); }))
                << test::format_name(f) << " glasses " << int(g) << " method " << int(m) << " swap " << swap
                << " right first " << rf;
          }
  }
}

TEST(PackAnaglyph, DuboisLinearTables) {
  const AnaglyphMatrices am = anaglyph_matrices(AnaglyphGlasses::RedCyan, AnaglyphMethod::DuboisLinear);
  ASSERT_TRUE(am.linear_light);
  EXPECT_FLOAT_EQ(am.to_linear[0], 0.f);
  EXPECT_FLOAT_EQ(am.to_linear[255], 1.f);
  EXPECT_NEAR(am.to_linear[128], 0.2158605, 1e-6);  // ((128/255 + 0.055) / 1.055)^2.4
  EXPECT_NEAR(am.to_linear[10], 10 / 255.0 / 12.92, 1e-7);
  for (int v = 0; v < 256; ++v) EXPECT_EQ(pack_detail::linear_to_code(am, am.to_linear[v]), v);
  EXPECT_EQ(pack_detail::linear_to_code(am, -1.f), 0);
  EXPECT_EQ(pack_detail::linear_to_code(am, 2.f), 255);
  // The same matrices as Dubois: black stays black, and with the eyes mixed
  // in linear light a mid grey pair comes out brighter than the gamma-space mix.
  const Rgba g0{0, 0, 0, 255}, g128{128, 128, 128, 255};
  EXPECT_TRUE(same(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::DuboisLinear, g0, g0), Rgba{0, 0, 0, 255}));
  // Red row sum 1.050 (left) - 0.050 (right): linear 0.2158605 -> 0.2158605, code 128.
  EXPECT_EQ(anaglyph_of(AnaglyphGlasses::RedCyan, AnaglyphMethod::DuboisLinear, g128, g128).r, 128);
}

// ---- stereo input arrangements ---------------------------------------------------------

PackParams input_params(StereoInput input, bool right_first, PackLayout out, bool swap = false) {
  PackParams p = layout_params(out, swap);
  p.input = input;
  p.input_right_first = right_first;
  return p;
}

HostFrame pack_input(const PackParams &p, const HostFrame &in) {
  int vw = 0, vh = 0, w = 0, h = 0;
  EXPECT_TRUE(input_view_size(p.input, in.width(), in.height(), &vw, &vh));
  pack_size(p.layout, vw, vh, &w, &h);
  HostFrame out(in.format(), w, h, 3);
  out.fill(kPoison);
  pack_cpu(p, in.view(), out.view());
  return out;
}

// Full-resolution arrangements hold the views exactly: any of them, either
// eye first, converts to a full side-by-side pair (and back) losslessly.
TEST(PackInputs, FullArrangementsRoundTrip) {
  HostFrame l(PixelFormat::RGBA, 9, 6), r(PixelFormat::RGBA, 9, 6);
  l.fill_random(31);
  r.fill_random(32);
  for (StereoInput in : {StereoInput::SideBySide, StereoInput::TopBottom})
    for (bool rf : {false, true}) {
      const HostFrame sbs = pack_input(input_params(in, rf, PackLayout::SideBySide), test::arrange_pair(in, rf, l, r));
      EXPECT_TRUE(all_pixels(sbs, [&](int x, int y) { return x < 9 ? at(l, x, y) : at(r, x - 9, y); }))
          << int(in) << " right first " << rf;
      const HostFrame tb = pack_input(input_params(StereoInput::SideBySide, false, PackLayout::TopBottom, rf), sbs);
      EXPECT_TRUE(equal_bgra(tb.to_bgra(), test::arrange_pair(StereoInput::TopBottom, rf, l, r).to_bgra()));
    }
}

// Half inputs: view column X is (3 s_i + s_j + 2) / 4 of the view's squeezed
// samples, i = X / 2, j = i -+ 1 clamped; hand-computed on a ramp.
TEST(PackInputs, HalfSideBySideInterpolatesBetweenSamples) {
  // A 5-wide frame: first view samples 0..2 (values 10, 50, 90), second 3..4 (200, 100).
  HostFrame in(PixelFormat::RGBx, 5, 1);
  const int v[5] = {10, 50, 90, 200, 100};
  for (int x = 0; x < 5; ++x) store_rgba(in.view(), x, 0, Rgba{uint8_t(v[x]), 0, 0, 255});
  const HostFrame out = pack_input(input_params(StereoInput::SideBySideHalf, false, PackLayout::SideBySide), in);
  ASSERT_EQ(out.width(), 10);
  // Left view X = 0..4: i = 0,0,1,1,2; j = 0,1,0,2,1 -> (30+10+2)/4=10, (30+50+2)/4=20, (150+10+2)/4=40,
  // (150+90+2)/4=60, (270+50+2)/4=80.
  const int left[5] = {10, 20, 40, 60, 80};
  // Right view: 2 samples; X = 0..4: i = 0,0,1,1,1(clamped); j = 0,1,0,1,1 ->
  // 200, (600+100+2)/4=175, (300+200+2)/4=125, 100, 100.
  const int right[5] = {200, 175, 125, 100, 100};
  for (int x = 0; x < 5; ++x) {
    EXPECT_EQ(at(out, x, 0).r, left[x]) << x;
    EXPECT_EQ(at(out, 5 + x, 0).r, right[x]) << x;
  }
}

// Interleaved and checkerboard views: owned samples as they are, the others
// the rounded mean of the owned neighbours (hand-computed).
TEST(PackInputs, InterleavedAndCheckerboardFillTheOtherSamples) {
  HostFrame in(PixelFormat::RGBA, 3, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) store_rgba(in.view(), x, y, Rgba{uint8_t(10 * (3 * y + x)), 0, 0, 255});
  // Row-interleaved, second view (odd rows): row 0 from row 1 (clamped: 30,40,50), row 2 likewise.
  const HostFrame rows = pack_input(input_params(StereoInput::RowInterleaved, false, PackLayout::Right), in);
  EXPECT_EQ(at(rows, 1, 0).r, 40);
  EXPECT_EQ(at(rows, 1, 1).r, 40);
  EXPECT_EQ(at(rows, 1, 2).r, 40);
  // First view at row 1: mean of rows 0 and 2 = (10 + 70 + 1) / 2 = 40.
  const HostFrame rows_l = pack_input(input_params(StereoInput::RowInterleaved, false, PackLayout::Left), in);
  EXPECT_EQ(at(rows_l, 1, 1).r, 40);
  EXPECT_EQ(at(rows_l, 0, 1).r, 30);  // (0 + 60 + 1) / 2
  // Column-interleaved, first view at column 1: (30 + 50 + 1) / 2 = 40 in row 1.
  const HostFrame cols = pack_input(input_params(StereoInput::ColumnInterleaved, false, PackLayout::Left), in);
  EXPECT_EQ(at(cols, 1, 1).r, 40);
  // Checkerboard, first view ((x+y) even) at the centre's neighbour (1,0):
  // neighbours (0,0)=0, (2,0)=20, (1,1)=40 -> (60 + 1) / 3 = 20.
  const HostFrame chk = pack_input(input_params(StereoInput::Checkerboard, false, PackLayout::Left), in);
  EXPECT_EQ(at(chk, 1, 0).r, 20);
  EXPECT_EQ(at(chk, 1, 1).r, 40);  // owned
  // Second view at the centre (owned by the first): (10 + 30 + 50 + 70 + 2) / 4 = 40.
  const HostFrame chk_r = pack_input(input_params(StereoInput::Checkerboard, false, PackLayout::Right), in);
  EXPECT_EQ(at(chk_r, 1, 1).r, 40);
  EXPECT_EQ(at(chk_r, 0, 0).r, 20);  // (10 + 30 + 1) / 2
}

// Views of one colour each survive every arrangement exactly, and the eye
// order and swap_eyes decide which view lands where.
TEST(PackInputs, EveryArrangementKeepsTheViewsApart) {
  HostFrame l(PixelFormat::RGBA, 6, 4), r(PixelFormat::RGBA, 6, 4);
  l.fill(40);
  r.fill(200);
  for (StereoInput in : test::kAllInputs)
    for (bool rf : {false, true})
      for (bool swap : {false, true}) {
        const HostFrame frame = test::arrange_pair(in, rf, l, r);
        const HostFrame out = pack_input(input_params(in, rf, PackLayout::SideBySide, swap), frame);
        ASSERT_EQ(out.width(), 12);
        ASSERT_EQ(out.height(), 4);
        const uint8_t first = swap ? 200 : 40, second = swap ? 40 : 200;
        EXPECT_TRUE(all_pixels(out, [&](int x, int) {
          const uint8_t v = x < 6 ? first : second;
          return Rgba{v, v, v, v};
        })) << "input " << int(in) << " right first " << rf << " swap " << swap;
      }
}

// Random pairs in every arrangement, either eye first, into full
// side-by-side: the views must be the reference reconstruction exactly.
TEST(PackInputs, EveryArrangementMatchesTheReference) {
  const int sizes[][2] = {{1, 1}, {2, 3}, {7, 5}, {32, 18}};
  for (const auto &sz : sizes) {
    HostFrame l(PixelFormat::RGBA, sz[0], sz[1]), r(PixelFormat::RGBA, sz[0], sz[1]);
    l.fill_random(41 + sz[0]);
    r.fill_random(42 + sz[1]);
    for (StereoInput in : test::kAllInputs)
      for (bool rf : {false, true}) {
        const HostFrame frame = test::arrange_pair(in, rf, l, r);
        const HostFrame out = pack_input(input_params(in, rf, PackLayout::SideBySide), frame);
        const HostFrame ref_l = test::reference_view(in, rf, frame, 0), ref_r = test::reference_view(in, rf, frame, 1);
        ASSERT_EQ(out.width(), 2 * ref_l.width());
        EXPECT_TRUE(all_pixels(out, [&](int x, int y) {
          return x < ref_l.width() ? at(ref_l, x, y) : at(ref_r, x - ref_l.width(), y);
        })) << "input " << int(in) << " right first " << rf << " " << sz[0] << "x" << sz[1];
      }
  }
}

TEST(PackInputs, IdentityAndSizes) {
  PackParams p = input_params(StereoInput::SideBySideHalf, true, PackLayout::SideBySideHalf, true);
  EXPECT_TRUE(pack_is_identity(p));
  p.swap_eyes = false;
  EXPECT_FALSE(pack_is_identity(p));
  EXPECT_FALSE(pack_is_identity(input_params(StereoInput::SideBySide, false, PackLayout::Anaglyph)));
  EXPECT_TRUE(pack_is_identity(input_params(StereoInput::Checkerboard, false, PackLayout::Checkerboard)));
  int w = 0, h = 0;
  EXPECT_FALSE(input_view_size(StereoInput::SideBySide, 7, 4, &w, &h));
  EXPECT_FALSE(input_view_size(StereoInput::TopBottom, 8, 5, &w, &h));
  ASSERT_TRUE(input_view_size(StereoInput::TopBottom, 8, 6, &w, &h));
  EXPECT_EQ(w, 8);
  EXPECT_EQ(h, 3);
  ASSERT_TRUE(input_view_size(StereoInput::SideBySideHalf, 7, 5, &w, &h));
  EXPECT_EQ(w, 7);
  EXPECT_EQ(h, 5);
  HostFrame odd(PixelFormat::RGBA, 7, 3), out(PixelFormat::RGBA, 7, 3);
  EXPECT_FALSE(pack_args_valid(input_params(StereoInput::SideBySide, false, PackLayout::Left), odd.view(), out.view()));
  EXPECT_TRUE(pack_args_valid(input_params(StereoInput::RowInterleaved, false, PackLayout::Left), odd.view(), out.view()));
}

// ---- every layout and format ---------------------------------------------------------

std::vector<PackParams> every_params() {
  std::vector<PackParams> all;
  for (StereoInput in : test::kAllInputs)
    for (bool rf : {false, true}) {
      if (in == StereoInput::SideBySide && !rf) continue;  // the loop below
      all.push_back(input_params(in, rf, PackLayout::SideBySideHalf));
    }
  for (PackLayout l : kAllLayouts)
    for (bool swap : {false, true}) {
      if (l != PackLayout::Anaglyph) {
        all.push_back(layout_params(l, swap));
        continue;
      }
      for (AnaglyphGlasses g : kAllGlasses)
        for (AnaglyphMethod m : kAllMethods) {
          PackParams p = anaglyph_params(g, m);
          p.swap_eyes = swap;
          all.push_back(p);
        }
    }
  return all;
}

TEST(PackFormats, EveryPackedFormatGivesTheSameResult) {
  cv::Mat bgr(18, 2 * 33, CV_8UC3);  // even height: a full top-bottom pair too
  cv::randu(bgr, 0, 256);
  for (const PackParams &p : every_params()) {
    const cv::Mat want = pack_input(p, HostFrame::from_bgr(bgr, PixelFormat::RGBA)).to_bgra();
    for (PixelFormat f : kPackedFormats) {
      const cv::Mat got = pack_input(p, HostFrame::from_bgr(bgr, f, 12)).to_bgra();
      EXPECT_TRUE(equal_bgra(got, want)) << test::format_name(f) << " layout " << int(p.layout) << " glasses "
                                         << int(p.glasses) << " method " << int(p.method) << " swap " << p.swap_eyes;
    }
  }
}

// The output rows' padding (and the byte after the last row) must keep the
// poison, and every output pixel must have been written.
TEST(PackFormats, NoWriteOutsideTheRows) {
  const int sizes[][2] = {{1, 1}, {3, 2}, {33, 17}};
  for (const auto &s : sizes)
    for (PixelFormat f : kPackedFormats)
      for (const PackParams &p : every_params()) {
        HostFrame in(f, 2 * s[0], s[1], 5);
        in.fill_random(15);
        if (p.input == StereoInput::TopBottom && s[1] % 2) continue;  // holds no full top-bottom pair
        int vw = 0, vh = 0, ow = 0, oh = 0;
        ASSERT_TRUE(input_view_size(p.input, in.width(), in.height(), &vw, &vh));
        pack_size(p.layout, vw, vh, &ow, &oh);
        HostFrame out(f, ow, oh, 7);
        out.fill(kPoison);
        pack_cpu(p, in.view(), out.view());
        const FrameView v = out.view();
        long long padding_hits = 0, unwritten = 0;
        for (int y = 0; y < v.height; ++y) {
          const uint8_t *row = v.plane[0] + static_cast<size_t>(y) * v.stride[0];
          for (int i = 4 * v.width; i < v.stride[0]; ++i) padding_hits += row[i] != kPoison;
          // A written pixel of an X format has 255 in its 4th byte; of an
          // alpha format, a random alpha: all four bytes poison is vanishingly rare.
          for (int x = 0; x < v.width; ++x)
            unwritten += row[4 * x] == kPoison && row[4 * x + 1] == kPoison && row[4 * x + 2] == kPoison &&
                         row[4 * x + 3] == kPoison;
        }
        padding_hits += v.plane[0][static_cast<size_t>(v.height) * v.stride[0]] != kPoison;
        EXPECT_EQ(padding_hits, 0) << test::format_name(f) << " layout " << int(p.layout) << " " << s[0] << "x"
                                   << s[1];
        EXPECT_EQ(unwritten, 0) << test::format_name(f) << " layout " << int(p.layout) << " " << s[0] << "x" << s[1];
      }
}

TEST(PackFormats, RejectsMismatchedFrames) {
  HostFrame in(PixelFormat::RGBA, 2 * 4, 3);
  HostFrame ok(PixelFormat::RGBA, 4, 3);
  const PackParams p = layout_params(PackLayout::Left);
  EXPECT_TRUE(pack_args_valid(p, in.view(), ok.view()));
  HostFrame wrong_size(PixelFormat::RGBA, 8, 3);
  EXPECT_THROW(pack_cpu(p, in.view(), wrong_size.view()), std::invalid_argument);
  HostFrame wrong_format(PixelFormat::BGRA, 4, 3);
  EXPECT_THROW(pack_cpu(p, in.view(), wrong_format.view()), std::invalid_argument);
  HostFrame yuv_in(PixelFormat::NV12, 2 * 4, 3), yuv_out(PixelFormat::NV12, 4, 3);
  EXPECT_THROW(pack_cpu(p, yuv_in.view(), yuv_out.view()), std::invalid_argument);
  HostFrame odd_in(PixelFormat::RGBA, 7, 3), odd_out(PixelFormat::RGBA, 3, 3);
  EXPECT_THROW(pack_cpu(p, odd_in.view(), odd_out.view()), std::invalid_argument);
  PackParams bad = p;
  bad.layout = static_cast<PackLayout>(99);
  EXPECT_FALSE(pack_args_valid(bad, in.view(), ok.view()));
  bad = p;
  bad.method = static_cast<AnaglyphMethod>(-1);
  EXPECT_FALSE(pack_args_valid(bad, in.view(), ok.view()));
}

// ---- 4:2:0 output ---------------------------------------------------------

// `in` packed by `p` into `format` (NV12 or I420) with every byte poisoned first.
HostFrame pack_yuv(const PackParams &p, const HostFrame &in, PixelFormat format, uint8_t poison = kPoison) {
  int vw = 0, vh = 0, w = 0, h = 0;
  EXPECT_TRUE(input_view_size(p.input, in.width(), in.height(), &vw, &vh));
  pack_size(p.layout, vw, vh, &w, &h);
  HostFrame out(format, w, h, 5);
  out.fill(poison);
  pack_cpu(p, in.view(), out.view());
  return out;
}

uint8_t y_at(const HostFrame &f, int x, int y) { return f.view().plane[0][static_cast<size_t>(y) * f.view().stride[0] + x]; }
// Cb (c = 0) or Cr (c = 1) of chroma sample (bx, by).
uint8_t c_at(const HostFrame &f, int bx, int by, int c) {
  const FrameView v = f.view();
  if (v.format == PixelFormat::NV12) return v.plane[1][static_cast<size_t>(by) * v.stride[1] + 2 * bx + c];
  return v.plane[1 + c][static_cast<size_t>(by) * v.stride[1 + c] + bx];
}

// The conversion as its definition reads (pack.h, frame.h), in double, from
// the packed R'G'B' frame `rgb`: the 4:2:0 output must be within one level
// of it everywhere (float rounding), for every sample.
::testing::AssertionResult matches_definition(const HostFrame &yuv, const HostFrame &rgb, double kr, double kb,
                                              bool full) {
  const double kg = 1 - kr - kb, ys = full ? 1 : 219.0 / 255, cs = full ? 1 : 224.0 / 255, yo = full ? 0 : 16;
  auto u8 = [](double v) { return static_cast<int>(std::floor(std::min(255.0, std::max(0.0, v)) + 0.5)); };
  for (int y = 0; y < rgb.height(); ++y)
    for (int x = 0; x < rgb.width(); ++x) {
      const Rgba c = at(rgb, x, y);
      const int want = u8(yo + ys * (kr * c.r + kg * c.g + kb * c.b));
      if (std::abs(want - y_at(yuv, x, y)) > 1)
        return ::testing::AssertionFailure() << "Y at (" << x << "," << y << "): " << int(y_at(yuv, x, y)) << " want "
                                             << want;
    }
  for (int by = 0; 2 * by < rgb.height(); ++by)
    for (int bx = 0; 2 * bx < rgb.width(); ++bx) {
      double r = 0, g = 0, b = 0;
      int n = 0;
      for (int y = 2 * by; y < std::min(2 * by + 2, rgb.height()); ++y)
        for (int x = 2 * bx; x < std::min(2 * bx + 2, rgb.width()); ++x, ++n) {
          const Rgba c = at(rgb, x, y);
          r += c.r;
          g += c.g;
          b += c.b;
        }
      r /= n;
      g /= n;
      b /= n;
      const double yl = kr * r + kg * g + kb * b;
      const int want[2] = {u8(128 + cs * (b - yl) / (2 * (1 - kb))), u8(128 + cs * (r - yl) / (2 * (1 - kr)))};
      for (int c = 0; c < 2; ++c)
        if (std::abs(want[c] - c_at(yuv, bx, by, c)) > 1)
          return ::testing::AssertionFailure() << (c ? "Cr" : "Cb") << " at block (" << bx << "," << by
                                               << "): " << int(c_at(yuv, bx, by, c)) << " want " << want[c];
    }
  return ::testing::AssertionSuccess();
}

struct Matrix {
  double kr, kb;
  bool full;
};
constexpr Matrix kMatrices[] = {{0.2126, 0.0722, false}, {0.299, 0.114, true}, {0.2627, 0.0593, false}};

// Every layout, anaglyph and input arrangement, odd and even sizes, three
// colorimetries: the samples are the packed pixels converted as defined,
// NV12 and I420 hold the same samples, and the poison is gone from every
// sample (each one written).
TEST(PackYuvOutput, EveryLayoutMatchesTheDefinition) {
  const int sizes[][2] = {{1, 1}, {3, 2}, {33, 17}, {8, 6}};
  for (const auto &sz : sizes)
    for (const PackParams &base : every_params())
      for (const Matrix &m : kMatrices) {
        HostFrame in(PixelFormat::BGRx, 2 * sz[0], sz[1], 3);
        in.fill_random(sz[0] * 131 + sz[1]);
        if (base.input == StereoInput::TopBottom && sz[1] % 2) continue;
        PackParams p = base;
        p.yuv = rgb_to_yuv_params(m.kr, m.kb, m.full);
        const HostFrame rgb = pack_input(p, in);
        const HostFrame nv12 = pack_yuv(p, in, PixelFormat::NV12), i420 = pack_yuv(p, in, PixelFormat::I420);
        const std::string what = "layout " + std::to_string(int(p.layout)) + " input " +
                                 std::to_string(int(p.input)) + " " + std::to_string(sz[0]) + "x" +
                                 std::to_string(sz[1]) + " kr " + std::to_string(m.kr);
        ASSERT_TRUE(matches_definition(nv12, rgb, m.kr, m.kb, m.full)) << what;
        const HostFrame again = pack_yuv(p, in, PixelFormat::I420, static_cast<uint8_t>(~kPoison));
        for (int y = 0; y < rgb.height(); ++y)
          for (int x = 0; x < rgb.width(); ++x) {
            ASSERT_EQ(y_at(nv12, x, y), y_at(i420, x, y)) << what;
            ASSERT_EQ(y_at(i420, x, y), y_at(again, x, y)) << what << ": a sample kept its poison";
            if (x % 2 || y % 2) continue;
            for (int c = 0; c < 2; ++c) {
              ASSERT_EQ(c_at(nv12, x / 2, y / 2, c), c_at(i420, x / 2, y / 2, c)) << what;
              ASSERT_EQ(c_at(i420, x / 2, y / 2, c), c_at(again, x / 2, y / 2, c)) << what << ": kept its poison";
            }
          }
      }
}

// OpenCV's BGR -> I420 (BT.601, limited range) on a view of flat 2x2
// blocks, where chroma siting cannot matter: within one level.
TEST(PackYuvOutput, AgreesWithOpenCvOnFlatBlocks) {
  cv::Mat blocks(12, 20, CV_8UC3);
  cv::randu(blocks, 0, 256);
  cv::Mat view;
  cv::resize(blocks, view, cv::Size(40, 24), 0, 0, cv::INTER_NEAREST);
  cv::Mat pair;
  cv::hconcat(view, view, pair);
  PackParams p = layout_params(PackLayout::Left);
  p.yuv = rgb_to_yuv_params(0.299, 0.114, false);
  const HostFrame ours = pack_yuv(p, HostFrame::from_bgr(pair, PixelFormat::RGBA), PixelFormat::I420);
  cv::Mat cv_i420;
  cv::cvtColor(view, cv_i420, cv::COLOR_BGR2YUV_I420);  // 36 rows: Y, then U, then V planes
  int worst = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 40; ++x) worst = std::max(worst, std::abs(int(cv_i420.at<uint8_t>(y, x)) - y_at(ours, x, y)));
  const uint8_t *u = cv_i420.ptr<uint8_t>(24), *v = u + 20 * 12;
  for (int by = 0; by < 12; ++by)
    for (int bx = 0; bx < 20; ++bx) {
      worst = std::max(worst, std::abs(int(u[by * 20 + bx]) - c_at(ours, bx, by, 0)));
      worst = std::max(worst, std::abs(int(v[by * 20 + bx]) - c_at(ours, bx, by, 1)));
    }
  EXPECT_LE(worst, 1);
}

// The plugin's own reader (load_rgba with the matching YuvToRgb) brings flat
// blocks back within the 8-bit rounding of the two conversions.
TEST(PackYuvOutput, ReadsBackThroughLoadRgba) {
  HostFrame in(PixelFormat::RGBA, 2 * 16, 10);
  HostFrame flat(PixelFormat::RGBA, 8, 5);
  flat.fill_random(77);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 32; ++x) store_rgba(in.view(), x, y, at(flat, (x % 16) / 2, y / 2));
  for (const Matrix &m : kMatrices) {
    PackParams p = layout_params(PackLayout::Right);
    p.yuv = rgb_to_yuv_params(m.kr, m.kb, m.full);
    const HostFrame yuv = pack_yuv(p, in, PixelFormat::NV12);
    const YuvToRgb back = yuv_to_rgb_params(m.kr, m.kb, m.full);
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 16; ++x) {
        const Rgba want = at(flat, x / 2, y / 2), got = load_rgba(yuv.view(), x, y, back);
        EXPECT_LE(std::abs(got.r - want.r), 3) << x << "," << y;
        EXPECT_LE(std::abs(got.g - want.g), 3) << x << "," << y;
        EXPECT_LE(std::abs(got.b - want.b), 3) << x << "," << y;
      }
  }
}

TEST(PackYuvOutput, RefusesYuvInputAndMissingPlanes) {
  const PackParams p = layout_params(PackLayout::Left);
  HostFrame in(PixelFormat::RGBA, 8, 4), out(PixelFormat::I420, 4, 4);
  EXPECT_TRUE(pack_args_valid(p, in.view(), out.view()));
  FrameView no_v = out.view();
  no_v.plane[2] = nullptr;
  EXPECT_FALSE(pack_args_valid(p, in.view(), no_v));
  FrameView short_stride = out.view();
  short_stride.stride[1] = 1;
  EXPECT_FALSE(pack_args_valid(p, in.view(), short_stride));
  HostFrame nv12_in(PixelFormat::NV12, 8, 4), nv12_out(PixelFormat::NV12, 4, 4);
  EXPECT_THROW(pack_cpu(p, nv12_in.view(), nv12_out.view()), std::invalid_argument);
}

}  // namespace
}  // namespace p3d
