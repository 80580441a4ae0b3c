// Step 2 and step 4's reductions of the depth estimator
// (common/depth_estimate.h): the regions of the block grid, as connected
// components of the "joined" graph of 4-connected blocks, and each
// region's statistics of the quantised hypothesis (sum, count, max).
//
// The rule is the estimator's: a region's label is the smallest block index
// in it. Any correct labelling gives those labels, and the statistics are
// exact integer reductions, so the result does not depend on how the work
// is split. Here the block rows are cut into strips that are labelled in
// parallel (union-find whose parents always point to a smaller index, so a
// root is its tree's smallest index) with each strip's statistics summed at
// its own roots; then the strips' boundary rows are joined in one serial
// pass that merges the statistics of the trees it unites, and every block
// reads its final root in parallel.
#pragma once

#include <cstdint>
#include <vector>

namespace p3d {

class BlockRegions {
 public:
  // Labels the bx x by grid of features (3 a block; yuv: Y'CbCr means,
  // blocks_joined()). hq: one quantised hypothesis a block, whose sum,
  // count and max per region are then available; null: labels only.
  void label(const std::vector<float> &features, int blocks_x, int blocks_y, float edge_threshold, bool yuv,
             const uint32_t *hq);

  const std::vector<int> &labels() const { return labels_; }
  // Step 4's statistics of region r (a label; after label() with hq).
  uint64_t sum(int r) const { return sum_[r]; }
  uint32_t count(int r) const { return count_[r]; }
  uint32_t max(int r) const { return max_[r]; }

 private:
  void unite(int a, int b);  // serial: merges the statistics of the two trees
  std::vector<int> parent_, labels_;
  std::vector<uint64_t> sum_;
  std::vector<uint32_t> count_, max_;
  bool stats_ = false;
};

}  // namespace p3d
