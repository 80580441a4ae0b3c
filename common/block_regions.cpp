#include "block_regions.h"

#include <algorithm>
#include <numeric>

#include <opencv2/core.hpp>

#include "depth_estimate.h"

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

// The root of i without writing: safe while other threads read the forest.
int root_of(const int *parent, int i) {
  while (parent[i] != i) i = parent[i];
  return i;
}

// The smaller root becomes the parent; returns {kept root, absorbed root},
// equal when a and b were already one tree.
std::pair<int, int> join(int *parent, int a, int b) {
  a = find_root(parent, a);
  b = find_root(parent, b);
  if (a == b) return {a, a};
  if (b < a) std::swap(a, b);
  parent[b] = a;
  return {a, b};
}

// Block rows a strip has: enough strips for every worker to get several
// (the rows' cost varies), few enough that the serial boundary pass stays
// small.
int strip_rows(int blocks_y) {
  const int strips = std::max(1, 4 * cv::getNumThreads());
  return std::max(8, (blocks_y + strips - 1) / strips);
}

}  // namespace

void BlockRegions::unite(int a, int b) {
  const auto [kept, gone] = join(parent_.data(), a, b);
  if (kept == gone || !stats_) return;
  sum_[kept] += sum_[gone];
  count_[kept] += count_[gone];
  max_[kept] = std::max(max_[kept], max_[gone]);
}

void BlockRegions::label(const std::vector<float> &features, int bx, int by, float edge_threshold, bool yuv,
                         const uint32_t *hq) {
  const size_t n = static_cast<size_t>(bx) * by;
  parent_.resize(n);
  labels_.resize(n);
  stats_ = hq != nullptr;
  if (stats_) {
    sum_.resize(n);
    count_.resize(n);
    max_.resize(n);
  }
  if (n == 0) return;
  int *parent = parent_.data();
  auto joined = [&](size_t a, size_t b) { return blocks_joined(&features[3 * a], &features[3 * b], edge_threshold, yuv); };
  const int rows = strip_rows(by), strips = (by + rows - 1) / rows;
  cv::parallel_for_(cv::Range(0, strips), [&](const cv::Range &range) {
    for (int s = range.start; s < range.end; ++s) {
      const size_t k0 = static_cast<size_t>(s) * rows * bx, k1 = std::min(n, k0 + static_cast<size_t>(rows) * bx);
      std::iota(parent + k0, parent + k1, static_cast<int>(k0));
      for (size_t k = k0; k < k1; ++k) {
        const bool has_right = static_cast<int>(k % bx) + 1 < bx, has_below = k + bx < k1;
        if (has_right && joined(k, k + 1)) join(parent, static_cast<int>(k), static_cast<int>(k + 1));
        if (has_below && joined(k, k + bx)) join(parent, static_cast<int>(k), static_cast<int>(k + bx));
      }
      if (!stats_) continue;
      std::fill(sum_.begin() + k0, sum_.begin() + k1, 0);
      std::fill(count_.begin() + k0, count_.begin() + k1, 0);
      std::fill(max_.begin() + k0, max_.begin() + k1, 0);
      for (size_t k = k0; k < k1; ++k) {  // the strip's trees have their roots inside it
        const int r = find_root(parent, static_cast<int>(k));
        sum_[r] += hq[k];
        ++count_[r];
        max_[r] = std::max(max_[r], hq[k]);
      }
    }
  });
  for (int s = 1; s < strips; ++s) {  // the row above each strip's first row
    const size_t above = (static_cast<size_t>(s) * rows - 1) * bx;
    for (size_t k = above; k < above + bx; ++k)
      if (joined(k, k + bx)) unite(static_cast<int>(k), static_cast<int>(k + bx));
  }
  cv::parallel_for_(cv::Range(0, by), [&](const cv::Range &range) {
    for (size_t k = static_cast<size_t>(range.start) * bx; k < static_cast<size_t>(range.end) * bx; ++k)
      labels_[k] = root_of(parent, static_cast<int>(k));
  });
}

}  // namespace p3d
