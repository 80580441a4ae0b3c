// The adaptive stages (common/change_map.h, common/adaptive.h and the
// adaptive entry points of the estimator, the filter, the warp and the
// pack) against the full computation. What the tests prove:
//  * ChangeMap: mark_pixels, any/all/fraction and merge agree with
//    brute-force readings of their definitions; dilated() marks the tiles
//    within the reach rounded up to whole tiles (so every pixel within the
//    reach of a changed pixel), clipped at the picture's edges, and reach 0
//    is the identity; rows() and runs() describe the changed tiles exactly
//    on odd sizes (runs maximal, clipped, in order, not overlapping, merged
//    down where the rows of tiles below repeat them).
//    compare_planes() and copy_plane_rect() do what they say, bitwise.
//  * FrameHistory: the first frame, a new size or format and reset() give
//    every tile; an unchanged frame none; one changed byte of any plane of
//    any format (odd sizes, padded rows) marks exactly the tile whose pixel
//    reads it (4:2:0 chroma: the tiles of the 2x2 block sharing the
//    sample), and a padding byte none; with tolerance t > 0 a tile changes
//    when the mean |difference| of all its bytes, every plane's, exceeds t,
//    against the last frame in which it changed, so slow drift adds up.
//    StageInputs merges the depth map's changes in.
//  * With tolerance 0, on random frame sequences (odd sizes, several
//    formats, parameters and random changes in a few tiles, unchanged
//    frames, big changes, scene cuts), each adaptive step gives byte for
//    byte what the full computation gives on every frame:
//      - the estimator fed estimate_blocks(&changes) from a FrameHistory:
//        the same decisions (Reuse, Smooth and Cut all occur), block
//        depths, differences, smoothed features, labels and expanded map
//        as an estimator fed whole frames; output_changed() is false
//        exactly when the block depths equal the previous frame's;
//      - bilateral_filter_changed_cpu() against the full filter (both
//        modes, steps 1-4 and automatic, radii 0 to 16), false exactly when
//        nothing changed, and then the full filter equals prev_out; the
//        filter over rectangles that cut the picture into odd pieces
//        equals the filter over the whole picture;
//      - warp_pack_changed_cpu() with its own pair buffer and scratch, its
//        output a copy of its previous one or (every other frame) other
//        bytes with the previous output kept apart (KeptOutput), against
//        warp_render_cpu() and pack_cpu() from scratch: every fill, view
//        and layout, packed RGB and 4:2:0 output, the pair being the
//        output where it is; the kept copy updated in the rows written
//        is the output;
//      - pack_changed_cpu() against pack_cpu(): every input arrangement,
//        layout and eye order, packed RGB and 4:2:0 output.
// Two cases of the warp's BackgroundSmooth fill run on their own as well:
// rows between two runs of changed rows, and an eye that is the source
// copied (in child processes, with the sweep's cases of that kind, so that
// a crash fails that test alone).
// Changes are placed against tile edges half of the time, where a reach
// that is one row or tile short shows. Fixed seeds throughout.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "adaptive.h"
#include "change_map.h"
#include "depth_estimate.h"
#include "test_data.h"

namespace p3d {
namespace {

using test::kAllFills;
using test::kAllFormats;
using test::kAllInputs;
using test::kAllLayouts;
using test::kAllViews;
using test::kPackedFormats;

int uniform(std::mt19937 &rng, int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }

std::string rect_text(const PixelRect &r) {
  return "[" + std::to_string(r.x0) + "," + std::to_string(r.x1) + ")x[" + std::to_string(r.y0) + "," +
         std::to_string(r.y1) + ")";
}

std::string tiles_text(const ChangeMap &m) {
  std::string s = std::to_string(m.width()) + "x" + std::to_string(m.height());
  for (int ty = 0; ty < m.tiles_y(); ++ty) {
    s += "\n  ";
    for (int tx = 0; tx < m.tiles_x(); ++tx) s += m.tile(tx, ty) ? '#' : '.';
  }
  return s;
}

::testing::AssertionResult same_tiles(const ChangeMap &got, const ChangeMap &want) {
  bool same = got.width() == want.width() && got.height() == want.height() && got.tiles_x() == want.tiles_x() &&
              got.tiles_y() == want.tiles_y();
  for (int ty = 0; same && ty < want.tiles_y(); ++ty)
    for (int tx = 0; same && tx < want.tiles_x(); ++tx) same = got.tile(tx, ty) == want.tile(tx, ty);
  if (same) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got " << tiles_text(got) << "\nwant " << tiles_text(want);
}

ChangeMap random_map(int w, int h, std::mt19937 &rng, double p) {
  ChangeMap m(w, h, false);
  std::bernoulli_distribution on(p);
  for (int ty = 0; ty < m.tiles_y(); ++ty)
    for (int tx = 0; tx < m.tiles_x(); ++tx)
      if (on(rng)) m.mark(tx, ty);
  return m;
}

int count_tiles(const ChangeMap &m) {
  int n = 0;
  for (int ty = 0; ty < m.tiles_y(); ++ty)
    for (int tx = 0; tx < m.tiles_x(); ++tx) n += m.tile(tx, ty);
  return n;
}

// The bytes of plane `plane` that hold the pixels of r: [b0, b1) of the
// rows [r0, r1). 4:2:0 chroma: the samples of r's 2x2 blocks.
struct PlaneBytes {
  int b0, b1, r0, r1;
};
PlaneBytes plane_bytes(PixelFormat f, int plane, const PixelRect &r) {
  if (is_packed_rgb(f)) return PlaneBytes{4 * r.x0, 4 * r.x1, r.y0, r.y1};
  if (plane == 0) return PlaneBytes{r.x0, r.x1, r.y0, r.y1};
  const int bytes = f == PixelFormat::NV12 ? 2 : 1;
  return PlaneBytes{bytes * (r.x0 / 2), bytes * ((r.x1 + 1) / 2), r.y0 / 2, (r.y1 + 1) / 2};
}

// The pixels that read byte b of row y of plane `plane`: one pixel, or for
// 4:2:0 chroma the 2x2 block sharing the sample (clipped by mark_pixels).
PixelRect pixels_of_byte(PixelFormat f, int plane, int b, int y) {
  if (is_packed_rgb(f)) return PixelRect{b / 4, y, b / 4 + 1, y + 1};
  if (plane == 0) return PixelRect{b, y, b + 1, y + 1};
  const int c = f == PixelFormat::NV12 ? b / 2 : b;
  return PixelRect{2 * c, 2 * y, 2 * c + 2, 2 * y + 2};
}

uint8_t *byte_at(const FrameView &v, int plane, int b, int y) {
  return v.plane[plane] + static_cast<size_t>(y) * v.stride[plane] + b;
}

// New random bytes for the pixels of r (every plane; 4:2:0 chroma of r's
// blocks, which lie in r's tiles: tiles are even).
void scribble(const HostFrame &f, const PixelRect &r, std::mt19937 &rng) {
  const FrameView v = f.view();
  for (int p = 0; p < frame_plane_count(v.format); ++p) {
    const PlaneBytes b = plane_bytes(v.format, p, r);
    for (int y = b.r0; y < b.r1; ++y)
      for (int i = b.b0; i < b.b1; ++i) *byte_at(v, p, i, y) = static_cast<uint8_t>(rng() >> 24);
  }
}

// A rectangle inside a random tile of a w x h picture, 1..max_side pixels a
// side, against one of the tile's edges half of the time on each axis:
// where a reach that is a row, a column or a tile short shows.
PixelRect rect_in_tile(std::mt19937 &rng, int w, int h, int max_side) {
  const PixelRect t = tile_pixels(uniform(rng, 0, change_tiles(w) - 1), uniform(rng, 0, change_tiles(h) - 1), w, h);
  const int sw = uniform(rng, 1, std::min(max_side, t.x1 - t.x0));
  const int sh = uniform(rng, 1, std::min(max_side, t.y1 - t.y0));
  auto place = [&rng](int lo, int hi, int side) {
    switch (uniform(rng, 0, 3)) {
      case 0: return lo;
      case 1: return hi - side;
      default: return uniform(rng, lo, hi - side);
    }
  };
  const int x0 = place(t.x0, t.x1, sw), y0 = place(t.y0, t.y1, sh);
  return PixelRect{x0, y0, x0 + sw, y0 + sh};
}

// Whether two frames of one format and size hold the same bytes in every
// row of every plane (padding is not compared).
::testing::AssertionResult same_bytes(const FrameView &got, const FrameView &want) {
  if (got.format != want.format || got.width != want.width || got.height != want.height)
    return ::testing::AssertionFailure() << "frames of different geometry";
  for (int p = 0; p < frame_plane_count(want.format); ++p) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(want.format, want.width, want.height, p, &row_bytes, &rows);
    for (int y = 0; y < rows; ++y) {
      const uint8_t *g = byte_at(got, p, 0, y), *w = byte_at(want, p, 0, y);
      if (std::memcmp(g, w, static_cast<size_t>(row_bytes)) == 0) continue;
      int i = 0;
      while (g[i] == w[i]) ++i;
      return ::testing::AssertionFailure() << "plane " << p << " row " << y << " byte " << i << ": got "
                                           << int(g[i]) << ", want " << int(w[i]);
    }
  }
  return ::testing::AssertionSuccess();
}

// Bitwise equality of two float images, naming the first pixel that differs.
::testing::AssertionResult same_floats(const cv::Mat &got, const cv::Mat &want) {
  if (got.size() != want.size() || got.type() != want.type())
    return ::testing::AssertionFailure() << "maps of different size";
  for (int y = 0; y < want.rows; ++y) {
    if (std::memcmp(got.ptr(y), want.ptr(y), want.cols * want.elemSize()) == 0) continue;
    int x = 0;
    while (std::memcmp(&got.ptr<float>(y)[x], &want.ptr<float>(y)[x], sizeof(float)) == 0) ++x;
    return ::testing::AssertionFailure() << "pixel (" << x << ", " << y << "): got " << got.ptr<float>(y)[x]
                                         << ", want " << want.ptr<float>(y)[x];
  }
  return ::testing::AssertionSuccess();
}

template <typename T>
bool same_vector(const std::vector<T> &a, const std::vector<T> &b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

cv::Rect cv_rect(const PixelRect &r) { return cv::Rect(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0); }

// A read-only view of a depth map (depth_view_of gives a writable one of a non-const matrix).
ImageView<const float> cview(const cv::Mat &m) { return depth_view_of(m); }

cv::Mat nan_map(int w, int h) { return cv::Mat(h, w, CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN())); }

// ---- ChangeMap ---------------------------------------------------------------------

TEST(AdaptiveChangeMap, GeometryAndMarkPixels) {
  EXPECT_EQ(change_tiles(0), 0);
  EXPECT_EQ(change_tiles(1), 1);
  EXPECT_EQ(change_tiles(32), 1);
  EXPECT_EQ(change_tiles(33), 2);
  EXPECT_EQ(change_tiles(97), 4);
  const PixelRect corner = tile_pixels(3, 1, 97, 45);
  EXPECT_EQ(rect_text(corner), rect_text(PixelRect{96, 32, 97, 45}));

  ChangeMap m(97, 45, false);
  EXPECT_EQ(m.tiles_x(), 4);
  EXPECT_EQ(m.tiles_y(), 2);
  EXPECT_FALSE(m.any());
  EXPECT_FALSE(m.all());
  EXPECT_EQ(m.fraction(), 0.0);
  EXPECT_TRUE(ChangeMap(97, 45, true).all());

  // Rectangles anywhere, partly or wholly outside the picture or empty: the
  // tiles holding a pixel of the rectangle clipped to the picture.
  std::mt19937 rng(11);
  for (int k = 0; k < 500; ++k) {
    const PixelRect r{uniform(rng, -40, 120), uniform(rng, -40, 70), uniform(rng, -40, 140), uniform(rng, -40, 90)};
    ChangeMap got(97, 45, false);
    got.mark_pixels(r);
    ChangeMap want(97, 45, false);
    const int x0 = std::max(r.x0, 0), y0 = std::max(r.y0, 0), x1 = std::min(r.x1, 97), y1 = std::min(r.y1, 45);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) want.mark(x / kChangeTile, y / kChangeTile);
    EXPECT_TRUE(same_tiles(got, want)) << rect_text(r);
  }
}

TEST(AdaptiveChangeMap, AnyAllFractionMerge) {
  ChangeMap m(97, 45, false);
  m.mark(3, 1);
  EXPECT_TRUE(m.any());
  EXPECT_FALSE(m.all());
  EXPECT_DOUBLE_EQ(m.fraction(), 1.0 / 8.0);
  m.mark_all();
  EXPECT_TRUE(m.all());
  EXPECT_DOUBLE_EQ(m.fraction(), 1.0);

  std::mt19937 rng(12);
  for (int k = 0; k < 50; ++k) {
    const ChangeMap a = random_map(130, 70, rng, 0.3), b = random_map(130, 70, rng, 0.3);
    ChangeMap got = a;
    got.merge(b);
    ChangeMap want(130, 70, false);
    for (int ty = 0; ty < want.tiles_y(); ++ty)
      for (int tx = 0; tx < want.tiles_x(); ++tx)
        if (a.tile(tx, ty) || b.tile(tx, ty)) want.mark(tx, ty);
    EXPECT_TRUE(same_tiles(got, want));
    EXPECT_DOUBLE_EQ(got.fraction(), static_cast<double>(count_tiles(want)) / (want.tiles_x() * want.tiles_y()));
    EXPECT_EQ(got.any(), count_tiles(want) > 0);
    EXPECT_EQ(got.all(), count_tiles(want) == want.tiles_x() * want.tiles_y());
  }
  // A map of another picture, larger, smaller or of the same tile grid,
  // even one with nothing changed, marks every tile.
  for (const cv::Size other : {cv::Size(131, 70), cv::Size(130, 69), cv::Size(64, 33), cv::Size(0, 0)}) {
    ChangeMap got(130, 70, false);
    got.merge(ChangeMap(other.width, other.height, false));
    EXPECT_TRUE(got.all()) << other;
  }
}

TEST(AdaptiveChangeMap, DilatedRoundsReachUpToWholeTilesAndClips) {
  std::mt19937 rng(13);
  const int reaches[][2] = {{0, 0},  {1, 0},   {0, 1},   {1, 1},  {31, 5}, {32, 32},
                            {33, 0}, {64, 65}, {-5, 3},  {3, -5}, {100, 100}, {200, 1}};
  for (const cv::Size sz : {cv::Size(97, 45), cv::Size(200, 150), cv::Size(1, 1), cv::Size(33, 97)})
    for (const double p : {0.0, 0.05, 0.2, 0.6})
      for (int k = 0; k < 4; ++k) {
        const ChangeMap m = random_map(sz.width, sz.height, rng, p);
        for (const auto &reach : reaches) {
          SCOPED_TRACE(::testing::Message() << sz << " reach " << reach[0] << "," << reach[1] << "\n"
                                            << tiles_text(m));
          const ChangeMap got = m.dilated(reach[0], reach[1]);
          if (reach[0] <= 0 && reach[1] <= 0) {
            EXPECT_TRUE(same_tiles(got, m)) << "reach 0 is the identity";
            continue;
          }
          // Whole tiles: ceil(reach / tile) tiles on either side, clipped.
          const int rx = (std::max(reach[0], 0) + kChangeTile - 1) / kChangeTile;
          const int ry = (std::max(reach[1], 0) + kChangeTile - 1) / kChangeTile;
          ChangeMap want(sz.width, sz.height, false);
          for (int ty = 0; ty < m.tiles_y(); ++ty)
            for (int tx = 0; tx < m.tiles_x(); ++tx)
              for (int cy = 0; cy < m.tiles_y(); ++cy)
                for (int cx = 0; cx < m.tiles_x(); ++cx)
                  if (m.tile(cx, cy) && std::abs(tx - cx) <= rx && std::abs(ty - cy) <= ry) want.mark(tx, ty);
          EXPECT_TRUE(same_tiles(got, want));
          // What that rounding is for: a tile holding a pixel within the
          // reach of a changed tile's pixel is marked.
          for (int ty = 0; ty < m.tiles_y(); ++ty)
            for (int tx = 0; tx < m.tiles_x(); ++tx)
              for (int cy = 0; cy < m.tiles_y(); ++cy)
                for (int cx = 0; cx < m.tiles_x(); ++cx) {
                  if (!m.tile(cx, cy)) continue;
                  const PixelRect t = tile_pixels(tx, ty, sz.width, sz.height);
                  const PixelRect c = tile_pixels(cx, cy, sz.width, sz.height);
                  const int gap_x = std::max({0, t.x0 - (c.x1 - 1), c.x0 - (t.x1 - 1)});
                  const int gap_y = std::max({0, t.y0 - (c.y1 - 1), c.y0 - (t.y1 - 1)});
                  if (gap_x <= std::max(reach[0], 0) && gap_y <= std::max(reach[1], 0)) {
                    EXPECT_TRUE(got.tile(tx, ty)) << "tile " << tx << "," << ty << " from " << cx << "," << cy;
                  }
                }
        }
      }
}

TEST(AdaptiveChangeMap, RowsAndRunsOnOddSizes) {
  std::mt19937 rng(14);
  for (const cv::Size sz : {cv::Size(97, 45), cv::Size(67, 35), cv::Size(1, 1), cv::Size(33, 70), cv::Size(200, 3)})
    for (const double p : {0.0, 0.3, 0.7, 1.0})
      for (int k = 0; k < 6; ++k) {
        const ChangeMap m = random_map(sz.width, sz.height, rng, p);
        SCOPED_TRACE(tiles_text(m));
        const std::vector<uint8_t> rows = m.rows();
        const std::vector<ColumnSpan> spans = m.row_spans();
        ASSERT_EQ(static_cast<int>(rows.size()), sz.height);
        ASSERT_EQ(static_cast<int>(spans.size()), sz.height);
        double span_pixels = 0;
        for (int y = 0; y < sz.height; ++y) {
          bool any = false;
          int first = sz.width, end = 0;  // the changed pixels' columns of row y
          for (int x = 0; x < sz.width; ++x)
            if (m.tile(x / kChangeTile, y / kChangeTile)) {
              any = true;
              first = std::min(first, x);
              end = x + 1;
            }
          EXPECT_EQ(rows[y] != 0, any) << "row " << y;
          EXPECT_EQ(spans[y].empty(), !any) << "row " << y;
          if (any) {
            EXPECT_EQ(spans[y].x0, first) << "row " << y;
            EXPECT_EQ(spans[y].x1, end) << "row " << y;
            span_pixels += end - first;
          }
        }
        EXPECT_DOUBLE_EQ(m.span_share(), span_pixels / (static_cast<double>(sz.width) * sz.height));
        const std::vector<PixelRect> runs = m.runs();
        ChangeMap covered(sz.width, sz.height, false);
        int tiles = 0;
        for (size_t i = 0; i < runs.size(); ++i) {
          const PixelRect &r = runs[i];
          SCOPED_TRACE(rect_text(r));
          ASSERT_FALSE(r.empty());
          // Whole tiles, clipped to the picture; each of its rows of
          // tiles holds a maximal run of changed tiles.
          const int ty0 = r.y0 / kChangeTile, ty1 = change_tiles(r.y1);
          const int tx0 = r.x0 / kChangeTile, tx1 = change_tiles(r.x1);
          EXPECT_EQ(r.y0, ty0 * kChangeTile);
          EXPECT_EQ(r.y1, std::min(sz.height, ty1 * kChangeTile));
          EXPECT_EQ(r.x0, tx0 * kChangeTile);
          EXPECT_EQ(r.x1, std::min(sz.width, tx1 * kChangeTile));
          auto maximal_run = [&](int ty) {
            for (int tx = tx0; tx < tx1; ++tx)
              if (!m.tile(tx, ty)) return false;
            return (tx0 == 0 || !m.tile(tx0 - 1, ty)) && (tx1 == m.tiles_x() || !m.tile(tx1, ty));
          };
          for (int ty = ty0; ty < ty1; ++ty) {
            EXPECT_TRUE(maximal_run(ty)) << "row of tiles " << ty;
            for (int tx = tx0; tx < tx1; ++tx) {
              EXPECT_FALSE(covered.tile(tx, ty)) << "runs overlap";
              covered.mark(tx, ty);
              ++tiles;
            }
          }
          // Merged down as far as the same run goes: the row of tiles
          // above holds no run with these columns.
          if (ty0 > 0) {
            EXPECT_FALSE(maximal_run(ty0 - 1));
          }
          // In order: row by row, left to right.
          if (i > 0) {
            const PixelRect &q = runs[i - 1];
            EXPECT_TRUE(q.y0 < r.y0 || (q.y0 == r.y0 && q.x1 <= r.x0));
          }
        }
        EXPECT_TRUE(same_tiles(covered, m));
        EXPECT_EQ(tiles, count_tiles(m));
      }
}

// rows_within: the rows within a reach of a changed tile's rows, which
// for the warp's reach (warp_rows_reach) are the rows the adaptive warp
// writes (warp_rows_written of the map's spans): the rule the warp's rows
// on the device follow (tests/gpu/test_gpu_change.cpp checks the kernel).
TEST(AdaptiveChangeMap, RowsWithinAReachAreTheWarpsRowsWritten) {
  ChangeMap one(50, 100, false);
  one.mark(1, 1);  // rows 32 .. 63
  std::vector<uint8_t> want(100, 0);
  std::fill(want.begin() + 27, want.begin() + 69, 1);
  EXPECT_EQ(one.rows_within(5), want);
  EXPECT_EQ(one.rows_within(0), one.rows());
  EXPECT_EQ(one.rows_within(100), std::vector<uint8_t>(100, 1));
  EXPECT_EQ(ChangeMap(50, 100, false).rows_within(100), std::vector<uint8_t>(100, 0));
  std::mt19937 rng(15);
  for (const cv::Size sz : {cv::Size(97, 45), cv::Size(33, 300), cv::Size(1920, 1080), cv::Size(1, 1)})
    for (const HoleFill fill :
         {HoleFill::BackgroundSmooth, HoleFill::Background, HoleFill::None, HoleFill::NeighborAverage})
      for (const float disparity : {3.f, 20.f})
        for (const double p : {0.0, 0.02, 0.3}) {
          const ChangeMap m = random_map(sz.width, sz.height, rng, p);
          SCOPED_TRACE(tiles_text(m));
          const WarpParams params = test::warp_params(disparity, 0.5f, StereoView::Both, fill);
          const int reach = warp_rows_reach(params, sz.width, sz.height);
          EXPECT_GE(reach, 0);
          if (fill == HoleFill::BackgroundSmooth) {
            EXPECT_GT(reach, 0);
          } else if (fill != HoleFill::NeighborAverage) {
            EXPECT_EQ(reach, 0);
          }
          EXPECT_EQ(m.rows_within(reach), warp_rows_written(params, sz.width, m.row_spans()));
        }
}

TEST(AdaptiveChangeMap, ComparePlanesAndCopyPlaneRect) {
  cv::Mat a(45, 97, CV_32FC1);
  cv::randu(a, 0.f, 1.f);
  a.at<float>(40, 96) = std::numeric_limits<float>::quiet_NaN();
  cv::Mat b = a.clone();
  EXPECT_FALSE(compare_planes(cview(a), cview(b)).any()) << "equal bits, NaN included";
  // One changed float anywhere marks its tile; bits count, not values (-0 is not 0).
  std::mt19937 rng(15);
  for (int k = 0; k < 200; ++k) {
    const int x = uniform(rng, 0, 96), y = uniform(rng, 0, 44);
    const float old = b.at<float>(y, x);
    b.at<float>(y, x) = k == 0 ? std::nextafter(old, 2.f) : static_cast<float>(k);
    ChangeMap want(97, 45, false);
    want.mark(x / kChangeTile, y / kChangeTile);
    EXPECT_TRUE(same_tiles(compare_planes(cview(a), cview(b)), want)) << x << "," << y;
    b.at<float>(y, x) = old;
  }
  cv::Mat zero(45, 97, CV_32FC1, cv::Scalar(0.f)), negative_zero(45, 97, CV_32FC1, cv::Scalar(0.f));
  negative_zero.at<float>(33, 64) = -0.f;
  ChangeMap want(97, 45, false);
  want.mark(2, 1);
  EXPECT_TRUE(same_tiles(compare_planes(cview(zero), cview(negative_zero)), want));
  // Another size or an empty first plane: every tile of the second.
  const cv::Mat smaller = a(cv::Rect(0, 0, 96, 45)).clone();
  EXPECT_TRUE(same_tiles(compare_planes(cview(a), cview(smaller)), ChangeMap(96, 45, true)));
  EXPECT_TRUE(same_tiles(compare_planes(ImageView<const float>(), cview(a)), ChangeMap(97, 45, true)));

  // copy_plane_rect writes the rectangle and nothing else.
  for (int k = 0; k < 50; ++k) {
    const int x0 = uniform(rng, 0, 96), y0 = uniform(rng, 0, 44);
    const PixelRect r{x0, y0, uniform(rng, x0, 97), uniform(rng, y0, 45)};
    cv::Mat to = nan_map(97, 45);
    copy_plane_rect(cview(a), depth_view_of(to), r);
    cv::Mat want_map = nan_map(97, 45);
    if (!r.empty()) a(cv_rect(r)).copyTo(want_map(cv_rect(r)));
    EXPECT_TRUE(same_floats(to, want_map)) << rect_text(r);
  }
}

// A grid's changes are those of its full-size map: compare_grids() against
// compare_planes() of the expanded grids, for cells smaller than, as large
// as and larger than a tile, on sizes that leave partial cells and tiles.
TEST(AdaptiveChangeMap, CompareGridsIsComparePlanesOfTheExpandedMaps) {
  std::mt19937 rng(21);
  for (int shift = 0; shift <= 6; ++shift)
    for (const cv::Size size : {cv::Size(97, 45), cv::Size(200, 131), cv::Size(64, 64)}) {
      const int cw = grid_cells(size.width, shift), ch = grid_cells(size.height, shift);
      cv::Mat a(ch, cw, CV_32FC1);
      cv::randu(a, 0.f, 1.f);
      for (int k = 0; k < 20; ++k) {
        cv::Mat b = a.clone();
        const int changes = k % 4;  // none, then one to three cells
        for (int c = 0; c < changes; ++c) b.at<float>(uniform(rng, 0, ch - 1), uniform(rng, 0, cw - 1)) += 1.f;
        const DepthGrid<const float> ga{cview(a), size.width, size.height, shift};
        const DepthGrid<const float> gb{cview(b), size.width, size.height, shift};
        cv::Mat fa(size.height, size.width, CV_32FC1), fb(size.height, size.width, CV_32FC1);
        expand_grid(ga, depth_view_of(fa));
        expand_grid(gb, depth_view_of(fb));
        EXPECT_TRUE(same_tiles(compare_grids(ga, gb), compare_planes(cview(fa), cview(fb))))
            << "shift " << shift << " " << size.width << "x" << size.height << " case " << k;
      }
      const DepthGrid<const float> ga{cview(a), size.width, size.height, shift};
      const DepthGrid<const float> other{cview(a), size.width, size.height, shift + 1};
      EXPECT_TRUE(compare_grids(ga, other).all()) << "another shift: every tile";
    }
}

// The frames uncompared after each busy one (compare_next() false in a
// row before the next true).
int pause_after_busy(ChangeBackOff &b) {
  b.observe(true);
  int n = 0;
  while (!b.compare_next()) ++n;
  return n;
}

// ChangeBackOff: a busy compared frame makes the next kBackOffFrames
// uncompared, doubling while busy up to kBackOffMax; a calm one starts
// over; reset() compares at once.
TEST(AdaptiveChangeMap, BackOffSkipsComparisonsAfterABusyFrame) {
  ChangeBackOff b;
  for (int k = 0; k < 5; ++k) {
    EXPECT_TRUE(b.compare_next());
    b.observe(false);
  }
  EXPECT_TRUE(b.compare_next());
  int want = kBackOffFrames;
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(pause_after_busy(b), want) << "busy frame " << k;
    want = std::min(2 * want, kBackOffMax);
  }
  b.observe(false);
  EXPECT_TRUE(b.compare_next()) << "a calm frame: compared again";
  EXPECT_EQ(pause_after_busy(b), kBackOffFrames) << "the pause starts over";
  b.observe(true);
  EXPECT_FALSE(b.compare_next());
  b.reset();
  EXPECT_TRUE(b.compare_next()) << "reset: compares at once";
  EXPECT_EQ(pause_after_busy(b), kBackOffFrames);
}

// ---- FrameHistory and StageInputs --------------------------------------------------

TEST(AdaptiveFrameHistory, FirstUnchangedAndNewGeometry) {
  HostFrame f(PixelFormat::NV12, 67, 35, 3);
  f.fill_random(21);
  FrameHistory h;
  EXPECT_TRUE(same_tiles(h.compare(f.view()), ChangeMap(67, 35, true))) << "first frame";
  EXPECT_TRUE(same_tiles(h.compare(f.view()), ChangeMap(67, 35, false))) << "unchanged";
  EXPECT_EQ(h.compare(HostFrame(f).view()).fraction(), 0.0) << "a copy elsewhere in memory";
  // The same bytes in another format, another size: every tile.
  HostFrame i420(PixelFormat::I420, 67, 35, 3);
  std::memcpy(i420.view().plane[0], f.view().plane[0], static_cast<size_t>(f.view().stride[0]) * 35);
  EXPECT_TRUE(h.compare(i420.view()).all()) << "NV12 -> I420";
  HostFrame rgba(PixelFormat::RGBA, 67, 35, 0), bgra(PixelFormat::BGRA, 67, 35, 0);
  rgba.fill_random(22);
  bgra.fill_random(22);
  EXPECT_TRUE(h.compare(rgba.view()).all());
  EXPECT_FALSE(h.compare(rgba.view()).any());
  EXPECT_TRUE(h.compare(bgra.view()).all()) << "RGBA -> BGRA, same bytes";
  HostFrame narrower(PixelFormat::BGRA, 66, 35, 4), shorter(PixelFormat::BGRA, 66, 34, 4);
  narrower.fill_random(23);
  shorter.fill_random(23);
  EXPECT_TRUE(same_tiles(h.compare(narrower.view()), ChangeMap(66, 35, true)));
  EXPECT_FALSE(h.compare(narrower.view()).any());
  EXPECT_TRUE(same_tiles(h.compare(shorter.view()), ChangeMap(66, 34, true)));
  h.reset();
  EXPECT_TRUE(h.compare(shorter.view()).all()) << "after reset";
  EXPECT_FALSE(h.compare(shorter.view()).any());
}

// One changed byte marks the tiles of the pixels that read it; restoring it
// marks them again (the reference took the changed byte). Every byte of
// the rows on either side of a tile edge, the first and last rows, and
// random bytes elsewhere; padding bytes mark nothing.
TEST(AdaptiveFrameHistory, OneChangedByteMarksItsTile) {
  struct Geometry {
    int w, h, padding;
  };
  std::mt19937 rng(24);
  for (const PixelFormat format : kAllFormats)
    for (const Geometry g : {Geometry{67, 35, 0}, Geometry{67, 35, 7}, Geometry{97, 45, 3}}) {
      SCOPED_TRACE(::testing::Message() << test::format_name(format) << " " << g.w << "x" << g.h << " padding "
                                        << g.padding);
      HostFrame f(format, g.w, g.h, g.padding);
      f.fill_random(rng());
      const FrameView v = f.view();
      FrameHistory h;
      ASSERT_TRUE(h.compare(v).all());
      for (int p = 0; p < frame_plane_count(format); ++p) {
        int row_bytes = 0, rows = 0;
        frame_plane_size(format, g.w, g.h, p, &row_bytes, &rows);
        // The rows on either side of the first tile edge (chroma: of its samples).
        const int edge = p == 0 ? kChangeTile : kChangeTile / 2;
        std::vector<std::pair<int, int>> where;
        for (const int y : {0, edge - 1, edge, rows - 1})
          if (y < rows)
            for (int b = 0; b < row_bytes; ++b) where.emplace_back(b, y);
        for (int k = 0; k < 100; ++k) where.emplace_back(uniform(rng, 0, row_bytes - 1), uniform(rng, 0, rows - 1));
        for (const auto &[b, y] : where) {
          ChangeMap want(g.w, g.h, false);
          want.mark_pixels(pixels_of_byte(format, p, b, y));
          uint8_t *byte = byte_at(v, p, b, y);
          const uint8_t old = *byte;
          *byte = static_cast<uint8_t>(old ^ (1u << (b % 8)));
          const ChangeMap changed = h.compare(v);
          *byte = old;
          const ChangeMap restored = h.compare(v);
          if (!same_tiles(changed, want) || !same_tiles(restored, want)) {
            ADD_FAILURE() << "plane " << p << " byte " << b << " row " << y << "\nchanged: "
                          << same_tiles(changed, want).message() << "\nrestored: "
                          << same_tiles(restored, want).message();
            break;
          }
        }
        for (int y = 0; y < rows && g.padding > 0; ++y)
          for (int b = row_bytes; b < v.stride[p]; ++b) {
            uint8_t *byte = byte_at(v, p, b, y);
            *byte = static_cast<uint8_t>(*byte + 1);
          }
        EXPECT_FALSE(h.compare(v).any()) << "padding of plane " << p;
      }
    }
}

// Tolerance t: a tile changes when the mean |difference| over all its bytes
// (every plane's samples of the tile) exceeds t, measured against the bytes
// of the last frame in which it changed.
TEST(AdaptiveFrameHistory, ToleranceIsAMeanOverTheTileAndDriftAddsUp) {
  const float t = 2.f;
  // Every byte of one tile moves by d: changed exactly when d > t. Tile
  // (2, 1) of 67 x 35 is 3 x 3 pixels: a partial tile counts its own bytes.
  for (const PixelFormat format : kAllFormats)
    for (const PixelRect tile : {tile_pixels(0, 0, 67, 35), tile_pixels(2, 1, 67, 35), tile_pixels(1, 1, 67, 35)})
      for (const int d : {1, 2, 3}) {
        SCOPED_TRACE(::testing::Message() << test::format_name(format) << " tile " << rect_text(tile) << " d " << d);
        HostFrame f(format, 67, 35, 5);
        f.fill(100);
        FrameHistory h;
        ASSERT_TRUE(h.compare(f.view(), t).all());
        const FrameView v = f.view();
        for (int p = 0; p < frame_plane_count(format); ++p) {
          const PlaneBytes b = plane_bytes(format, p, tile);
          for (int y = b.r0; y < b.r1; ++y)
            for (int i = b.b0; i < b.b1; ++i) *byte_at(v, p, i, y) = static_cast<uint8_t>(100 + ((i + y) % 2 ? d : -d));
        }
        ChangeMap want(67, 35, false);
        if (d > t) want.mark_pixels(tile);
        EXPECT_TRUE(same_tiles(h.compare(v, t), want));
      }
  // Only the chroma of a 4:2:0 tile moves: the mean is over the luma too.
  // A full tile holds 1024 luma and 512 chroma bytes: chroma moved by 3d
  // is a mean of d.
  for (const PixelFormat format : {PixelFormat::NV12, PixelFormat::I420})
    for (const int d : {2, 3}) {
      HostFrame f(format, 67, 35, 0);
      f.fill(100);
      FrameHistory h;
      h.compare(f.view(), t);
      const FrameView v = f.view();
      for (int p = 1; p < frame_plane_count(format); ++p) {
        const PlaneBytes b = plane_bytes(format, p, tile_pixels(1, 0, 67, 35));
        for (int y = b.r0; y < b.r1; ++y)
          for (int i = b.b0; i < b.b1; ++i) *byte_at(v, p, i, y) = static_cast<uint8_t>(100 + 3 * d);
      }
      EXPECT_EQ(h.compare(v, t).tile(1, 0), d > t) << test::format_name(format) << " d " << d;
    }
  // One byte far off in a full tile is a small mean: no change.
  {
    HostFrame f(PixelFormat::RGBA, 67, 35, 0);
    f.fill(100);
    FrameHistory h;
    h.compare(f.view(), t);
    *byte_at(f.view(), 0, 40, 5) = 255;
    EXPECT_FALSE(h.compare(f.view(), t).any());
  }
  // Drift: tile (0, 0) moves by 1 a frame, tile (1, 0) by 3 a frame, the
  // rest stays. The slow tile changes every third frame (3 > t against the
  // frame it last changed in, 1 and 2 are not), the fast one every frame.
  for (const PixelFormat format : {PixelFormat::RGBx, PixelFormat::I420}) {
    SCOPED_TRACE(test::format_name(format));
    HostFrame f(format, 67, 35, 2);
    f.fill(50);
    FrameHistory h;
    h.compare(f.view(), t);
    const FrameView v = f.view();
    for (int frame = 1; frame <= 12; ++frame) {
      for (int p = 0; p < frame_plane_count(format); ++p)
        for (const auto &[tx, step] : {std::pair<int, int>{0, 1}, std::pair<int, int>{1, 3}}) {
          const PlaneBytes b = plane_bytes(format, p, tile_pixels(tx, 0, 67, 35));
          for (int y = b.r0; y < b.r1; ++y)
            for (int i = b.b0; i < b.b1; ++i) *byte_at(v, p, i, y) = static_cast<uint8_t>(*byte_at(v, p, i, y) + step);
        }
      ChangeMap want(67, 35, false);
      if (frame % 3 == 0) want.mark(0, 0);
      want.mark(1, 0);
      EXPECT_TRUE(same_tiles(h.compare(v, t), want)) << "frame " << frame;
    }
  }
}

TEST(AdaptiveStageInputs, DepthChangesMergeIn) {
  HostFrame f(PixelFormat::BGRA, 97, 45, 0);
  f.fill_random(31);
  cv::Mat d0(45, 97, CV_32FC1);
  cv::randu(d0, 0.f, 1.f);
  StageInputs in;
  EXPECT_TRUE(in.compare(f.view(), cview(d0), ImageView<const float>(), 0.f).all());
  // The same map (one data pointer): only the frame is compared.
  EXPECT_FALSE(in.compare(f.view(), cview(d0), cview(d0), 0.f).any());
  cv::Mat d1 = d0.clone();
  EXPECT_FALSE(in.compare(f.view(), cview(d1), cview(d0), 0.f).any()) << "equal copy";
  d1.at<float>(40, 70) += 0.25f;
  *byte_at(f.view(), 0, 4 * 5, 3) ^= 1;
  ChangeMap want(97, 45, false);
  want.mark(2, 1);
  want.mark(0, 0);
  EXPECT_TRUE(same_tiles(in.compare(f.view(), cview(d1), cview(d0), 0.f), want));
  // No previous map: every tile; no map: the frame's tiles alone.
  EXPECT_TRUE(in.compare(f.view(), cview(d1), ImageView<const float>(), 0.f).all());
  EXPECT_FALSE(in.compare(f.view(), ImageView<const float>(), cview(d1), 0.f).any());
}

// On the CPU a stage backs off after a compared frame in which more than
// kBusyShare of the tiles changed; its fresh first comparison after the
// pause is not observed, the one after it is; adaptive=false resets.
TEST(AdaptiveStageInputs, BacksOffAfterABusyFrameOnly) {
  const int w = 128, h = 64;  // 4 x 2 tiles
  HostFrame f(PixelFormat::RGBA, w, h, 0);
  f.fill_random(41);
  std::mt19937 rng(1);
  StageInputs in;
  auto frame = [&](bool expect_compared, const char *what) {
    const bool compared = in.begin(true);
    EXPECT_EQ(compared, expect_compared) << what;
    if (compared) in.compare(f.view(), {}, {}, 0.f);
    return compared;
  };
  frame(true, "first frame");  // fresh: every tile, not observed
  EXPECT_FALSE(in.compared());
  frame(true, "after a fresh comparison");
  EXPECT_TRUE(in.compared());
  // 6 of 8 tiles changed: 75 %, not busy.
  scribble(f, PixelRect{0, 0, 96, 64}, rng);
  frame(true, "three quarters changed");
  frame(true, "not busy: compared again");
  // Every tile changed: busy, a pause of kBackOffFrames frames.
  f.fill_random(42);
  frame(true, "compared");
  for (int k = 0; k < kBackOffFrames; ++k) frame(false, "backing off");
  frame(true, "fresh comparison after the pause");
  EXPECT_FALSE(in.compared()) << "the history was dropped during the pause";
  f.fill_random(43);
  frame(true, "observed comparison");
  for (int k = 0; k < 2 * kBackOffFrames; ++k) frame(false, "busy again: the pause doubled");
  EXPECT_TRUE(in.begin(true));
  EXPECT_FALSE(in.begin(false)) << "adaptive=false";
  EXPECT_TRUE(in.begin(true)) << "adaptive=false reset the back-off";

  // A stage that redoes whole rows of tiles: one tile in each row changed
  // (2 of 8) is busy for it, and not for the others.
  StageInputs rows(ChangeReach::Rows), tiles;
  for (StageInputs *s : {&rows, &tiles})
    for (int k = 0; k < 2; ++k) {
      ASSERT_TRUE(s->begin(true));
      s->compare(f.view(), {}, {}, 0.f);
    }
  scribble(f, PixelRect{32, 0, 64, 64}, rng);
  for (StageInputs *s : {&rows, &tiles}) {
    ASSERT_TRUE(s->begin(true));
    EXPECT_EQ(s->compare(f.view(), {}, {}, 0.f).fraction(), 0.25);
  }
  EXPECT_FALSE(rows.begin(true)) << "a change in every row of tiles";
  EXPECT_TRUE(tiles.begin(true)) << "a quarter of the tiles";

  // The warp's spans: a column of tiles (a quarter of the picture) is not
  // busy; a tile at each end of every row spans it all and is.
  for (const bool ends : {false, true}) {
    StageInputs spans(ChangeReach::Spans);
    for (int k = 0; k < 2; ++k) {
      ASSERT_TRUE(spans.begin(true));
      spans.compare(f.view(), {}, {}, 0.f);
    }
    scribble(f, PixelRect{ends ? 0 : 32, 0, ends ? 1 : 64, 64}, rng);
    if (ends) scribble(f, PixelRect{127, 0, 128, 64}, rng);
    ASSERT_TRUE(spans.begin(true));
    const ChangeMap c = spans.compare(f.view(), {}, {}, 0.f);
    EXPECT_EQ(busy_for(ChangeReach::Spans, c), ends) << c.span_share();
    EXPECT_EQ(spans.begin(true), !ends);
  }
}

// The warp's reach follows its fill: windows for BackgroundSmooth and None,
// whole rows for Background and NeighborAverage; a change in the middle
// column of tiles in every row is busy only for the latter.
TEST(AdaptiveStageInputs, WarpReachFollowsTheFill) {
  ChangeMap middle(128, 64, false);
  for (int ty = 0; ty < middle.tiles_y(); ++ty) middle.mark(1, ty);
  for (const HoleFill fill : kAllFills) {
    WarpParams p;
    p.fill = fill;
    const bool windows = fill == HoleFill::BackgroundSmooth || fill == HoleFill::None;
    EXPECT_EQ(warp_change_reach(p), windows ? ChangeReach::Spans : ChangeReach::Rows) << enum_nick(kHoleFillNames, fill);
    EXPECT_EQ(busy_for(warp_change_reach(p), middle), !windows) << enum_nick(kHoleFillNames, fill);
  }
}

// ---- depth estimator -----------------------------------------------------------------

// A picture of flat rectangles on a gradient with light noise: regions for
// the estimator, which a little change leaves alone and a rectangle moves.
cv::Mat scene(int w, int h, std::mt19937 &rng) {
  cv::Mat bgr(h, w, CV_8UC3);
  const int base[3] = {uniform(rng, 20, 200), uniform(rng, 20, 200), uniform(rng, 20, 200)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        bgr.at<cv::Vec3b>(y, x)[c] =
            cv::saturate_cast<uint8_t>(base[c] + (c + 1) * y / 3 - x / 4 + uniform(rng, -2, 2));
  for (int k = 0; k < 5; ++k) {
    const int x0 = uniform(rng, 0, w - 2), y0 = uniform(rng, 0, h - 2);
    const cv::Rect r(x0, y0, uniform(rng, 1, w - x0), uniform(rng, 1, h - y0));
    bgr(r).setTo(cv::Scalar(uniform(rng, 0, 255), uniform(rng, 0, 255), uniform(rng, 0, 255)));
  }
  return bgr;
}

void jitter(cv::Mat &bgr, const PixelRect &r, std::mt19937 &rng, int delta) {
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x)
      for (int c = 0; c < 3; ++c) {
        uint8_t &v = bgr.at<cv::Vec3b>(y, x)[c];
        v = cv::saturate_cast<uint8_t>(v + uniform(rng, -delta, delta));
      }
}

void paint(cv::Mat &bgr, const PixelRect &r, std::mt19937 &rng) {
  bgr(cv_rect(r)).setTo(cv::Scalar(uniform(rng, 0, 255), uniform(rng, 0, 255), uniform(rng, 0, 255)));
}

struct DepthCase {
  DepthParams params;
  PixelFormat format;
  bool full_through_estimate;  // the full side calls estimate() (else estimate_blocks(nullptr) and expand())
};

// One random sequence through an adaptive and a full estimator. Returns
// the first difference; counts the decisions.
::testing::AssertionResult run_depth_sequence(const DepthCase &c, uint32_t seed, int counts[3]) {
  std::mt19937 rng(seed);
  const cv::Size sizes[2] = {cv::Size(97, 67), cv::Size(64, 33)};
  int size = 0;
  cv::Mat bgr = scene(sizes[0].width, sizes[0].height, rng);
  DepthEstimatorCpu adaptive, full;
  FrameHistory history;
  std::vector<float> prev_adaptive, prev_full;
  int still_run = 0;
  for (int frame = 0; frame < 36; ++frame) {
    const char *what = "first";
    bool whole = false;  // the adaptive side is told nothing this frame (parameters changed, say)
    if (frame > 0) {
      const int w = bgr.cols, h = bgr.rows;
      const int r = still_run > 0 ? -1 : uniform(rng, 0, 99);
      if (r < 0) {
        what = "still, in a run";
        --still_run;
      } else if (r < 20) {
        what = "still";
        if (r < 8) still_run = uniform(rng, 1, 3);
      } else if (r < 45) {
        what = "small";
        for (int k = uniform(rng, 1, 3); k > 0; --k) jitter(bgr, rect_in_tile(rng, w, h, 4), rng, 30);
      } else if (r < 70) {
        what = "medium";
        for (int k = uniform(rng, 1, 3); k > 0; --k) paint(bgr, rect_in_tile(rng, w, h, 32), rng);
      } else if (r < 82) {
        what = "big";
        for (int ty = 0; ty < change_tiles(h); ++ty)
          for (int tx = 0; tx < change_tiles(w); ++tx)
            if (uniform(rng, 0, 2) > 0) paint(bgr, tile_pixels(tx, ty, w, h), rng);
      } else if (r < 92) {
        what = "cut";
        bgr = scene(w, h, rng);
      } else if (r < 96) {
        what = "resize";
        size ^= 1;
        bgr = scene(sizes[size].width, sizes[size].height, rng);
      } else {
        what = "small, whole";
        whole = true;
        jitter(bgr, rect_in_tile(rng, w, h, 4), rng, 30);
      }
    }
    const HostFrame f = HostFrame::from_bgr(bgr, c.format, 3);
    const ChangeMap changes = history.compare(f.view());
    const TemporalDecision da = adaptive.estimate_blocks(c.params, f.view(), whole ? nullptr : &changes);
    cv::Mat map_a = nan_map(f.width(), f.height()), map_f = nan_map(f.width(), f.height());
    adaptive.expand(depth_view_of(map_a));
    TemporalDecision df;
    if (c.full_through_estimate) {
      df = full.estimate(c.params, f.view(), depth_view_of(map_f));
    } else {
      df = full.estimate_blocks(c.params, f.view(), nullptr);
      full.expand(depth_view_of(map_f));
    }
    auto fail = [&]() {
      return ::testing::AssertionFailure() << "frame " << frame << " (" << what << ", " << 100 * changes.fraction()
                                           << "% of the tiles, decision " << static_cast<int>(df) << "): ";
    };
    if (da != df) return fail() << "adaptive decided " << static_cast<int>(da);
    ++counts[static_cast<int>(df)];
    if (!same_vector(adaptive.block_depth(), full.block_depth())) return fail() << "block depths differ";
    const float diff_a = adaptive.last_diff(), diff_f = full.last_diff();
    if (std::memcmp(&diff_a, &diff_f, sizeof(float)) != 0)
      return fail() << "difference " << diff_a << ", full " << diff_f;
    if (!same_vector(adaptive.smoothed_features(), full.smoothed_features())) return fail() << "smoothed features";
    if (df != TemporalDecision::Reuse && adaptive.labels() != full.labels()) return fail() << "labels differ";
    if (adaptive.blocks_x() != full.blocks_x() || adaptive.blocks_y() != full.blocks_y()) return fail() << "grid";
    const bool moved_a = !same_vector(adaptive.block_depth(), prev_adaptive);
    const bool moved_f = !same_vector(full.block_depth(), prev_full);
    if (adaptive.output_changed() != moved_a)
      return fail() << "adaptive output_changed() " << adaptive.output_changed() << ", block depths moved " << moved_a;
    if (full.output_changed() != moved_f)
      return fail() << "full output_changed() " << full.output_changed() << ", block depths moved " << moved_f;
    const ::testing::AssertionResult maps = same_floats(map_a, map_f);
    if (!maps) return fail() << "expanded map: " << maps.message();
    prev_adaptive = adaptive.block_depth();
    prev_full = full.block_depth();
  }
  return ::testing::AssertionSuccess();
}

TEST(AdaptiveDepth, ChangedTilesGiveTheFullEstimate) {
  const float thresholds[][2] = {{0.5f, 30.f}, {0.f, 30.f}, {2.f, 20.f}};
  const float edges[] = {24.f, 0.f, 60.f};
  int index = 0;
  for (const int block : {0, 2, 3, 5, 8})
    for (const float temporal : {0.f, 0.5f, 0.3f})
      for (const float feature : {0.f, 0.9f}) {
        DepthCase c;
        c.params.block_size = block;
        c.params.temporal_smoothing = temporal;
        c.params.feature_smoothing = feature;
        c.params.static_threshold = thresholds[index % 3][0];
        c.params.cut_threshold = thresholds[index % 3][1];
        c.params.edge_threshold = edges[index / 3 % 3];
        c.params.hypothesis = static_cast<Hypothesis>(index % 4);
        c.params.ground_contact = index % 2 ? 1.f : 0.4f;
        c.format = kAllFormats[index / 2 % 6];
        c.full_through_estimate = index % 2 == 0;
        SCOPED_TRACE(::testing::Message() << "block " << block << " temporal " << temporal << " feature " << feature
                                          << " static " << c.params.static_threshold << " cut "
                                          << c.params.cut_threshold << " edge " << c.params.edge_threshold << " "
                                          << test::format_name(c.format));
        int counts[3] = {0, 0, 0};
        EXPECT_TRUE(run_depth_sequence(c, 1000 + index, counts));
        // The sequence went through every branch of step 5.
        EXPECT_GT(counts[static_cast<int>(TemporalDecision::Reuse)], 0);
        EXPECT_GT(counts[static_cast<int>(TemporalDecision::Smooth)], 0);
        EXPECT_GT(counts[static_cast<int>(TemporalDecision::Cut)], 1);
        ++index;
      }
}

// ---- filter --------------------------------------------------------------------------

cv::Mat full_filter(const BilateralParams &p, const HostFrame &guide, const cv::Mat &depth) {
  cv::Mat out = nan_map(depth.cols, depth.rows);
  bilateral_filter_cpu(p, guide.view(), cview(depth), depth_view_of(out));
  return out;
}

// Piecewise constant (4 x 4 blocks, as the estimator's) with noise on some blocks.
cv::Mat block_depth_map(int w, int h, std::mt19937 &rng) {
  cv::Mat d(h, w, CV_32FC1);
  for (int by = 0; by < h; by += 4)
    for (int bx = 0; bx < w; bx += 4) {
      const float v = std::uniform_real_distribution<float>(0.f, 1.f)(rng);
      const bool noisy = uniform(rng, 0, 3) == 0;
      for (int y = by; y < std::min(h, by + 4); ++y)
        for (int x = bx; x < std::min(w, bx + 4); ++x)
          d.at<float>(y, x) = noisy ? std::uniform_real_distribution<float>(0.f, 1.f)(rng) : v;
    }
  return d;
}

void new_depth(cv::Mat &d, const PixelRect &r, std::mt19937 &rng) {
  const bool flat = uniform(rng, 0, 1) == 0;
  const float v = std::uniform_real_distribution<float>(0.f, 1.f)(rng);
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x)
      d.at<float>(y, x) = flat ? v : std::uniform_real_distribution<float>(0.f, 1.f)(rng);
}

struct FilterCase {
  BilateralParams params;
  PixelFormat format;
  int w, h;
};

std::vector<FilterCase> filter_cases() {
  std::vector<FilterCase> cases;
  const cv::Size sizes[] = {cv::Size(97, 67), cv::Size(64, 33), cv::Size(130, 70)};
  int index = 0;
  for (const BilateralMode mode : {BilateralMode::Separable, BilateralMode::Exact})
    for (const int scale : {1, 2, 3, 4, 0})
      for (const int radius : {0, 1, 5, 16}) {
        FilterCase c;
        c.params = test::bilateral_params(radius, radius == 16 ? 8.f : 3.f, index % 7 == 3 ? 0.f : 12.f);
        c.params.mode = mode;
        c.params.scale = scale;
        c.format = kAllFormats[index % 6];
        c.w = sizes[index % 3].width;
        c.h = sizes[index % 3].height;
        cases.push_back(c);
        ++index;
      }
  return cases;
}

std::string filter_case_text(const FilterCase &c) {
  return std::string(c.params.mode == BilateralMode::Separable ? "separable" : "exact") + " scale " +
         std::to_string(c.params.scale) + " radius " + std::to_string(c.params.radius) + " sigma_range " +
         std::to_string(c.params.sigma_range) + " " + test::format_name(c.format) + " " + std::to_string(c.w) + "x" +
         std::to_string(c.h);
}

::testing::AssertionResult run_filter_sequence(const FilterCase &c, uint32_t seed) {
  std::mt19937 rng(seed);
  HostFrame guide(c.format, c.w, c.h, 5);
  guide.fill_random(rng());
  cv::Mat depth = block_depth_map(c.w, c.h, rng), prev_depth;
  StageInputs inputs;
  BilateralScratch scratch;
  cv::Mat prev_out;
  for (int frame = 0; frame < 8; ++frame) {
    const char *what = "first";
    bool whole = false;
    if (frame > 0) {
      prev_depth = depth;
      switch (frame == 1 ? 0 : uniform(rng, 0, 5)) {
        case 0: what = "unchanged"; break;
        case 1:
          what = "guide";
          for (int k = uniform(rng, 1, 3); k > 0; --k) scribble(guide, rect_in_tile(rng, c.w, c.h, 6), rng);
          break;
        case 2:
          what = "depth";
          depth = depth.clone();
          for (int k = uniform(rng, 1, 3); k > 0; --k) new_depth(depth, rect_in_tile(rng, c.w, c.h, 6), rng);
          break;
        case 3:
        case 4:
          what = "guide and depth";
          depth = depth.clone();
          for (int k = uniform(rng, 1, 3); k > 0; --k) {
            scribble(guide, rect_in_tile(rng, c.w, c.h, 32), rng);
            new_depth(depth, rect_in_tile(rng, c.w, c.h, 3), rng);
          }
          break;
        default:
          what = "guide, whole";
          whole = true;
          scribble(guide, rect_in_tile(rng, c.w, c.h, 6), rng);
          break;
      }
    }
    const ChangeMap changes = inputs.compare(guide.view(), cview(depth),
                                             prev_depth.empty() ? ImageView<const float>() : cview(prev_depth), 0.f);
    cv::Mat out = nan_map(c.w, c.h);
    const cv::Mat poison = out.clone();
    const bool wrote = bilateral_filter_changed_cpu(
        c.params, guide.view(), cview(depth),
        prev_out.empty() ? ImageView<const float>() : cview(prev_out), depth_view_of(out),
        whole ? nullptr : &changes, scratch);
    const cv::Mat want = full_filter(c.params, guide, depth);
    auto fail = [&]() {
      return ::testing::AssertionFailure() << "frame " << frame << " (" << what << ", " << 100 * changes.fraction()
                                           << "% of the tiles): ";
    };
    // False exactly when no tile changed (every reach reaches the changed tile itself).
    const bool expect_write = whole || prev_out.empty() || changes.any();
    if (wrote != expect_write) return fail() << "returned " << wrote;
    if (wrote) {
      const ::testing::AssertionResult same = same_floats(out, want);
      if (!same) return fail() << same.message();
      prev_out = out;
    } else {
      const ::testing::AssertionResult same = same_floats(prev_out, want);
      if (!same) return fail() << "prev_out is not this frame's filter: " << same.message();
      if (!same_floats(out, poison)) return fail() << "returned false, yet wrote out";
    }
  }
  return ::testing::AssertionSuccess();
}

TEST(AdaptiveFilter, ChangedTilesGiveTheFullFilter) {
  uint32_t seed = 2000;
  for (const FilterCase &c : filter_cases()) {
    SCOPED_TRACE(filter_case_text(c));
    EXPECT_TRUE(run_filter_sequence(c, seed++));
  }
  // prev_out of another size, or none: everything is filtered.
  std::mt19937 rng(2100);
  HostFrame guide(PixelFormat::I420, 97, 67, 1);
  guide.fill_random(2101);
  const cv::Mat depth = block_depth_map(97, 67, rng), other = nan_map(96, 67);
  const BilateralParams p = test::bilateral_params(5, 3.f, 12.f);
  const ChangeMap nothing(97, 67, false);
  BilateralScratch scratch;
  cv::Mat out = nan_map(97, 67);
  EXPECT_TRUE(bilateral_filter_changed_cpu(p, guide.view(), cview(depth), cview(other),
                                           depth_view_of(out), &nothing, scratch));
  EXPECT_TRUE(same_floats(out, full_filter(p, guide, depth)));
}

// The filter over rectangles that cut the picture into odd pieces, in one
// call or one call a piece, equals the filter over the whole picture, and
// leaves the pixels outside the rectangles alone.
TEST(AdaptiveFilter, PiecesGiveTheWholePicture) {
  std::mt19937 rng(2200);
  for (const FilterCase &c : filter_cases()) {
    SCOPED_TRACE(filter_case_text(c));
    HostFrame guide(c.format, c.w, c.h, 3);
    guide.fill_random(rng());
    const cv::Mat depth = block_depth_map(c.w, c.h, rng);
    const cv::Mat want = full_filter(c.params, guide, depth);
    auto cuts = [&rng](int n) {
      std::vector<int> at = {0};
      while (at.back() < n) at.push_back(std::min(n, at.back() + uniform(rng, 1, 40)));
      return at;
    };
    const std::vector<int> xs = cuts(c.w), ys = cuts(c.h);
    std::vector<PixelRect> pieces;
    for (size_t j = 0; j + 1 < ys.size(); ++j)
      for (size_t i = 0; i + 1 < xs.size(); ++i) pieces.push_back(PixelRect{xs[i], ys[j], xs[i + 1], ys[j + 1]});
    std::shuffle(pieces.begin(), pieces.end(), rng);
    BilateralScratch scratch;
    cv::Mat together = nan_map(c.w, c.h);
    bilateral_filter_cpu(c.params, guide.view(), cview(depth), depth_view_of(together), pieces, scratch);
    EXPECT_TRUE(same_floats(together, want)) << "one call";
    cv::Mat apart = nan_map(c.w, c.h);
    for (const PixelRect &r : pieces)
      bilateral_filter_cpu(c.params, guide.view(), cview(depth), depth_view_of(apart), {r}, scratch);
    EXPECT_TRUE(same_floats(apart, want)) << "a call a piece";
    const std::vector<PixelRect> some(pieces.begin(), pieces.begin() + (pieces.size() + 1) / 2);
    cv::Mat part = nan_map(c.w, c.h), part_want = nan_map(c.w, c.h);
    bilateral_filter_cpu(c.params, guide.view(), cview(depth), depth_view_of(part), some, scratch);
    for (const PixelRect &r : some) want(cv_rect(r)).copyTo(part_want(cv_rect(r)));
    EXPECT_TRUE(same_floats(part, part_want)) << "half of the pieces";
  }
}

// The pack of a sequence of input frames.
::testing::AssertionResult run_pack_sequence(const PackParams &p, PixelFormat in_format, PixelFormat out_format,
                                             int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  HostFrame in(in_format, w, h, 4);
  in.fill_random(rng());
  int vw = 0, vh = 0, ow = 0, oh = 0;
  if (!input_view_size(p.input, w, h, &vw, &vh)) return ::testing::AssertionFailure() << "no views";
  pack_size(p.layout, vw, vh, &ow, &oh);
  HostFrame out(out_format, ow, oh, 2);
  out.fill(0xC3);
  FrameHistory history;
  for (int frame = 0; frame < 6; ++frame) {
    const char *what = "first";
    if (frame > 0) {
      switch (uniform(rng, 0, 4)) {
        case 0: what = "unchanged"; break;
        case 1:
          what = "one pixel";
          scribble(in, rect_in_tile(rng, w, h, 1), rng);
          break;
        default:
          what = "a few tiles";
          for (int k = uniform(rng, 1, 4); k > 0; --k) scribble(in, rect_in_tile(rng, w, h, 5), rng);
          break;
      }
    }
    const ChangeMap changes = history.compare(in.view());
    HostFrame want(out_format, ow, oh, 1);
    want.fill(0x5A);
    pack_cpu(p, in.view(), want.view());
    // Every other frame into a new buffer of old bytes, the previous
    // output handed over as kept (KeptOutput): the rows not packed come
    // from it, and every row that differs from it is reported written.
    const bool into_new = frame % 2 == 1;
    HostFrame next = out;
    if (into_new) next.fill(0x77);
    const FrameView previous = out.view();
    KeptOutput kept{&previous, {}};
    if (!pack_changed_cpu(p, in.view(), next.view(), frame == 0 ? nullptr : &changes, into_new ? &kept : nullptr))
      return ::testing::AssertionFailure() << "frames do not fit";
    const ::testing::AssertionResult same = same_bytes(next.view(), want.view());
    if (!same)
      return ::testing::AssertionFailure() << "frame " << frame << " (" << what << ", " << 100 * changes.fraction()
                                           << "% of the tiles" << (into_new ? ", kept output" : "")
                                           << "): " << same.message();
    if (into_new) {
      if (kept.written.size() != static_cast<size_t>(oh))
        return ::testing::AssertionFailure() << "frame " << frame << ": " << kept.written.size() << " rows written of "
                                             << oh;
      // A 4:2:0 chroma row goes with its two rows (KeptOutput).
      const FrameView a = want.view(), b = previous;
      for (int pl = 0; pl < frame_plane_count(out_format); ++pl) {
        int row_bytes = 0, rows = 0;
        frame_plane_size(out_format, ow, oh, pl, &row_bytes, &rows);
        const int step = pl > 0 ? 2 : 1;
        for (int y = 0; y < rows; ++y) {
          const bool written = kept.written[step * y] || (step * y + 1 < oh && step == 2 && kept.written[2 * y + 1]);
          if (std::memcmp(a.plane[pl] + static_cast<size_t>(y) * a.stride[pl],
                          b.plane[pl] + static_cast<size_t>(y) * b.stride[pl], static_cast<size_t>(row_bytes)) != 0 &&
              !written)
            return ::testing::AssertionFailure()
                   << "frame " << frame << ": plane " << pl << " row " << y << " changed, not written";
        }
      }
    }
    out = std::move(next);
  }
  return ::testing::AssertionSuccess();
}

TEST(AdaptivePack, ChangedTilesGiveTheFullPack) {
  uint32_t seed = 4000;
  int index = 0;
  for (const StereoInput input : kAllInputs)
    for (const PackLayout layout : kAllLayouts)
      for (int order = 0; order < 4; ++order)
        for (const bool yuv : {false, true}) {
          PackParams p = test::pack_params(layout, AnaglyphGlasses::RedCyan,
                                           index % 3 ? AnaglyphMethod::Dubois : AnaglyphMethod::DuboisLinear,
                                           (order & 1) != 0);
          p.input = input;
          p.input_right_first = (order & 2) != 0;
          // Full side-by-side and top-bottom frames need an even axis; the
          // others take odd sizes.
          const int w = input == StereoInput::SideBySide ? 130 : 97;
          const int h = input == StereoInput::TopBottom ? 70 : 67;
          const PixelFormat in_format = kPackedFormats[(index / 2 + index / 8) % 4];
          const PixelFormat out_format = yuv ? (index / 2 % 2 ? PixelFormat::NV12 : PixelFormat::I420) : in_format;
          SCOPED_TRACE(::testing::Message() << "input " << enum_nick(kStereoInputNames, input) << " layout "
                                            << enum_nick(kPackLayoutNames, layout) << " swap " << p.swap_eyes
                                            << " right first " << p.input_right_first << " "
                                            << test::format_name(in_format) << " -> " << test::format_name(out_format));
          EXPECT_TRUE(run_pack_sequence(p, in_format, out_format, w, h, seed++));
          ++index;
        }
}

// cropped(r): a tile of the picture inside r is marked exactly when one of
// its pixels lies in a changed tile of the whole picture (brute force over
// pixels), for rects on and off the tile grid.
TEST(ChangeMapCropped, MarksTheTilesOverlappingAChange) {
  std::mt19937 rng(21);
  for (int k = 0; k < 40; ++k) {
    const ChangeMap whole = random_map(150, 97, rng, 0.2);
    const int x0 = uniform(rng, 0, 60), y0 = uniform(rng, 0, 40);
    const PixelRect r{x0, y0, uniform(rng, x0 + 1, 150), uniform(rng, y0 + 1, 97)};
    const ChangeMap got = whole.cropped(r);
    ChangeMap want(r.width(), r.height(), false);
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x)
        if (whole.tile(x / kChangeTile, y / kChangeTile)) want.mark((x - r.x0) / kChangeTile, (y - r.y0) / kChangeTile);
    EXPECT_TRUE(same_tiles(got, want)) << rect_text(r);
  }
}

// ---- warp and pack -----------------------------------------------------------------

// Depth of flat rectangles on a ramp: disocclusions beside them, in runs of
// rows that cross tile edges (what the fills spread along).
cv::Mat warp_depth_map(int w, int h, std::mt19937 &rng) {
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<float>(y, x) = 0.2f * static_cast<float>(y) / static_cast<float>(h);
  for (int k = 0; k < 4; ++k) {
    const int x0 = uniform(rng, 0, w - 2), y0 = uniform(rng, 0, h - 2);
    const cv::Rect r(x0, y0, uniform(rng, 1, std::min(40, w - x0)), uniform(rng, 1, h - y0));
    d(r).setTo(cv::Scalar(std::uniform_real_distribution<float>(0.3f, 1.f)(rng)));
  }
  return d;
}

struct WarpPackCase {
  WarpParams warp;
  PackParams pack;
  PixelFormat src_format, out_format;
  PixelRect active;  // the views rendered inside it (bars.h); empty: the whole picture
};

std::string warp_case_text(const WarpPackCase &c) {
  return std::string("fill ") + enum_nick(kHoleFillNames, c.warp.fill) + " view " +
         enum_nick(kStereoViewNames, c.warp.view) + " disparity " + std::to_string(c.warp.max_disparity) +
         " layout " + enum_nick(kPackLayoutNames, c.pack.layout) + (c.pack.swap_eyes ? " swapped" : "") +
         " method " + enum_nick(kAnaglyphMethodNames, c.pack.method) + " src " + test::format_name(c.src_format) +
         " out " + test::format_name(c.out_format);
}

// The adaptive warp and pack as the element runs them, beside the full
// computation from nothing. The adaptive side keeps its pair buffer and
// scratch from frame to frame; its output starts as a copy of its previous
// output, or every other frame as other bytes, the previous output handed
// over as KeptOutput; where the layout is the pair itself (and the output
// packed RGB) the pair is the output.
class WarpPackRun {
 public:
  WarpPackRun(const WarpPackCase &c, int w, int h) : c_(c), w_(w), h_(h) {
    pack_size(c.pack.layout, w, h, &out_w_, &out_h_);
    pair_is_out_ = pack_is_identity(c.pack) && is_packed_rgb(c.out_format);
    pair_format_ = is_packed_rgb(c.out_format) ? c.out_format : PixelFormat::RGBA;
    pair_ = HostFrame(pair_format_, 2 * w, h, 8);
    out_ = HostFrame(c.out_format, out_w_, out_h_, 3);
    pair_.fill(0x3C);
    out_.fill(0xC3);
    if (!c.active.empty()) {
      active_pair_ = HostFrame(pair_format_, 2 * c.active.width(), c.active.height(), 4);
      active_pair_.fill(0x69);
    }
  }

  // One frame: the first computes everything, later ones the changes
  // since the previous frame (StageInputs: source and depth map).
  ::testing::AssertionResult frame(const HostFrame &src, const cv::Mat &depth) {
    const ChangeMap changes = inputs_.compare(
        src.view(), cview(depth), prev_depth_.empty() ? ImageView<const float>() : cview(prev_depth_), 0.f);
    HostFrame pair_full(pair_format_, 2 * w_, h_, 2), out_full(c_.out_format, out_w_, out_h_, 1);
    pair_full.fill(0xA5);
    out_full.fill(0x5A);
    long long holes_full;
    const bool cropped = !c_.active.empty();
    if (cropped) {  // the full computation with the rect: from nothing, as ActiveWarp tests prove it
      HostFrame active_full(pair_format_, 2 * c_.active.width(), c_.active.height(), 0);
      WarpCpuScratch fresh;
      const ActiveArea area{c_.active, active_full.view()};
      const FrameView full_pair = pair_is_out_ ? out_full.view() : pair_full.view();
      holes_full = warp_pack_changed_cpu(c_.warp, c_.pack, src.view(), m_, cview(depth), full_pair, out_full.view(),
                                         fresh, nullptr, &area);
      if (pair_is_out_) pair_full = out_full;
    } else {
      holes_full = warp_render_cpu(c_.warp, src.view(), m_, cview(depth), pair_full.view());
      if (!pair_is_out_) pack_cpu(c_.pack, pair_full.view(), out_full.view());
    }
    // Every other frame the output buffer starts as other bytes and the
    // call takes the rows it does not write from the kept previous output
    // (KeptOutput); the others start as a copy of it.
    const bool from_kept = frames_++ % 2 == 1;
    HostFrame next = out_;
    if (from_kept) next.fill(0x77);
    const FrameView previous = out_.view();
    KeptOutput kept{from_kept ? &previous : nullptr, {}};
    const FrameView pair = pair_is_out_ ? next.view() : pair_.view();
    const ActiveArea area{c_.active, active_pair_.view()};
    const long long holes = warp_pack_changed_cpu(c_.warp, c_.pack, src.view(), m_, cview(depth), pair, next.view(),
                                                  scratch_, prev_depth_.empty() ? nullptr : &changes,
                                                  cropped ? &area : nullptr, &kept);
    const bool first = prev_depth_.empty();
    prev_depth_ = depth;
    // The kept copy brought up to date in the rows written: the output.
    HostFrame updated = out_;
    copy_flagged_rows(next.view(), updated.view(), kept.written, true);
    const ::testing::AssertionResult written_same = same_bytes(updated.view(), next.view());
    out_ = next;
    auto fail = [&]() {
      return ::testing::AssertionFailure() << 100 * changes.fraction() << "% of the tiles changed, " << holes_full
                                           << " holes" << (from_kept ? ", from the kept output" : "") << ": ";
    };
    if (holes < 0) return fail() << "frames do not fit";
    if (!written_same) return fail() << "rows written: " << written_same.message();
    if (first && holes != holes_full) return fail() << holes << " holes, full " << holes_full;
    const ::testing::AssertionResult pair_same = same_bytes(pair, pair_full.view());
    if (!pair_same) return fail() << "pair: " << pair_same.message();
    if (!pair_is_out_) {
      const ::testing::AssertionResult out_same = same_bytes(next.view(), out_full.view());
      if (!out_same) return fail() << "output: " << out_same.message();
    }
    return ::testing::AssertionSuccess();
  }

 private:
  WarpPackCase c_;
  int w_, h_, out_w_ = 0, out_h_ = 0;
  bool pair_is_out_ = false;
  PixelFormat pair_format_ = PixelFormat::RGBA;
  HostFrame pair_, out_, active_pair_;
  WarpCpuScratch scratch_;
  StageInputs inputs_;
  cv::Mat prev_depth_;
  const YuvToRgb m_;
  int frames_ = 0;
};

// A depth map of narrow near and far stripes in blocks of rows: holes
// everywhere, at every distance from each other.
cv::Mat hole_rich_depth(int w, int h, std::mt19937 &rng) {
  cv::Mat d(h, w, CV_32FC1);
  for (int y0 = 0; y0 < h;) {
    const int y1 = std::min(h, y0 + uniform(rng, 1, 12));
    for (int x0 = 0; x0 < w;) {
      const int x1 = std::min(w, x0 + uniform(rng, 1, 14));
      d(cv::Rect(x0, y0, x1 - x0, y1 - y0)).setTo(cv::Scalar(uniform(rng, 0, 1) ? 1.f : 0.f));
      x0 = x1;
    }
    y0 = y1;
  }
  return d;
}

// Frames of W x H (default: 97 x 67) whose source and depth change in a
// few rects each frame; every frame's output is compared with the full
// computation. hole_rich: the depth of hole_rich_depth() instead of a few
// near rects.
::testing::AssertionResult run_warp_sequence(const WarpPackCase &c, uint32_t seed, int W = 97, int H = 67,
                                             int frames = 7, bool hole_rich = false) {
  std::mt19937 rng(seed);
  HostFrame src(c.src_format, W, H, 3);
  src.fill_random(rng());
  cv::Mat depth = hole_rich ? hole_rich_depth(W, H, rng) : warp_depth_map(W, H, rng);
  WarpPackRun run(c, W, H);
  for (int frame = 0; frame < frames; ++frame) {
    const char *what = "first";
    if (frame > 0) {
      switch (uniform(rng, 0, 5)) {
        case 0: what = "unchanged, the same map"; break;
        case 1:
          what = "unchanged, a copy of the map";
          depth = depth.clone();
          break;
        case 2:
          what = "source";
          for (int k = uniform(rng, 1, 3); k > 0; --k) scribble(src, rect_in_tile(rng, W, H, 8), rng);
          break;
        case 3:
          what = "depth";
          depth = depth.clone();
          for (int k = uniform(rng, 1, 3); k > 0; --k) {
            const PixelRect r = rect_in_tile(rng, W, H, 20);
            if (hole_rich)  // new stripes: holes appear and go
              hole_rich_depth(r.width(), r.height(), rng).copyTo(depth(cv::Rect(r.x0, r.y0, r.width(), r.height())));
            else
              new_depth(depth, r, rng);
          }
          break;
        default:
          what = "source and depth";
          depth = depth.clone();
          for (int k = uniform(rng, 1, 4); k > 0; --k) {
            scribble(src, rect_in_tile(rng, W, H, 32), rng);
            new_depth(depth, rect_in_tile(rng, W, H, 20), rng);
          }
          break;
      }
    }
    const ::testing::AssertionResult same = run.frame(src, depth);
    if (!same) return ::testing::AssertionFailure() << "frame " << frame << " (" << what << "): " << same.message();
  }
  return ::testing::AssertionSuccess();
}

// A column of near depth down the whole picture: BackgroundSmooth's holes
// beside it run from the top row to the bottom one.
cv::Mat near_column_depth(int w, int h) {
  cv::Mat d(h, w, CV_32FC1, cv::Scalar(0.f));
  d(cv::Rect(w / 2 - 10, 0, 20, h)).setTo(cv::Scalar(1.f));
  return d;
}

WarpPackCase smooth_case(StereoView view, float max_disparity) {
  WarpPackCase c;
  c.warp = test::warp_params(max_disparity, 0.5f, view, HoleFill::BackgroundSmooth);
  c.pack = test::pack_params(PackLayout::SideBySide);
  c.src_format = c.out_format = PixelFormat::RGBA;
  return c;
}

// BackgroundSmooth refills the rows within its radius R of a changed row
// (5 here): with the source changed in the first and the last row of
// tiles of 97 x 67, rows 0-36 and 59-66. Rows 59-63 sit between two runs
// of such rows, the first of which is not a whole number of the fill's
// bands (32 rows) long.
TEST(AdaptiveWarpPack, BackgroundSmoothFillsEveryRowItReaches) {
  const int W = 97, H = 67;
  std::mt19937 rng(3500);
  const WarpPackCase c = smooth_case(StereoView::Both, 20.f);
  HostFrame src(c.src_format, W, H, 0);
  src.fill_random(rng());
  const cv::Mat depth = near_column_depth(W, H);
  WarpPackRun run(c, W, H);
  ASSERT_TRUE(run.frame(src, depth));
  scribble(src, PixelRect{0, 0, W, 1}, rng);
  scribble(src, PixelRect{0, 64, W, H}, rng);
  EXPECT_TRUE(run.frame(src, depth));
}

// The sweep's case `index`: parameters, formats and eye order rotate with it.
WarpPackCase sweep_case(HoleFill fill, StereoView view, PackLayout layout, bool yuv, int index) {
  WarpPackCase c;
  c.warp = test::warp_params(20.f, index % 3 == 0 ? 0.5f : 0.3f, view, fill);
  c.pack = test::pack_params(layout, AnaglyphGlasses::RedCyan,
                             index / 4 % 2 ? AnaglyphMethod::DuboisLinear : AnaglyphMethod::Dubois,
                             layout != PackLayout::SideBySide && index % 3 == 1);
  c.src_format = kAllFormats[index % 6];
  c.out_format = yuv ? (index / 2 % 2 ? PixelFormat::NV12 : PixelFormat::I420) : kPackedFormats[index / 2 % 4];
  return c;
}

// BackgroundSmooth with a copied eye (view left or right): its sweep runs
// in a child process (BackgroundSmoothWithACopiedEye).
bool copied_eye_smooth(HoleFill fill, StereoView view) {
  return fill == HoleFill::BackgroundSmooth && view != StereoView::Both;
}

TEST(AdaptiveWarpPack, ChangedTilesGiveTheFullWarpAndPack) {
  uint32_t seed = 3000;
  int index = 0;
  long long pair_is_out = 0;
  for (const HoleFill fill : kAllFills)
    for (const StereoView view : kAllViews)
      for (const PackLayout layout : kAllLayouts)
        for (const bool yuv : {false, true}) {
          const WarpPackCase c = sweep_case(fill, view, layout, yuv, index++);
          if (copied_eye_smooth(fill, view)) continue;
          pair_is_out += pack_is_identity(c.pack) && !yuv;
          SCOPED_TRACE(warp_case_text(c));
          EXPECT_TRUE(run_warp_sequence(c, seed + index));
        }
  EXPECT_EQ(pair_is_out, 4 * 3 - 2);  // every fill and view with the pair as the output
}

// The same inside bars (warp_pack_changed_cpu with an ActiveArea): a
// letterbox, rendered into the pair's rows, and a pillarbox and both,
// rendered apart and placed; changes fall inside and outside the rect.
TEST(AdaptiveWarpPack, ChangedTilesGiveTheFullWarpAndPackInsideBars) {
  uint32_t seed = 3900;
  int index = 0;
  const PixelRect rects[] = {{0, 16, 97, 56}, {16, 0, 80, 67}, {8, 8, 88, 64}};
  for (const HoleFill fill : kAllFills)
    for (const PackLayout layout : kAllLayouts)
      for (const bool yuv : {false, true}) {
        WarpPackCase c = sweep_case(fill, StereoView::Both, layout, yuv, index++);
        c.active = rects[index % 3];
        SCOPED_TRACE(warp_case_text(c) + " rect " + rect_text(c.active));
        EXPECT_TRUE(run_warp_sequence(c, seed + index));
      }
}

// Rows much wider than the spans' reach: the warp renders again only the
// columns a change reaches (warp_render_cpu, ColumnSpan), out to a clean
// pixel on either side for BackgroundSmooth, whose fill then runs over the
// rows and columns those reach. Depth of narrow stripes puts holes and
// their runs at every distance from the windows' edges; changes in one
// tile at a time, frame after frame, some making and removing holes.
TEST(AdaptiveWarpPack, ColumnWindowsOfWideRowsGiveTheFullWarp) {
  uint32_t seed = 4100;
  int index = 0;
  for (const HoleFill fill : kAllFills)
    for (const StereoView view : kAllViews)
      for (const PackLayout layout : {PackLayout::SideBySide, PackLayout::SideBySideHalf, PackLayout::Anaglyph}) {
        WarpPackCase c = sweep_case(fill, view, layout, false, index++);
        if (copied_eye_smooth(fill, view)) continue;
        // 2 % and 5 %: the fill's Rx (R / 4) is within kSmoothClean; 16 %
        // on 640 columns: beyond it.
        for (const float disparity : {2.f, 5.f}) {
          c.warp.max_disparity = disparity;
          SCOPED_TRACE(warp_case_text(c));
          EXPECT_TRUE(run_warp_sequence(c, seed + index, 420, 70, 10, true));
          EXPECT_TRUE(run_warp_sequence(c, seed + 1000 + index, 333, 40, 10, false));
        }
        c.warp.max_disparity = 16.f;
        SCOPED_TRACE(warp_case_text(c));
        EXPECT_TRUE(run_warp_sequence(c, seed + 2000 + index, 640, 48, 8, true));
      }
}

// In a child process: one changed pixel after a first frame in a minimal
// case, or the sweep's sequences over every layout and output. Exits 0
// when every frame equals the full computation, 1 (saying where) when not.
[[noreturn]] void one_change_then_exit(const WarpPackCase &c) {
  const int W = 97, H = 67;
  std::mt19937 rng(3600);
  HostFrame src(c.src_format, W, H, 0);
  src.fill_random(rng());
  const cv::Mat depth = near_column_depth(W, H);
  WarpPackRun run(c, W, H);
  ::testing::AssertionResult same = run.frame(src, depth);
  if (same) {
    scribble(src, PixelRect{40, 40, 41, 41}, rng);
    same = run.frame(src, depth);
  }
  if (!same) std::fprintf(stderr, "%s\n", same.message());
  std::exit(same ? 0 : 1);
}
[[noreturn]] void sweep_then_exit(HoleFill fill, StereoView view) {
  int index = 0, failures = 0;
  for (const HoleFill f : kAllFills)
    for (const StereoView v : kAllViews)
      for (const PackLayout layout : kAllLayouts)
        for (const bool yuv : {false, true}) {
          const WarpPackCase c = sweep_case(f, v, layout, yuv, index++);
          if (f != fill || v != view) continue;
          const ::testing::AssertionResult same = run_warp_sequence(c, 3000 + index);
          if (!same) {
            std::fprintf(stderr, "%s: %s\n", warp_case_text(c).c_str(), same.message());
            ++failures;
          }
        }
  std::exit(failures ? 1 : 0);
}

// An eye that is the source copied (view left or right; both with no
// disparity) has no BackgroundSmooth fill; a changed row must not run one
// on it. In child processes, so that a crash fails this test alone.
TEST(AdaptiveWarpPack, BackgroundSmoothWithACopiedEye) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  for (const auto &[view, disparity] : {std::pair<StereoView, float>{StereoView::Right, 20.f},
                                        std::pair<StereoView, float>{StereoView::Left, 20.f},
                                        std::pair<StereoView, float>{StereoView::Both, 0.f}}) {
    const WarpPackCase c = smooth_case(view, disparity);
    SCOPED_TRACE(warp_case_text(c));
    EXPECT_EXIT(one_change_then_exit(c), ::testing::ExitedWithCode(0), "");
  }
  for (const StereoView view : kAllViews)
    if (copied_eye_smooth(HoleFill::BackgroundSmooth, view)) {
      SCOPED_TRACE(::testing::Message() << "the sweep's cases of view " << enum_nick(kStereoViewNames, view));
      EXPECT_EXIT(sweep_then_exit(HoleFill::BackgroundSmooth, view), ::testing::ExitedWithCode(0), "");
    }
}

}  // namespace
}  // namespace p3d
