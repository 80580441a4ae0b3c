// Step 2 and step 4's reductions of the depth estimator
// (common/depth_estimate.h): the regions of the block grid, as connected
// components of the "joined" graph of 4-connected blocks, and each
// region's statistics of the quantised hypothesis (sum, count, max).
//
// The rule is the estimator's: a region's label is the smallest block index
// in it. Any correct labelling gives those labels, and the statistics are
// exact integer reductions, so the result does not depend on how the work
// is split. Here the grid is cut into tiles of kTileW x kTileH blocks,
// labelled in parallel (union-find whose parents always point to a
// smaller index, so a root is its tree's smallest index), each tile's
// statistics summed at its own roots. One serial pass then joins the tiles'
// roots across the tile edges, merging the statistics of the trees it
// unites, and every block reads its final root in parallel.
//
// Incremental calls keep the tiles' labels and statistics: the next
// incremental call labels again only the tiles whose features differ
// (bytewise) from the ones it kept, and joins the edges again, which is the
// same function. A screen where a cursor moves relabels a few tiles.
#pragma once

#include <cstdint>
#include <vector>

#include "p3d_defs.h"

namespace p3d {

class BlockRegions {
 public:
  static constexpr int kTileW = 32, kTileH = 16;  // blocks

  // Labels the bx x by grid of features (3 a block; yuv: Y'CbCr means,
  // blocks_joined()). hq: one quantised hypothesis a block, whose sum,
  // count and max per region are then available; null: labels only.
  // incremental: relabel only the tiles whose features changed since the
  // last incremental call (with the same grid, threshold, yuv and hq
  // presence); hq must be the values of that call, else forget() first.
  void label(const std::vector<float> &features, int blocks_x, int blocks_y, float edge_threshold, bool yuv,
             const uint32_t *hq, bool incremental = false);
  // The next call labels every tile.
  void forget() { kept_ = false; }

  const std::vector<int> &labels() const { return labels_; }
  // Step 4's statistics of region r (a label; after label() with hq).
  uint64_t sum(int r) const { return merged_[r] ? merged_sum_[r] : sum_[r]; }
  uint32_t count(int r) const { return merged_[r] ? merged_count_[r] : count_[r]; }
  uint32_t max(int r) const { return merged_[r] ? merged_max_[r] : max_[r]; }
  // Tiles the last call labelled (all of them unless it was incremental).
  int tiles_labelled() const { return tiles_labelled_; }

 private:
  PixelRect tile_blocks(int tile) const;  // the blocks of a tile (x: columns, y: rows of blocks)
  void label_tile(const std::vector<float> &features, int tile, const uint32_t *hq);
  void join_tiles(const std::vector<float> &features);
  void unite(int a, int b);  // serial: roots across a tile edge, statistics merged
  void take_stats(int r);    // the first merge at root r starts from its tile's statistics

  int bx_ = 0, by_ = 0, tiles_x_ = 0, tiles_y_ = 0;
  float threshold_ = 0.f;
  bool yuv_ = false, stats_ = false, kept_ = false;
  int tiles_labelled_ = 0;
  // Per block: the root of its tree within its tile (parents point to the
  // tree's smallest index); the roots' statistics over their tile.
  std::vector<int> tile_root_;
  std::vector<uint64_t> sum_;
  std::vector<uint32_t> count_, max_;
  // Across tiles: a forest over the tiles' roots, identity except at the
  // indices in touched_; statistics of the roots that absorbed others.
  std::vector<int> parent_, touched_, labels_;
  std::vector<uint8_t> merged_;
  std::vector<uint64_t> merged_sum_;
  std::vector<uint32_t> merged_count_, merged_max_;
  std::vector<float> kept_features_;
  std::vector<uint8_t> dirty_;
};

}  // namespace p3d
