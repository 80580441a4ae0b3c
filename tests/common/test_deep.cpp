// The deep formats (P010, I420_10, RGBA64: 16-bit samples) through the CPU
// references:
//  * the 8-bit readers (depth, filter guide, bars) take the high bits;
//  * the warp and the pack compute the 8-bit function on 16-bit samples:
//    a 16-bit picture widened from an 8-bit one gives the 8-bit output
//    widened, within one 8-bit level;
//  * nothing goes through 8 bits: the samples a layout copies come out
//    with every one of their 16 bits, and the half layouts' and the
//    interleaved layouts' means are the 16-bit means;
//  * P010 and I420_10 holding the same codes give the same output;
//  * 4:2:0 output of 10-bit codes agrees with the 8-bit output.
#include <algorithm>
#include <cstring>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "bars.h"
#include "change_map.h"
#include "depth_estimate.h"
#include "host_frame.h"
#include "pack.h"
#include "test_data.h"
#include "warp.h"

namespace p3d {
namespace {

// A depth map with steps (holes for the fills) and slopes.
cv::Mat depth_map(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<float>(y, x) = 0.2f + 0.3f * static_cast<float>(y) / static_cast<float>(h);
  for (int k = 0; k < 3; ++k) {
    const int x0 = static_cast<int>(rng() % (w / 2)), y0 = static_cast<int>(rng() % (h / 2));
    d(cv::Rect(x0, y0, w / 3, h / 3)) = cv::Scalar(0.6 + 0.1 * k);
  }
  return d;
}

// The 8-bit RGBA frame of a BGR picture, and the RGBA64 frame of it widened.
HostFrame rgba8(const cv::Mat &bgr) { return HostFrame::from_bgr(bgr, PixelFormat::RGBA); }

// max |a16 - 257 a8| over every channel of two packed frames of one size.
int widened_gap(const HostFrame &a16, const HostFrame &a8) {
  int gap = 0;
  for (int y = 0; y < a8.height(); ++y)
    for (int x = 0; x < a8.width(); ++x) {
      Rgba16 w;
      Rgba n;
      load_pixel(a16.view(), x, y, &w);
      load_pixel(a8.view(), x, y, &n);
      gap = std::max({gap, std::abs(w.r - 257 * n.r), std::abs(w.g - 257 * n.g), std::abs(w.b - 257 * n.b),
                      std::abs(w.a - 257 * n.a)});
    }
  return gap;
}

TEST(DeepFormats, EightBitReadersTakeTheHighBits) {
  const cv::Mat pic = test::deep_picture(34, 22, 1);
  for (PixelFormat f : test::kDeepFormats) {
    const HostFrame frame = HostFrame::from_bgr16(pic, f);
    const FrameView v = frame.view();
    for (int y = 0; y < v.height; ++y)
      for (int x = 0; x < v.width; ++x) {
        int native[3];
        load_native3(v, x, y, native);
        if (f == PixelFormat::RGBA64) {
          const Rgba16 c = load_packed16(v, x, y);
          EXPECT_EQ(native[0], c.r >> 8);
          EXPECT_EQ(native[1], c.g >> 8);
          EXPECT_EQ(native[2], c.b >> 8);
          continue;
        }
        int u, vv;
        load_chroma(v, x, y, &u, &vv);
        ASSERT_EQ(load_luma(v, x, y), load_code(v, 0, y, x) >> 2) << test::format_name(f);
        EXPECT_EQ(native[1], u >> 2);
        EXPECT_EQ(native[2], vv >> 2);
      }
  }
}

// The high-byte copy (the GPU depth estimate's and filter's input) reads
// as the deep frame does through the 8-bit readers, so the 8-bit stages of
// the copy are those of the frame; and the copy is of the format's 8-bit
// twin.
TEST(DeepFormats, HighByteCopyReadsAsTheDeepFrame) {
  const cv::Mat pic = test::deep_picture(35, 23, 6);
  for (PixelFormat f : test::kDeepFormats) {
    const HostFrame frame = HostFrame::from_bgr16(pic, f);
    HostFrame copy(high_byte_format(f), frame.width(), frame.height(), 3);
    copy.fill(0x5A);
    high_byte_copy_cpu(frame.view(), copy.view());
    EXPECT_FALSE(is_deep(copy.format()));
    EXPECT_EQ(is_rgba64(f), is_packed_rgb(copy.format())) << test::format_name(f);
    for (int y = 0; y < frame.height(); ++y)
      for (int x = 0; x < frame.width(); ++x) {
        ASSERT_EQ(load_luma(copy.view(), x, y), load_luma(frame.view(), x, y)) << test::format_name(f);
        int a[3], b[3];
        load_native3(copy.view(), x, y, a);
        load_native3(frame.view(), x, y, b);
        ASSERT_TRUE(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]) << test::format_name(f) << " " << x << "," << y;
      }
  }
  EXPECT_EQ(high_byte_format(PixelFormat::NV12), PixelFormat::NV12);
}

// A 10-bit frame whose codes are 8-bit codes shifted up estimates the very
// depth of the 8-bit frame.
TEST(DeepFormats, DepthOfShiftedCodesIsTheEightBitDepth) {
  const cv::Mat bgr = test::load_data_image("aloeL.jpg");
  ASSERT_FALSE(bgr.empty());
  cv::Mat small;
  cv::resize(bgr, small, cv::Size(160, 128));
  const HostFrame nv12 = HostFrame::from_bgr(small, PixelFormat::NV12);
  HostFrame p010(PixelFormat::P010, nv12.width(), nv12.height());
  for (int p = 0; p < 2; ++p) {
    int row = 0, rows = 0;
    frame_plane_size(PixelFormat::NV12, nv12.width(), nv12.height(), p, &row, &rows);
    for (int y = 0; y < rows; ++y)
      for (int i = 0; i < row; ++i) store_code(p010.view(), p, y, i, load_code(nv12.view(), p, y, i) << 2);
  }
  DepthParams params;
  cv::Mat d8(nv12.height(), nv12.width(), CV_32FC1), d10(nv12.height(), nv12.width(), CV_32FC1);
  DepthEstimatorCpu e8, e10;
  e8.estimate(params, nv12.view(), depth_view_of(d8));
  e10.estimate(params, p010.view(), depth_view_of(d10));
  EXPECT_EQ(cv::norm(d8, d10, cv::NORM_INF), 0.0);
}

// Warp of a 16-bit picture widened from an 8-bit one: every fill, every view.
TEST(DeepWarp, SameFunctionAsEightBit) {
  const int w = 96, h = 64;
  cv::Mat bgr8;
  test::deep_picture(w, h, 2).convertTo(bgr8, CV_8UC3, 1.0 / 257.0);
  const HostFrame src8 = rgba8(bgr8), src16 = HostFrame::from_bgr(bgr8, PixelFormat::RGBA64);
  const cv::Mat depth = depth_map(w, h, 3);
  for (const auto &fill : kHoleFillNames)
    for (const auto &view : kStereoViewNames) {
      WarpParams p;
      p.max_disparity = 8.f;
      p.fill = fill.value;
      p.view = view.value;
      HostFrame out8(PixelFormat::RGBA, 2 * w, h), out16(PixelFormat::RGBA64, 2 * w, h);
      const long long h8 = warp_render_cpu(p, src8.view(), YuvToRgb{}, depth_view_of(depth), out8.view());
      const long long h16 = warp_render_cpu(p, src16.view(), YuvToRgb{}, depth_view_of(depth), out16.view());
      ASSERT_GT(h8, 0) << fill.nick;
      EXPECT_EQ(h8, h16) << fill.nick << " " << view.nick << ": the holes are the geometry's";
      // One 8-bit level; the neighbour average's iterations round twice.
      const int allowed = fill.value == HoleFill::NeighborAverage ? 2 * 257 : 257;
      EXPECT_LE(widened_gap(out16, out8), allowed) << fill.nick << " " << view.nick;
    }
}

// With no parallax both views are the source: every 16-bit sample arrives.
TEST(DeepWarp, CopiesEverySixteenBitSample) {
  const int w = 40, h = 30;
  const cv::Mat pic = test::deep_picture(w, h, 4), depth = depth_map(w, h, 5);
  const YuvToRgb ten = yuv_to_rgb_params(0.299, 0.114, false, 10);
  for (PixelFormat f : test::kDeepFormats) {
    const HostFrame src = HostFrame::from_bgr16(pic, f);
    WarpParams p;
    p.max_disparity = 0.f;
    HostFrame out(PixelFormat::RGBA64, 2 * w, h);
    ASSERT_GE(warp_render_cpu(p, src.view(), ten, depth_view_of(depth), out.view()), 0) << test::format_name(f);
    int low_bits = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Rgba16 want = load_rgba16(src.view(), x, y, ten);
        for (int eye = 0; eye < 2; ++eye) {
          const Rgba16 got = load_packed16(out.view(), x + eye * w, y);
          ASSERT_TRUE(got.r == want.r && got.g == want.g && got.b == want.b && got.a == want.a)
              << test::format_name(f) << " at " << x << "," << y;
        }
        low_bits += want.g % 257 != 0;
      }
    EXPECT_GT(low_bits, w * h / 2) << test::format_name(f) << ": the test picture must use more than 8 bits";
  }
}

// The 10-bit Y'CbCr formats differ only in where the code sits.
TEST(DeepWarp, P010AndI420_10Agree) {
  const int w = 64, h = 48;
  const cv::Mat pic = test::deep_picture(w, h, 6), depth = depth_map(w, h, 7);
  const YuvToRgb ten = yuv_to_rgb_params(0.2126, 0.0722, false, 10);
  const HostFrame a = HostFrame::from_bgr16(pic, PixelFormat::P010), b = HostFrame::from_bgr16(pic, PixelFormat::I420_10);
  WarpParams p;
  p.max_disparity = 6.f;
  HostFrame oa(PixelFormat::RGBA64, 2 * w, h), ob(PixelFormat::RGBA64, 2 * w, h);
  ASSERT_GE(warp_render_cpu(p, a.view(), ten, depth_view_of(depth), oa.view()), 0);
  ASSERT_GE(warp_render_cpu(p, b.view(), ten, depth_view_of(depth), ob.view()), 0);
  for (int y = 0; y < h; ++y)
    ASSERT_EQ(0, std::memcmp(oa.view().plane[0] + y * oa.view().stride[0], ob.view().plane[0] + y * ob.view().stride[0],
                             8 * 2 * w))
        << "row " << y;
}

// 10-bit parameters with an 8-bit frame (or the reverse) are refused.
TEST(DeepWarp, ParametersOfAnotherDepthAreRefused) {
  const cv::Mat pic = test::deep_picture(16, 8, 8), depth = depth_map(16, 8, 9);
  const HostFrame p010 = HostFrame::from_bgr16(pic, PixelFormat::P010);
  HostFrame out(PixelFormat::RGBA64, 32, 8), out8(PixelFormat::RGBA, 32, 8);
  EXPECT_EQ(warp_render_cpu(WarpParams{}, p010.view(), YuvToRgb{}, depth_view_of(depth), out.view()), -1);
  EXPECT_EQ(warp_render_cpu(WarpParams{}, p010.view(), yuv_to_rgb_params(0.299, 0.114, false, 10),
                            depth_view_of(depth), out8.view()),
            -1)
      << "deep frames render 16-bit views";
  const HostFrame nv12 = HostFrame::from_bgr(cv::Mat(8, 16, CV_8UC3, cv::Scalar(90, 120, 30)), PixelFormat::NV12);
  EXPECT_EQ(warp_render_cpu(WarpParams{}, nv12.view(), yuv_to_rgb_params(0.299, 0.114, false, 10),
                            depth_view_of(depth), out8.view()),
            -1)
      << "10-bit parameters, 8-bit frame";
}

HostFrame pair16(int w, int h, uint32_t seed) {
  return HostFrame::from_bgr16(test::deep_picture(2 * w, h, seed), PixelFormat::RGBA64);
}

// Layouts that copy samples copy all 16 bits; the half layouts store the
// rounded 16-bit mean of two samples.
TEST(DeepPack, LayoutsKeepSixteenBits) {
  const int w = 21, h = 13;  // odd: the half layouts' shorter view
  const HostFrame in = pair16(w, h, 10);
  auto at = [&](int eye, int x, int y) { return load_packed16(in.view(), x + eye * w, y); };
  auto same = [](Rgba16 a, Rgba16 b) { return a.r == b.r && a.g == b.g && a.b == b.b && a.a == b.a; };
  for (const auto &layout : test::kAllLayouts) {
    if (layout == PackLayout::Anaglyph) continue;
    PackParams p;
    p.layout = layout;
    int ow = 0, oh = 0;
    pack_size(layout, w, h, &ow, &oh);
    HostFrame out(PixelFormat::RGBA64, ow, oh);
    pack_cpu(p, in.view(), out.view());
    const FrameView o = out.view();
    for (int y = 0; y < oh; ++y)
      for (int x = 0; x < ow; ++x) {
        const Rgba16 got = load_packed16(o, x, y);
        Rgba16 want = got;
        switch (layout) {
          case PackLayout::SideBySide: want = x < w ? at(0, x, y) : at(1, x - w, y); break;
          case PackLayout::TopBottom: want = y < h ? at(0, x, y) : at(1, x, y - h); break;
          case PackLayout::RowInterleaved: want = at(y & 1, x, y); break;
          case PackLayout::ColumnInterleaved: want = at(x & 1, x, y); break;
          case PackLayout::Checkerboard: want = at((x + y) & 1, x, y); break;
          case PackLayout::Left: want = at(0, x, y); break;
          case PackLayout::Right: want = at(1, x, y); break;
          case PackLayout::SideBySideHalf: {
            const int eye = x < half_split(w) ? 0 : 1, i = eye ? x - half_split(w) : x;
            want = pack_detail::mean2(at(eye, 2 * i, y), at(eye, std::min(2 * i + 1, w - 1), y));
            break;
          }
          case PackLayout::TopBottomHalf: {
            const int eye = y < half_split(h) ? 0 : 1, i = eye ? y - half_split(h) : y;
            want = pack_detail::mean2(at(eye, x, 2 * i), at(eye, x, std::min(2 * i + 1, h - 1)));
            break;
          }
          default: break;
        }
        ASSERT_TRUE(same(got, want)) << enum_nick(kPackLayoutNames, layout) << " at " << x << "," << y;
      }
  }
}

// The 16-bit gamma mix (anaglyph_gamma16), computed in 32-bit integers,
// equals its definition in 64 bits, sum(q * c) + 2^15 shifted down 16 bits
// and clipped, for every method's matrices and for random matrices up to
// the 2^17 bound, on random channels and the extremes 0 and 65535.
TEST(DeepPack, GammaMixEqualsItsSixtyFourBitSums) {
  std::mt19937 rng(2026);
  std::uniform_int_distribution<int> level(0, 65535), q(-(1 << 17) + 1, (1 << 17) - 1);
  auto reference = [](const AnaglyphMatrices &am, Rgba16 l, Rgba16 r) {
    const long long lc[3] = {l.r, l.g, l.b}, rc[3] = {r.r, r.g, r.b};
    uint16_t v[3];
    for (int k = 0; k < 3; ++k) {
      long long sum = 32768;
      for (int i = 0; i < 3; ++i)
        sum += static_cast<long long>(am.left_q[3 * k + i]) * lc[i] +
               static_cast<long long>(am.right_q[3 * k + i]) * rc[i];
      const long long shifted = sum >> 16;
      v[k] = static_cast<uint16_t>(shifted < 0 ? 0 : (shifted > 65535 ? 65535 : shifted));
    }
    return Rgba16{v[0], v[1], v[2], l.a};
  };
  std::vector<AnaglyphMatrices> matrices;
  for (const auto method : test::kAllMethods) matrices.push_back(anaglyph_matrices(AnaglyphGlasses::RedCyan, method));
  for (int m = 0; m < 200; ++m) {
    AnaglyphMatrices am = matrices[0];
    for (int i = 0; i < 9; ++i) {
      am.left_q[i] = q(rng);
      am.right_q[i] = q(rng);
    }
    matrices.push_back(am);
  }
  const uint16_t extremes[2] = {0, 65535};
  for (const AnaglyphMatrices &am : matrices) {
    for (int n = 0; n < 2000; ++n) {
      Rgba16 l{}, r{};
      if (n < 128) {  // every corner of the extremes
        l = Rgba16{extremes[n & 1], extremes[(n >> 1) & 1], extremes[(n >> 2) & 1], 65535};
        r = Rgba16{extremes[(n >> 3) & 1], extremes[(n >> 4) & 1], extremes[(n >> 5) & 1], 65535};
      } else {
        l = Rgba16{static_cast<uint16_t>(level(rng)), static_cast<uint16_t>(level(rng)),
                   static_cast<uint16_t>(level(rng)), static_cast<uint16_t>(level(rng))};
        r = Rgba16{static_cast<uint16_t>(level(rng)), static_cast<uint16_t>(level(rng)),
                   static_cast<uint16_t>(level(rng)), static_cast<uint16_t>(level(rng))};
      }
      const Rgba16 got = pack_detail::anaglyph_gamma16(am, l, r), want = reference(am, l, r);
      ASSERT_TRUE(got.r == want.r && got.g == want.g && got.b == want.b && got.a == want.a)
          << "l " << l.r << "," << l.g << "," << l.b << " r " << r.r << "," << r.g << "," << r.b << ": " << got.r
          << "," << got.g << "," << got.b << " want " << want.r << "," << want.g << "," << want.b;
    }
  }
}

// Every layout and anaglyph method of a pair widened from an 8-bit one
// gives the 8-bit output widened, within one level; reading back a pair
// packed in each arrangement too.
TEST(DeepPack, SameFunctionAsEightBit) {
  const int w = 24, h = 16;
  cv::Mat bgr8;
  test::deep_picture(2 * w, h, 11).convertTo(bgr8, CV_8UC3, 1.0 / 257.0);
  const HostFrame in8 = rgba8(bgr8), in16 = HostFrame::from_bgr(bgr8, PixelFormat::RGBA64);
  for (const auto &layout : test::kAllLayouts)
    for (const auto method : test::kAllMethods) {
      if (layout != PackLayout::Anaglyph && method != AnaglyphMethod::Dubois) continue;
      PackParams p;
      p.layout = layout;
      p.method = method;
      int ow = 0, oh = 0;
      pack_size(layout, w, h, &ow, &oh);
      HostFrame o8(PixelFormat::RGBA, ow, oh), o16(PixelFormat::RGBA64, ow, oh);
      pack_cpu(p, in8.view(), o8.view());
      pack_cpu(p, in16.view(), o16.view());
      EXPECT_LE(widened_gap(o16, o8), 257) << enum_nick(kPackLayoutNames, layout) << " " << static_cast<int>(method);
    }
  for (const auto &name : kStereoInputNames) {
    PackParams p;
    p.layout = PackLayout::SideBySide;
    p.input = name.value;
    int vw = 0, vh = 0;
    if (!input_view_size(name.value, 2 * w, h, &vw, &vh)) continue;
    HostFrame o8(PixelFormat::RGBA, 2 * vw, vh), o16(PixelFormat::RGBA64, 2 * vw, vh);
    pack_cpu(p, in8.view(), o8.view());
    pack_cpu(p, in16.view(), o16.view());
    EXPECT_LE(widened_gap(o16, o8), 257) << name.nick;
  }
}

// 4:2:0 output at 10 bits: its codes agree with the 8-bit output's codes
// (two low bits more), and the two 10-bit layouts hold the same codes.
TEST(DeepPack, TenBitYuvOutputAgreesWithEightBit) {
  const int w = 24, h = 16;
  cv::Mat bgr8;
  test::deep_picture(2 * w, h, 12).convertTo(bgr8, CV_8UC3, 1.0 / 257.0);
  const HostFrame in8 = rgba8(bgr8), in16 = HostFrame::from_bgr(bgr8, PixelFormat::RGBA64);
  for (const auto &layout : {PackLayout::SideBySideHalf, PackLayout::TopBottom, PackLayout::Checkerboard}) {
    PackParams p8, p10;
    p8.layout = p10.layout = layout;
    p8.yuv = rgb_to_yuv_params(0.2126, 0.0722, false, 8);
    p10.yuv = rgb_to_yuv_params(0.2126, 0.0722, false, 10);
    int ow = 0, oh = 0;
    pack_size(layout, w, h, &ow, &oh);
    HostFrame nv12(PixelFormat::NV12, ow, oh), p010(PixelFormat::P010, ow, oh), i010(PixelFormat::I420_10, ow, oh);
    pack_cpu(p8, in8.view(), nv12.view());
    pack_cpu(p10, in16.view(), p010.view());
    pack_cpu(p10, in16.view(), i010.view());
    EXPECT_THROW(pack_cpu(p8, in16.view(), p010.view()), std::invalid_argument) << "8-bit parameters, 10-bit frame";
    EXPECT_THROW(pack_cpu(p10, in8.view(), p010.view()), std::invalid_argument) << "8-bit pair, 10-bit frame";
    for (int y = 0; y < oh; ++y)
      for (int x = 0; x < ow; ++x) {
        ASSERT_LE(std::abs(load_code(p010.view(), 0, y, x) - 4 * load_code(nv12.view(), 0, y, x)), 4)
            << enum_nick(kPackLayoutNames, layout) << " Y at " << x << "," << y;
        ASSERT_EQ(load_code(p010.view(), 0, y, x), load_code(i010.view(), 0, y, x));
        int u8, v8, u10, v10, ui, vi;
        load_chroma(nv12.view(), x, y, &u8, &v8);
        load_chroma(p010.view(), x, y, &u10, &v10);
        load_chroma(i010.view(), x, y, &ui, &vi);
        ASSERT_LE(std::abs(u10 - 4 * u8), 4);
        ASSERT_LE(std::abs(v10 - 4 * v8), 4);
        ASSERT_TRUE(u10 == ui && v10 == vi);
      }
  }
}

// Letterbox bars of a deep frame: their rows count no bright pixel, the
// picture's rows do (the threshold at the frame's depth).
TEST(DeepFormats, BarsAreFoundAtEveryDepth) {
  cv::Mat pic = test::deep_picture(48, 40, 14);
  pic.rowRange(0, 8).setTo(cv::Scalar(0, 0, 0));
  pic.rowRange(32, 40).setTo(cv::Scalar(0, 0, 0));
  pic.rowRange(8, 32).setTo(cv::Scalar(30000, 30000, 30000));
  for (PixelFormat f : test::kDeepFormats) {
    const HostFrame frame = HostFrame::from_bgr16(pic, f);
    BarCounts counts;
    bar_counts_cpu(frame.view(), bar_luma_threshold(yuv_to_rgb_params(0.299, 0.114, false, 10)), &counts);
    for (int y = 0; y < 40; ++y)
      EXPECT_EQ(counts.rows[y], (y >= 8 && y < 32) ? 48u : 0u) << test::format_name(f) << " row " << y;
  }
}

int changed_tiles(const ChangeMap &m) {
  int n = 0;
  for (int ty = 0; ty < m.tiles_y(); ++ty)
    for (int tx = 0; tx < m.tiles_x(); ++tx) n += m.tile(tx, ty);
  return n;
}

// Every stored sample of tile (1, 1) moved by `units` (down where up
// would leave the 16 bits).
void shift_tile(HostFrame &frame, int units) {
  const FrameView v = frame.view();
  const PixelRect tile = tile_pixels(1, 1, v.width, v.height);
  for (int p = 0; p < frame_plane_count(v.format); ++p) {
    const PlaneBox box = plane_box(v.format, p, tile);
    for (int y = box.r0; y < box.r1; ++y) {
      uint8_t *row = v.plane[p] + static_cast<size_t>(y) * v.stride[p];
      for (int i = box.b0 / 2; i < box.b1 / 2; ++i) {
        const int s = load_u16(row, i);
        store_u16(row, i, s + units <= 65535 - 63 ? s + units : s - units);
      }
    }
  }
}

// A change in a sample's low bits alone is a change (exact comparison),
// and a tolerance counts 8-bit levels at every depth: a tile moved by 3/4
// of a level is over a tolerance of 1/2, one moved by 1/4 under it.
TEST(DeepFormats, ChangeMapSeesTheLowBits) {
  for (PixelFormat f : test::kDeepFormats) {
    const HostFrame a = HostFrame::from_bgr16(test::deep_picture(64, 64, 13), f);
    HostFrame b = a;
    // The lowest bit of the code of one sample of tile (1, 1).
    const int low = f == PixelFormat::P010 ? 1 << 6 : 1;
    uint8_t *p = b.view().plane[0] + 40 * b.view().stride[0] + 2 * (f == PixelFormat::RGBA64 ? 4 * 40 : 40);
    store_u16(p, 0, load_u16(p, 0) ^ low);
    FrameHistory history;
    history.compare(a.view(), 0.f);
    EXPECT_EQ(changed_tiles(history.compare(b.view(), 0.f)), 1) << test::format_name(f);
    const int level = units_per_level(f);
    for (const int quarters : {3, 1}) {
      HostFrame c = a;
      shift_tile(c, quarters * level / 4);
      FrameHistory tolerant;
      tolerant.compare(a.view(), 0.5f);
      EXPECT_EQ(changed_tiles(tolerant.compare(c.view(), 0.5f)), quarters == 3 ? 1 : 0)
          << test::format_name(f) << ", " << quarters << "/4 of a level";
    }
  }
}

}  // namespace
}  // namespace p3d
