// CPU reference of the DIBR warp (common/warp.h). Rows are independent for
// the warp and the Background fill, so each row is scattered, resolved and
// filled by one cv::parallel_for_ task with its own key array; the
// NeighborAverage fill is an image-wide Jacobi iteration, and BackgroundSmooth
// a row pass (anchors), a column pass and a row pass (run sums), run
// afterwards.
#include "warp.h"

#include <algorithm>
#include <atomic>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace p3d {
namespace {

struct WarpJob {
  WarpParams params;  // sanitised
  FrameView src;
  YuvToRgb m;
  ImageView<const float> depth;
  FrameView out;
  float D;
  int width, height;
};

// One eye of the output: its shift factor and first output column.
struct Eye {
  float shift;
  int col0;
};

// The source row y converted once to R'G'B'A (load_rgba), as the GPU does
// in shared memory: both eyes sample it (sample_row), so a pixel is
// converted once instead of twice per eye.
struct SourceRow {
  std::vector<Rgba> rgba;
  explicit SourceRow(int width) : rgba(static_cast<size_t>(width)) {}
  void load(const WarpJob &j, int y) {
    for (int x = 0; x < j.width; ++x) rgba[x] = load_rgba(j.src, x, y, j.m);
  }
};

// Per-row scratch of a row task: the converted source row, every pixel's
// read depth and target for the eye being scattered, the z-buffer keys and
// the Background fill's nearest-right index.
struct RowScratch {
  SourceRow src;
  std::vector<float> depth, target;
  std::vector<unsigned long long> keys;
  std::vector<int> right;
  explicit RowScratch(int width)
      : src(width), depth(width), target(width), keys(width), right(width) {}
};

// Z-buffer of row y: keys[X] = the largest key any source pixel offers X.
// Each pixel's depth and target are computed once (warp_source would
// compute them for x and again for x + 1) and linked with warp_link.
void scatter_row(const WarpJob &j, const Eye &eye, int y, RowScratch &r) {
  std::vector<unsigned long long> &keys = r.keys;
  std::fill(keys.begin(), keys.end(), 0ull);
  const float *drow = j.depth.row(y);
  float *d = r.depth.data(), *t = r.target.data();
  for (int x = 0; x < j.width; ++x) {
    d[x] = warp_depth(drow[x]);
    t[x] = warp_target(x, d[x], eye.shift, j.D, j.params.convergence);
  }
  for (int x = 0; x < j.width; ++x) {
    const bool has_next = x + 1 < j.width;
    const WarpSource s = warp_link(x, d[x], t[x], has_next ? d[x + 1] : d[x], has_next ? t[x + 1] : t[x], has_next);
    const WarpSpan span = warp_span(s, j.width);
    for (int X = span.first; X <= span.last; ++X) keys[X] = std::max(keys[X], warp_key_at(s, X, j.width));
  }
}

// Colours of the covered targets, sampled from the converted source row;
// holes get kHoleColour for fill=None and are left for the fill otherwise.
// Returns the row's hole count.
long long resolve_row(const WarpJob &j, const Eye &eye, int y, const SourceRow &src,
                      const std::vector<unsigned long long> &keys) {
  long long holes = 0;
  for (int X = 0; X < j.width; ++X) {
    if (keys[X] != 0) {
      store_rgba(j.out, eye.col0 + X, y, sample_row(src.rgba.data(), j.width, keys[X]));
    } else {
      ++holes;
      if (j.params.fill == HoleFill::None) store_rgba(j.out, eye.col0 + X, y, kHoleColour);
    }
  }
  return holes;
}

// Background fill of row y: right[X] = nearest non-hole right of X, then a
// left-to-right pass that knows the nearest non-hole to the left.
void background_fill_row(const WarpJob &j, const Eye &eye, int y, const std::vector<unsigned long long> &keys,
                         std::vector<int> &right) {
  const YuvToRgb packed;
  int next = -1;
  for (int X = j.width - 1; X >= 0; --X) {
    right[X] = next;
    if (keys[X] != 0) next = X;
  }
  int prev = -1;
  for (int X = 0; X < j.width; ++X) {
    if (keys[X] != 0) {
      prev = X;
      continue;
    }
    const int xr = right[X];
    const int pick = background_source(X, prev, prev >= 0 ? keys[prev] : 0ull, xr, xr >= 0 ? keys[xr] : 0ull);
    store_rgba(j.out, eye.col0 + X, y, pick >= 0 ? load_rgba(j.out, eye.col0 + pick, y, packed) : kFillBlack);
  }
}

// What the image-wide fills keep of the warp: the hole mask (W x H, 1 =
// hole) and, for BackgroundSmooth, every pixel's key.
struct EyeScratch {
  std::vector<uint8_t> mask;
  std::vector<unsigned long long> keys;
};

// Warps both eyes row by row (a row task converts its source row once);
// an eye with shift 0 is the source row copied. scratch[e] (when its mask
// is sized) receives eye e's holes and, if its key array is sized, the keys.
// holes[e]: eye e's hole count.
void warp_eyes(const WarpJob &j, const Eye eyes[2], EyeScratch scratch[2], long long holes[2]) {
  std::atomic<long long> total[2] = {{0}, {0}};
  cv::parallel_for_(cv::Range(0, j.height), [&](const cv::Range &rows) {
    RowScratch row(j.width);
    const SourceRow &src = row.src;
    const std::vector<unsigned long long> &keys = row.keys;
    long long local[2] = {0, 0};
    for (int y = rows.start; y < rows.end; ++y) {
      row.src.load(j, y);
      for (int e = 0; e < 2; ++e) {
        const Eye &eye = eyes[e];
        if (eye.shift == 0.f) {
          for (int x = 0; x < j.width; ++x) store_rgba(j.out, eye.col0 + x, y, src.rgba[x]);
          continue;
        }
        scatter_row(j, eye, y, row);
        const long long h = resolve_row(j, eye, y, src, keys);
        local[e] += h;
        if (h > 0 && j.params.fill == HoleFill::Background) background_fill_row(j, eye, y, keys, row.right);
        EyeScratch &s = scratch[e];
        if (s.mask.empty()) continue;
        const size_t base = static_cast<size_t>(y) * j.width;
        for (int X = 0; X < j.width; ++X) s.mask[base + X] = keys[X] == 0;
        if (!s.keys.empty()) std::copy(keys.begin(), keys.end(), s.keys.begin() + base);
      }
    }
    total[0] += local[0];
    total[1] += local[1];
  });
  holes[0] = total[0].load();
  holes[1] = total[1].load();
}

// BackgroundSmooth, pass 1 (rows): every hole's anchor. state: 0 = not a
// hole, 1 = a hole without an anchor, 2 = a hole with anchor[i].
void smooth_anchor_rows(const WarpJob &j, const Eye &eye, const EyeScratch &s, std::vector<uint8_t> &state,
                        std::vector<Rgba> &anchor) {
  const YuvToRgb packed;
  const int W = j.width, H = j.height;
  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range &rows) {
    std::vector<uint8_t> clean(W);
    std::vector<int> right_clean(W), right_any(W);
    for (int y = rows.start; y < rows.end; ++y) {
      const size_t base = static_cast<size_t>(y) * W;
      const uint8_t *row = &s.mask[base];
      for (int X = 0; X < W; ++X) clean[X] = smooth_is_clean(row, X, W);
      int near_clean = -1, near_any = -1;
      for (int X = W - 1; X >= 0; --X) {  // nearest clean / non-hole pixel right of X
        right_clean[X] = near_clean;
        right_any[X] = near_any;
        if (!row[X]) near_any = X;
        if (clean[X]) near_clean = X;
      }
      near_clean = -1;
      near_any = -1;
      for (int X = 0; X < W; ++X) {
        state[base + X] = row[X] ? 1 : 0;
        if (row[X]) {
          const int xl = smooth_side(near_clean, near_any), xr = smooth_side(right_clean[X], right_any[X]);
          const int pick = background_source(X, xl, xl >= 0 ? s.keys[base + xl] : 0ull, xr,
                                             xr >= 0 ? s.keys[base + xr] : 0ull);
          if (pick >= 0) {
            state[base + X] = 2;
            anchor[base + X] = load_rgba(j.out, eye.col0 + pick, y, packed);
          }
        }
        if (!row[X]) near_any = X;
        if (clean[X]) near_clean = X;
      }
    }
  });
}

// BackgroundSmooth, pass 2 (columns): V of every hole, the anchors of its
// column's run of holes within +-R rows, from prefix sums over each run. Columns
// are independent; a task takes a range of them.
void smooth_column_sums(const WarpJob &j, const std::vector<uint8_t> &state, const std::vector<Rgba> &anchor, int R,
                        std::vector<SmoothSum> &column) {
  const int W = j.width, H = j.height;
  cv::parallel_for_(cv::Range(0, W), [&](const cv::Range &cols) {
    std::vector<SmoothSum> prefix(static_cast<size_t>(H) + 1);
    for (int X = cols.start; X < cols.end; ++X) {
      int y = 0;
      while (y < H) {
        if (!state[static_cast<size_t>(y) * W + X]) {
          ++y;
          continue;
        }
        const int a = y;  // the run is rows a..b
        prefix[0] = SmoothSum{0, 0, 0, 0, 0};
        for (; y < H && state[static_cast<size_t>(y) * W + X]; ++y) {
          SmoothSum next = prefix[y - a];
          const size_t i = static_cast<size_t>(y) * W + X;
          if (state[i] == 2) smooth_add(next, anchor[i]);
          prefix[y - a + 1] = next;
        }
        const int b = y - 1;
        for (int t = a; t <= b; ++t)
          column[static_cast<size_t>(t) * W + X] =
              smooth_window(prefix[std::min(b, t + R) - a + 1], prefix[std::max(a, t - R) - a]);
      }
    }
  });
}

// BackgroundSmooth, pass 3 (rows): every hole becomes the mean of the column
// sums over its row's run of holes within +-Rx columns.
void smooth_fill_rows(const WarpJob &j, const Eye &eye, const std::vector<uint8_t> &state,
                      const std::vector<SmoothSum> &column, int Rx) {
  const int W = j.width, H = j.height;
  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range &rows) {
    std::vector<SmoothSum> prefix(static_cast<size_t>(W) + 1);
    for (int y = rows.start; y < rows.end; ++y) {
      const size_t base = static_cast<size_t>(y) * W;
      int X = 0;
      while (X < W) {
        if (!state[base + X]) {
          ++X;
          continue;
        }
        const int a = X;  // the run is columns a..b
        prefix[0] = SmoothSum{0, 0, 0, 0, 0};
        for (; X < W && state[base + X]; ++X) {
          prefix[X - a + 1] = prefix[X - a];
          smooth_add(prefix[X - a + 1], column[base + X]);
        }
        const int b = X - 1;
        for (int t = a; t <= b; ++t) {
          const SmoothSum &hi = prefix[std::min(b, t + Rx) - a + 1], &lo = prefix[std::max(a, t - Rx) - a];
          store_rgba(j.out, eye.col0 + t, y, smooth_mean(smooth_window(hi, lo)));
        }
      }
    }
  });
}

void background_smooth_fill(const WarpJob &j, const Eye &eye, const EyeScratch &s) {
  const size_t n = static_cast<size_t>(j.width) * j.height;
  std::vector<uint8_t> state(n);
  std::vector<Rgba> anchor(n);
  std::vector<SmoothSum> column(n);
  const int R = smooth_fill_radius(eye.shift, j.D);
  smooth_anchor_rows(j, eye, s, state, anchor);
  smooth_column_sums(j, state, anchor, R, column);
  smooth_fill_rows(j, eye, state, column, smooth_fill_radius_x(R));
}

// NeighborAverage: Jacobi steps ping-ponging between two hole masks (reads
// from `cur` only, so rows can run in parallel), until no hole is left or a
// step fills nothing; what is left becomes kFillBlack.
void neighbour_average_fill(const WarpJob &j, const Eye &eye, std::vector<uint8_t> &mask, long long holes) {
  std::vector<uint8_t> next(mask.size());
  std::vector<uint8_t> *cur = &mask, *nxt = &next;
  const size_t W = static_cast<size_t>(j.width);
  while (holes > 0) {
    std::atomic<long long> filled{0};
    cv::parallel_for_(cv::Range(0, j.height), [&](const cv::Range &rows) {
      long long local = 0;
      for (int y = rows.start; y < rows.end; ++y)
        for (int X = 0; X < j.width; ++X) {
          const size_t i = y * W + X;
          uint8_t still = 0;
          Rgba c;
          if ((*cur)[i]) {
            if (neighbour_average(j.out, eye.col0, cur->data(), W, j.width, j.height, X, y, &c)) {
              store_rgba(j.out, eye.col0 + X, y, c);
              ++local;
            } else {
              still = 1;
            }
          }
          (*nxt)[i] = still;
        }
      filled += local;
    });
    std::swap(cur, nxt);
    if (filled.load() == 0) break;
    holes -= filled.load();
  }
  if (holes <= 0) return;
  for (int y = 0; y < j.height; ++y)
    for (int X = 0; X < j.width; ++X)
      if ((*cur)[y * W + X]) store_rgba(j.out, eye.col0 + X, y, kFillBlack);
}

}  // namespace

long long warp_render_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &out) {
  if (!warp_frames_fit(src, depth, out)) return -1;
  WarpJob j{warp_sanitize(params), src, m, depth, out, 0.f, src.width, src.height};
  j.D = disparity_scale(j.params, j.width);
  const Eye eyes[2] = {{warp_eye_shift(j.params, j.D, 0), 0}, {warp_eye_shift(j.params, j.D, 1), j.width}};
  const bool average = j.params.fill == HoleFill::NeighborAverage;
  const bool smooth = j.params.fill == HoleFill::BackgroundSmooth;
  EyeScratch scratch[2];
  const size_t n = static_cast<size_t>(j.width) * j.height;
  for (int e = 0; e < 2; ++e) {
    if (eyes[e].shift == 0.f) continue;
    if (average || smooth) scratch[e].mask.resize(n);
    if (smooth) scratch[e].keys.resize(n);
  }
  long long holes[2] = {0, 0};
  warp_eyes(j, eyes, scratch, holes);
  for (int e = 0; e < 2; ++e) {
    if (average && holes[e] > 0) neighbour_average_fill(j, eyes[e], scratch[e].mask, holes[e]);
    if (smooth && holes[e] > 0) background_smooth_fill(j, eyes[e], scratch[e]);
  }
  return holes[0] + holes[1];
}

}  // namespace p3d
