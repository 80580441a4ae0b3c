// CPU reference of the DIBR warp (common/warp.h). Rows are independent for
// the warp and the Background fill, so each row is scattered, resolved and
// filled by one cv::parallel_for_ task with its own key array; the
// NeighborAverage fill is an image-wide Jacobi iteration, run afterwards.
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

void copy_rows(const WarpJob &j, const Eye &eye) {
  cv::parallel_for_(cv::Range(0, j.height), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < j.width; ++x) store_rgba(j.out, eye.col0 + x, y, load_rgba(j.src, x, y, j.m));
  });
}

// Z-buffer of row y: keys[X] = the largest key any source pixel offers X.
void scatter_row(const WarpJob &j, const Eye &eye, int y, std::vector<unsigned long long> &keys) {
  std::fill(keys.begin(), keys.end(), 0ull);
  const float *drow = j.depth.row(y);
  for (int x = 0; x < j.width; ++x) {
    const WarpSource s = warp_source(drow, x, j.width, eye.shift, j.D, j.params.convergence);
    const WarpSpan span = warp_span(s, j.width);
    for (int X = span.first; X <= span.last; ++X) keys[X] = std::max(keys[X], warp_key_at(s, X, j.width));
  }
}

// Colours of the covered targets; holes get kHoleColour for fill=None and
// are left for the fill otherwise. Returns the row's hole count.
long long resolve_row(const WarpJob &j, const Eye &eye, int y, const std::vector<unsigned long long> &keys) {
  long long holes = 0;
  for (int X = 0; X < j.width; ++X) {
    if (keys[X] != 0) {
      store_rgba(j.out, eye.col0 + X, y, sample_row(j.src, warp_key_u(keys[X]), y, j.m));
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

// Warps one eye row by row; mask (W x H) receives the holes when not null.
long long warp_eye(const WarpJob &j, const Eye &eye, std::vector<uint8_t> *mask) {
  std::atomic<long long> holes{0};
  cv::parallel_for_(cv::Range(0, j.height), [&](const cv::Range &rows) {
    std::vector<unsigned long long> keys(j.width);
    std::vector<int> right(j.width);
    long long local = 0;
    for (int y = rows.start; y < rows.end; ++y) {
      scatter_row(j, eye, y, keys);
      const long long h = resolve_row(j, eye, y, keys);
      local += h;
      if (h > 0 && j.params.fill == HoleFill::Background) background_fill_row(j, eye, y, keys, right);
      if (mask)
        for (int X = 0; X < j.width; ++X) (*mask)[static_cast<size_t>(y) * j.width + X] = keys[X] == 0;
    }
    holes += local;
  });
  return holes.load();
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
  long long holes = 0;
  for (int e = 0; e < 2; ++e) {
    const Eye eye{warp_eye_shift(j.params, j.D, e), e * j.width};
    if (eye.shift == 0.f) {
      copy_rows(j, eye);
      continue;
    }
    const bool average = j.params.fill == HoleFill::NeighborAverage;
    std::vector<uint8_t> mask(average ? static_cast<size_t>(j.width) * j.height : 0);
    const long long h = warp_eye(j, eye, average ? &mask : nullptr);
    if (average && h > 0) neighbour_average_fill(j, eye, mask, h);
    holes += h;
  }
  return holes;
}

}  // namespace p3d
