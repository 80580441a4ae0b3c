// Tile bookkeeping of the adaptive stages (common/change_map.h).
#include "change_map.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include <opencv2/core.hpp>

namespace p3d {

ChangeMap::ChangeMap(int width, int height, bool all)
    : width_(std::max(width, 0)),
      height_(std::max(height, 0)),
      tiles_x_(change_tiles(width_)),
      tiles_y_(change_tiles(height_)),
      flags_(static_cast<size_t>(tiles_x_) * tiles_y_, all ? 1 : 0) {}

void ChangeMap::mark_pixels(PixelRect r) {
  r.x0 = std::max(r.x0, 0);
  r.y0 = std::max(r.y0, 0);
  r.x1 = std::min(r.x1, width_);
  r.y1 = std::min(r.y1, height_);
  if (r.empty()) return;
  for (int ty = r.y0 / kChangeTile; ty <= (r.y1 - 1) / kChangeTile; ++ty)
    for (int tx = r.x0 / kChangeTile; tx <= (r.x1 - 1) / kChangeTile; ++tx) mark(tx, ty);
}

void ChangeMap::mark_all() { std::fill(flags_.begin(), flags_.end(), 1); }

bool ChangeMap::any() const { return std::find(flags_.begin(), flags_.end(), 1) != flags_.end(); }

bool ChangeMap::all() const { return std::find(flags_.begin(), flags_.end(), 0) == flags_.end(); }

bool ChangeMap::row_changed(int ty) const {
  const auto first = flags_.begin() + static_cast<size_t>(ty) * tiles_x_;
  return std::find(first, first + tiles_x_, 1) != first + tiles_x_;
}

bool ChangeMap::all_rows() const {
  for (int ty = 0; ty < tiles_y_; ++ty)
    if (!row_changed(ty)) return false;
  return true;
}

double ChangeMap::fraction() const {
  if (flags_.empty()) return 0.0;
  return static_cast<double>(std::count(flags_.begin(), flags_.end(), 1)) / static_cast<double>(flags_.size());
}

void ChangeMap::merge(const ChangeMap &o) {
  if (!same_geometry(o)) {
    mark_all();
    return;
  }
  for (size_t i = 0; i < flags_.size(); ++i) flags_[i] |= o.flags_[i];
}

ChangeMap ChangeMap::dilated(int reach_x, int reach_y) const {
  const int rx = reach_tiles(reach_x), ry = reach_tiles(reach_y);
  if (rx == 0 && ry == 0) return *this;
  ChangeMap across(width_, height_, false), out(width_, height_, false);
  for (int ty = 0; ty < tiles_y_; ++ty)
    for (int tx = 0; tx < tiles_x_; ++tx)
      if (tile(tx, ty))
        for (int x = std::max(0, tx - rx); x <= std::min(tiles_x_ - 1, tx + rx); ++x) across.mark(x, ty);
  for (int ty = 0; ty < tiles_y_; ++ty)
    for (int tx = 0; tx < tiles_x_; ++tx)
      if (across.tile(tx, ty))
        for (int y = std::max(0, ty - ry); y <= std::min(tiles_y_ - 1, ty + ry); ++y) out.mark(tx, y);
  return out;
}

std::vector<uint8_t> ChangeMap::rows_within(int reach) const {
  std::vector<uint8_t> rows(static_cast<size_t>(height_), 0);
  std::vector<uint8_t> tile_rows(static_cast<size_t>(tiles_y_));
  for (int ty = 0; ty < tiles_y_; ++ty) tile_rows[ty] = row_changed(ty);
  for (int y = 0; y < height_; ++y) rows[y] = row_within_reach(tile_rows.data(), height_, y, reach);
  return rows;
}

std::vector<ColumnSpan> ChangeMap::row_spans() const {
  std::vector<ColumnSpan> spans(static_cast<size_t>(height_));
  for (int ty = 0; ty < tiles_y_; ++ty) {
    int first = tiles_x_, last = -1;
    for (int tx = 0; tx < tiles_x_; ++tx)
      if (tile(tx, ty)) {
        first = std::min(first, tx);
        last = tx;
      }
    if (last < 0) continue;
    const PixelRect r = tile_pixels(first, ty, width_, height_);
    const ColumnSpan span{r.x0, tile_pixels(last, ty, width_, height_).x1};
    std::fill(spans.begin() + r.y0, spans.begin() + r.y1, span);
  }
  return spans;
}

double ChangeMap::span_share() const {
  double pixels = 0;
  for (const ColumnSpan &c : row_spans())
    if (!c.empty()) pixels += c.x1 - c.x0;
  return width_ > 0 && height_ > 0 ? pixels / (static_cast<double>(width_) * height_) : 0.0;
}

std::vector<PixelRect> ChangeMap::runs() const {
  std::vector<PixelRect> runs;
  for (int ty = 0; ty < tiles_y_; ++ty)
    for (int tx = 0; tx < tiles_x_;) {
      if (!tile(tx, ty)) {
        ++tx;
        continue;
      }
      const int first = tx;
      while (tx < tiles_x_ && tile(tx, ty)) ++tx;
      PixelRect r = tile_pixels(first, ty, width_, height_);
      r.x1 = tile_pixels(tx - 1, ty, width_, height_).x1;
      // The same columns as a run of the row of tiles above: one rectangle.
      auto above = std::find_if(runs.begin(), runs.end(), [&r](const PixelRect &a) {
        return a.y1 == r.y0 && a.x0 == r.x0 && a.x1 == r.x1;
      });
      if (above != runs.end())
        above->y1 = r.y1;
      else
        runs.push_back(r);
    }
  return runs;
}

ChangeMap ChangeMap::cropped(PixelRect r) const {
  ChangeMap sub(r.width(), r.height(), false);
  for (int ty = 0; ty < tiles_y_; ++ty)
    for (int tx = 0; tx < tiles_x_; ++tx) {
      if (!tile(tx, ty)) continue;
      const PixelRect p = tile_pixels(tx, ty, width_, height_);
      sub.mark_pixels(PixelRect{p.x0 - r.x0, p.y0 - r.y0, p.x1 - r.x0, p.y1 - r.y0});
    }
  return sub;
}

ChangeMap FrameHistory::compare(const FrameView &frame, float tolerance) {
  const int n = frame_plane_count(frame.format);
  const bool fresh = planes_.empty() || frame.format != format_ || frame.width != width_ || frame.height != height_;
  compared_ = !fresh;
  if (fresh) {
    format_ = frame.format;
    width_ = frame.width;
    height_ = frame.height;
    planes_.assign(static_cast<size_t>(n), Plane{});
    for (int p = 0; p < n; ++p) {
      Plane &h = planes_[p];
      frame_plane_size(frame.format, frame.width, frame.height, p, &h.row_bytes, &h.rows);
      h.bytes.resize(static_cast<size_t>(h.row_bytes) * h.rows);
      for (int y = 0; y < h.rows; ++y)
        std::memcpy(&h.bytes[static_cast<size_t>(y) * h.row_bytes],
                    frame.plane[p] + static_cast<size_t>(y) * frame.stride[p], static_cast<size_t>(h.row_bytes));
    }
    return ChangeMap(frame.width, frame.height, true);
  }
  ChangeMap map(frame.width, frame.height, false);
  // One task per row of tiles: each tile is compared, and recorded when it
  // changed, by one thread. Exact comparison first compares the row of
  // tiles' rows whole, which for the unchanged rows of a frame is one call
  // a row instead of one a tile and row.
  cv::parallel_for_(cv::Range(0, map.tiles_y()), [&](const cv::Range &range) {
    for (int ty = range.start; ty < range.end; ++ty) {
      if (tolerance <= 0.f) {
        const PixelRect band = tile_pixels(0, ty, width_, height_);
        bool same = true;
        for (int p = 0; p < n && same; ++p) {
          const PlaneBox b = plane_box(format_, p, PixelRect{0, band.y0, width_, band.y1});
          const Plane &h = planes_[p];
          for (int y = b.r0; y < b.r1 && same; ++y)
            same = std::memcmp(frame.plane[p] + static_cast<size_t>(y) * frame.stride[p],
                               &h.bytes[static_cast<size_t>(y) * h.row_bytes], static_cast<size_t>(h.row_bytes)) == 0;
        }
        if (same) continue;
      }
      for (int tx = 0; tx < map.tiles_x(); ++tx) {
        const PixelRect r = tile_pixels(tx, ty, width_, height_);
        bool changed = false;
        uint64_t diff = 0, samples = 0;
        for (int p = 0; p < n && (tolerance > 0.f || !changed); ++p) {
          const PlaneBox b = plane_box(format_, p, r);
          const Plane &h = planes_[p];
          for (int y = b.r0; y < b.r1 && (tolerance > 0.f || !changed); ++y) {
            const uint8_t *cur = frame.plane[p] + static_cast<size_t>(y) * frame.stride[p] + b.b0;
            const uint8_t *old = &h.bytes[static_cast<size_t>(y) * h.row_bytes + b.b0];
            if (tolerance <= 0.f) {
              changed = std::memcmp(cur, old, static_cast<size_t>(b.b1 - b.b0)) != 0;
              continue;
            }
            if (is_deep(format_)) {
              const int n16 = (b.b1 - b.b0) / 2;
              for (int i = 0; i < n16; ++i)
                diff += static_cast<uint64_t>(std::abs(load_u16(cur, i) - load_u16(old, i)));
              samples += static_cast<uint64_t>(n16);
              continue;
            }
            for (int i = 0; i < b.b1 - b.b0; ++i) diff += static_cast<uint64_t>(std::abs(cur[i] - old[i]));
            samples += static_cast<uint64_t>(b.b1 - b.b0);
          }
        }
        if (tolerance > 0.f) changed = tile_over_tolerance(diff, samples, tolerance * units_per_level(format_));
        if (!changed) continue;
        map.mark(tx, ty);
        for (int p = 0; p < n; ++p) {
          const PlaneBox b = plane_box(format_, p, r);
          Plane &h = planes_[p];
          for (int y = b.r0; y < b.r1; ++y)
            std::memcpy(&h.bytes[static_cast<size_t>(y) * h.row_bytes + b.b0],
                        frame.plane[p] + static_cast<size_t>(y) * frame.stride[p] + b.b0,
                        static_cast<size_t>(b.b1 - b.b0));
        }
      }
    }
  });
  return map;
}

ChangeMap compare_planes(ImageView<const float> a, ImageView<const float> b) {
  return compare_grids(full_grid(a), full_grid(b));
}

ChangeMap compare_grids(DepthGrid<const float> a, DepthGrid<const float> b) {
  if (a.width != b.width || a.height != b.height || a.shift != b.shift || a.cells.width != b.cells.width ||
      a.cells.height != b.cells.height || a.empty())
    return ChangeMap(b.width, b.height, true);
  ChangeMap map(a.width, a.height, false);
  const int s = a.shift;
  auto differ = [&](int cy, int cx0, int cx1) {
    return std::memcmp(a.cells.row(cy) + cx0, b.cells.row(cy) + cx0, sizeof(float) * static_cast<size_t>(cx1 - cx0)) != 0;
  };
  if ((kChangeTile >> s) << s != kChangeTile) {  // cells larger than a tile: few of them, each marks its pixels
    for (int cy = 0; cy < a.cells.height; ++cy)
      for (int cx = 0; cx < a.cells.width; ++cx)
        if (differ(cy, cx, cx + 1)) map.mark_pixels(PixelRect{cx << s, cy << s, (cx + 1) << s, (cy + 1) << s});
    return map;
  }
  // A tile holds whole cells: each row of tiles is its own task, its cell
  // rows compared whole first (one call a row where nothing changed).
  cv::parallel_for_(cv::Range(0, map.tiles_y()), [&](const cv::Range &range) {
    for (int ty = range.start; ty < range.end; ++ty) {
      const PixelRect band = tile_pixels(0, ty, a.width, a.height);
      for (int cy = band.y0 >> s; cy <= (band.y1 - 1) >> s; ++cy) {
        if (!differ(cy, 0, a.cells.width)) continue;
        for (int tx = 0; tx < map.tiles_x(); ++tx) {
          const PixelRect t = tile_pixels(tx, ty, a.width, a.height);
          if (!map.tile(tx, ty) && differ(cy, t.x0 >> s, ((t.x1 - 1) >> s) + 1)) map.mark(tx, ty);
        }
      }
    }
  });
  return map;
}

void copy_plane_rect(ImageView<const float> from, ImageView<float> to, PixelRect r) {
  cv::parallel_for_(cv::Range(r.y0, r.y1), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y)
      std::memcpy(to.row(y) + r.x0, from.row(y) + r.x0, sizeof(float) * static_cast<size_t>(r.x1 - r.x0));
  });
}

void copy_rows(uint8_t *to, size_t to_stride, const uint8_t *from, size_t from_stride, size_t row_bytes, int rows) {
  cv::parallel_for_(cv::Range(0, rows), [&](const cv::Range &range) {
    for (int y = range.start; y < range.end; ++y)
      std::memcpy(to + static_cast<size_t>(y) * to_stride, from + static_cast<size_t>(y) * from_stride, row_bytes);
  });
}

}  // namespace p3d
