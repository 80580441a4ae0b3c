#include "block_regions.h"

#include <algorithm>
#include <cstring>
#include <numeric>

#include <opencv2/core.hpp>

#include "depth_estimate.h"
#include "row_convert.h"

namespace p3d {
namespace {

// The root of i, halving the path on the way (writes parents of the tree's
// own blocks only).
int find_root(int *parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// The smaller root becomes the parent.
void join(int *parent, int a, int b) {
  a = find_root(parent, a);
  b = find_root(parent, b);
  if (a == b) return;
  if (b < a) std::swap(a, b);
  parent[b] = a;
}

}  // namespace

void BlockRegions::label(const std::vector<float> &features, int bx, int by, float edge_threshold, bool yuv,
                         const uint32_t *hq, bool incremental) {
  const size_t n = static_cast<size_t>(bx) * by;
  const bool stats = hq != nullptr;
  const bool keep = incremental && kept_ && bx == bx_ && by == by_ && edge_threshold == threshold_ && yuv == yuv_ &&
                    stats == stats_ && kept_features_.size() == 3 * n;
  // The cross-tile forest and merge flags go back to identity: only the
  // touched indices differ from it.
  if (parent_.size() == n) {
    for (const int i : touched_) {
      parent_[i] = i;
      merged_[i] = 0;
    }
  } else {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0);
    merged_.assign(n, 0);
  }
  touched_.clear();
  tile_root_.resize(n);
  labels_.resize(n);
  if (stats) {
    sum_.resize(n);
    count_.resize(n);
    max_.resize(n);
    merged_sum_.resize(n);
    merged_count_.resize(n);
    merged_max_.resize(n);
  }
  if (incremental) kept_features_.resize(3 * n);
  bx_ = bx;
  by_ = by;
  threshold_ = edge_threshold;
  yuv_ = yuv;
  stats_ = stats;
  tiles_x_ = (bx + kTileW - 1) / kTileW;
  tiles_y_ = (by + kTileH - 1) / kTileH;
  const int tiles = tiles_x_ * tiles_y_;
  dirty_.assign(static_cast<size_t>(tiles), 1);
  kept_ = incremental;
  tiles_labelled_ = 0;
  if (n == 0) return;

  cv::parallel_for_(cv::Range(0, tiles), [&](const cv::Range &range) {
    for (int t = range.start; t < range.end; ++t) {
      const PixelRect tile = tile_blocks(t);
      const size_t row_bytes = 3 * sizeof(float) * tile.width();
      if (keep) {
        bool differs = false;
        for (int y = tile.y0; y < tile.y1 && !differs; ++y) {
          const size_t f = 3 * (static_cast<size_t>(y) * bx + tile.x0);
          differs = std::memcmp(&features[f], &kept_features_[f], row_bytes) != 0;
        }
        dirty_[t] = differs;
      }
      if (!dirty_[t]) continue;
      label_tile(features, t, hq);
      if (incremental)
        for (int y = tile.y0; y < tile.y1; ++y) {
          const size_t f = 3 * (static_cast<size_t>(y) * bx + tile.x0);
          std::memcpy(&kept_features_[f], &features[f], row_bytes);
        }
    }
  });
  tiles_labelled_ = static_cast<int>(std::count(dirty_.begin(), dirty_.end(), 1));
  join_tiles(features);
  for (const int i : touched_) parent_[i] = find_root(parent_.data(), i);  // straight at the region's root
  cv::parallel_for_(cv::Range(0, by), [&](const cv::Range &range) {
    for (size_t k = static_cast<size_t>(range.start) * bx; k < static_cast<size_t>(range.end) * bx; ++k)
      labels_[k] = parent_[tile_root_[k]];
  });
}

namespace {

// Bit i: blocks_joined(a + 3 i, b + 3 i), for i < n <= 64; several pairs
// at a time (the same float operations in the same order, lane by lane).
uint64_t joined_bits(const float *a, const float *b, int n, float threshold, bool yuv) {
  uint64_t bits = 0;
  int i = 0;
#if P3D_CPU_VECTORS
  using namespace cv;
  constexpr int L = v_float32::nlanes;
  const YuvToRgb m;
  const v_float32 thr = vx_setall_f32(threshold), ys = vx_setall_f32(m.y_scale), cs = vx_setall_f32(m.c_scale);
  const v_float32 rv = vx_setall_f32(m.rv), gu = vx_setall_f32(m.gu), gv = vx_setall_f32(m.gv), bu = vx_setall_f32(m.bu);
  for (; i + L <= n; i += L) {
    v_float32 a0, a1, a2, b0, b1, b2;
    v_load_deinterleave(a + 3 * i, a0, a1, a2);
    v_load_deinterleave(b + 3 * i, b0, b1, b2);
    v_float32 d0 = a0 - b0, d1 = a1 - b1, d2 = a2 - b2;
    if (yuv) {
      const v_float32 yn = d0 * ys, cb = d1 * cs, cr = d2 * cs;
      d0 = yn + rv * cr;
      d1 = yn + gu * cb + gv * cr;
      d2 = yn + bu * cb;
    }
    const v_float32 joined = v_abs(d0) + v_abs(d1) + v_abs(d2) < thr;
    bits |= static_cast<uint64_t>(v_signmask(joined)) << i;
  }
#endif
  for (; i < n; ++i)
    if (blocks_joined(a + 3 * i, b + 3 * i, threshold, yuv)) bits |= uint64_t{1} << i;
  return bits;
}

}  // namespace

void BlockRegions::label_tile(const std::vector<float> &features, int t, const uint32_t *hq) {
  static_assert(kTileW <= 64, "a tile row's joins are one 64-bit mask");
  const int bx = bx_;
  const PixelRect tile = tile_blocks(t);
  const int x0 = tile.x0, x1 = tile.x1, y0 = tile.y0, y1 = tile.y1;
  int *parent = tile_root_.data();
  // Row by row: each run of right-joined blocks points at its first block;
  // then the runs joined to the row above are united, once a pair of runs
  // (neighbouring columns mostly join the same two).
  for (int y = y0; y < y1; ++y) {
    const int k0 = y * bx + x0, n = x1 - x0;
    const float *f = &features[3 * static_cast<size_t>(k0)];
    const uint64_t right = joined_bits(f, f + 3, n - 1, threshold_, yuv_);
    parent[k0] = k0;
    for (int x = 1; x < n; ++x) parent[k0 + x] = (right >> (x - 1)) & 1 ? parent[k0 + x - 1] : k0 + x;
    if (y == y0) continue;
    int last_above = -1, last_here = -1;
    for (uint64_t down = joined_bits(f - 3 * static_cast<size_t>(bx), f, n, threshold_, yuv_); down;
         down &= down - 1) {
      const int k = k0 + __builtin_ctzll(down), above = parent[k - bx], here = parent[k];
      if (above == last_above && here == last_here) continue;
      join(parent, above, here);
      last_above = above;
      last_here = here;
    }
  }
  // In index order every block's parent is already flat, so each block
  // points straight at its tile root; a root comes first in its tree, so
  // its statistics start there.
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const int k = y * bx + x, r = parent[parent[k]];
      parent[k] = r;
      if (!stats_) continue;
      if (r == k) {
        sum_[k] = hq[k];
        count_[k] = 1;
        max_[k] = hq[k];
      } else {
        sum_[r] += hq[k];
        ++count_[r];
        max_[r] = std::max(max_[r], hq[k]);
      }
    }
}

PixelRect BlockRegions::tile_blocks(int t) const {
  const int x0 = (t % tiles_x_) * kTileW, y0 = (t / tiles_x_) * kTileH;
  return PixelRect{x0, y0, std::min(bx_, x0 + kTileW), std::min(by_, y0 + kTileH)};
}

void BlockRegions::join_tiles(const std::vector<float> &features) {
  const int bx = bx_;
  // Along a tile edge neighbouring pairs mostly link the same two tile
  // roots: a pair joined as the last one was is already united.
  auto edge = [&](int a, int b, int &last_a, int &last_b) {
    const int ra = tile_root_[a], rb = tile_root_[b];
    if (ra == last_a && rb == last_b) return;
    if (!blocks_joined(&features[3 * static_cast<size_t>(a)], &features[3 * static_cast<size_t>(b)], threshold_, yuv_))
      return;
    unite(ra, rb);
    last_a = ra;
    last_b = rb;
  };
  for (int tx = 1; tx < tiles_x_; ++tx) {
    int last_a = -1, last_b = -1;
    for (int y = 0; y < by_; ++y) edge(y * bx + tx * kTileW - 1, y * bx + tx * kTileW, last_a, last_b);
  }
  for (int ty = 1; ty < tiles_y_; ++ty) {
    int last_a = -1, last_b = -1;
    const int above = (ty * kTileH - 1) * bx;
    for (int x = 0; x < bx; ++x) edge(above + x, above + x + bx, last_a, last_b);
  }
}

void BlockRegions::take_stats(int r) {
  if (merged_[r]) return;
  merged_[r] = 1;
  touched_.push_back(r);
  merged_sum_[r] = sum_[r];
  merged_count_[r] = count_[r];
  merged_max_[r] = max_[r];
}

void BlockRegions::unite(int a, int b) {
  a = find_root(parent_.data(), a);
  b = find_root(parent_.data(), b);
  if (a == b) return;
  if (b < a) std::swap(a, b);
  parent_[b] = a;
  touched_.push_back(b);
  if (!stats_) return;
  const uint64_t s = sum(b);
  const uint32_t c = count(b), m = max(b);
  take_stats(a);
  merged_sum_[a] += s;
  merged_count_[a] += c;
  merged_max_[a] = std::max(merged_max_[a], m);
}

}  // namespace p3d
