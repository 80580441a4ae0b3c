// DepthGrid (common/p3d_defs.h): the grid geometry and copy-out that the GPU
// stages' depth handoff and its read-backs rely on, and the shifts the
// estimator and the filter hand on at.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "bilateral.h"
#include "depth_estimate.h"
#include "p3d_defs.h"

namespace p3d {
namespace {

TEST(DepthGrid, CellsCoverThePictureWithPartialCellsAtTheEdges) {
  EXPECT_EQ(grid_cells(1, 0), 1);
  EXPECT_EQ(grid_cells(3840, 2), 960);
  EXPECT_EQ(grid_cells(3841, 2), 961);
  EXPECT_EQ(grid_cells(1, 3), 1);
  EXPECT_EQ(grid_cells(7, 3), 1);
  EXPECT_EQ(grid_cells(9, 3), 2);
  EXPECT_EQ(grid_cells(65536, 6), 1024);
  EXPECT_EQ(grid_cells(2147483647, 1), 1073741824);  // no overflow in the rounding up
}

TEST(DepthGrid, StepShiftIsLog2OfPowersOfTwoOnly) {
  EXPECT_EQ(step_shift(1), 0);
  EXPECT_EQ(step_shift(2), 1);
  EXPECT_EQ(step_shift(4), 2);
  EXPECT_EQ(step_shift(64), 6);
  for (int s : {0, -4, 3, 6, 12, 63}) EXPECT_EQ(step_shift(s), -1) << s;
}

// Each pixel reads its own cell, cells cut at the right and bottom edges
// included, through at() and through expand_grid() alike.
TEST(DepthGrid, ExpandCopiesEachCellToItsPixels) {
  for (int shift : {0, 1, 2, 3}) {
    const int w = 13, h = 6, cw = grid_cells(w, shift), ch = grid_cells(h, shift);
    const int pitch = cw + 3;  // padded rows: a pitch taken for the width shows
    std::vector<float> cells(static_cast<size_t>(pitch) * ch, NAN);
    for (int y = 0; y < ch; ++y)
      for (int x = 0; x < cw; ++x) cells[static_cast<size_t>(y) * pitch + x] = static_cast<float>(y * cw + x) + 0.5f;
    const DepthGrid<const float> g{ImageView<const float>{cells.data(), cw, ch, pitch * sizeof(float)}, w, h, shift};
    EXPECT_TRUE(grid_fits(g));
    std::vector<float> full(static_cast<size_t>(w) * h, NAN);
    expand_grid(g, ImageView<float>{full.data(), w, h, w * sizeof(float)});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float want = static_cast<float>((y >> shift) * cw + (x >> shift)) + 0.5f;
        EXPECT_EQ(full[static_cast<size_t>(y) * w + x], want) << "shift " << shift << " at " << x << "," << y;
        EXPECT_EQ(g.at(x, y), want);
      }
  }
}

TEST(DepthGrid, FitsOnlyWithTheCellsOfItsPictureAndShift) {
  float cell = 0.f;
  const ImageView<const float> one{&cell, 1, 1, sizeof(float)};
  EXPECT_TRUE(grid_fits(DepthGrid<const float>{one, 4, 4, 2}));
  EXPECT_FALSE(grid_fits(DepthGrid<const float>{one, 5, 4, 2}));
  EXPECT_FALSE(grid_fits(DepthGrid<const float>{one, 4, 4, 1}));
  EXPECT_FALSE(grid_fits(DepthGrid<const float>{one, 4, 4, -1}));
}

// The estimator hands its blocks on where they are a power of two (the
// automatic sizes at 1080p, 4K and 8K, not at 1620 rows), the filter its
// cells where its step is one above 1.
TEST(DepthGrid, StagesHandOnAtTheirPowerOfTwoSteps) {
  DepthParams d;
  EXPECT_EQ(block_grid_shift(d, 1920, 1080), 1);  // automatic block 2
  EXPECT_EQ(block_grid_shift(d, 3840, 2160), 2);  // 4
  EXPECT_EQ(block_grid_shift(d, 7680, 4320), 3);  // 8
  EXPECT_EQ(block_grid_shift(d, 2880, 1620), 0);  // 3: full-size
  d.block_size = 6;
  EXPECT_EQ(block_grid_shift(d, 3840, 2160), 0);
  d.block_size = 1000;  // clamped to 64
  EXPECT_EQ(block_grid_shift(d, 3840, 2160), 6);
  const BilateralParams f = bilateral_sanitize(default_filter_params());
  EXPECT_EQ(bilateral_grid_shift(f, 1920, 1080), 0);  // step 1: full-size
  EXPECT_EQ(bilateral_grid_shift(f, 3840, 2160), 2);  // step 4
  EXPECT_EQ(bilateral_grid_shift(f, 7680, 4320), 2);
  BilateralParams three = f;
  three.scale = 3;
  EXPECT_EQ(bilateral_grid_shift(three, 3840, 2160), 0);
  BilateralParams identity = f;
  identity.radius = 0;
  EXPECT_EQ(bilateral_grid_shift(identity, 7680, 4320), 0);  // radius 0 needs no grid
}

}  // namespace
}  // namespace p3d
