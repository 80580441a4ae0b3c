// Letterbox and pillarbox bars (common/bars.h). What the tests prove:
//  * bar_counts_cpu counts, per row and per column, exactly the pixels
//    over the bar level: the brightest R'G'B' byte on packed RGB, Y' over
//    bar_luma_threshold() on 4:2:0 (limited and full range), chroma never;
//    on 8-bit Y' for rows wider than its 16-bit chunks and thresholds
//    past either end of a byte.
//  * measure_active_rect finds a letterbox, a pillarbox and both, the
//    top left corner moved onto kBarAlign cells; a few noisy pixels in a bar (up to a
//    1/64 share of a row) do not count as picture; a black frame gives
//    an empty rect.
//  * BarTracker: the whole picture until a measure is adopted; the first
//    plausible measure at once; a new one only after kBarConfirmFrames
//    frames in a row, an interruption restarting the count; a fade to
//    black, a subtitle in one bar (asymmetric), and a picture smaller
//    than half the frame keep the rect; a scene cut adopts at once; a
//    reset or a new size starts over. In the stages' order each frame is
//    decided from the counts of the frames before it (a cut moves the
//    rect at the next frame), the first after a reset from its own.
//  * The warp inside an active rect (warp_pack_changed_cpu with an
//    ActiveArea): outside the rect both views are the source converted,
//    inside them the views are those warp_render_cpu gives for the
//    cropped picture with active_warp_params() (the parallax of the
//    whole width), for a letterbox (rendered into the pair's rows) and a
//    pillarbox (rendered apart and placed), every fill; the pack then
//    packs that pair. The adaptive warp with a rect is in
//    test_adaptive.cpp.
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "adaptive.h"
#include "bars.h"
#include "host_frame.h"
#include "test_data.h"

namespace p3d {
namespace {

// A frame of `format` whose pixels are black except in `picture`, where
// they are random bright colours; `noise` dark-but-over-level pixels are
// scattered in the bars.
HostFrame letterboxed(PixelFormat format, int w, int h, PixelRect picture, int noise, uint32_t seed) {
  std::mt19937 rng(seed);
  cv::Mat bgr(h, w, CV_8UC3, cv::Scalar(0, 0, 0));
  for (int y = picture.y0; y < picture.y1; ++y)
    for (int x = picture.x0; x < picture.x1; ++x)
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(80 + rng() % 170, 80 + rng() % 170, 80 + rng() % 170);
  for (int k = 0; k < noise; ++k) {
    const int x = rng() % w, y = rng() % h;
    if (y >= picture.y0 && y < picture.y1 && x >= picture.x0 && x < picture.x1) continue;
    bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(200, 200, 200);
  }
  return HostFrame::from_bgr(bgr, format, 3);
}

BarCounts counts_of(const HostFrame &f) {
  BarCounts c;
  bar_counts_cpu(f.view(), bar_luma_threshold(YuvToRgb()), &c);
  return c;
}

TEST(BarCounts, CountThePixelsOverTheBarLevel) {
  for (const PixelFormat format : test::kAllFormats) {
    SCOPED_TRACE(test::format_name(format));
    HostFrame f(format, 37, 23, 5);
    f.fill_random(7);
    const FrameView v = f.view();
    for (const bool full_range : {false, true}) {
      const YuvToRgb m = yuv_to_rgb_params(0.2126, 0.0722, full_range);
      const int threshold = bar_luma_threshold(m);
      BarCounts c;
      bar_counts_cpu(v, threshold, &c);
      ASSERT_EQ(c.rows.size(), 23u);
      ASSERT_EQ(c.cols.size(), 37u);
      std::vector<uint32_t> rows(23, 0), cols(37, 0);
      for (int y = 0; y < 23; ++y)
        for (int x = 0; x < 37; ++x) {
          bool bright;
          if (is_packed_rgb(format)) {
            const uint8_t *p = v.plane[0] + y * v.stride[0] + 4 * x;
            bright = std::max({p[0], p[1], p[2]}) > kBarLevel;  // byte 3 is alpha or padding
          } else {
            bright = v.plane[0][y * v.stride[0] + x] > threshold;
          }
          rows[y] += bright;
          cols[x] += bright;
        }
      EXPECT_EQ(c.rows, rows) << "full range " << full_range;
      EXPECT_EQ(c.cols, cols) << "full range " << full_range;
    }
  }
}

// 8-bit Y' is counted a band at a time in bytes and 16-bit chunks: the
// counts are still bar_pixel_bright()'s, for rows wider than a chunk (4096
// pixels) and of odd width, bands cut short by the frame's last row, and
// thresholds at and past the ends of the byte (nothing or everything
// bright).
TEST(BarCounts, WideLumaRowsCountEveryThreshold) {
  for (const PixelFormat format : {PixelFormat::I420, PixelFormat::NV12}) {
    SCOPED_TRACE(test::format_name(format));
    for (const int w : {4097, kMaxFrameSide - 1}) {
      const int h = 67;
      HostFrame f(format, w, h, 3);
      f.fill_random(static_cast<uint32_t>(w));
      const FrameView v = f.view();
      for (const int threshold : {-5, -1, 0, 1, 36, 127, 254, 255, 256, 1000}) {
        BarCounts c;
        bar_counts_cpu(v, threshold, &c);
        std::vector<uint32_t> rows(h, 0), cols(w, 0);
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x) {
            const bool bright = bar_pixel_bright(v, x, y, threshold);
            rows[y] += bright;
            cols[x] += bright;
          }
        EXPECT_EQ(c.rows, rows) << "width " << w << ", threshold " << threshold;
        EXPECT_EQ(c.cols, cols) << "width " << w << ", threshold " << threshold;
      }
    }
  }
}

// Counting again only the bands with a changed tile, from the counts of
// the frame before, gives the counts of the whole frame: random tiles of a
// letterboxed frame turned black or bright, frame after frame, and a frame
// of another size (counted whole).
TEST(BarCounts, ChangedBandsGiveTheWholeFramesCounts) {
  const uint32_t seed = std::random_device{}();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  for (const PixelFormat format : {PixelFormat::I420, PixelFormat::NV12, PixelFormat::BGRA}) {
    SCOPED_TRACE(test::format_name(format));
    const int w = 150, h = 101;
    HostFrame f = letterboxed(format, w, h, PixelRect{0, 14, w, 87}, 40, rng());
    const int threshold = bar_luma_threshold(YuvToRgb());
    BarCounts kept;
    bar_counts_cpu(f.view(), threshold, &kept);
    for (int step = 0; step < 12; ++step) {
      HostFrame next = letterboxed(format, w, h, PixelRect{0, 14, w, 87}, 40, rng());
      ChangeMap changes(w, h, false);
      const FrameView from = next.view(), to = f.view();
      for (int k = 0; k < 3; ++k) {  // a few tiles of the new frame into the old one
        const int tx = rng() % changes.tiles_x(), ty = rng() % changes.tiles_y();
        const PixelRect r = tile_pixels(tx, ty, w, h);
        for (int p = 0; p < frame_plane_count(format); ++p) {
          const PlaneBox b = plane_box(format, p, r);
          for (int y = b.r0; y < b.r1; ++y)
            std::memcpy(to.plane[p] + y * to.stride[p] + b.b0, from.plane[p] + y * from.stride[p] + b.b0, b.b1 - b.b0);
        }
        changes.mark(tx, ty);
      }
      bar_counts_cpu(f.view(), threshold, &kept, &changes);
      const BarCounts whole = counts_of(f);
      ASSERT_EQ(kept.rows, whole.rows) << "step " << step;
      ASSERT_EQ(kept.cols, whole.cols) << "step " << step;
    }
    HostFrame other = letterboxed(format, w + 10, h, PixelRect{0, 14, w + 10, 87}, 40, rng());
    const ChangeMap none(w + 10, h, false);
    bar_counts_cpu(other.view(), threshold, &kept, &none);  // other sizes: counted whole
    EXPECT_EQ(kept.cols, counts_of(other).cols);
  }
}

// A Y' value is over the threshold exactly when it converts to R'G'B'
// levels over kBarLevel.
TEST(BarCounts, TheLumaThresholdIsTheBarLevelInYLevels) {
  for (const bool full_range : {false, true}) {
    const YuvToRgb m = yuv_to_rgb_params(0.2126, 0.0722, full_range);
    const int threshold = bar_luma_threshold(m);
    for (int luma = 0; luma < 256; ++luma)
      EXPECT_EQ(luma > threshold, (static_cast<float>(luma) - m.y_offset) * m.y_scale > kBarLevel)
          << "Y' " << luma << " full range " << full_range;
  }
}

TEST(MeasureActiveRect, FindsLetterboxPillarboxAndBoth) {
  struct Case {
    PixelRect picture, want;
  } cases[] = {
      {{0, 40, 320, 200}, {0, 40, 320, 200}},    // letterbox on cells
      {{0, 43, 320, 197}, {0, 40, 320, 197}},    // the corner onto cells
      {{40, 0, 280, 240}, {40, 0, 280, 240}},    // pillarbox
      {{36, 30, 284, 210}, {32, 24, 284, 210}},  // both
      {{0, 0, 320, 240}, {0, 0, 320, 240}},      // no bars
  };
  for (const Case &c : cases)
    for (const PixelFormat format : {PixelFormat::I420, PixelFormat::BGRx}) {
      const PixelRect m = measure_active_rect(counts_of(letterboxed(format, 320, 240, c.picture, 0, 1)));
      EXPECT_EQ(m, c.want) << test::format_name(format) << " picture " << c.picture.x0 << "," << c.picture.y0 << " "
                           << c.picture.x1 << "," << c.picture.y1 << " got " << m.x0 << "," << m.y0 << " " << m.x1
                           << "," << m.y1;
    }
}

TEST(MeasureActiveRect, NoisyBarsStayBarsAndBlackIsEmpty) {
  // 320 x 240: a row allows 5 bright pixels, a column 3; 60 noise pixels
  // over 320 x 80 bar pixels leave every row and column under that
  // (checked), and the rect stays the picture's.
  const PixelRect picture{0, 40, 320, 200};
  const HostFrame f = letterboxed(PixelFormat::NV12, 320, 240, picture, 60, 2);
  const BarCounts c = counts_of(f);
  uint32_t worst_bar_row = 0;
  for (int y = 0; y < 40; ++y) worst_bar_row = std::max(worst_bar_row, c.rows[y]);
  ASSERT_GT(worst_bar_row, 0u) << "the noise must be in the bars";
  ASSERT_LE(worst_bar_row, 5u);
  EXPECT_EQ(measure_active_rect(c), picture);
  EXPECT_TRUE(measure_active_rect(counts_of(letterboxed(PixelFormat::RGBA, 64, 48, PixelRect{}, 0, 3))).empty());
}

// Counts of a letterbox frame with the picture in `picture` (a fresh
// random picture each call: frames of a film).
BarCounts film_frame(PixelRect picture, uint32_t seed) {
  return counts_of(letterboxed(PixelFormat::I420, 320, 240, picture, 0, seed));
}

TEST(BarTracker, AdoptsAtOnceThenOnlyAfterConfirmation) {
  // wide to wider moves 16 rows of 320 pixels: under the cut share.
  const PixelRect whole{0, 0, 320, 240}, wide{0, 40, 320, 200}, wider{0, 48, 320, 192};
  BarTracker t;
  EXPECT_EQ(t.active(320, 240), whole) << "nothing seen";
  t.observe(film_frame(wide, 1));
  EXPECT_EQ(t.active(320, 240), wide) << "the first plausible measure";
  // The same picture, slightly different frames: no cut, and the new bars
  // are adopted after kBarConfirmFrames frames only.
  for (int k = 1; k < kBarConfirmFrames; ++k) {
    t.observe(film_frame(wider, 10 + k));
    EXPECT_EQ(t.active(320, 240), wide) << "frame " << k;
  }
  t.observe(film_frame(wider, 30));
  EXPECT_EQ(t.active(320, 240), wider);
  // An interruption (one frame of the old bars) restarts the count.
  for (int k = 1; k < kBarConfirmFrames; ++k) t.observe(film_frame(wide, 40 + k));
  t.observe(film_frame(wider, 60));
  for (int k = 1; k < kBarConfirmFrames; ++k) t.observe(film_frame(wide, 70 + k));
  EXPECT_EQ(t.active(320, 240), wider);
  t.observe(film_frame(wide, 90));
  EXPECT_EQ(t.active(320, 240), wide);
  t.reset();
  EXPECT_EQ(t.active(320, 240), whole);
  t.observe(film_frame(wider, 91));
  EXPECT_EQ(t.active(640, 480), (PixelRect{0, 0, 640, 480})) << "another size";
}

TEST(BarTracker, FadesSubtitlesAndDarkScenesKeepTheRect) {
  const PixelRect wide{0, 40, 320, 200};
  BarTracker t;
  t.observe(film_frame(wide, 1));
  ASSERT_EQ(t.active(320, 240), wide);
  // A fade to black: the picture's top and bottom go dark first (the
  // measure shrinks frame by frame), then all of it, for many frames.
  for (int k = 0; k < 20; ++k) t.observe(film_frame(PixelRect{0, 40 + 4 * k, 320, 200 - 4 * k}, 100 + k));
  for (int k = 0; k < 3 * kBarConfirmFrames; ++k) t.observe(film_frame(PixelRect{}, 200 + k));
  EXPECT_EQ(t.active(320, 240), wide) << "the fade";
  // A subtitle in the bottom bar for many frames: asymmetric.
  for (int k = 0; k < 3 * kBarConfirmFrames; ++k) {
    BarCounts c = film_frame(wide, 300 + k);
    for (int y = 210; y < 224; ++y) c.rows[y] = 120;
    for (int x = 60; x < 260; ++x) c.cols[x] += 14;
    t.observe(c);
  }
  EXPECT_EQ(t.active(320, 240), wide) << "the subtitle";
  // A dark scene whose lit part is small: less than half the frame.
  for (int k = 0; k < 3 * kBarConfirmFrames; ++k) t.observe(film_frame(PixelRect{80, 80, 240, 160}, 400 + k));
  EXPECT_EQ(t.active(320, 240), wide) << "the small picture";
}

TEST(BarTracker, ASceneCutAdoptsAtOnce) {
  const PixelRect wide{0, 40, 320, 200}, whole{0, 0, 320, 240};
  BarTracker t;
  for (int k = 0; k < 4; ++k) t.observe(film_frame(wide, 1 + k));
  ASSERT_EQ(t.active(320, 240), wide);
  // Full-frame picture after the letterbox: the bars' rows turn bright,
  // an eighth of the frame's pixels and more.
  t.observe(film_frame(whole, 9));
  EXPECT_EQ(t.active(320, 240), whole);
}

// The order the stages keep (common/bars.h, step 4): a frame's rect comes
// from the counts of the frames before it, each frame's counts observed
// once; the first frame, and the first after a reset, from its own.
TEST(BarTracker, EachFrameIsDecidedFromTheFramesBefore) {
  const PixelRect wide{0, 40, 320, 200}, whole{0, 0, 320, 240};
  BarTracker t;
  BarCounts held;  // the last frame's counts (on the device: queued)
  int observed = 0;
  auto frame = [&](const BarCounts &own) {
    if (t.previous_due()) {
      t.observe(held);
      ++observed;
    }
    held = own;
    if (t.counted()) {
      t.observe(held);
      ++observed;
    }
    return t.active(320, 240);
  };
  EXPECT_EQ(frame(film_frame(wide, 1)), wide) << "the first frame: its own counts";
  EXPECT_EQ(observed, 1);
  EXPECT_FALSE(t.previous_due()) << "the first frame's counts were seen on it";
  for (int k = 1; k < 4; ++k) EXPECT_EQ(frame(film_frame(wide, 1 + k)), wide) << "frame " << k;
  EXPECT_EQ(observed, 3) << "frames 0-2 seen by frame 3";
  // A cut to a full-frame picture at frame 4 moves the rect at frame 5.
  EXPECT_EQ(frame(film_frame(whole, 9)), wide) << "the cut's own frame";
  EXPECT_EQ(frame(film_frame(whole, 10)), whole) << "the frame after the cut";
  EXPECT_EQ(observed, 5);
  // After a reset the next frame is decided from its own counts again.
  t.reset();
  EXPECT_FALSE(t.previous_due());
  EXPECT_EQ(frame(film_frame(wide, 11)), wide);
  EXPECT_EQ(observed, 6);
  // Counts of another size (observed at the next frame) decide afresh and
  // keep the order: one observation a frame.
  EXPECT_EQ(frame(counts_of(letterboxed(PixelFormat::I420, 160, 120, PixelRect{0, 16, 160, 104}, 0, 12))), wide);
  EXPECT_TRUE(t.previous_due());
  frame(film_frame(wide, 13));
  EXPECT_EQ(t.active(160, 120), (PixelRect{0, 16, 160, 104})) << "decided from the small frame's counts";
  EXPECT_EQ(observed, 7);
  EXPECT_TRUE(t.previous_due()) << "the last frame's counts are the next frame's to observe";
}

// ---- the warp inside an active rect -------------------------------------------------

cv::Mat ramp_depth(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<float>(y, x) = static_cast<float>(y) / h;
  for (int k = 0; k < 4; ++k) {
    const int x0 = rng() % (w - 8), y0 = rng() % (h - 8);
    d(cv::Rect(x0, y0, 8, 8)).setTo(cv::Scalar(0.9));
  }
  return d;
}

TEST(ActiveWarp, OutsideIsTheSourceInsideTheCroppedPicturesViews) {
  const int W = 96, H = 72;
  const YuvToRgb m;
  // The last rect has odd edges: the views outside start and end inside a
  // 4:2:0 pair.
  for (const PixelRect rect :
       {PixelRect{0, 16, W, 56}, PixelRect{16, 0, 80, H}, PixelRect{8, 8, 88, 64}, PixelRect{7, 5, 89, 65}})
    for (const HoleFill fill : test::kAllFills)
      for (const PixelFormat format : {PixelFormat::NV12, PixelFormat::I420, PixelFormat::RGBA, PixelFormat::BGRx}) {
        SCOPED_TRACE(::testing::Message() << "rect " << rect.x0 << "," << rect.y0 << " " << rect.x1 << "," << rect.y1
                                          << " fill " << enum_nick(kHoleFillNames, fill) << " "
                                          << test::format_name(format));
        HostFrame src(format, W, H, 3);
        src.fill_random(11);
        const cv::Mat depth = ramp_depth(W, H, 5);
        const WarpParams params = test::warp_params(6.f, 0.4f, StereoView::Both, fill);
        const PackParams pack = test::pack_params(PackLayout::SideBySide);
        // The pair in the source's order where it is packed RGB (the BGR
        // orders store their words swapped), else RGBA.
        const PixelFormat pair_format = is_packed_rgb(format) ? format : PixelFormat::RGBA;
        HostFrame pair(pair_format, 2 * W, H, 4), active_pair(pair_format, 2 * rect.width(), rect.height(), 0);
        pair.fill(0x77);
        active_pair.fill(0x33);
        WarpCpuScratch scratch;
        const ActiveArea area{rect, active_pair.view()};
        ASSERT_GE(warp_pack_changed_cpu(params, pack, src.view(), m, depth_view_of(depth), pair.view(), pair.view(),
                                        scratch, nullptr, &area),
                  0);
        // The cropped picture warped on its own, with the parallax of W.
        HostFrame want(pair_format, 2 * rect.width(), rect.height(), 0);
        const cv::Mat sub_depth = depth(cv::Rect(rect.x0, rect.y0, rect.width(), rect.height())).clone();
        const WarpParams active_params = active_warp_params(params, W, rect.width());
        EXPECT_FLOAT_EQ(disparity_scale(active_params, rect.width()), disparity_scale(params, W));
        ASSERT_GE(warp_render_cpu(active_params, sub_frame(src.view(), rect), m, depth_view_of(sub_depth), want.view()),
                  0);
        const FrameView got = pair.view(), ref = want.view();
        int wrong = 0;
        for (int y = 0; y < H; ++y)
          for (int eye = 0; eye < 2; ++eye)
            for (int x = 0; x < W; ++x) {
              const bool inside = x >= rect.x0 && x < rect.x1 && y >= rect.y0 && y < rect.y1;
              const Rgba expect = inside ? load_rgba(ref, eye * rect.width() + x - rect.x0, y - rect.y0, m)
                                         : load_rgba(src.view(), x, y, m);
              const Rgba have = load_rgba(got, eye * W + x, y, m);
              wrong += expect.r != have.r || expect.g != have.g || expect.b != have.b || expect.a != have.a;
            }
        EXPECT_EQ(wrong, 0);
      }
}

TEST(ActiveWarp, ThePackPacksThePair) {
  const int W = 96, H = 72;
  const PixelRect rect{16, 8, 80, 64};
  HostFrame src(PixelFormat::I420, W, H, 0);
  src.fill_random(3);
  const cv::Mat depth = ramp_depth(W, H, 9);
  const WarpParams params = test::warp_params(4.f, 0.5f, StereoView::Both, HoleFill::BackgroundSmooth);
  const PackParams pack = test::pack_params(PackLayout::TopBottomHalf);
  int out_w, out_h;
  pack_size(pack.layout, W, H, &out_w, &out_h);
  HostFrame pair(PixelFormat::RGBA, 2 * W, H, 0), active_pair(PixelFormat::RGBA, 2 * rect.width(), rect.height(), 0);
  HostFrame out(PixelFormat::NV12, out_w, out_h, 0), want(PixelFormat::NV12, out_w, out_h, 0);
  WarpCpuScratch scratch;
  const ActiveArea area{rect, active_pair.view()};
  ASSERT_GE(warp_pack_changed_cpu(params, pack, src.view(), YuvToRgb(), depth_view_of(depth), pair.view(), out.view(),
                                  scratch, nullptr, &area),
            0);
  pack_cpu(pack, pair.view(), want.view());
  EXPECT_EQ(cv::norm(out.to_bgra(), want.to_bgra(), cv::NORM_INF), 0.0);
}

// A sub-picture starts on the stages' cells or is the whole picture; the
// bands outside it are the grid's cells that no cell of it covers.
TEST(BarRects, OnCellsAndTheCellsOutside) {
  const PixelRect r{0, 140, 1920, 940};
  EXPECT_EQ(rect_on_cells(r, 2, 1920, 1080), r);
  EXPECT_EQ(rect_on_cells(r, 3, 1920, 1080), whole_picture(1920, 1080));  // 140 is not a multiple of 8
  EXPECT_EQ(rect_on_cells(PixelRect{6, 142, 1914, 938}, 2, 1920, 1080), whole_picture(1920, 1080));
  EXPECT_EQ(rect_on_cells(PixelRect{6, 142, 1914, 938}, 1, 1920, 1080), (PixelRect{6, 142, 1914, 938}));
  EXPECT_EQ(rect_on_cells(PixelRect{3, 5, 9, 9}, 0, 20, 20), (PixelRect{3, 5, 9, 9}));
  const int shift = 2, cw = grid_cells(30, shift), ch = grid_cells(22, shift);  // 8 x 6 cells
  const PixelRect inside{4, 8, 21, 17};  // cells 1..5 x 2..4
  std::vector<int> covered(static_cast<size_t>(cw) * ch, 0);
  for (const PixelRect &b : cells_outside(inside, shift, cw, ch))
    for (int y = b.y0; y < b.y1; ++y)
      for (int x = b.x0; x < b.x1; ++x) ++covered[static_cast<size_t>(y) * cw + x];
  for (int y = 0; y < ch; ++y)
    for (int x = 0; x < cw; ++x) {
      const bool in = x >= 1 && x <= 5 && y >= 2 && y <= 4;
      EXPECT_EQ(covered[static_cast<size_t>(y) * cw + x], in ? 0 : 1) << "cell " << x << "," << y;
    }
}

}  // namespace
}  // namespace p3d
