// Colour conversion parameters, packed-format swizzles, luma and plane
// geometry (common/frame.h, common/colour.cpp).
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "frame.h"
#include "host_frame.h"
#include "row_convert.h"
#include "test_data.h"

namespace p3d {
namespace {

// A 2x2 4:2:0 frame of one Y'CbCr value, read back through load_rgba.
Rgba yuv_pixel(PixelFormat f, uint8_t y, uint8_t u, uint8_t v, const YuvToRgb &m) {
  HostFrame h(f, 2, 2, 3);
  const FrameView fv = h.view();
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) fv.plane[0][r * fv.stride[0] + c] = y;
  if (f == PixelFormat::NV12) {
    fv.plane[1][0] = u;
    fv.plane[1][1] = v;
  } else {
    fv.plane[1][0] = u;
    fv.plane[2][0] = v;
  }
  return load_rgba(fv, 1, 1, m);
}

void expect_rgb_near(Rgba c, int r, int g, int b, int tol, const char *what) {
  EXPECT_NEAR(c.r, r, tol) << what;
  EXPECT_NEAR(c.g, g, tol) << what;
  EXPECT_NEAR(c.b, b, tol) << what;
}

TEST(ColourParams, Bt601Coefficients) {
  const YuvToRgb m = yuv_to_rgb_params(0.299, 0.114, false);
  EXPECT_NEAR(m.rv, 1.402f, 1e-6);
  EXPECT_NEAR(m.gu, -0.344136f, 1e-6);
  EXPECT_NEAR(m.gv, -0.714136f, 1e-6);
  EXPECT_NEAR(m.bu, 1.772f, 1e-6);
  EXPECT_EQ(m.y_offset, 16.f);
  EXPECT_NEAR(m.y_scale, 255.0 / 219.0, 1e-6);
  EXPECT_NEAR(m.c_scale, 255.0 / 224.0, 1e-6);
  // The defaults of YuvToRgb are BT.601 limited range.
  const YuvToRgb d;
  EXPECT_NEAR(d.rv, m.rv, 1e-6);
  EXPECT_NEAR(d.gu, m.gu, 1e-6);
  EXPECT_NEAR(d.gv, m.gv, 1e-6);
  EXPECT_NEAR(d.bu, m.bu, 1e-6);
}

TEST(ColourParams, Bt709Coefficients) {
  const YuvToRgb m = yuv_to_rgb_params(0.2126, 0.0722, false);
  EXPECT_NEAR(m.rv, 1.5748f, 1e-5);
  EXPECT_NEAR(m.gu, -0.187324f, 1e-5);
  EXPECT_NEAR(m.gv, -0.468124f, 1e-5);
  EXPECT_NEAR(m.bu, 1.8556f, 1e-5);
  const YuvToRgb full = yuv_to_rgb_params(0.2126, 0.0722, true);
  EXPECT_EQ(full.y_offset, 0.f);
  EXPECT_EQ(full.y_scale, 1.f);
  EXPECT_EQ(full.c_scale, 1.f);
  EXPECT_EQ(full.rv, m.rv);
}

TEST(ColourParams, LimitedRangeWhiteAndBlack) {
  for (auto kr_kb : {std::pair{0.299, 0.114}, std::pair{0.2126, 0.0722}}) {
    const YuvToRgb m = yuv_to_rgb_params(kr_kb.first, kr_kb.second, false);
    for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420}) {
      const Rgba white = yuv_pixel(f, 235, 128, 128, m);
      EXPECT_EQ(white.r, 255);
      EXPECT_EQ(white.g, 255);
      EXPECT_EQ(white.b, 255);
      EXPECT_EQ(white.a, 255);
      const Rgba black = yuv_pixel(f, 16, 128, 128, m);
      EXPECT_EQ(black.r, 0);
      EXPECT_EQ(black.g, 0);
      EXPECT_EQ(black.b, 0);
      // Below black / above white saturates instead of wrapping.
      EXPECT_EQ(yuv_pixel(f, 0, 128, 128, m).r, 0);
      EXPECT_EQ(yuv_pixel(f, 255, 128, 128, m).g, 255);
      // Mid grey: (126 - 16) * 255/219 = 128.08.
      EXPECT_EQ(yuv_pixel(f, 126, 128, 128, m).b, 128);
    }
  }
}

TEST(ColourParams, FullRangeWhiteBlackGrey) {
  const YuvToRgb m = yuv_to_rgb_params(0.2126, 0.0722, true);
  const Rgba white = yuv_pixel(PixelFormat::NV12, 255, 128, 128, m);
  EXPECT_EQ(white.r + white.g + white.b, 3 * 255);
  const Rgba black = yuv_pixel(PixelFormat::I420, 0, 128, 128, m);
  EXPECT_EQ(black.r + black.g + black.b, 0);
  const Rgba grey = yuv_pixel(PixelFormat::NV12, 77, 128, 128, m);
  EXPECT_EQ(grey.r, 77);
  EXPECT_EQ(grey.g, 77);
  EXPECT_EQ(grey.b, 77);
}

TEST(ColourParams, KnownPrimaries) {
  // Limited-range codes of the primaries (Rec. 601 / Rec. 709 tables);
  // 8-bit codes are rounded, so the decoded value may be 2 levels off.
  const YuvToRgb m601 = yuv_to_rgb_params(0.299, 0.114, false);
  expect_rgb_near(yuv_pixel(PixelFormat::NV12, 81, 90, 240, m601), 255, 0, 0, 2, "601 red");
  expect_rgb_near(yuv_pixel(PixelFormat::NV12, 145, 54, 34, m601), 0, 255, 0, 2, "601 green");
  expect_rgb_near(yuv_pixel(PixelFormat::I420, 41, 240, 110, m601), 0, 0, 255, 2, "601 blue");
  const YuvToRgb m709 = yuv_to_rgb_params(0.2126, 0.0722, false);
  expect_rgb_near(yuv_pixel(PixelFormat::NV12, 63, 102, 240, m709), 255, 0, 0, 2, "709 red");
  expect_rgb_near(yuv_pixel(PixelFormat::NV12, 173, 42, 26, m709), 0, 255, 0, 2, "709 green");
  expect_rgb_near(yuv_pixel(PixelFormat::I420, 32, 240, 118, m709), 0, 0, 255, 2, "709 blue");
}

TEST(ColourRoundTrip, PrimariesThroughYuvFrames) {
  // from_bgr (OpenCV, BT.601 limited) then load_rgba with the default
  // parameters: 8-bit quantisation twice, so up to 3 levels.
  const cv::Vec3b colours[] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}, {255, 255, 255},
                               {0, 0, 0},   {40, 90, 200}, {128, 128, 128}};
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420}) {
    for (const cv::Vec3b &bgr : colours) {
      const cv::Mat img(5, 3, CV_8UC3, cv::Scalar(bgr[0], bgr[1], bgr[2]));  // odd size: edge chroma
      const cv::Mat back = HostFrame::from_bgr(img, f, 3).to_bgra();
      for (int y = 0; y < back.rows; ++y)
        for (int x = 0; x < back.cols; ++x) {
          const cv::Vec4b p = back.at<cv::Vec4b>(y, x);
          for (int c = 0; c < 3; ++c) ASSERT_NEAR(p[c], bgr[c], 3) << test::format_name(f) << " " << bgr;
          ASSERT_EQ(p[3], 255);
        }
    }
  }
}

TEST(ColourSwizzle, LoadRgbaOfEveryPackedFormat) {
  struct Expect {
    PixelFormat f;
    uint8_t r, g, b, a;
  };
  // Memory bytes 10, 20, 30, 40 at the pixel.
  const Expect cases[] = {{PixelFormat::RGBA, 10, 20, 30, 40},
                          {PixelFormat::BGRA, 30, 20, 10, 40},
                          {PixelFormat::RGBx, 10, 20, 30, 255},
                          {PixelFormat::BGRx, 30, 20, 10, 255}};
  for (const Expect &e : cases) {
    HostFrame h(e.f, 3, 2, 6);
    const FrameView v = h.view();
    uint8_t *p = v.plane[0] + v.stride[0] + 4 * 2;  // pixel (2, 1): stride matters
    p[0] = 10, p[1] = 20, p[2] = 30, p[3] = 40;
    const Rgba c = load_rgba(v, 2, 1, YuvToRgb());
    EXPECT_EQ(c.r, e.r) << test::format_name(e.f);
    EXPECT_EQ(c.g, e.g) << test::format_name(e.f);
    EXPECT_EQ(c.b, e.b) << test::format_name(e.f);
    EXPECT_EQ(c.a, e.a) << test::format_name(e.f);
  }
}

TEST(ColourSwizzle, StoreRgbaOfEveryPackedFormat) {
  for (PixelFormat f : test::kPackedFormats) {
    HostFrame h(f, 3, 2, 6);
    h.fill(0);
    const FrameView v = h.view();
    store_rgba(v, 1, 1, Rgba{11, 22, 33, 44});
    const uint8_t *p = v.plane[0] + v.stride[0] + 4;
    const bool bgr = f == PixelFormat::BGRA || f == PixelFormat::BGRx;
    EXPECT_EQ(p[0], bgr ? 33 : 11) << test::format_name(f);
    EXPECT_EQ(p[1], 22) << test::format_name(f);
    EXPECT_EQ(p[2], bgr ? 11 : 33) << test::format_name(f);
    // Neighbours untouched.
    EXPECT_EQ(p[-1], 0);
    EXPECT_EQ(p[4], 0);
    EXPECT_EQ(v.plane[0][4], 0);
    const Rgba c = load_rgba(v, 1, 1, YuvToRgb());
    EXPECT_EQ(c.r, 11);
    EXPECT_EQ(c.g, 22);
    EXPECT_EQ(c.b, 33);
    EXPECT_EQ(c.a, is_packed_rgb(f) && (f == PixelFormat::RGBA || f == PixelFormat::BGRA) ? 44 : 255);
  }
}

// swap_rb_word(rgba_word(c)) is the word store_rgba() writes for the BGR
// orders (the warp's row writers store words so), for every byte value in
// every position.
TEST(ColourSwizzle, SwapRbWordIsTheBgrStore) {
  HostFrame h(PixelFormat::BGRA, 1, 1);
  for (int v = 0; v < 256; ++v) {
    const uint8_t b = static_cast<uint8_t>(v);
    for (const Rgba c : {Rgba{b, 1, 2, 3}, Rgba{1, b, 2, 3}, Rgba{1, 2, b, 3}, Rgba{1, 2, 3, b}}) {
      store_rgba(h.view(), 0, 0, c);
      uint32_t stored;
      std::memcpy(&stored, h.view().plane[0], 4);
      ASSERT_EQ(swap_rb_word(rgba_word(c)), stored) << v;
    }
  }
}

TEST(ColourSwizzle, StoreIsNoOpOnYuv) {
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420}) {
    HostFrame h(f, 4, 4, 2);
    h.fill(7);
    store_rgba(h.view(), 1, 1, Rgba{1, 2, 3, 4});
    const cv::Mat back = h.to_bgra(yuv_to_rgb_params(0.299, 0.114, true));
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) ASSERT_EQ(back.at<cv::Vec4b>(y, x), back.at<cv::Vec4b>(0, 0));
  }
}

TEST(ColourLuma, YuvIsThePlaneAndRgbIsBt601) {
  HostFrame nv(PixelFormat::NV12, 3, 3, 1);
  nv.fill(99);
  nv.view().plane[0][nv.view().stride[0] * 2 + 1] = 201;
  EXPECT_EQ(load_luma(nv.view(), 1, 2), 201);
  EXPECT_EQ(load_luma(nv.view(), 0, 0), 99);
  struct Case {
    uint8_t r, g, b, y;
  };
  // 0.299 R + 0.587 G + 0.114 B, rounded.
  const Case cases[] = {{255, 0, 0, 76}, {0, 255, 0, 150}, {0, 0, 255, 29}, {255, 255, 255, 255},
                        {0, 0, 0, 0},    {100, 150, 200, 141}};
  for (PixelFormat f : test::kPackedFormats)
    for (const Case &c : cases) {
      HostFrame h(f, 2, 1, 0);
      store_rgba(h.view(), 1, 0, Rgba{c.r, c.g, c.b, 255});
      EXPECT_EQ(load_luma(h.view(), 1, 0), c.y) << test::format_name(f) << " " << int(c.r) << "," << int(c.g)
                                                 << "," << int(c.b);
    }
}

TEST(ColourChroma, OneChromaSampleServesA2x2Block) {
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420}) {
    HostFrame h(f, 5, 3, 2);  // odd: the last column/row has a chroma sample of its own
    h.fill_random(4);
    const FrameView v = h.view();
    int a[3], b[3];
    load_native3(v, 2, 0, a);
    load_native3(v, 3, 1, b);
    EXPECT_EQ(a[1], b[1]);
    EXPECT_EQ(a[2], b[2]);
    load_native3(v, 4, 2, a);
    const int cu = f == PixelFormat::NV12 ? v.plane[1][v.stride[1] + 4] : v.plane[1][v.stride[1] + 2];
    EXPECT_EQ(a[1], cu);
    EXPECT_EQ(a[0], v.plane[0][2 * v.stride[0] + 4]);
  }
}

// load_rgba() of Y'CbCr goes through chroma_terms() and yuv_rgba(), which a
// 4:2:0 pixel pair shares: the result must be the float formula of
// YuvToRgb's comment, evaluated as written (left to right, no fused
// multiply-add), for every Y' and a grid of Cb/Cr under every matrix.
TEST(ColourYuv, LoadRgbaIsTheWrittenFormula) {
  const YuvToRgb matrices[] = {YuvToRgb(), yuv_to_rgb_params(0.2126, 0.0722, false),
                               yuv_to_rgb_params(0.299, 0.114, true), yuv_to_rgb_params(0.2627, 0.0593, true)};
  HostFrame h(PixelFormat::I420, 2, 2, 0);
  const FrameView v = h.view();
  int mismatches = 0;
  for (const YuvToRgb &m : matrices)
    for (int y = 0; y < 256; ++y)
      for (int u = 0; u < 256; u += 3)
        for (int w = 0; w < 256; w += 5) {
          v.plane[0][0] = static_cast<uint8_t>(y);
          v.plane[1][0] = static_cast<uint8_t>(u);
          v.plane[2][0] = static_cast<uint8_t>(w);
          const float yn = (static_cast<float>(y) - m.y_offset) * m.y_scale;
          const float cb = (static_cast<float>(u) - 128.f) * m.c_scale;
          const float cr = (static_cast<float>(w) - 128.f) * m.c_scale;
          const Rgba want{to_u8(yn + m.rv * cr), to_u8(yn + m.gu * cb + m.gv * cr), to_u8(yn + m.bu * cb), 255};
          const Rgba got = load_rgba(v, 0, 0, m);
          if (rgba_word(got) != rgba_word(want) && ++mismatches <= 5)
            ADD_FAILURE() << "Y'CbCr " << y << "," << u << "," << w << ": got " << int(got.r) << "," << int(got.g)
                          << "," << int(got.b) << " want " << int(want.r) << "," << int(want.g) << ","
                          << int(want.b);
        }
  EXPECT_EQ(mismatches, 0);
}

// The warp converts its source rows a pixel pair at a time
// (load_rgba_pair_words): the same words as load_rgba() pixel by pixel, for
// every format, odd widths (the last pixel alone) and padded rows.
TEST(ColourChroma, PairWordsAreLoadRgbaWords) {
  const YuvToRgb m = yuv_to_rgb_params(0.2126, 0.0722, false);
  for (PixelFormat f : test::kAllFormats)
    for (int width : {1, 2, 7, 64}) {
      HostFrame h(f, width, 3, 3);
      h.fill_random(static_cast<uint32_t>(width) * 7 + static_cast<uint32_t>(f));
      const FrameView v = h.view();
      for (int y = 0; y < 3; ++y) {
        std::vector<uint32_t> words(static_cast<size_t>(width) + 1, 0xdeadbeefu);
        for (int x = 0; x < width; x += 2) load_rgba_pair_words(v, x, y, m, words.data() + x);
        for (int x = 0; x < width; ++x)
          ASSERT_EQ(words[x], rgba_word(load_rgba(v, x, y, m)))
              << test::format_name(f) << " width " << width << " pixel " << x << "," << y;
        EXPECT_EQ(words[width], 0xdeadbeefu) << "wrote past the row: " << test::format_name(f) << " " << width;
      }
    }
}

// rgba_words_of_row() converts 8-bit 4:2:0 rows several pixels at a time
// (vector code); its words must be load_rgba()'s, bit for bit, for every
// format, every width from 1 to 70 (all remainders of the vector width),
// on random samples and on the extreme codes that clamp, with the
// parameters of BT.601 and BT.709 in both ranges and of the default.
TEST(ColourChroma, RowWordsAreLoadRgbaWords) {
  const YuvToRgb params[] = {YuvToRgb(), yuv_to_rgb_params(0.299, 0.114, false), yuv_to_rgb_params(0.299, 0.114, true),
                             yuv_to_rgb_params(0.2126, 0.0722, false), yuv_to_rgb_params(0.2126, 0.0722, true)};
  for (const YuvToRgb &m : params)
    for (PixelFormat f : test::kAllFormats) {
      if (!params_fit(f, m)) continue;
      for (int width = 1; width <= 70; ++width) {
        HostFrame h(f, width, 4, 3);
        h.fill_random(static_cast<uint32_t>(width) * 11 + static_cast<uint32_t>(f));
        const FrameView v = h.view();
        if (width % 3 == 0)  // extremes: black and white luma under the strongest chroma
          for (int p = 0; p < 3 && v.plane[p]; ++p)
            for (int y = 0; y < (p ? 2 : 4); ++y)
              for (int i = 0; i < v.stride[p]; ++i) v.plane[p][static_cast<size_t>(y) * v.stride[p] + i] = (i + y) % 2 ? 255 : 0;
        for (int y = 0; y < 4; ++y) {
          std::vector<uint32_t> words(static_cast<size_t>(width) + 1, 0xdeadbeefu);
          rgba_words_of_row(v, y, m, words.data());
          for (int x = 0; x < width; ++x)
            ASSERT_EQ(words[x], rgba_word(load_rgba(v, x, y, m)))
                << test::format_name(f) << " width " << width << " pixel " << x << "," << y;
          ASSERT_EQ(words[width], 0xdeadbeefu) << "wrote past the row: " << test::format_name(f) << " " << width;
        }
      }
    }
}

// The same on every 8-bit code: a 4096 x 4096 frame whose 2 x 2 blocks
// hold each Cb/Cr pair under every luma code once (64 blocks of four
// codes a pair), so every input the vector rows can meet is compared.
TEST(ColourChroma, RowWordsOfEveryCodeAreLoadRgbaWords) {
  const int side = 4096;
  const struct {
    PixelFormat format;
    YuvToRgb m;
  } cases[] = {{PixelFormat::NV12, YuvToRgb()},
               {PixelFormat::NV12, yuv_to_rgb_params(0.2126, 0.0722, true)},
               {PixelFormat::I420, yuv_to_rgb_params(0.2126, 0.0722, false)}};
  for (const auto &c : cases) {
    HostFrame h(c.format, side, side);
    const FrameView v = h.view();
    for (int by = 0; by < side / 2; ++by)
      for (int bx = 0; bx < side / 2; ++bx) {
        const int block = by * (side / 2) + bx, pair = block / 64, group = block % 64;
        for (int k = 0; k < 4; ++k)
          v.plane[0][static_cast<size_t>(2 * by + k / 2) * v.stride[0] + 2 * bx + k % 2] = static_cast<uint8_t>(4 * group + k);
        uint8_t *chroma = v.plane[1] + static_cast<size_t>(by) * v.stride[1];
        if (c.format == PixelFormat::NV12) {
          chroma[2 * bx] = static_cast<uint8_t>(pair & 255);
          chroma[2 * bx + 1] = static_cast<uint8_t>(pair >> 8);
        } else {
          chroma[bx] = static_cast<uint8_t>(pair & 255);
          v.plane[2][static_cast<size_t>(by) * v.stride[2] + bx] = static_cast<uint8_t>(pair >> 8);
        }
      }
    std::vector<uint32_t> words(side);
    long long mismatches = 0;
    for (int y = 0; y < side; ++y) {
      rgba_words_of_row(v, y, c.m, words.data());
      for (int x = 0; x < side; ++x) mismatches += words[x] != rgba_word(load_rgba(v, x, y, c.m));
    }
    EXPECT_EQ(mismatches, 0) << test::format_name(c.format);
  }
}

TEST(ColourPlanes, PlaneSizesOfOddFrames) {
  int bpr = 0, rows = 0;
  EXPECT_EQ(frame_plane_count(PixelFormat::NV12), 2);
  EXPECT_EQ(frame_plane_count(PixelFormat::I420), 3);
  for (PixelFormat f : test::kPackedFormats) {
    EXPECT_EQ(frame_plane_count(f), 1);
    frame_plane_size(f, 5, 3, 0, &bpr, &rows);
    EXPECT_EQ(bpr, 20);
    EXPECT_EQ(rows, 3);
  }
  frame_plane_size(PixelFormat::NV12, 5, 3, 0, &bpr, &rows);
  EXPECT_EQ(bpr, 5);
  EXPECT_EQ(rows, 3);
  frame_plane_size(PixelFormat::NV12, 5, 3, 1, &bpr, &rows);
  EXPECT_EQ(bpr, 6);  // 3 interleaved U,V pairs
  EXPECT_EQ(rows, 2);
  for (int plane : {1, 2}) {
    frame_plane_size(PixelFormat::I420, 5, 3, plane, &bpr, &rows);
    EXPECT_EQ(bpr, 3);
    EXPECT_EQ(rows, 2);
  }
  frame_plane_size(PixelFormat::NV12, 1, 1, 1, &bpr, &rows);
  EXPECT_EQ(bpr, 2);
  EXPECT_EQ(rows, 1);
  frame_plane_size(PixelFormat::I420, 1, 1, 2, &bpr, &rows);
  EXPECT_EQ(bpr, 1);
  EXPECT_EQ(rows, 1);
  frame_plane_size(PixelFormat::I420, 4, 2, 1, &bpr, &rows);
  EXPECT_EQ(bpr, 2);
  EXPECT_EQ(rows, 1);
}

}  // namespace
}  // namespace p3d
