#include "depth_estimate.h"

#include <algorithm>
#include <cstring>

#include <opencv2/core.hpp>

#include "row_convert.h"

namespace p3d {

namespace {

// acc[x] += row[x] for n bytes, 16-bit sums (a block row adds at most 64
// rows of 255).
void add_row(uint16_t *acc, const uint8_t *row, int n) {
  int x = 0;
#if P3D_CPU_VECTORS
  using namespace cv;
  constexpr int L = v_uint8::nlanes;
  for (; x + L <= n; x += L) {
    v_uint16 lo, hi;
    v_expand(vx_load(row + x), lo, hi);
    v_store(acc + x, vx_load(acc + x) + lo);
    v_store(acc + x + L / 2, vx_load(acc + x + L / 2) + hi);
  }
#endif
  for (; x < n; ++x) acc[x] = static_cast<uint16_t>(acc[x] + row[x]);
}

// out[x - x0] = col[step * (x / 2)] for pixel columns [x0, x1): a 4:2:0
// chroma sample's column sum for each pixel column that reads it (step 2
// for NV12's interleaved pairs).
void chroma_per_pixel(const uint16_t *col, int step, int x0, int x1, uint16_t *out) {
  for (int x = x0; x < x1; ++x) out[x - x0] = col[step * (x / 2)];
}

// sums[i] = the sum of in[i B .. i B + B) for the n whole blocks of a row.
void block_sums(const uint16_t *in, int B, int n, uint32_t *sums) {
  int i = 0;
#if P3D_CPU_VECTORS
  using namespace cv;
  constexpr int L = v_uint16::nlanes;
  if (B == 2 || B == 4) {  // a block then adds at most 16 samples of 255: 16-bit sums
    for (; i + L <= n; i += L) {
      v_uint16 s;
      if (B == 2) {
        v_uint16 a, b;
        v_load_deinterleave(in + 2 * i, a, b);
        s = a + b;
      } else {
        v_uint16 a, b, c, d;
        v_load_deinterleave(in + 4 * i, a, b, c, d);
        s = a + b + c + d;
      }
      v_uint32 lo, hi;
      v_expand(s, lo, hi);
      v_store(sums + i, lo);
      v_store(sums + i + L / 2, hi);
    }
  }
#endif
  for (; i < n; ++i) {
    uint32_t s = 0;
    for (int x = i * B; x < i * B + B; ++x) s += in[x];
    sums[i] = s;
  }
}

// One row of blocks of an 8-bit frame (blocks [i0, i1) of block row j),
// the sums of step 1 taken from column sums: every plane's rows of the
// block row are added up per byte column (a 4:2:0 chroma row once for each
// pixel row that reads it), each channel's sums set out per pixel column,
// then each block adds its columns. The same integers as summing
// load_native3() pixel by pixel.
void block_row_features_8bit(const FrameView &frame, int B, int j, int i0, int i1, const std::vector<uint8_t> *only,
                             std::vector<uint16_t> (&cols)[3], std::vector<uint16_t> (&pixel)[3],
                             std::vector<uint32_t> (&sums)[3], float *f) {
  const int W = frame.width, H = frame.height, rows = block_extent(j, B, H);
  const int bx = blocks_along(W, B), c0 = i0 * B, c1 = std::min(W, i1 * B), n = c1 - c0;
  const bool rgb = is_packed_rgb(frame.format), nv12 = is_semi_planar(frame.format);
  const int planes = rgb ? 1 : nv12 ? 2 : 3;
  for (int p = 0; p < planes; ++p) {
    // Byte columns of plane p that pixels [c0, c1) read.
    const int b0 = rgb ? 4 * c0 : p == 0 ? c0 : nv12 ? 2 * (c0 / 2) : c0 / 2;
    const int b1 = rgb ? 4 * c1 : p == 0 ? c1 : nv12 ? 2 * ((c1 - 1) / 2) + 2 : (c1 - 1) / 2 + 1;
    cols[p].assign(static_cast<size_t>(b1), 0);
    for (int y = j * B; y < j * B + rows; ++y) {
      const int r = p == 0 ? y : y / 2;
      add_row(cols[p].data() + b0, frame.plane[p] + static_cast<size_t>(r) * frame.stride[p] + b0, b1 - b0);
    }
  }
  // Channel c's column sums for pixel columns [c0, c1).
  const uint16_t *channel[3];
  for (std::vector<uint16_t> &v : pixel) v.resize(static_cast<size_t>(n));
  if (rgb) {
    const int red = is_bgr_order(frame.format) ? 2 : 0;
    const uint16_t *c = cols[0].data();
    for (int x = c0; x < c1; ++x) {
      pixel[0][x - c0] = c[4 * x + red];
      pixel[1][x - c0] = c[4 * x + 1];
      pixel[2][x - c0] = c[4 * x + 2 - red];
    }
    for (int c = 0; c < 3; ++c) channel[c] = pixel[c].data();
  } else {
    channel[0] = cols[0].data() + c0;
    chroma_per_pixel(cols[1].data(), nv12 ? 2 : 1, c0, c1, pixel[1].data());
    chroma_per_pixel(nv12 ? cols[1].data() + 1 : cols[2].data(), nv12 ? 2 : 1, c0, c1, pixel[2].data());
    channel[1] = pixel[1].data();
    channel[2] = pixel[2].data();
  }
  // The sums: whole blocks, then a partial last one.
  const int whole = std::min(i1, W / B) - i0;
  for (int c = 0; c < 3; ++c) {
    sums[c].resize(static_cast<size_t>(i1 - i0));
    block_sums(channel[c], B, whole, sums[c].data());
    if (whole < i1 - i0) {
      uint32_t s = 0;
      for (int x = whole * B; x < n; ++x) s += channel[c][x];
      sums[c][static_cast<size_t>(whole)] = s;
    }
  }
  // The means: whole blocks several at a time (a float division is IEEE in
  // either form), the row's partial last block alone.
  int i = i0;
#if P3D_CPU_VECTORS
  if (!only) {
    using namespace cv;
    constexpr int L = v_float32::nlanes;
    const v_float32 count = vx_setall_f32(static_cast<float>(B * rows));
    for (; i + L <= i0 + whole; i += L) {
      v_float32 m[3];
      for (int c = 0; c < 3; ++c)
        m[c] = v_cvt_f32(v_reinterpret_as_s32(vx_load(sums[c].data() + (i - i0)))) / count;
      v_store_interleave(f + 3 * i, m[0], m[1], m[2]);
    }
  }
#endif
  for (; i < i1; ++i) {
    if (only && !(*only)[static_cast<size_t>(j) * bx + i]) continue;
    const int count = block_extent(i, B, W) * rows;
    for (int c = 0; c < 3; ++c) f[i * 3 + c] = block_mean(sums[c][i - i0], count);
  }
}

}  // namespace

void block_features_cpu(const FrameView &frame, int block_size, std::vector<float> &features,
                        const std::vector<uint8_t> *only) {
  const int B = block_size, W = frame.width, H = frame.height;
  if (B < 1 || W <= 0 || H <= 0) {
    features.clear();
    return;
  }
  const int bx = blocks_along(W, B), by = blocks_along(H, B);
  features.resize(static_cast<size_t>(bx) * by * 3);
  const bool column_sums = !is_deep(frame.format) && B <= 64;
  // One task per block row: every block's pixels are then summed by one
  // thread, in integers, so the result does not depend on the split.
  cv::parallel_for_(cv::Range(0, by), [&](const cv::Range &range) {
    std::vector<uint16_t> cols[3];
    std::vector<uint16_t> pixel[3];
    std::vector<uint32_t> sums[3];
    for (int j = range.start; j < range.end; ++j) {
      const int rows = block_extent(j, B, H);
      float *f = &features[static_cast<size_t>(j) * bx * 3];
      int i0 = 0, i1 = bx;  // the blocks to sum: all, or from the first flagged to the last
      if (only) {  // memchr: a row of thousands of unflagged blocks is a few vector compares
        const uint8_t *flags = only->data() + static_cast<size_t>(j) * bx;
        const void *first = std::memchr(flags, 1, static_cast<size_t>(bx));
        if (!first) continue;
        i0 = static_cast<int>(static_cast<const uint8_t *>(first) - flags);
        while (!flags[i1 - 1]) --i1;
      }
      if (column_sums) {
        block_row_features_8bit(frame, B, j, i0, i1, only, cols, pixel, sums, f);
        continue;
      }
      for (int i = i0; i < i1; ++i) {
        if (only && !(*only)[static_cast<size_t>(j) * bx + i]) continue;
        const int cols_i = block_extent(i, B, W);
        uint32_t sum[3] = {0, 0, 0};
        for (int y = j * B; y < j * B + rows; ++y)
          for (int x = i * B; x < i * B + cols_i; ++x) {
            int c[3];
            load_native3(frame, x, y, c);
            sum[0] += c[0];
            sum[1] += c[1];
            sum[2] += c[2];
          }
        for (int c = 0; c < 3; ++c) f[i * 3 + c] = block_mean(sum[c], cols_i * rows);
      }
    }
  });
}

void region_labels_cpu(const std::vector<float> &features, int blocks_x, int blocks_y, float edge_threshold, bool yuv,
                       std::vector<int> &labels) {
  BlockRegions regions;
  regions.label(features, blocks_x, blocks_y, edge_threshold, yuv, nullptr);
  labels = regions.labels();
}

void block_hypotheses_cpu(Hypothesis h, int blocks_x, int blocks_y, int width, int height, int block_size,
                          std::vector<uint32_t> &hq) {
  hq.resize(static_cast<size_t>(blocks_x) * blocks_y);
  std::vector<float> cx(blocks_x);  // block_centre() once per column, not per block
  for (int i = 0; i < blocks_x; ++i) cx[i] = block_centre(i, block_size, width);
  cv::parallel_for_(cv::Range(0, blocks_y), [&](const cv::Range &range) {
    for (int j = range.start; j < range.end; ++j) {
      const float cy = block_centre(j, block_size, height);
      for (int i = 0; i < blocks_x; ++i) hq[static_cast<size_t>(j) * blocks_x + i] = hypothesis_q(h, cx[i], cy);
    }
  });
}

void expand_block_depth_cpu(const std::vector<float> &block_depth, int blocks_x, int block_size,
                            ImageView<float> depth) {
  if (depth.empty() || block_size < 1 || blocks_x < 1) return;
  const int blocks_y = static_cast<int>(block_depth.size() / blocks_x);
  const int w = std::min(depth.width, blocks_x * block_size), h = std::min(depth.height, blocks_y * block_size);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &range) {
    for (int y = range.start; y < range.end; ++y) {
      const float *src = &block_depth[static_cast<size_t>(y / block_size) * blocks_x];
      float *dst = depth.row(y);
      for (int x0 = 0, i = 0; x0 < w; x0 += block_size, ++i) std::fill(dst + x0, dst + std::min(w, x0 + block_size), src[i]);
    }
  });
}

void depth_from_grey_cpu(const FrameView &grey, const YuvToRgb &m, ImageView<float> depth) {
  if (depth.empty()) return;
  const int w = std::min(depth.width, grey.width), h = std::min(depth.height, grey.height);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &range) {
    for (int y = range.start; y < range.end; ++y) {
      float *dst = depth.row(y);
      for (int x = 0; x < w; ++x) dst[x] = depth_from_grey(grey, x, y, m);
    }
  });
}

void DepthEstimatorCpu::reset() { have_state_ = false; }

namespace {

// The blocks with a pixel in a changed tile: one flag a block (bx x by).
std::vector<uint8_t> blocks_touched(const ChangeMap &changes, int B, int bx, int by) {
  std::vector<uint8_t> touched(static_cast<size_t>(bx) * by, 0);
  for (int ty = 0; ty < changes.tiles_y(); ++ty)
    for (int tx = 0; tx < changes.tiles_x(); ++tx) {
      if (!changes.tile(tx, ty)) continue;
      const PixelRect r = tile_pixels(tx, ty, changes.width(), changes.height());
      for (int j = r.y0 / B; j <= (r.y1 - 1) / B; ++j)
        std::fill(touched.begin() + static_cast<size_t>(j) * bx + r.x0 / B,
                  touched.begin() + static_cast<size_t>(j) * bx + (r.x1 - 1) / B + 1, 1);
    }
  return touched;
}

}  // namespace

TemporalDecision DepthEstimatorCpu::estimate(const DepthParams &params, const FrameView &frame,
                                             ImageView<float> depth) {
  const TemporalDecision d = estimate_blocks(params, frame, nullptr);
  expand(depth);
  return d;
}

void DepthEstimatorCpu::expand(ImageView<float> depth) const {
  expand_block_depth_cpu(block_depth_, bx_, block_, depth);
}

TemporalDecision DepthEstimatorCpu::estimate_blocks(const DepthParams &params, const FrameView &frame,
                                                    const ChangeMap *changes) {
  const int W = frame.width, H = frame.height, B = effective_block_size(params, W, H);
  output_changed_ = true;
  if (W <= 0 || H <= 0) {
    reset();
    return TemporalDecision::Cut;
  }
  const int bx = blocks_along(W, B), by = blocks_along(H, B);
  const bool same_grid = have_state_ && bx == bx_ && by == by_ && B == block_ && W == width_ && H == height_;
  // Adaptive: features_ still holds the previous frame's features, and
  // only the blocks that a changed tile touches are summed again (the
  // others have the same pixels, so the same sums).
  const bool incremental = changes && same_grid && features_current_ && changes->width() == W &&
                           changes->height() == H;
  // one flag a block (none where no tile changed); one a block row
  std::vector<uint8_t> touched, row_touched;
  const bool none_touched = incremental && !changes->any();
  if (none_touched) {
    row_touched.assign(by, 0);
  } else if (incremental) {
    touched = blocks_touched(*changes, B, bx, by);
    row_touched.resize(by);
    for (int j = 0; j < by; ++j)
      row_touched[j] = std::memchr(touched.data() + static_cast<size_t>(j) * bx, 1, static_cast<size_t>(bx)) != nullptr;
    block_features_cpu(frame, B, features_, &touched);
  } else {
    block_features_cpu(frame, B, features_);
  }
  const size_t row_values = static_cast<size_t>(bx) * 3;
  float diff = 0.f;
  if (same_grid) {
    // Integer partial sums per block row: exact, so the split does not
    // matter. Incremental: a row without a touched block keeps its sum when
    // the reference stayed (a reused frame), and is 0 when the reference is
    // the previous frame itself.
    row_diff_.resize(by);
    cv::parallel_for_(cv::Range(0, by), [&](const cv::Range &range) {
      for (int j = range.start; j < range.end; ++j) {
        if (incremental && !row_touched[j]) {
          if (last_decision_ != TemporalDecision::Reuse) row_diff_[j] = 0;
          continue;
        }
        uint64_t s = 0;
        for (size_t k = static_cast<size_t>(j) * row_values; k < static_cast<size_t>(j + 1) * row_values; ++k)
          s += temporal_diff_fixed(features_[k], ref_features_[k]);
        row_diff_[j] = s;
      }
    });
    uint64_t fixed_sum = 0;
    for (const uint64_t s : row_diff_) fixed_sum += s;
    diff = temporal_mean_diff(fixed_sum, static_cast<long long>(features_.size()));
  }
  const TemporalDecision decision = temporal_decision(same_grid, diff, params);
  // The reference becomes this frame's features. Adaptive calls copy them,
  // since the next call updates features_ in place; others, and a frame
  // that changed every block (the next one likely does too), trade buffers.
  const bool all_touched = incremental ? !none_touched && std::find(touched.begin(), touched.end(), 0) == touched.end()
                                       : !changes || changes->all();
  bool features_current = changes != nullptr;
  // Incremental: the reference differs from features_ only in the rows a
  // change touched since it was taken (ref_behind_), so those rows are
  // the copy; after a whole sum any row may.
  if (incremental) {
    ref_behind_.resize(by, 1);
    for (int j = 0; j < by; ++j) ref_behind_[j] |= row_touched[j];
  } else {
    ref_behind_.assign(by, 1);
  }
  if (decision != TemporalDecision::Reuse) {
    if (incremental && !all_touched && ref_features_.size() == features_.size()) {
      for (int j = 0; j < by; ++j)
        if (ref_behind_[j])
          std::copy(features_.begin() + j * row_values, features_.begin() + (j + 1) * row_values,
                    ref_features_.begin() + j * row_values);
      std::fill(ref_behind_.begin(), ref_behind_.end(), 0);
    } else if (changes && !all_touched) {
      ref_features_ = features_;
      ref_behind_.assign(by, 0);
    } else {
      ref_features_.swap(features_);
      features_current = false;
    }
  }
  const std::vector<float> &features = decision != TemporalDecision::Reuse ? ref_features_ : features_;
  features_current_ = features_current;

  const bool cut = decision == TemporalDecision::Cut;
  smoothed_.resize(features.size());  // a cut never reads the (then stale) old values
  // Adaptive: a block row whose smoothed features came out of the last
  // pass unchanged, with the same features and weight, comes out of this
  // one unchanged too (the pass is a function of them): it is left out.
  const bool skip_settled = incremental && !cut && params.feature_smoothing == settled_weight_;
  settled_rows_.resize(by, 0);
  cv::parallel_for_(cv::Range(0, by), [&](const cv::Range &range) {
    for (int j = range.start; j < range.end; ++j) {
      const size_t k0 = static_cast<size_t>(j) * row_values, k1 = k0 + row_values;
      if (skip_settled && settled_rows_[j] && !row_touched[j]) continue;
      bool settled = true;
      for (size_t k = k0; k < k1; k += 3) {
        float s[3] = {smoothed_[k], smoothed_[k + 1], smoothed_[k + 2]};
        smooth_block_feature(cut, params.feature_smoothing, &features[k], &smoothed_[k]);
        settled = settled && std::memcmp(s, &smoothed_[k], sizeof s) == 0;
      }
      settled_rows_[j] = settled && !cut;
    }
  });
  settled_weight_ = params.feature_smoothing;
  have_state_ = true;
  bx_ = bx;
  by_ = by;
  block_ = B;
  width_ = W;
  height_ = H;
  last_diff_ = diff;
  last_decision_ = decision;
  // A reused frame outputs the previous block depths whatever the regions
  // are: adaptive calls leave steps 2-4 out (labels() then describe the
  // last frame that used them).
  if (changes && decision == TemporalDecision::Reuse && !block_depth_.empty()) {
    output_changed_ = false;
    return decision;
  }
  // Step 3's hypotheses depend on the grid alone: kept while it stays.
  const HypothesisGrid grid{params.hypothesis, bx, by, W, H, B};
  if (!(grid == hq_grid_)) {
    block_hypotheses_cpu(params.hypothesis, bx, by, W, H, B, hq_);
    hq_grid_ = grid;
    regions_.forget();  // its tiles' statistics are of the old hypotheses
  }
  // Adaptive calls relabel only the tiles whose smoothed features changed.
  regions_.label(smoothed_, bx, by, params.edge_threshold, !is_packed_rgb(frame.format), hq_.data(),
                 changes != nullptr);
  const std::vector<int> &labels = regions_.labels();

  const size_t n = static_cast<size_t>(bx) * by;
  const bool had_output = block_depth_.size() == n;
  block_depth_.resize(n);  // a cut ignores the (then stale) previous values
  row_changed_.assign(static_cast<size_t>(by), had_output ? 0 : 1);
  cv::parallel_for_(cv::Range(0, by), [&](const cv::Range &range) {
    for (int j = range.start; j < range.end; ++j) {
      bool changed = false;
      int region = -1;  // a row's blocks come in runs of one region: its depth once a run
      float r = 0.f;
      for (size_t k = static_cast<size_t>(j) * bx; k < static_cast<size_t>(j + 1) * bx; ++k) {
        if (labels[k] != region) {
          region = labels[k];
          r = region_depth(params.ground_contact, regions_.sum(region), regions_.count(region), regions_.max(region));
        }
        const float fresh = block_depth_from_region(params, r, hq_[k]);  // step 4
        const float out = temporal_output(decision, block_depth_[k], fresh, params.temporal_smoothing);
        changed = changed || std::memcmp(&out, &block_depth_[k], sizeof out) != 0;
        block_depth_[k] = out;
      }
      if (changed) row_changed_[j] = 1;
    }
  });
  output_changed_ = std::find(row_changed_.begin(), row_changed_.end(), 1) != row_changed_.end();
  return decision;
}

}  // namespace p3d
