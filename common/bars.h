// Letterbox and pillarbox bars: the black bands a film of another aspect
// ratio gets in the frame. With crop-bars=auto the 3D stages run on the
// picture between them (the active rect) and hand the bars on as they are,
// so the bars stay black in both views and no depth edge comes from them
// (docs/architecture.md, "Bars").
//
//  1. Counts. Per row and per column, the pixels brighter than the bar
//     level (bar_pixel_bright()): bar_counts_cpu, and BarCountsGpu on
//     the device (cuda/bars_gpu.h), the same integers.
//  2. Measure. The picture's rows and columns are those with more bright
//     pixels than a 1/64 share of their length (noise in a compressed bar
//     stays under it); measure_active_rect() moves their bounding rect's
//     top left corner up and left onto kBarAlign cells.
//  3. Decide. BarTracker adopts a measured rect only when it is plausible
//     (bars on opposite sides of about equal size, at least half of the
//     frame each way) and it has been measured on kBarConfirmFrames
//     frames in a row; a darker or asymmetric frame (a fade to black, a
//     night sky, a subtitle in a bar) keeps the rect. The first frame, a
//     scene cut (the rows' counts move by an eighth of the frame's pixels)
//     and a reset adopt the next plausible measure at once.
//  4. Order. A frame's rect comes from the counts of the frames before it,
//     the previous frame's last (BarTracker::previous_due), so that on CUDA
//     memory a frame's counts are read back at the next frame instead of
//     waited for before its depth is queued; a frame with no counted frame
//     before it (the first, after a reset) is decided from its own
//     (BarTracker::counted). A cut or a new rect thus takes effect one
//     frame after the frame that shows it, on both devices alike.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "bilateral.h"
#include "change_map.h"
#include "depth_estimate.h"
#include "frame.h"
#include "warp.h"

namespace p3d {

// A pixel is part of the picture when its brightest R'G'B' channel, or on
// Y'CbCr its Y' in 8-bit R'G'B' levels, is over this level.
constexpr int kBarLevel = 24;
// The active rect's top left corner lies on multiples of this many
// pixels: a whole 4:2:0 chroma sample and a corner of the cells of the
// depth grids the GPU stages hand on (blocks and filter cells up to 8
// pixels). The bottom right corner is where the picture ends.
constexpr int kBarAlign = 8;
// Frames a new rect must be measured in a row before it is adopted.
constexpr int kBarConfirmFrames = 8;

// The Y' code over which a Y'CbCr pixel is brighter than kBarLevel (8-bit
// levels; a code of the depth m converts: 10 bits for 10-bit parameters).
inline int bar_luma_threshold(const YuvToRgb &m) {
  return static_cast<int>(m.y_offset + static_cast<float>(kBarLevel) * (static_cast<float>(m.top) / 255.f) / m.y_scale);
}

P3D_HD bool bar_pixel_bright(const FrameView &f, int x, int y, int luma_threshold) {
  if (is_rgba64(f.format)) {
    const Rgba16 c = load_packed16(f, x, y);
    const int brightest = c.r > c.g ? (c.r > c.b ? c.r : c.b) : (c.g > c.b ? c.g : c.b);
    return brightest > kBarLevel * 257;
  }
  if (is_deep(f.format)) return load_code(f, 0, y, x) > luma_threshold;
  if (is_packed_rgb(f.format)) {
    const uint8_t *p = f.plane[0] + static_cast<size_t>(y) * f.stride[0] + 4 * x;
    const int brightest = p[0] > p[1] ? (p[0] > p[2] ? p[0] : p[2]) : (p[1] > p[2] ? p[1] : p[2]);
    return brightest > kBarLevel;
  }
  return f.plane[0][static_cast<size_t>(y) * f.stride[0] + x] > luma_threshold;
}

// Bright pixels of each row (height values) and of each column (width).
// band_cols: bar_counts_cpu's column counts of each band of kChangeTile
// rows, kept so that a frame recounts only the bands that changed.
struct BarCounts {
  std::vector<uint32_t> rows, cols, band_cols;
};
// changes: the tiles that changed since the frame `counts` holds (from
// this function), null: every row is counted. With a reuse tolerance the
// bands of tiles under it keep the counts of the frame they were counted
// on, as the stages keep their other results there.
void bar_counts_cpu(const FrameView &frame, int luma_threshold, BarCounts *counts,
                    const ChangeMap *changes = nullptr);

// The picture's bounding rect, its top left corner moved onto kBarAlign
// cells; empty when no row has picture.
PixelRect measure_active_rect(const BarCounts &counts);

// Both views of the pixels outside `active`: the source converted
// (load_rgba), unshifted. pair: the views side by side (packed RGB, twice
// the source's width); rows: one flag a source row (null: all rows).
void views_outside_cpu(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                       const std::vector<uint8_t> *rows);
// Copies the pair of the active picture (packed RGB, 2 w x h: the left
// view, then the right) into its place in the pair of the frame (left view
// at (x0, y0), right view at (W + x0, y0)); rows: one flag a row of the
// active pair (null: all).
void place_active_pair_cpu(const FrameView &active_pair, PixelRect active, const FrameView &pair,
                           const std::vector<uint8_t> *rows);

// Where the warp renders the views (warp_pack_changed_cpu() and
// ActiveWarpGpu): from the picture inside `rect` only, with the parallax
// of the whole frame's width (active_warp_params()); outside it both
// views are the source (views_outside_cpu). Where the rect is narrower
// than the frame the views are rendered into `pair` (packed RGB,
// 2 w x h, kept between calls by an adaptive caller) and placed from
// there; a rect of the frame's width renders into the frame pair's rows.
struct ActiveArea {
  PixelRect rect;
  FrameView pair;
};

// The warp's parameters for a picture `active_width` wide inside a frame
// `frame_width` wide: the same parallax in pixels (max_disparity is a
// share of the width), within kMaxDisparityPercent.
WarpParams active_warp_params(const WarpParams &params, int frame_width, int active_width);

// rect where its corner lies on the grid of 2^shift-pixel cells, else the
// whole width x height picture: the stages on CUDA memory read the depth's
// cells in place, so the picture they work on starts on a cell
// (pseudo3ddepth's block grid, pseudo3dfilter's cell grid).
PixelRect rect_on_cells(PixelRect rect, int shift, int width, int height);

// The cells of a depth grid (grid_cells of its picture at `shift`, cells_w
// x cells_h) outside the active rect r: the bands above, below, left and
// right of it (some empty). A plane's depth there is 0
// (DepthPlane::set_active).
std::array<PixelRect, 4> cells_outside(PixelRect r, int shift, int cells_w, int cells_h);

// The automatic sizes of the whole frame (the depth's block, the filter's
// grid step) made explicit, for stages that run inside an active rect: a
// film in bars is estimated and filtered at the scale of its frame, as
// without the crop. Parameters that set them keep theirs.
DepthParams frame_scaled(const DepthParams &p, int frame_width, int frame_height);
BilateralParams frame_scaled(const BilateralParams &p, int frame_width, int frame_height);

class BarTracker {
 public:
  // Takes one frame's counts; active() is then the rect decided from them
  // and those observed before.
  void observe(const BarCounts &counts);
  // The order of step 4, per frame: before counting it, whether the
  // previous frame's counts are still to be observed (observe() them
  // first); after counting it (in hand or queued), counted() says whether
  // its own counts are to be observed now: true when no frame before it
  // was counted since the last reset.
  bool previous_due() const { return counted_ && !seen_; }
  bool counted() {
    seen_ = !counted_;
    counted_ = true;
    return seen_;
  }
  // The rect the 3D stages run on: the whole picture until a measure was
  // adopted (and after a reset or a change of size).
  PixelRect active(int width, int height) const;
  void reset();

 private:
  void forget_decision();

  bool decided_ = false;
  bool counted_ = false, seen_ = false;  // a frame was counted; its counts were observed on that frame
  int width_ = 0, height_ = 0;
  PixelRect active_, candidate_;
  int candidate_frames_ = 0;
  std::vector<uint32_t> last_rows_;  // the previous frame's row counts (cut detection)
};

}  // namespace p3d
