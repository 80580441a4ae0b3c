// What changed since the previous frame, tile by tile: the bookkeeping of
// the adaptive stages (docs/architecture.md, "Adaptive work"). A stage
// compares its inputs with those of the frame before, recomputes the
// output tiles that a changed input can reach, and keeps the rest of its
// previous output: with tolerance 0 the output is, byte for byte, what a
// full computation gives.
//
// The picture is cut into kChangeTile x kChangeTile tiles (the last row
// and column may be partial). A ChangeMap holds one flag a tile. Reach
// (ChangeMap::dilated) is given in pixels and rounded up to whole tiles,
// so a dilated map covers every pixel within that reach of a changed one.
#pragma once

#include <cstdint>
#include <vector>

#include "frame.h"

namespace p3d {

// 32 pixels: a multiple of every power-of-two depth block and filter cell
// up to 32 and even (a 4:2:0 tile holds whole chroma samples); small
// enough that a cursor or a clock is a few tiles, large enough that the
// flags of a 4K picture (120 x 68) cost nothing to walk.
constexpr int kChangeTile = 32;

// The changed columns [x0, x1) of one row of pixels (empty: x0 >= x1).
struct ColumnSpan {
  int x0 = 0, x1 = 0;
  bool empty() const { return x0 >= x1; }
};

class ChangeMap {
 public:
  ChangeMap() = default;
  // A width x height picture with every tile changed (all) or none.
  ChangeMap(int width, int height, bool all);

  int width() const { return width_; }
  int height() const { return height_; }
  int tiles_x() const { return tiles_x_; }
  int tiles_y() const { return tiles_y_; }
  bool same_geometry(const ChangeMap &o) const { return width_ == o.width_ && height_ == o.height_; }

  bool tile(int tx, int ty) const { return flags_[static_cast<size_t>(ty) * tiles_x_ + tx] != 0; }
  void mark(int tx, int ty) { flags_[static_cast<size_t>(ty) * tiles_x_ + tx] = 1; }
  // Marks every tile that a pixel of r (clipped to the picture) lies in.
  void mark_pixels(PixelRect r);
  void mark_all();

  bool any() const;
  bool all() const;
  // Whether row of tiles ty holds a changed tile; whether every row does
  // (rows() all set).
  bool row_changed(int ty) const;
  bool all_rows() const;
  // Share of the tiles changed (0..1).
  double fraction() const;

  // Tiles changed in this map or in o (same geometry; o of another size
  // marks every tile).
  void merge(const ChangeMap &o);
  // Every tile within reach_x pixels across and reach_y down or up of a
  // changed tile's pixels.
  ChangeMap dilated(int reach_x, int reach_y) const;
  // The map of the picture inside r (within this picture): its tiles, cut
  // from r's corner, are marked where a changed tile of this map overlaps.
  ChangeMap cropped(PixelRect r) const;
  // The pixel rows of the changed tiles: one flag a row (height()).
  std::vector<uint8_t> rows() const { return rows_within(0); }
  // The pixel rows within `reach` rows of a changed tile's rows
  // (row_within_reach): one flag a row.
  std::vector<uint8_t> rows_within(int reach) const;
  // Each pixel row's changed columns (height() spans): from the first
  // changed tile of its row of tiles to the last, clipped to the picture.
  std::vector<ColumnSpan> row_spans() const;
  // The share of the picture's pixels inside row_spans().
  double span_share() const;
  // The changed tiles as rectangles of pixels: in each row of tiles, the
  // maximal runs of changed tiles, clipped to the picture; a run with the
  // columns of one in the row of tiles above extends that rectangle down.
  std::vector<PixelRect> runs() const;

 private:
  int width_ = 0, height_ = 0, tiles_x_ = 0, tiles_y_ = 0;
  std::vector<uint8_t> flags_;
};

// Tiles along an axis of `pixels`.
P3D_HD int change_tiles(int pixels) { return (pixels + kChangeTile - 1) / kChangeTile; }

// A rectangle of pixels: the tile's, clipped to a width x height picture.
P3D_HD PixelRect tile_pixels(int tx, int ty, int width, int height) {
  const int x1 = (tx + 1) * kChangeTile, y1 = (ty + 1) * kChangeTile;
  return PixelRect{tx * kChangeTile, ty * kChangeTile, x1 < width ? x1 : width, y1 < height ? y1 : height};
}

// Whether pixel row y of a picture of `height` rows lies within `reach`
// rows (up or down) of a row of tiles with a changed tile; tile_rows: one
// flag a row of tiles (ChangeMap::row_changed). The rule of
// ChangeMap::rows_within on the host and of the adaptive warp's rows on
// the device.
P3D_HD bool row_within_reach(const uint8_t *tile_rows, int height, int y, int reach) {
  const int y0 = y - reach < 0 ? 0 : y - reach, y1 = y + reach >= height ? height - 1 : y + reach;
  for (int ty = y0 / kChangeTile; ty <= y1 / kChangeTile; ++ty)
    if (tile_rows[ty]) return true;
  return false;
}

// Tiles on either side that a reach of `pixels` covers: a changed pixel at
// a tile's edge reaches that far into the tiles beside it.
P3D_HD int reach_tiles(int pixels) { return pixels > 0 ? (pixels + kChangeTile - 1) / kChangeTile : 0; }

// The bytes of plane `plane` of a frame that hold the pixels of r: [b0, b1)
// of each of the rows [r0, r1). 4:2:0 chroma: the samples of r's 2 x 2
// blocks (r starts on even coordinates: tiles do).
struct PlaneBox {
  int b0, b1, r0, r1;
};
P3D_HD PlaneBox plane_box(PixelFormat f, int plane, const PixelRect &r) {
  if (is_packed_rgb(f)) {
    const int px = packed_pixel_bytes(f);
    return PlaneBox{px * r.x0, px * r.x1, r.y0, r.y1};
  }
  const int sb = sample_bytes(f);
  if (plane == 0) return PlaneBox{sb * r.x0, sb * r.x1, r.y0, r.y1};
  const int c0 = r.x0 / 2, c1 = (r.x1 + 1) / 2, bytes = sb * (is_semi_planar(f) ? 2 : 1);
  return PlaneBox{bytes * c0, bytes * c1, r.y0 / 2, (r.y1 + 1) / 2};
}

// How many units of a format's stored samples make one 8-bit level: 1 for
// the 8-bit formats, 256 for 16-bit samples (P010's codes sit in the high
// bits), 4 for I420_10's 10-bit codes.
P3D_HD int units_per_level(PixelFormat f) {
  return !is_deep(f) ? 1 : (f == PixelFormat::I420_10 ? 4 : 256);
}

// A tile compared with tolerance t > 0 (FrameHistory) counts as changed
// when the mean |difference| of its `samples` samples exceeds t (in the
// samples' units: t 8-bit levels times units_per_level()).
P3D_HD bool tile_over_tolerance(unsigned long long diff, unsigned long long samples, float tolerance) {
  return samples > 0 && static_cast<double>(diff) > static_cast<double>(tolerance) * static_cast<double>(samples);
}

// When a stage compares its inputs with the previous frame's. A stage
// whose inputs keep changing gains nothing from the comparison, which then
// only adds its cost (on the GPU, where a stage is a few passes over the
// frame, as much as the stage saves on a partly changed frame). After a
// compared frame that was busy (the stage's rule; on the GPU: anything
// changed), the stage computes the next frames whole without comparing,
// its histories reset (what they hold is then out of date), and compares
// again after them: the first comparison of a fresh history finds every
// tile changed and is not observed; the one after it tells whether the
// scene calmed down. Busy on the CPU: more than kBusyShare of the tiles
// changed (busy_on_cpu), where a stage's saving is small beside the
// comparison and the copies into the histories, or what busy_for() says
// for a stage whose work follows the change otherwise (common/adaptive.h:
// whole rows, the warp's spans); a partly changed frame there saves more
// than it costs, so the stage goes on comparing. The pause doubles while the frames stay busy, from
// kBackOffFrames up to kBackOffMax, so that a film pays a comparison
// every few seconds and a scene that stops is found within that. Whole
// frames are what adaptive=false computes: the output stays exact.
constexpr int kBackOffFrames = 16;
constexpr double kBusyShare = 0.75;
// The warp's busy share: widened by its reach, spans over more than this
// share of the picture (busy_for) cover nearly every row; on CUDA memory,
// changes that reach more than this share of its rows
// (KeptOutputGpu::last_busy).
constexpr double kWholeWarpShare = 0.9;
constexpr int kBackOffMax = 128;
class ChangeBackOff {
 public:
  // A compared frame's changes on the CPU: busy or not.
  static bool busy_on_cpu(double changed_share) { return changed_share > kBusyShare; }
  // Before a frame: false when the stage computes it whole, uncompared.
  bool compare_next() {
    if (skip_ == 0) return true;
    --skip_;
    return false;
  }
  // After a compared frame that was compared with a previous one.
  void observe(bool busy) {
    skip_ = busy ? pause_ : 0;
    pause_ = busy ? (2 * pause_ < kBackOffMax ? 2 * pause_ : kBackOffMax) : kBackOffFrames;
  }
  void reset() {
    skip_ = 0;
    pause_ = kBackOffFrames;
  }

 private:
  int skip_ = 0, pause_ = kBackOffFrames;
};

// Compares each frame with the one before (a copy kept here) and tells
// which tiles differ. tolerance 0: a tile differs when any of its bytes
// does. tolerance t > 0: when the mean |difference| of its bytes (every
// plane's samples of the tile) exceeds t 8-bit levels; the copy then keeps
// the bytes of the last frame in which the tile counted as changed, so
// slow drift adds up until it does.
class FrameHistory {
 public:
  // The tiles of `frame` that differ from the previous frame's. Every
  // tile, when there is no previous frame or it had another size or
  // format. Records the changed tiles' bytes as the new reference.
  ChangeMap compare(const FrameView &frame, float tolerance = 0.f);
  // Whether the last compare() had a previous frame of its size and format.
  bool compared() const { return compared_; }
  void reset() {
    planes_.clear();
    compared_ = false;
  }

 private:
  struct Plane {
    std::vector<uint8_t> bytes;
    int row_bytes = 0, rows = 0;
  };
  PixelFormat format_ = PixelFormat::RGBA;
  int width_ = 0, height_ = 0;
  std::vector<Plane> planes_;
  bool compared_ = false;
};

// The tiles in which two float planes of one size differ in any byte
// (all tiles when their sizes differ).
ChangeMap compare_planes(ImageView<const float> a, ImageView<const float> b);
// The same for two grids (p3d_defs.h DepthGrid) of one geometry: the tiles
// with a pixel of a cell whose values differ in any byte (all tiles when
// the geometries differ). compare_planes() is its case of shift 0.
ChangeMap compare_grids(DepthGrid<const float> a, DepthGrid<const float> b);

// Copies the rows and columns of rect r from one float plane to another of
// the same size.
void copy_plane_rect(ImageView<const float> from, ImageView<float> to, PixelRect r);

// Copies `rows` rows of row_bytes bytes between two strided buffers. The
// copies of frames the adaptive stages keep and restore are memory-bound
// and, on a machine of many cores, a copy on one core costs more than a
// stage's work on an unchanged frame: bands of rows are copied in
// parallel.
void copy_rows(uint8_t *to, size_t to_stride, const uint8_t *from, size_t from_stride, size_t row_bytes, int rows);

}  // namespace p3d
