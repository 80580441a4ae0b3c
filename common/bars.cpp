#include "bars.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include <opencv2/core.hpp>

#include "row_convert.h"

namespace p3d {

namespace {

// The bright pixels of row y into *row, added to the column counts `cols`
// (any format: bar_pixel_bright()).
void count_row(const FrameView &f, int y, int luma_threshold, uint32_t *row, uint32_t *cols) {
  const int width = f.width;  // a local: the stores to cols could alias f.width
  uint32_t n = 0;
  for (int x = 0; x < width; ++x) {
    const uint32_t bright = bar_pixel_bright(f, x, y, luma_threshold);
    n += bright;
    cols[x] += bright;
  }
  *row = n;
}

// The same for the rows [y0, y1) of an 8-bit Y' plane (bar_pixel_bright()
// on 4:2:0: Y' over the threshold), a band of at most 255 rows: its column
// counts add up in bytes and each row's count in 16-bit chunks, so that
// the compiler's vectors take 16 pixels where 32-bit counts take 4.
void count_luma8_rows(const FrameView &f, int y0, int y1, uint8_t threshold, uint32_t *rows, uint32_t *cols,
                      uint8_t *band) {
  const int width = f.width;
  constexpr int kChunk = 4096;  // 0/1 flags a uint16_t sums without overflow
  static_assert(kChangeTile <= 255, "a band's column counts fit a byte");
  std::fill(band, band + width, uint8_t{0});
  for (int y = y0; y < y1; ++y) {
    const uint8_t *luma = f.plane[0] + static_cast<size_t>(y) * f.stride[0];
    uint32_t n = 0;
    for (int x0 = 0; x0 < width; x0 += kChunk) {
      const int x1 = std::min(width, x0 + kChunk);
      uint16_t chunk = 0;
      for (int x = x0; x < x1; ++x) {
        const uint8_t bright = luma[x] > threshold;
        band[x] = static_cast<uint8_t>(band[x] + bright);
        chunk = static_cast<uint16_t>(chunk + bright);
      }
      n += chunk;
    }
    rows[y] = n;
  }
  for (int x = 0; x < width; ++x) cols[x] = band[x];
}

}  // namespace

// Bands of kChangeTile rows in parallel, each with column counts of its
// own, added up at the end (integers: the order does not matter). Given
// the changes since the frame the counts hold, only the bands with a
// changed tile are counted again; the others' rows and column counts are
// that frame's, so the sums are this frame's.
void bar_counts_cpu(const FrameView &frame, int luma_threshold, BarCounts *counts, const ChangeMap *changes) {
  const size_t W = static_cast<size_t>(frame.width), H = static_cast<size_t>(frame.height);
  const int bands = change_tiles(frame.height);
  const bool some = changes && changes->width() == frame.width && changes->height() == frame.height &&
                    counts->rows.size() == H && counts->cols.size() == W && counts->band_cols.size() == bands * W;
  if (!some) {
    counts->rows.assign(H, 0);
    counts->band_cols.assign(bands * W, 0);
  }
  // 8-bit Y' with a threshold a byte holds (no Y' byte is over 255).
  const bool luma8 = !is_packed_rgb(frame.format) && !is_deep(frame.format) && luma_threshold >= 0;
  const uint8_t threshold8 = static_cast<uint8_t>(std::min(luma_threshold, 255));
  cv::parallel_for_(cv::Range(0, bands), [&](const cv::Range &range) {
    std::vector<uint8_t> band(luma8 ? W : 0);
    for (int b = range.start; b < range.end; ++b) {
      if (some && !changes->row_changed(b)) continue;
      uint32_t *cols = counts->band_cols.data() + b * W;
      const int y0 = b * kChangeTile, y1 = std::min(frame.height, (b + 1) * kChangeTile);
      if (luma8) {
        count_luma8_rows(frame, y0, y1, threshold8, counts->rows.data(), cols, band.data());
        continue;
      }
      std::fill(cols, cols + W, 0u);
      for (int y = y0; y < y1; ++y) count_row(frame, y, luma_threshold, &counts->rows[static_cast<size_t>(y)], cols);
    }
  });
  counts->cols.assign(W, 0);
  for (int b = 0; b < bands; ++b) {
    const uint32_t *cols = counts->band_cols.data() + b * W;
    for (size_t x = 0; x < W; ++x) counts->cols[x] += cols[x];
  }
}

namespace {

// Pixels [x0, x1) of row y of the source into both views of the pair:
// load_rgba's bytes as store_rgba writes them (load_rgba16's for an RGBA64
// pair). Word: the pair's pixel word (uint32_t, or uint64_t for RGBA64);
// words: the row's words, width() of them (rgba_words_of_row() fills
// those of 8-bit pairs, several pixels at a time).
template <class Word>
void source_into_views(const FrameView &src, const YuvToRgb &m, int y, int x0, int x1, const FrameView &pair,
                       Word *words) {
  if (x0 >= x1) return;
  constexpr size_t kBytes = sizeof(Word);
  uint8_t *left = pair.plane[0] + static_cast<size_t>(y) * pair.stride[0];
  uint8_t *right = left + kBytes * static_cast<size_t>(src.width);
  if constexpr (kBytes == 4) {
    rgba_words_of_row(src, y, m, words, x0, x1);
    if (is_bgr_order(pair.format))
      for (int x = x0; x < x1; ++x) words[x] = swap_rb_word(words[x]);
  } else {
    for (int x = x0 & ~1; x < x1; x += 2) load_rgba_pair_words(src, x, y, m, words + x);
  }
  std::memcpy(left + kBytes * static_cast<size_t>(x0), words + x0, kBytes * static_cast<size_t>(x1 - x0));
  std::memcpy(right + kBytes * static_cast<size_t>(x0), words + x0, kBytes * static_cast<size_t>(x1 - x0));
}

template <class Word>
void views_outside(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                   const std::vector<uint8_t> *rows) {
  cv::parallel_for_(cv::Range(0, src.height), [&](const cv::Range &range) {
    std::vector<Word> words(static_cast<size_t>(src.width));
    for (int y = range.start; y < range.end; ++y) {
      if (rows && !(*rows)[y]) continue;
      if (y < active.y0 || y >= active.y1) {
        source_into_views(src, m, y, 0, src.width, pair, words.data());
        continue;
      }
      source_into_views(src, m, y, 0, active.x0, pair, words.data());
      source_into_views(src, m, y, active.x1, src.width, pair, words.data());
    }
  });
}

}  // namespace

void views_outside_cpu(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                       const std::vector<uint8_t> *rows) {
  if (pair.format == PixelFormat::RGBA64)
    views_outside<uint64_t>(src, m, active, pair, rows);
  else
    views_outside<uint32_t>(src, m, active, pair, rows);
}

void place_active_pair_cpu(const FrameView &active_pair, PixelRect active, const FrameView &pair,
                           const std::vector<uint8_t> *rows) {
  const size_t view_width = static_cast<size_t>(pair.width / 2), w = static_cast<size_t>(active.width());
  const size_t px = static_cast<size_t>(packed_pixel_bytes(pair.format)), x0 = static_cast<size_t>(active.x0);
  for (int y = 0; y < active.height(); ++y) {
    if (rows && !(*rows)[y]) continue;
    const uint8_t *from = active_pair.plane[0] + static_cast<size_t>(y) * active_pair.stride[0];
    uint8_t *to = pair.plane[0] + static_cast<size_t>(active.y0 + y) * pair.stride[0];
    std::memcpy(to + px * x0, from, px * w);
    std::memcpy(to + px * (view_width + x0), from + px * w, px * w);
  }
}

DepthParams frame_scaled(const DepthParams &p, int frame_width, int frame_height) {
  DepthParams s = p;
  if (p.block_size == 0) s.block_size = effective_block_size(p, frame_width, frame_height);
  return s;
}

BilateralParams frame_scaled(const BilateralParams &p, int frame_width, int frame_height) {
  BilateralParams s = p;
  if (p.scale == 0) s.scale = bilateral_effective_scale(bilateral_sanitize(p), frame_width, frame_height);
  return s;
}

WarpParams active_warp_params(const WarpParams &params, int frame_width, int active_width) {
  WarpParams p = params;
  if (active_width > 0 && active_width < frame_width)
    p.max_disparity = std::min(kMaxDisparityPercent, params.max_disparity * static_cast<float>(frame_width) /
                                                         static_cast<float>(active_width));
  return p;
}

namespace {

// The first and one past the last index whose count is over `allowed`
// (first == last: none).
void picture_span(const std::vector<uint32_t> &counts, uint32_t allowed, int *first, int *last) {
  const int n = static_cast<int>(counts.size());
  int a = 0, b = n;
  while (a < n && counts[a] <= allowed) ++a;
  while (b > a && counts[b - 1] <= allowed) --b;
  *first = a;
  *last = b;
}

int align_down(int v) { return v / kBarAlign * kBarAlign; }

// Bars on opposite sides of about equal size (a letterbox, a pillarbox or
// both), the picture at least half the frame each way.
bool plausible(const PixelRect &r, int width, int height) {
  if (r.empty() || 2 * r.width() < width || 2 * r.height() < height) return false;
  const int slack_x = std::max(2 * kBarAlign, width / 32), slack_y = std::max(2 * kBarAlign, height / 32);
  return std::abs(r.x0 - (width - r.x1)) <= slack_x && std::abs(r.y0 - (height - r.y1)) <= slack_y;
}

}  // namespace

PixelRect measure_active_rect(const BarCounts &counts) {
  const int width = static_cast<int>(counts.cols.size()), height = static_cast<int>(counts.rows.size());
  int y0, y1, x0, x1;
  picture_span(counts.rows, static_cast<uint32_t>(width / 64), &y0, &y1);
  picture_span(counts.cols, static_cast<uint32_t>(height / 64), &x0, &x1);
  if (y0 >= y1 || x0 >= x1) return PixelRect{};
  return PixelRect{align_down(x0), align_down(y0), x1, y1};
}

void BarTracker::observe(const BarCounts &counts) {
  const int width = static_cast<int>(counts.cols.size()), height = static_cast<int>(counts.rows.size());
  if (width != width_ || height != height_) {  // another size: decided afresh (the order goes on)
    forget_decision();
    width_ = width;
    height_ = height;
  }
  // A scene cut: the rows' bright counts moved by an eighth of the frame's
  // pixels from one frame to the next.
  bool cut = false;
  if (last_rows_.size() == counts.rows.size()) {
    long long moved = 0;
    for (size_t y = 0; y < counts.rows.size(); ++y)
      moved += std::llabs(static_cast<long long>(counts.rows[y]) - static_cast<long long>(last_rows_[y]));
    cut = 8 * moved > static_cast<long long>(width) * height;
  }
  last_rows_ = counts.rows;
  const PixelRect measured = measure_active_rect(counts);
  if (!plausible(measured, width, height)) {
    candidate_frames_ = 0;
    return;
  }
  if (!decided_ || cut) {
    active_ = measured;
    decided_ = true;
    candidate_frames_ = 0;
    return;
  }
  if (measured == active_) {
    candidate_frames_ = 0;
    return;
  }
  if (candidate_frames_ > 0 && measured == candidate_) {
    ++candidate_frames_;
  } else {
    candidate_ = measured;
    candidate_frames_ = 1;
  }
  if (candidate_frames_ >= kBarConfirmFrames) {
    active_ = measured;
    candidate_frames_ = 0;
  }
}

PixelRect BarTracker::active(int width, int height) const {
  if (!decided_ || width != width_ || height != height_) return whole_picture(width, height);
  return active_;
}

void BarTracker::reset() {
  forget_decision();
  counted_ = seen_ = false;
}

void BarTracker::forget_decision() {
  decided_ = false;
  width_ = height_ = 0;
  candidate_frames_ = 0;
  last_rows_.clear();
}

PixelRect rect_on_cells(PixelRect rect, int shift, int width, int height) {
  const int cell = 1 << shift;
  return rect.x0 % cell == 0 && rect.y0 % cell == 0 ? rect : whole_picture(width, height);
}

std::array<PixelRect, 4> cells_outside(PixelRect r, int shift, int cells_w, int cells_h) {
  const PixelRect in{r.x0 >> shift, r.y0 >> shift, grid_cells(r.x1, shift), grid_cells(r.y1, shift)};
  return {PixelRect{0, 0, cells_w, in.y0}, PixelRect{0, in.y1, cells_w, cells_h}, PixelRect{0, in.y0, in.x0, in.y1},
          PixelRect{in.x1, in.y0, cells_w, in.y1}};
}

}  // namespace p3d
