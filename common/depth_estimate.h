// Depth from a single frame using edge information (regions grouped along
// image edges, each given depth from a depth-gradient hypothesis), plus the
// temporal smoothing used for video. CPU reference; cuda/depth_estimate_gpu.h
// computes the same function on the GPU.
//
// The function, exactly (both implementations follow these steps):
//  1. Blocks. The frame is cut into B x B blocks, B = effective_block_size()
//     (block_size, or with block_size 0 one block per 1/540 of the shorter
//     side; the last row/column of blocks may be partial). Each block's
//     feature f is the mean of load_native3() over its pixels: integer sums
//     per channel, then mean = (float)sum / (float)count.
//  2. Edges. Two 4-connected blocks belong to one region when
//     |ds0| + |ds1| + |ds2| < edge_threshold (ds in R'G'B' levels: on Y'CbCr
//     frames the difference is converted first, blocks_joined()), s being
//     the blocks' smoothed
//     features (step 5's smooth_block_feature(): s = f on a still picture, a
//     cut and with feature_smoothing 0; otherwise f averaged over the frames
//     since the block last moved, so that camera noise does not flip edges).
//     Regions are the connected components of that graph. A component's label
//     is the smallest block index (by * blocks_x + bx) in it, so any correct
//     connected-components algorithm (union-find in parallel tiles on the
//     CPU, common/block_regions.h; parallel union-find on the GPU) gives
//     identical labels.
//  3. Hypothesis. h(block) = hypothesis evaluated at the block's centre
//     (cx = (bx*B + min(B, W - bx*B) / 2.0) / W, likewise cy), see
//     hypothesis_depth(). It is quantised hq = (uint32)(h * 65535 + 0.5).
//  4. Region depth, from three exact integer reductions over the region's
//     blocks: S = sum of hq (uint64), N = block count, M = max of hq (the
//     block the hypothesis puts nearest: for top-bottom the region's lowest
//     block, where an object stands on the ground). region_depth():
//       r_mean = (float)S / (float)N / 65535, r_near = (float)M / 65535,
//       r = ground_contact * r_near + (1 - ground_contact) * r_mean.
//     Block depth b = region_weight * r + (1 - region_weight) * h_q, with
//     h_q = hq / 65535 (block_depth_value()). ground_contact 0 is the
//     region mean alone, bit for bit the estimator before the cue.
//  5. Temporal (when the estimator has state from an earlier frame):
//     diff = mean over blocks and channels of |feature - reference feature|
//     (the reference is the last frame whose depth was computed, not reused).
//       diff <= static_threshold -> reuse: output the previous block depths
//                                   unchanged, keep the reference;
//       diff >= cut_threshold    -> cut: output b, reset the state;
//       otherwise                -> out = temporal_smoothing * prev + (1 - temporal_smoothing) * b.
//     A first frame or a size change behaves as a cut. The decision is taken
//     from the features alone, before step 2, whose smoothed features restart
//     from f at a cut and otherwise (reused frames included) follow
//     smooth_block_feature().
//     (The mean is taken in fixed point, see temporal_diff_fixed(); a change
//     of block_size is a size change of the block grid, so also a cut.)
//     Steps 1-4 run on every frame, reused or not, so labels() always
//     describe the current frame; an adaptive call (estimate_blocks() with
//     a ChangeMap) sums step 1 only over the blocks a changed tile touches,
//     labels again only the tiles of blocks whose smoothed features changed
//     (BlockRegions keeps the others), and leaves steps 2-4 out on a reused
//     frame, whose output does not depend on them: the same block depths.
//  6. Expansion. Every pixel takes its block's depth (piecewise constant; the
//     cross-bilateral filter aligns the block edges with image edges later).
// Depth convention: 0 = farthest, 1 = nearest.
#pragma once

#include <cstdint>
#include <vector>

#include "block_regions.h"
#include "change_map.h"
#include "enum_name.h"
#include "frame.h"

namespace p3d {

enum class Hypothesis : int {
  TopBottom = 0,   // far at the top, near at the bottom: h = cy
  LeftRight = 1,   // far at the left, near at the right: h = cx
  CenterNear = 2,  // near in the centre: h = 1 - min(1, dist(c, centre) / sqrt(0.5))
  Flat = 3,        // h = 0.5 everywhere
};

inline constexpr EnumName<Hypothesis> kHypothesisNames[] = {
    {Hypothesis::TopBottom, "top-bottom", "Far at the top, near at the bottom"},
    {Hypothesis::LeftRight, "left-right", "Far at the left, near at the right"},
    {Hypothesis::CenterNear, "center-near", "Near in the centre, far at the edges"},
    {Hypothesis::Flat, "flat", "No gradient (regions only)"},
};
P3D_CHECK_ENUM_NAMES(kHypothesisNames);

struct DepthParams {
  Hypothesis hypothesis = Hypothesis::TopBottom;
  int block_size = 0;              // pixels, 2..64; 0 = auto (effective_block_size())
  float edge_threshold = 24.f;     // L1 of 8-bit R'G'B' channel means; 0 = every block its own region
  float region_weight = 0.9f;      // 0..1: share of the region's depth in a block's depth
  float ground_contact = 1.f;      // 0..1: share of the region's nearest block (vs its mean), step 4
  float temporal_smoothing = 0.5f; // 0..0.99: weight of the previous depth (0 = none)
  float feature_smoothing = 0.9f;  // 0..0.99: weight of the past in the features edges compare (step 2)
  float static_threshold = 0.5f;   // mean |difference| (8-bit levels) under which depth is reused
  float cut_threshold = 30.f;      // mean |difference| at or over which the history is dropped
};

P3D_HD float hypothesis_depth(Hypothesis h, float cx, float cy) {
  switch (h) {
    case Hypothesis::TopBottom: return cy;
    case Hypothesis::LeftRight: return cx;
    case Hypothesis::CenterNear: {
      const float dx = cx - 0.5f, dy = cy - 0.5f;
      const float d = sqrtf(dx * dx + dy * dy) / 0.70710678f;
      return 1.f - (d < 1.f ? d : 1.f);
    }
    default: return 0.5f;
  }
}

P3D_HD int blocks_along(int pixels, int block) { return (pixels + block - 1) / block; }

// What step 5 decided for a frame.
enum class TemporalDecision : int { Cut = 0, Smooth = 1, Reuse = 2 };

// ---------------------------------------------------------------------------
// The per-block maths of steps 1-5, shared by the CPU loops and the kernels so
// that both compute one function (same operation order; common/ is built with
// -ffp-contract=off and cuda/ with -fmad=false, division and sqrtf are IEEE on
// both sides, so the results are bitwise identical).

// With block_size 0 (auto), one block per kAutoBlockDivisor pixels of the
// picture's shorter side: 2 up to 1079 rows, 2 at 1080p, 4 at 4K, 8 at 8K. The
// blocks then cover the same share of the scene at every resolution, so a
// film gives the same regions at 1080p and at 4K; and at 2 pixels a block
// (every picture up to 1080p) thin objects stay whole at sizes where 4-pixel
// blocks break them up (docs/quality.md: Aloe at half size). Any other value
// outside 2..64 is clamped (the kernels size shared memory for 64).
constexpr int kAutoBlockDivisor = 540;
P3D_HD int effective_block_size(const DepthParams &p, int width, int height) {
  if (p.block_size == 0) return clamp_value((width < height ? width : height) / kAutoBlockDivisor, 2, 64);
  return clamp_value(p.block_size, 2, 64);
}

// The grid (p3d_defs.h DepthGrid) that holds a frame's depth with one value
// a block: log2 B where the effective block B is a power of two (the
// automatic 2, 4 and 8 at 1080p, 4K and 8K; not 3 at 1620 rows), else 0,
// the full-size map.
P3D_HD int block_grid_shift(const DepthParams &p, int width, int height) {
  const int s = step_shift(effective_block_size(p, width, height));
  return s > 0 ? s : 0;
}

// Pixels of block number b along an axis of `pixels` (the last block may be partial).
P3D_HD int block_extent(int b, int block, int pixels) {
  const int left = pixels - b * block;
  return left < block ? left : block;
}

// Step 1: one channel's mean from its integer sum.
P3D_HD float block_mean(uint32_t sum, int count) { return static_cast<float>(sum) / static_cast<float>(count); }

// Step 2: whether two 4-connected blocks with features a[3], b[3] share a
// region. The threshold is an L1 distance of R'G'B' levels whatever the
// frame's format: on Y'CbCr frames (`yuv`) the feature difference goes
// through the Y'CbCr -> R'G'B' matrix first (BT.601 limited range, the
// default YuvToRgb: an edge test needs no exact colorimetry). Compared raw,
// a grey step of d levels would count 0.86 d instead of 3 d, and decoded
// video (I420, NV12) grouped nearly the whole picture into one region
// (Aloe's rho 0.647 as I420 against 0.838 as RGBA, docs/quality.md).
P3D_HD bool blocks_joined(const float *a, const float *b, float edge_threshold, bool yuv) {
  float d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
  if (yuv) {
    const YuvToRgb m;
    const float yn = d0 * m.y_scale, cb = d1 * m.c_scale, cr = d2 * m.c_scale;
    d0 = yn + m.rv * cr;
    d1 = yn + m.gu * cb + m.gv * cr;
    d2 = yn + m.bu * cb;
  }
  return fabsf(d0) + fabsf(d1) + fabsf(d2) < edge_threshold;
}

// Step 3: normalised centre of block b along an axis (computed in double as the
// spec writes it; exact up to the final rounding to float).
P3D_HD float block_centre(int b, int block, int pixels) {
  return static_cast<float>((b * block + block_extent(b, block, pixels) / 2.0) / pixels);
}

// Step 3: the quantised hypothesis at block centre (cx, cy) (block_centre()
// of the block's column and row, which loops may compute once per column).
P3D_HD uint32_t hypothesis_q(Hypothesis h, float cx, float cy) {
  return static_cast<uint32_t>(hypothesis_depth(h, cx, cy) * 65535.f + 0.5f);
}
// Step 3: the quantised hypothesis of block (bx, by).
P3D_HD uint32_t block_hypothesis_q(Hypothesis h, int bx, int by, int block, int width, int height) {
  return hypothesis_q(h, block_centre(bx, block, width), block_centre(by, block, height));
}

// Step 4: a region's depth from its hq sum, block count and largest hq.
P3D_HD float region_depth(float ground_contact, uint64_t region_sum, uint32_t region_count, uint32_t region_max) {
  const float r_mean = static_cast<float>(region_sum) / static_cast<float>(region_count) / 65535.f;
  const float r_near = static_cast<float>(region_max) / 65535.f;
  return ground_contact * r_near + (1.f - ground_contact) * r_mean;
}

// Step 4: a block's depth from its region's depth r and its own hq.
P3D_HD float block_depth_from_region(const DepthParams &p, float r, uint32_t hq) {
  const float h_q = static_cast<float>(hq) / 65535.f;
  return p.region_weight * r + (1.f - p.region_weight) * h_q;
}

// Step 4: a block's depth from its region's statistics and its own hq.
P3D_HD float block_depth_value(const DepthParams &p, uint64_t region_sum, uint32_t region_count, uint32_t region_max,
                               uint32_t hq) {
  return block_depth_from_region(p, region_depth(p.ground_contact, region_sum, region_count, region_max), hq);
}

// Step 5, the mean |difference|. A float sum would depend on the summation
// order (sequential on the CPU, a tree of atomics on the GPU) and could flip a
// decision near a threshold. Each |feature - reference| is therefore truncated
// to 40.24 fixed point (multiplying by 2^24 is exact) and summed as uint64,
// which is exact in any order; the mean is then within 2^-24 of the exact one.
// Sum bound: 3 * blocks * 256 * 2^24 < 2^64 for up to 2^29 blocks.
P3D_HD uint64_t temporal_diff_fixed(float feature, float reference) {
  return static_cast<uint64_t>(fabsf(feature - reference) * 16777216.f);
}
P3D_HD float temporal_mean_diff(uint64_t fixed_sum, long long values) {
  return static_cast<float>(static_cast<double>(fixed_sum) / 16777216.0 / static_cast<double>(values));
}
P3D_HD TemporalDecision temporal_decision(bool have_state, float diff, const DepthParams &p) {
  if (!have_state) return TemporalDecision::Cut;
  if (diff <= p.static_threshold) return TemporalDecision::Reuse;
  if (diff >= p.cut_threshold) return TemporalDecision::Cut;
  return TemporalDecision::Smooth;
}

// Step 2's smoothed feature s of one block (3 channels), updated in place
// from this frame's feature f. On a cut s restarts from f; otherwise s moves
// towards f by (1 - feature_smoothing), unless the block moved (L1 distance
// from s of kFeatureMotionGate 8-bit levels or more, several times the noise
// of a 2x2 block mean of decoded video), when it takes f at once: smoothing
// removes the noise that flips edges on a static background without making
// the regions of moving objects lag. Measured in docs/quality.md (flicker).
constexpr float kFeatureMotionGate = 8.f;
P3D_HD void smooth_block_feature(bool cut, float feature_smoothing, const float *f, float *s) {
  const float w = clamp_value(feature_smoothing, 0.f, 0.99f);
  if (!cut && w > 0.f && fabsf(s[0] - f[0]) + fabsf(s[1] - f[1]) + fabsf(s[2] - f[2]) < kFeatureMotionGate) {
    for (int c = 0; c < 3; ++c) s[c] = w * s[c] + (1.f - w) * f[c];
    return;
  }
  for (int c = 0; c < 3; ++c) s[c] = f[c];
}

// Step 5, the output block depth given the decision (prev: last output, fresh: b).
P3D_HD float temporal_output(TemporalDecision d, float prev, float fresh, float temporal_smoothing) {
  switch (d) {
    case TemporalDecision::Reuse: return prev;
    case TemporalDecision::Smooth: return temporal_smoothing * prev + (1.f - temporal_smoothing) * fresh;
    default: return fresh;
  }
}

// Stateful CPU estimator (one per element instance; not thread-safe).
class DepthEstimatorCpu {
 public:
  // Estimates depth for one frame into `depth` (same size as the frame).
  // Returns what the temporal step decided.
  TemporalDecision estimate(const DepthParams &params, const FrameView &frame, ImageView<float> depth);
  // Steps 1-5 only: the block depths of `frame`. changes: the tiles in
  // which `frame` differs from the frame of the previous call (null: not
  // known, all of them); the block depths are bit for bit those of a call
  // without it. output_changed() then tells whether any block depth
  // differs from the previous call's, and expand() writes the map.
  TemporalDecision estimate_blocks(const DepthParams &params, const FrameView &frame, const ChangeMap *changes);
  bool output_changed() const { return output_changed_; }
  void expand(ImageView<float> depth) const;
  void reset();  // forget history (next frame is treated as a cut)

  // Block-level results of the last call, for tests.
  const std::vector<int> &labels() const { return regions_.labels(); }
  const std::vector<float> &smoothed_features() const { return smoothed_; }  // step 2's s, 3 per block
  const std::vector<float> &block_depth() const { return block_depth_; }
  int blocks_x() const { return bx_; }
  int blocks_y() const { return by_; }
  // Mean |feature difference| of the last call (step 5; 0 after a cut for want of history).
  float last_diff() const { return last_diff_; }

 private:
  int bx_ = 0, by_ = 0, block_ = 0, width_ = 0, height_ = 0;
  std::vector<float> features_;      // 3 per block, this frame
  std::vector<float> ref_features_;  // 3 per block, last computed frame
  std::vector<uint8_t> ref_behind_;  // block rows where features_ may differ from ref_features_
  std::vector<float> smoothed_;      // 3 per block, step 2's s
  std::vector<uint64_t> row_diff_;   // step 5's fixed-point sum, per block row
  // The grid step 3's hypotheses were computed for.
  struct HypothesisGrid {
    Hypothesis hypothesis = Hypothesis::TopBottom;
    int bx = 0, by = 0, width = 0, height = 0, block = 0;
    bool operator==(const HypothesisGrid &o) const {
      return hypothesis == o.hypothesis && bx == o.bx && by == o.by && width == o.width && height == o.height &&
             block == o.block;
    }
  };
  HypothesisGrid hq_grid_;
  std::vector<uint32_t> hq_;         // step 3, one a block, for hq_grid_
  BlockRegions regions_;             // steps 2 and 4
  std::vector<float> block_depth_;   // output of the last frame
  std::vector<uint8_t> row_changed_; // block rows whose output changed in the last call
  float last_diff_ = 0.f;
  TemporalDecision last_decision_ = TemporalDecision::Cut;
  bool have_state_ = false;
  bool features_current_ = false;  // features_ holds the previous call's features (adaptive calls)
  bool output_changed_ = true;
  std::vector<uint8_t> settled_rows_;  // block rows whose last smoothing pass changed nothing
  float settled_weight_ = -1.f;        // the feature_smoothing of that pass
};

// Stateless helpers the estimator is built from (exposed for tests and for
// the GPU tests that compare intermediate results).
// only: one flag a block (0 or 1); the blocks without it keep their values
// in features.
void block_features_cpu(const FrameView &frame, int block_size, std::vector<float> &features,
                        const std::vector<uint8_t> *only = nullptr);
// yuv: the features are Y'CbCr means (blocks_joined()).
void region_labels_cpu(const std::vector<float> &features, int blocks_x, int blocks_y, float edge_threshold, bool yuv,
                       std::vector<int> &labels);
// Step 3's quantised hypothesis of every block (block_hypothesis_q()).
void block_hypotheses_cpu(Hypothesis h, int blocks_x, int blocks_y, int width, int height, int block_size,
                          std::vector<uint32_t> &hq);
// Writes depth's pixels that the block grid covers (all of them when depth has the frame's size).
void expand_block_depth_cpu(const std::vector<float> &block_depth, int blocks_x, int block_size, ImageView<float> depth);

// Depth from a grey picture (RGBD input): depth = rgb_luma(load_rgba(grey, x, y)) / 255.
P3D_HD float depth_from_grey(const FrameView &grey, int x, int y, const YuvToRgb &m) {
  const Rgba c = load_rgba(grey, x, y, m);
  return rgb_luma(c.r, c.g, c.b) / 255.f;
}
void depth_from_grey_cpu(const FrameView &grey, const YuvToRgb &m, ImageView<float> depth);

}  // namespace p3d
