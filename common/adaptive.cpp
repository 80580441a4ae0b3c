// The adaptive stages' steps (common/adaptive.h).
#include "adaptive.h"

#include <algorithm>
#include <cstring>

#include <opencv2/core.hpp>

namespace p3d {

namespace {
// The grown rects' summed area (a share of the picture) above which the
// filter runs over the whole picture: a rect's row pass also covers the
// rows its reach reads, and each rect is a pass of its own (camera video
// at reuse-tolerance 2 measured no faster in rects above about half).
constexpr double kWholeFilterShare = 0.5;
// And the number of rects above which it does: each rect's passes are
// parallel loops of their own (camera video at 4K, hundreds of scattered
// runs, took longer in rects than whole).
constexpr size_t kMaxFilterRects = 32;

}  // namespace

bool busy_for(ChangeReach reach, const ChangeMap &changes) {
  switch (reach) {
    case ChangeReach::Rows: return changes.all_rows();
    case ChangeReach::Spans: return changes.span_share() > kWholeWarpShare;
    default: return ChangeBackOff::busy_on_cpu(changes.fraction());
  }
}

ChangeReach warp_change_reach(const WarpParams &params) {
  const HoleFill fill = warp_sanitize(params).fill;
  return fill == HoleFill::BackgroundSmooth || fill == HoleFill::None ? ChangeReach::Spans : ChangeReach::Rows;
}

bool StageInputs::begin(bool adaptive) {
  if (!adaptive) {
    reset();
    return false;
  }
  if (backoff_.compare_next()) return true;
  frame_.reset();
  compared_ = false;
  return false;
}

ChangeMap StageInputs::compare(const FrameView &frame, ImageView<const float> depth, ImageView<const float> prev_depth,
                               float tolerance) {
  ChangeMap changes = frame_.compare(frame, tolerance);
  compared_ = frame_.compared() && (depth.empty() || !prev_depth.empty());
  if (!depth.empty() && !changes.all()) {  // all: nothing left for the depth to add
    if (prev_depth.empty()) {
      changes.mark_all();
    } else if (depth.data != prev_depth.data) {
      changes.merge(compare_planes(prev_depth, depth));
    }
  }
  if (compared_) backoff_.observe(busy_for(reach_, changes));
  return changes;
}

bool bilateral_filter_changed_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth,
                                  ImageView<const float> prev_out, ImageView<float> out, const ChangeMap *changes,
                                  BilateralScratch &scratch) {
  const int W = depth.width, H = depth.height;
  const PixelRect whole{0, 0, W, H};
  const bool keep = changes && prev_out.width == W && prev_out.height == H && !prev_out.empty();
  if (keep && !changes->any()) return false;
  // The changed tiles' runs, each grown by the filter's reach in pixels
  // (not rounded up to whole tiles: a cursor's tile costs its window, not
  // its eight neighbours); rects may overlap, which computes a pixel twice
  // to the same bits.
  std::vector<PixelRect> dirty;
  double area = 0;
  if (keep) {
    const int reach = bilateral_reach(params, W, H);
    for (const PixelRect &r : changes->runs()) {
      const PixelRect g = grown(r, reach, W, H);
      dirty.push_back(g);
      area += static_cast<double>(g.width()) * g.height();
    }
  }
  // Where much of the picture changed, one pass over it costs less than
  // the rectangles (each reads a margin of its reach) and the copy.
  if (!keep || area > kWholeFilterShare * W * H || dirty.size() > kMaxFilterRects) {
    bilateral_filter_cpu(params, guide, depth, out, {whole}, scratch);
    return true;
  }
  copy_plane_rect(prev_out, out, whole);
  bilateral_filter_cpu(params, guide, depth, out, dirty, scratch);
  return true;
}

namespace {

// The rows of a picture `height` tall flagged in `rows` (null: all).
std::vector<uint8_t> row_flags(const std::vector<uint8_t> *rows, int height) {
  return rows ? *rows : std::vector<uint8_t>(static_cast<size_t>(height), 1);
}

// The spans of the rows of rect r, within r and counted from its corner.
std::vector<ColumnSpan> spans_inside(const std::vector<ColumnSpan> &spans, const PixelRect &r) {
  std::vector<ColumnSpan> inside(static_cast<size_t>(r.height()));
  for (int y = r.y0; y < r.y1; ++y) {
    const ColumnSpan c = spans[y];
    const int x0 = std::max(c.x0, r.x0), x1 = std::min(c.x1, r.x1);
    if (x0 < x1) inside[y - r.y0] = ColumnSpan{x0 - r.x0, x1 - r.x0};
  }
  return inside;
}

// warp_pack_changed_cpu() inside a rect smaller than the frame. spans:
// each row's changed columns (null: all); rows: the same as row flags.
long long warp_active_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &pair, WarpCpuScratch &scratch,
                          const std::vector<ColumnSpan> *spans, const std::vector<uint8_t> *rows,
                          const ActiveArea &active, std::vector<uint8_t> *written) {
  const PixelRect r = active.rect;
  // A letterbox (the full width): the views are rows of the pair itself.
  const bool full_width = r.x0 == 0 && r.x1 == src.width;
  const FrameView target = full_width ? sub_frame(pair, PixelRect{0, r.y0, pair.width, r.y1}) : active.pair;
  if (!full_width && (!target.plane[0] || target.width != 2 * r.width() || target.height != r.height())) return -1;
  std::vector<ColumnSpan> sub_spans;
  if (spans) sub_spans = spans_inside(*spans, r);
  const WarpParams active_params = active_warp_params(params, src.width, r.width());
  const long long holes = warp_render_cpu(active_params, sub_frame(src, r), m, sub_image(depth, r), target, scratch,
                                          spans ? &sub_spans : nullptr);
  if (holes < 0) return holes;
  const std::vector<uint8_t> sub_written =
      spans ? warp_rows_written(active_params, r.width(), sub_spans) : row_flags(nullptr, r.height());
  if (!full_width) place_active_pair_cpu(target, r, pair, &sub_written);
  views_outside_cpu(src, m, r, pair, rows);
  *written = row_flags(rows, src.height);
  for (int y = 0; y < r.height(); ++y) (*written)[r.y0 + y] |= sub_written[y];
  return holes;
}

}  // namespace

void copy_flagged_rows(const FrameView &from, const FrameView &to, const std::vector<uint8_t> &rows, bool flagged) {
  const bool yuv = !is_packed_rgb(to.format);
  const int n = static_cast<int>(rows.size());
  for (int p = 0; p < frame_plane_count(to.format); ++p) {
    int row_bytes = 0, plane_rows = 0;
    frame_plane_size(to.format, to.width, to.height, p, &row_bytes, &plane_rows);
    const bool chroma = yuv && p > 0;
    cv::parallel_for_(cv::Range(0, plane_rows), [&](const cv::Range &range) {
      for (int y = range.start; y < range.end; ++y) {
        const bool f = chroma ? rows[2 * y] || (2 * y + 1 < n && rows[2 * y + 1]) : rows[y] != 0;
        if (f != flagged) continue;
        std::memcpy(to.plane[p] + static_cast<size_t>(y) * to.stride[p],
                    from.plane[p] + static_cast<size_t>(y) * from.stride[p], static_cast<size_t>(row_bytes));
      }
    });
  }
}

namespace {

// What the pack rewrites of a 4:2:0 output: whole 2 x 2 blocks, so a
// flagged row takes its pair with it.
std::vector<uint8_t> whole_pairs(std::vector<uint8_t> rows, PixelFormat f) {
  if (is_packed_rgb(f)) return rows;
  for (size_t y = 0; y + 1 < rows.size(); y += 2) rows[y] = rows[y + 1] = rows[y] || rows[y + 1];
  return rows;
}

// The pack of the output rows flagged in `rows`, the others taken from the
// kept previous output when there is one.
void pack_rows_over(const PackParams &pack, const FrameView &in, const FrameView &dst, std::vector<uint8_t> rows,
                    KeptOutput *kept) {
  if (kept && kept->previous) {
    rows = whole_pairs(std::move(rows), dst.format);
    copy_flagged_rows(*kept->previous, dst, rows, false);
  }
  pack_cpu(pack, in, dst, &rows);
  if (kept) kept->written = std::move(rows);
}

}  // namespace

long long warp_pack_changed_cpu(const WarpParams &params, const PackParams &pack, const FrameView &src,
                                const YuvToRgb &m, ImageView<const float> depth, const FrameView &pair,
                                const FrameView &dst, WarpCpuScratch &scratch, const ChangeMap *changes,
                                const ActiveArea *active, KeptOutput *kept) {
  const bool pair_is_dst = pair.plane[0] == dst.plane[0];
  if (!pair_is_dst && !pack_args_valid(pack, pair, dst)) return -1;
  // Busy spans: their windows, widened by the reach, cover nearly every
  // row whole, and the whole warp costs less than their bookkeeping.
  if (changes && busy_for(warp_change_reach(params), *changes)) changes = nullptr;
  const std::vector<ColumnSpan> spans = changes ? changes->row_spans() : std::vector<ColumnSpan>();
  const std::vector<uint8_t> rows = changes ? changes->rows() : std::vector<uint8_t>();
  const bool cropped = active && active->rect != whole_picture(src.width, src.height);
  if (cropped && (!warp_frames_fit(src, depth, pair) || active->rect.empty() ||
                  active->rect.x1 > src.width || active->rect.y1 > src.height))
    return -1;
  if (kept) kept->written.assign(static_cast<size_t>(dst.height), 1);
  // Nothing changed: the previous output is the output, no row written
  // (frames that fit, as the warp would check them).
  if (changes && !changes->any() && kept && kept->previous && warp_frames_fit(src, depth, pair) &&
      changes->width() == src.width && changes->height() == src.height) {
    copy_flagged_rows(*kept->previous, dst, kept->written, true);
    std::fill(kept->written.begin(), kept->written.end(), 0);
    return 0;
  }
  // Rendered into dst itself, the views are written in windows of rows:
  // every row starts as the previous output.
  if (changes && pair_is_dst && kept && kept->previous) copy_flagged_rows(*kept->previous, dst, kept->written, true);
  std::vector<uint8_t> written;
  const long long holes =
      cropped ? warp_active_cpu(params, src, m, depth, pair, scratch, changes ? &spans : nullptr,
                                changes ? &rows : nullptr, *active, &written)
              : warp_render_cpu(params, src, m, depth, pair, scratch, changes ? &spans : nullptr);
  if (holes < 0) return holes;
  if (changes && !cropped) written = warp_rows_written(params, src.width, spans);
  if (pair_is_dst) {  // packed RGB (the pair's format): no rows in pairs
    if (changes && kept) kept->written = std::move(written);
    return holes;
  }
  if (!changes) {
    pack_cpu(pack, pair, dst);
    return holes;
  }
  pack_rows_over(pack, pair, dst, pack_rows_reading(pack, pair.width, pair.height, written), kept);
  return holes;
}

bool pack_changed_cpu(const PackParams &params, const FrameView &in, const FrameView &dst, const ChangeMap *changes,
                      KeptOutput *kept) {
  if (!pack_args_valid(params, in, dst)) return false;
  if (kept) kept->written.assign(static_cast<size_t>(dst.height), 1);
  if (!changes) {
    pack_cpu(params, in, dst);
    return true;
  }
  pack_rows_over(params, in, dst, pack_rows_reading(params, in.width, in.height, changes->rows()), kept);
  return true;
}

}  // namespace p3d
