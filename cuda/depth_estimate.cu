#include "chained_launch.cuh"
#include "depth_estimate_gpu.h"
#include "depth_grey.cuh"
#include "warp_reduce.cuh"

namespace p3d {

namespace {

constexpr unsigned kFullMask = 0xffffffffu;
constexpr int kThreads = 256;        // 1-D kernels and the features kernel
constexpr int kTile = 32;            // labels: tiles of 32 x 32 blocks ...
constexpr int kTileRowsPerPass = 8;  // ... worked by 32 x 8 threads, 4 rows each
constexpr int kExpandX = 32, kExpandY = 8;

struct DepthDeviceState {
  unsigned long long diff_sum;  // step 5, fixed point (temporal_diff_fixed)
  float diff;                   // the mean, recorded for last_diff()
  int decision;                 // TemporalDecision, recorded for last_decision()
};

unsigned grid_for(long long items, int per_block) { return static_cast<unsigned>((items + per_block - 1) / per_block); }

// ---------------------------------------------------------------- step 1 ---
// A CTA covers `per_cta` blocks side by side (per_cta * B <= 256 pixel
// columns, one thread a column) and `rows_per_cta` block rows
// (feature_rows_per_cta: 8 up to B = 8). First every thread sums its
// column over each of the CTA's block rows in integers, all of its loads
// independent of each other so that they are in flight together (a loop
// per block row, each waiting for its loads, is latency bound; measured:
// docs/benchmarks.md, Design measurements, "Depth"); then one thread per
// block adds the block's B column sums, so every block sum is formed by one
// thread, exactly. kB > 0: B is kB, known at compile time (the automatic
// sizes); 0: any B.
constexpr int kFeatureRowsMax = 8;  // block rows a CTA holds: feature_rows_per_cta(B) at most

// Block rows a CTA of the features kernel sums: 8 up to B = 8 (16, 32 and
// 64 pixel rows at the automatic 2, 4 and 8), else 1. With fewer rows a
// CTA at B = 4 and 8, a thread would sum a single four-column item or none
// (at 8K half the threads idle); 8 block rows give every thread loads in
// flight (measured: docs/benchmarks.md, Design measurements, "Depth").
__host__ __device__ constexpr int feature_rows_per_cta(int B) { return B <= 8 ? 8 : 1; }

// Column x's sums over the kB rows from y0 (clipped to the frame) of a
// 4:2:0 frame (NV12, I420), load_native3()'s values added up: with kB even
// (and so y0 even) the rows come in pairs sharing one chroma row, whose
// sample each pair loads once and counts twice (a lone last row of an odd
// height, once). Integer sums, so the totals are those of a load per
// pixel, with a third fewer loads and the row addresses stepped, not
// recomputed (the features kernel is bound by its loads' instructions).
template <int kB>
__device__ void column_sums_420(const FrameView &f, int x, int y0, uint32_t *s0, uint32_t *s1, uint32_t *s2) {
  static_assert(kB % 2 == 0, "rows pair up from an even first row");
  const bool nv12 = f.format == PixelFormat::NV12;
  const uint8_t *luma = f.plane[0] + static_cast<size_t>(y0) * f.stride[0] + x;
  const size_t chroma_row = static_cast<size_t>(y0 / 2);
  const uint8_t *cb = nv12 ? f.plane[1] + chroma_row * f.stride[1] + 2 * (x / 2)
                           : f.plane[1] + chroma_row * f.stride[1] + x / 2;
  const uint8_t *cr = nv12 ? cb + 1 : f.plane[2] + chroma_row * f.stride[2] + x / 2;
  const size_t cr_stride = nv12 ? f.stride[1] : f.stride[2];
#pragma unroll
  for (int dy = 0; dy < kB; dy += 2) {
    const int y = y0 + dy;
    if (y >= f.height) break;
    const bool pair = y + 1 < f.height;
    *s0 += luma[0] + (pair ? luma[f.stride[0]] : 0u);
    const uint32_t n = pair ? 2u : 1u;
    *s1 += n * cb[0];
    *s2 += n * cr[0];
    luma += 2 * static_cast<size_t>(f.stride[0]);
    cb += f.stride[1];
    cr += cr_stride;
  }
}

// column_sums_420 for the four columns x .. x + 3 at once (x a multiple
// of 4, all four in the frame, rows 4-byte aligned: the launcher checks
// that the frame's planes and strides allow it): a luma row is one 32-bit
// load, the chroma of the four columns one more (NV12's interleaved
// Cb Cr Cb Cr) or one 16-bit load a plane (I420). Bytes are added two a
// word in 16-bit lanes (kB rows of 255, doubled for chroma, stay below
// 2^16), then split into the columns' sums: the same integers as four
// column_sums_420 calls with a quarter of their load instructions.
template <int kB>
__device__ void column_sums_420_x4(const FrameView &f, int x, int y0, uint32_t s0[4], uint32_t s1[4],
                                   uint32_t s2[4]) {
  static_assert(kB % 2 == 0 && 2 * kB * 255 < 65536, "16-bit lanes hold a column's sum");
  const bool nv12 = f.format == PixelFormat::NV12;
  const uint8_t *luma = f.plane[0] + static_cast<size_t>(y0) * f.stride[0] + x;
  const size_t chroma_row = static_cast<size_t>(y0 / 2);
  const uint8_t *c1 = f.plane[1] + chroma_row * f.stride[1] + (nv12 ? x : x / 2);
  const uint8_t *c2 = nv12 ? c1 : f.plane[2] + chroma_row * f.stride[2] + x / 2;
  const size_t c2_stride = nv12 ? f.stride[1] : f.stride[2];
  uint32_t y02 = 0, y13 = 0;  // luma of columns 0 and 2, 1 and 3, in 16-bit lanes
  uint32_t cb = 0, cr = 0;    // the two chroma samples' sums, in 16-bit lanes (low: columns 0-1)
#pragma unroll
  for (int dy = 0; dy < kB; dy += 2) {
    const int y = y0 + dy;
    if (y >= f.height) break;
    const bool pair = y + 1 < f.height;
    const uint32_t a = *reinterpret_cast<const uint32_t *>(luma);
    const uint32_t b = pair ? *reinterpret_cast<const uint32_t *>(luma + f.stride[0]) : 0u;
    y02 += (a & 0x00ff00ffu) + (b & 0x00ff00ffu);
    y13 += ((a >> 8) & 0x00ff00ffu) + ((b >> 8) & 0x00ff00ffu);
    const uint32_t n = pair ? 2u : 1u;
    if (nv12) {
      const uint32_t w = *reinterpret_cast<const uint32_t *>(c1);  // Cb0 Cr0 Cb1 Cr1
      cb += n * (w & 0x00ff00ffu);
      cr += n * ((w >> 8) & 0x00ff00ffu);
    } else {
      const uint32_t u = *reinterpret_cast<const uint16_t *>(c1), v = *reinterpret_cast<const uint16_t *>(c2);
      cb += n * ((u & 0xffu) | (u & 0xff00u) << 8);
      cr += n * ((v & 0xffu) | (v & 0xff00u) << 8);
    }
    luma += 2 * static_cast<size_t>(f.stride[0]);
    c1 += f.stride[1];
    c2 += c2_stride;
  }
  s0[0] = y02 & 0xffffu;
  s0[1] = y13 & 0xffffu;
  s0[2] = y02 >> 16;
  s0[3] = y13 >> 16;
  s1[0] = s1[1] = cb & 0xffffu;
  s1[2] = s1[3] = cb >> 16;
  s2[0] = s2[1] = cr & 0xffffu;
  s2[2] = s2[3] = cr >> 16;
}

template <int kB>
__global__ void __launch_bounds__(kThreads) block_features_kernel(FrameView frame, int B_arg, int bx, int by,
                                                                  float *__restrict__ features,
                                                                  const float *__restrict__ ref, bool have_state,
                                                                  DepthDeviceState *state, bool words,
                                                                  TileFlags changes, bool incremental) {
  chained_kernel_start();
  constexpr int kRows = kB > 0 ? feature_rows_per_cta(kB) : kFeatureRowsMax;
  __shared__ uint32_t col[kRows][3][kThreads];
  __shared__ unsigned long long warp_diff[kThreads / 32];
  const int B = kB > 0 ? kB : B_arg;
  const int per_cta = kThreads / B, rows_per_cta = feature_rows_per_cta(B);
  const int t = threadIdx.x;
  const int x = blockIdx.x * per_cta * B + t;
  const bool column_in = t < per_cta * B && x < frame.width;
  const int j0 = blockIdx.y * rows_per_cta;
  // Adaptive: a CTA whose pixels lie in no changed tile keeps its blocks'
  // features (features holds the previous frame's) and only adds their
  // differences from the reference.
  const int cta_x0 = blockIdx.x * per_cta * B, cta_y0 = j0 * B;
  const bool kept = incremental && !changes.any_in(PixelRect{cta_x0, cta_y0, cta_x0 + per_cta * B,
                                                             cta_y0 + rows_per_cta * B});
  if constexpr (kB > 0 && kB % 2 == 0) {
    if (words && !kept) {  // 4:2:0, rows 4-byte aligned: a thread sums four columns of a block row
      const int x_cta = blockIdx.x * per_cta * B;
      for (int item = t; item < (kThreads / 4) * rows_per_cta; item += kThreads) {
        const int r = item / (kThreads / 4), c0 = 4 * (item - r * (kThreads / 4)), x4 = x_cta + c0;
        const int y0 = (j0 + r) * B;
        uint32_t s0[4] = {0, 0, 0, 0}, s1[4] = {0, 0, 0, 0}, s2[4] = {0, 0, 0, 0};
        if (x4 + 3 < frame.width && c0 + 3 < per_cta * B) {
          column_sums_420_x4<kB>(frame, x4, y0, s0, s1, s2);
        } else {
          for (int k = 0; k < 4; ++k)
            if (c0 + k < per_cta * B && x4 + k < frame.width)
              column_sums_420<kB>(frame, x4 + k, y0, &s0[k], &s1[k], &s2[k]);
        }
        for (int k = 0; k < 4; ++k) {
          col[r][0][c0 + k] = s0[k];
          col[r][1][c0 + k] = s1[k];
          col[r][2][c0 + k] = s2[k];
        }
      }
    }
  }
#pragma unroll
  for (int r = 0; r < kRows; ++r) {
    if ((kB > 0 && kB % 2 == 0 && words) || kept) break;  // summed above, or kept
    if (r >= rows_per_cta) break;  // kB > 0: never
    const int y0 = (j0 + r) * B;
    uint32_t s0 = 0, s1 = 0, s2 = 0;
    if constexpr (kB > 0 && kB % 2 == 0) {
      if (column_in && !is_packed_rgb(frame.format)) {
        column_sums_420<kB>(frame, x, y0, &s0, &s1, &s2);
        col[r][0][t] = s0;
        col[r][1][t] = s1;
        col[r][2][t] = s2;
        continue;
      }
    }
    if (column_in) {
#pragma unroll 4
      for (int dy = 0; dy < B; ++dy) {
        if (y0 + dy >= frame.height) continue;  // the last block row may be partial, or past the frame
        int c[3];
        load_native3(frame, x, y0 + dy, c);
        s0 += c[0];
        s1 += c[1];
        s2 += c[2];
      }
    }
    col[r][0][t] = s0;
    col[r][1][t] = s1;
    col[r][2][t] = s2;
  }
  __syncthreads();
  unsigned long long diff = 0;
  for (int item = t; item < per_cta * rows_per_cta; item += kThreads) {
    const int r = item / per_cta, b = item - r * per_cta;
    const int i = blockIdx.x * per_cta + b, j = j0 + r;
    if (i >= bx || j >= by) continue;
    const size_t base = (static_cast<size_t>(j) * bx + i) * 3;
    if (kept) {
      if (have_state)
        for (int c = 0; c < 3; ++c) diff += temporal_diff_fixed(features[base + c], ref[base + c]);
      continue;
    }
    const int cols = block_extent(i, B, frame.width), rows = block_extent(j, B, frame.height);
    uint32_t sum[3] = {0, 0, 0};
    for (int k = b * B; k < b * B + cols; ++k)
      for (int c = 0; c < 3; ++c) sum[c] += col[r][c][k];
    for (int c = 0; c < 3; ++c) {
      const float f = block_mean(sum[c], cols * rows);
      features[base + c] = f;
      if (have_state) diff += temporal_diff_fixed(f, ref[base + c]);
    }
  }
  if (!have_state) return;  // uniform: a kernel parameter
  for (int o = 16; o > 0; o >>= 1) diff += __shfl_down_sync(kFullMask, diff, o);
  if ((t & 31) == 0) warp_diff[t >> 5] = diff;
  __syncthreads();
  if (t == 0) {
    unsigned long long total = 0;
    for (int w = 0; w < kThreads / 32; ++w) total += warp_diff[w];
    if (total) atomicAdd(&state->diff_sum, total);
  }
}

// ---------------------------------------------------------------- step 2 ---
// Union-find shared by the tile and the border passes. Invariant: parent[i] <=
// i, and only a root (parent[r] == r) is ever re-pointed, by atomicCAS from r
// to a smaller root, so a root is its tree's smallest index. Path halving
// lowers a non-root's parent to its grandparent, an ancestor either way, with
// atomicMin so that concurrent halvings only ever move a parent up the tree
// (and compute-sanitizer's racecheck sees no plain store racing with a load).
// volatile: another thread's hook must be seen, not a stale L1 copy.
__device__ int find_root(volatile int *parent, int i) {
  while (true) {
    const int p = parent[i];
    if (p == i) return i;
    const int g = parent[p];
    if (g == p) return p;
    atomicMin(const_cast<int *>(parent + i), g);
    i = g;
  }
}

__device__ void unite(volatile int *parent, int a, int b) {
  while (true) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a == b) return;
    if (a > b) {
      const int s = a;
      a = b;
      b = s;
    }
    const int old = atomicCAS(const_cast<int *>(parent + b), b, a);
    if (old == b) return;
    b = old;  // b was hooked meanwhile: join a with b's new tree instead
  }
}

// After the merges: a plain walk. No path halving here, because a halving
// store could land after the owner's final `labels[i] = root` and leave a
// non-root label behind.
__device__ int find_root_final(const int *parent, int i) {
  int p;
  while ((p = parent[i]) != i) i = p;
  return i;
}

__device__ void load_feature(const float *__restrict__ features, int k, float out[3]) {
  out[0] = features[static_cast<size_t>(k) * 3];
  out[1] = features[static_cast<size_t>(k) * 3 + 1];
  out[2] = features[static_cast<size_t>(k) * 3 + 2];
}

// The decision of step 5, from the difference sum the features kernel left
// (every thread of the later kernels derives it: same input, same function).
__device__ TemporalDecision device_decision(const DepthDeviceState *state, const DepthParams &params, bool have_state,
                                            int n, float *diff_out = nullptr) {
  const float diff = have_state ? temporal_mean_diff(state->diff_sum, 3LL * n) : 0.f;
  if (diff_out) *diff_out = diff;
  return temporal_decision(have_state, diff, params);
}

// Adaptive: the passes of steps 2-4 after the tile pass leave a reused
// frame out (DepthEstimatorGpu::estimate with changes).
struct ReuseSkip {
  bool on;
  const DepthDeviceState *state;
  DepthParams params;
  bool have_state;
  __device__ bool skipped(int n) const {
    return on && device_decision(state, params, have_state, n) == TemporalDecision::Reuse;
  }
};

// Tile pass: components inside one 32x32 tile of blocks, in shared memory.
// The local index ly*32+lx orders a tile's blocks as the global index does, so
// the local root maps to the tile-local smallest global index. Each block's
// smoothed feature (step 2) is updated here, by the one thread that loads
// it, and left in `smoothed` for the border pass. Also clears the region
// sums, counts and maxima that the resolve pass accumulates into.
// A warp works one tile row at a time, so the horizontal joins come from a
// ballot: every block points straight at the first block of its row run
// (no atomics; that is a valid forest, each run's root its smallest
// index), and only the vertical joins go through unite(), skipping those
// that the join to the left already made (both blocks joined to their left
// neighbours, which are joined vertically). So a large region costs about
// one unite per run and row, not two a block.
__global__ void tile_labels_kernel(const float *__restrict__ features, float *__restrict__ smoothed, int bx, int by,
                                   DepthParams params, bool yuv, bool have_state, const DepthDeviceState *state, int *labels,
                                   unsigned long long *region_sums, uint32_t *region_counts, uint32_t *region_max,
                                   bool skip_reused) {
  chained_kernel_start();
  __shared__ int parent[kTile * kTile];
  __shared__ float feat[kTile * kTile][3];
  __shared__ unsigned left_bits[kTile], up_bits[kTile];  // per tile row: bit lx set when joined to the left / above
  const int lx = threadIdx.x, x0 = blockIdx.x * kTile, y0 = blockIdx.y * kTile;
  const int gx = x0 + lx;
  const float edge_threshold = params.edge_threshold;
  const TemporalDecision decision = device_decision(state, params, have_state, bx * by);
  const bool cut = decision == TemporalDecision::Cut;
  for (int ly = threadIdx.y; ly < kTile; ly += kTileRowsPerPass) {
    const int l = ly * kTile + lx, gy = y0 + ly;
    if (gx < bx && gy < by) {
      const int g = gy * bx + gx;
      float f[3];
      load_feature(features, g, f);
      if (!cut) load_feature(smoothed, g, feat[l]);  // a cut never reads stale (or unset) memory
      smooth_block_feature(cut, params.feature_smoothing, f, feat[l]);
      for (int c = 0; c < 3; ++c) smoothed[static_cast<size_t>(g) * 3 + c] = feat[l][c];
    }
  }
  // Adaptive: a reused frame outputs the previous depths, so its regions
  // are never read (uniform: the decision is the kernel's).
  if (skip_reused && decision == TemporalDecision::Reuse) return;
  __syncthreads();
  // Row runs: lane lx's run starts at the highest lane <= lx not joined to
  // its left (lane 0 never is).
  for (int ly = threadIdx.y; ly < kTile; ly += kTileRowsPerPass) {
    const int l = ly * kTile + lx, gy = y0 + ly;
    const bool in = gx < bx && gy < by;
    const bool left = in && lx > 0 && blocks_joined(feat[l], feat[l - 1], edge_threshold, yuv);
    const bool up = in && ly > 0 && blocks_joined(feat[l], feat[l - kTile], edge_threshold, yuv);
    const unsigned lb = __ballot_sync(kFullMask, left), ub = __ballot_sync(kFullMask, up);
    if (lx == 0) {
      left_bits[ly] = lb;
      up_bits[ly] = ub;
    }
    const unsigned starts = ~lb & (lx == 31 ? kFullMask : (2u << lx) - 1u);
    parent[l] = ly * kTile + 31 - __clz(starts);
  }
  __syncthreads();
  for (int ly = threadIdx.y; ly < kTile; ly += kTileRowsPerPass) {
    if (ly == 0) continue;
    const unsigned lb = left_bits[ly], lb_above = left_bits[ly - 1], ub = up_bits[ly];
    if (!((ub >> lx) & 1u)) continue;
    // Already linked when this block and the one above both continue the
    // runs of their left neighbours, and those two are joined.
    const bool made = lx > 0 && ((lb >> lx) & 1u) && ((lb_above >> lx) & 1u) && ((ub >> (lx - 1)) & 1u);
    const int l = ly * kTile + lx;
    if (!made) unite(parent, l, l - kTile);
  }
  __syncthreads();
  for (int ly = threadIdx.y; ly < kTile; ly += kTileRowsPerPass) {
    const int l = ly * kTile + lx, gy = y0 + ly;
    if (gx >= bx || gy >= by) continue;
    const int root = find_root(parent, l);
    const int g = gy * bx + gx;
    labels[g] = (y0 + root / kTile) * bx + x0 + root % kTile;
    region_sums[g] = 0;
    region_counts[g] = 0;
    region_max[g] = 0;
  }
}

// Border pass: one thread per 4-neighbour pair that crosses a tile border
// (first the vertical borders, row-major, then the horizontal ones). A
// joined pair skips its unite when the pair before it on the same border
// is joined and each of its blocks is joined to its neighbour there inside
// one tile (the tile pass linked those): the four blocks are connected
// already, by induction along the border from its first joined pair, which
// always unites. Large regions cross a border with one unite instead of
// one per block of the border (each a chain of global atomics).
__global__ void border_labels_kernel(const float *__restrict__ smoothed, int bx, int by, float edge_threshold,
                                     bool yuv, int *labels, int tiles_x, long long vertical_pairs, long long pairs,
                                     ReuseSkip skip) {
  chained_kernel_start();
  const long long e = static_cast<long long>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (e >= pairs || skip.skipped(bx * by)) return;
  int a, b, step;  // step: from a pair's blocks to those of the pair before it on the border (0: none in the tile)
  if (e < vertical_pairs) {
    const int gy = static_cast<int>(e / (tiles_x - 1));
    const int gx = static_cast<int>(e % (tiles_x - 1) + 1) * kTile;
    b = gy * bx + gx;
    a = b - 1;
    step = gy % kTile ? bx : 0;
  } else {
    const long long h = e - vertical_pairs;
    const int gy = static_cast<int>(h / bx + 1) * kTile;
    const int gx = static_cast<int>(h % bx);
    b = gy * bx + gx;
    a = b - bx;
    step = gx % kTile ? 1 : 0;
  }
  float fa[3], fb[3];
  load_feature(smoothed, a, fa);
  load_feature(smoothed, b, fb);
  if (!blocks_joined(fa, fb, edge_threshold, yuv)) return;
  if (step) {
    float pa[3], pb[3];
    load_feature(smoothed, a - step, pa);
    load_feature(smoothed, b - step, pb);
    if (blocks_joined(pa, pb, edge_threshold, yuv) && blocks_joined(fa, pa, edge_threshold, yuv) &&
        blocks_joined(fb, pb, edge_threshold, yuv))
      return;
  }
  unite(labels, a, b);
}

// ------------------------------------------------------------- steps 3-4 ---
// The merges are done: every block takes its root as label, and adds its hq
// to the root's sum and count and raises the root's maximum (ground contact).
// Integer atomics make the results exact in any order; they are aggregated
// first (a whole CTA when it lies in one region, the common case, else per
// warp and label) because a large region would otherwise put every block's
// atomic on one address.
__global__ void resolve_kernel(int *labels, int n, int bx, int B, int width, int height, Hypothesis hypothesis,
                               unsigned long long *region_sums, uint32_t *region_counts, uint32_t *region_max,
                               ReuseSkip skip) {
  chained_kernel_start();
  if (skip.skipped(n)) return;  // uniform
  __shared__ int cta_root;
  __shared__ uint32_t warp_sum[kThreads / 32], warp_count[kThreads / 32], warp_max[kThreads / 32];
  const int i = blockIdx.x * kThreads + threadIdx.x;
  const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
  const bool valid = i < n;
  int root = -1;
  uint32_t hq = 0;
  if (valid) {
    root = find_root_final(labels, i);
    if (root != labels[i]) labels[i] = root;
    hq = block_hypothesis_q(hypothesis, i % bx, i / bx, B, width, height);
  }
  if (threadIdx.x == 0) cta_root = root;  // thread 0 is always valid
  __syncthreads();
  if (__syncthreads_and(!valid || root == cta_root)) {
    const uint32_t s = warp_reduce_sum(hq);  // <= 256 * 65535: no overflow
    const uint32_t c = __popc(__ballot_sync(kFullMask, valid));
    const uint32_t m = warp_reduce_max(hq);  // invalid lanes hold 0
    if (lane == 0) {
      warp_sum[warp] = s;
      warp_count[warp] = c;
      warp_max[warp] = m;
    }
    __syncthreads();
    if (threadIdx.x == 0) {
      uint32_t total = 0, count = 0, top = 0;
      for (int w = 0; w < kThreads / 32; ++w) {
        total += warp_sum[w];
        count += warp_count[w];
        top = max(top, warp_max[w]);
      }
      atomicAdd(&region_sums[cta_root], static_cast<unsigned long long>(total));
      atomicAdd(&region_counts[cta_root], count);
      atomicMax(&region_max[cta_root], top);
    }
    return;
  }
  // One round per distinct label in the warp; all 32 lanes take part in every
  // round, so the full-mask warp intrinsics are well defined.
  unsigned pending = __ballot_sync(kFullMask, valid);
  while (pending) {
    const int leader = __ffs(pending) - 1;
    const int r = __shfl_sync(kFullMask, root, leader);
    const bool mine = valid && root == r;
    const unsigned group = __ballot_sync(kFullMask, mine);
    const uint32_t s = warp_reduce_sum(mine ? hq : 0u);
    const uint32_t m = warp_reduce_max(mine ? hq : 0u);
    if (lane == leader) {
      atomicAdd(&region_sums[r], static_cast<unsigned long long>(s));
      atomicAdd(&region_counts[r], static_cast<uint32_t>(__popc(group)));
      atomicMax(&region_max[r], m);
    }
    pending &= ~group;
  }
}

// ------------------------------------------------------------- steps 4-5 ---
__global__ void block_depth_kernel(const int *__restrict__ labels, const unsigned long long *__restrict__ region_sums,
                                   const uint32_t *__restrict__ region_counts, const uint32_t *__restrict__ region_max,
                                   const float *__restrict__ features,
                                   float *__restrict__ ref, float *__restrict__ block_depth, DepthDeviceState *state,
                                   DepthDeviceState *next_state, DepthParams params, bool have_state, int n, int bx, int B, int width, int height,
                                   ImageView<float> grid) {
  chained_kernel_start();
  const int i = blockIdx.x * kThreads + threadIdx.x;
  if (i >= n) return;
  float diff;
  const TemporalDecision decision = device_decision(state, params, have_state, n, &diff);
  if (i == 0) {
    state->diff = diff;
    state->decision = static_cast<int>(decision);
    next_state->diff_sum = 0;  // the next frame's: no kernel of this frame reads it
  }
  // grid (not empty): the output map held at the blocks' own cells, one
  // value a block (estimate() with a DepthGrid of shift log2(B)), written
  // here instead of expanded.
  if (decision == TemporalDecision::Reuse) {  // previous depth and reference stay
    if (!grid.empty()) grid.at(i % bx, i / bx) = block_depth[i];
    return;
  }
  const int label = labels[i];
  const uint32_t hq = block_hypothesis_q(params.hypothesis, i % bx, i / bx, B, width, height);
  const float fresh = block_depth_value(params, region_sums[label], region_counts[label], region_max[label], hq);
  const float prev = decision == TemporalDecision::Smooth ? block_depth[i] : 0.f;  // a cut never reads stale memory
  const float d = temporal_output(decision, prev, fresh, params.temporal_smoothing);
  block_depth[i] = d;
  if (!grid.empty()) grid.at(i % bx, i / bx) = d;
  for (int c = 0; c < 3; ++c) ref[static_cast<size_t>(i) * 3 + c] = features[static_cast<size_t>(i) * 3 + c];
}

// ---------------------------------------------------------------- step 6 ---
// Each thread writes kExpandPixels consecutive pixels of a row: one
// division by the block size for all of them, and one 16-byte store where
// the row allows it: a division and a 4-byte store per pixel would make the
// kernel compute bound (measured: docs/benchmarks.md, Design measurements,
// "Depth"). kB > 0: B is kB, known at compile time (the automatic sizes, as
// block_features_kernel), so the divisions are shifts (and at 4 and 8 a
// thread's four pixels one load); 0: any B.
constexpr int kExpandPixels = 4;  // the float4 below
static_assert(kExpandPixels == 4, "expand_kernel stores a float4");
template <int kB>
__global__ void expand_kernel(const float *__restrict__ block_depth, int bx, int B_arg, int width, int height,
                              ImageView<float> depth) {
  chained_kernel_start();
  const int B = kB > 0 ? kB : B_arg;
  const int x0 = (blockIdx.x * kExpandX + threadIdx.x) * kExpandPixels, y = blockIdx.y * kExpandY + threadIdx.y;
  if (x0 >= width || y >= height) return;
  const float *src = block_depth + static_cast<size_t>(y / B) * bx;
  int q = x0 / B, r = x0 - q * B;  // pixel x is in block q, r pixels in
  float v[kExpandPixels];
#pragma unroll
  for (int k = 0; k < kExpandPixels; ++k) {
    v[k] = src[q < bx ? q : bx - 1];  // q >= bx only past `width`: never stored
    if (++r == B) {
      r = 0;
      ++q;
    }
  }
  float *dst = depth.row(y) + x0;
  if (x0 + kExpandPixels <= width && (reinterpret_cast<uintptr_t>(dst) & 15u) == 0) {
    *reinterpret_cast<float4 *>(dst) = make_float4(v[0], v[1], v[2], v[3]);
    return;
  }
#pragma unroll
  for (int k = 0; k < kExpandPixels; ++k)
    if (x0 + k < width) dst[k] = v[k];
}

}  // namespace

void DepthEstimatorGpu::reset() { have_state_ = false; }

CudaStatus DepthEstimatorGpu::estimate(const DepthParams &params, const FrameView &frame, ImageView<float> depth,
                                       cudaStream_t stream) {
  return estimate(params, frame, full_grid(depth), stream);
}

CudaStatus DepthEstimatorGpu::estimate(const DepthParams &params, const FrameView &input, DepthGrid<float> depth,
                                       cudaStream_t stream, const TileFlags *changes) {
  const int W = input.width, H = input.height, B = effective_block_size(params, W, H);
  if (W <= 0 || H <= 0) {
    reset();
    return {};
  }
  FrameView frame;  // the input, or its high bytes (a deep frame)
  P3D_CUDA_TRY_STATUS(high_bytes_.of(input, stream, &frame));
  const bool block_grid = depth.shift > 0;  // the blocks' own cells: no expansion
  // A full-size map is expanded within its own size (as an ImageView is);
  // a grid must have the cells of its picture, and a block grid the
  // frame's blocks.
  if ((!depth.cells.empty() && !grid_fits(depth)) ||
      (block_grid && (depth.cells.empty() || (1 << depth.shift) != B || depth.width != W || depth.height != H)))
    return CudaStatus{cudaErrorInvalidValue,
                      "DepthEstimatorGpu::estimate: the depth grid's cells fit it, and one of shift > 0 is the "
                      "frame's blocks",
                      __FILE__, __LINE__};
  const int bx = blocks_along(W, B), by = blocks_along(H, B);
  const int n = bx * by;
  const bool same_grid = have_state_ && bx == bx_ && by == by_ && B == block_ && W == width_ && H == height_;
  // Until this frame is fully queued the history is not trustworthy: a failure
  // part-way makes the next frame a cut.
  have_state_ = false;
  const size_t nb = static_cast<size_t>(n);
  P3D_CUDA_TRY_STATUS(features_.ensure(nb * 3 * sizeof(float)));
  P3D_CUDA_TRY_STATUS(ref_features_.ensure(nb * 3 * sizeof(float)));
  P3D_CUDA_TRY_STATUS(smoothed_features_.ensure(nb * 3 * sizeof(float)));
  P3D_CUDA_TRY_STATUS(labels_.ensure(nb * sizeof(int)));
  P3D_CUDA_TRY_STATUS(region_sums_.ensure(nb * sizeof(unsigned long long)));
  P3D_CUDA_TRY_STATUS(region_counts_.ensure(nb * sizeof(uint32_t)));
  P3D_CUDA_TRY_STATUS(region_max_.ensure(nb * sizeof(uint32_t)));
  P3D_CUDA_TRY_STATUS(block_depth_.ensure(nb * sizeof(float)));
  // Two states, this frame's and the next one's, in turn: this frame's
  // depth kernel clears the next one's difference sum, so that no kernel
  // of its own has to (a clearing kernel before the features costs a
  // launch; measured: docs/benchmarks.md, Design measurements, "Depth").
  // Cleared here instead where the last frame did not queue its depth
  // kernel.
  P3D_CUDA_TRY_STATUS(state_.ensure(2 * sizeof(DepthDeviceState)));
  const int slot = 1 - state_slot_;
  auto *state = state_.as<DepthDeviceState>() + slot;
  auto *next_state = state_.as<DepthDeviceState>() + state_slot_;
  if (!next_state_zeroed_) P3D_CUDA_TRY(zero_chained(state, sizeof(DepthDeviceState), stream));
  next_state_zeroed_ = false;
  state_slot_ = slot;

  // Step 1 (+ the difference sum of step 5). 8 block rows a CTA (up to
  // B = 8), so that small blocks do not make one atomic per handful of
  // pixels and every thread has loads in flight.
  const int per_cta = kThreads / B, rows_per_cta = feature_rows_per_cta(B);
  auto features_kernel = B == 2 ? block_features_kernel<2>
                         : B == 4 ? block_features_kernel<4>
                         : B == 8 ? block_features_kernel<8>
                                  : block_features_kernel<0>;
  // 32-bit row loads (column_sums_420_x4) where every row of the 4:2:0
  // planes starts 4-byte aligned (2-byte for I420's chroma rows).
  const bool words =
      frame.format == PixelFormat::NV12   ? rows_aligned(frame, 0, 4) && rows_aligned(frame, 1, 4)
      : frame.format == PixelFormat::I420 ? rows_aligned(frame, 0, 4) && rows_aligned(frame, 1, 2) &&
                                                rows_aligned(frame, 2, 2)
                                          : false;
  P3D_CUDA_TRY(launch_chained(features_kernel, dim3(grid_for(bx, per_cta), grid_for(by, rows_per_cta)), kThreads, 0,
                              stream, frame, B, bx, by, features_.as<float>(), ref_features_.as<float>(), same_grid,
                              state, words, changes ? *changes : TileFlags{}, changes != nullptr && same_grid));

  // Step 2.
  const bool yuv = !is_packed_rgb(frame.format);
  const int tiles_x = blocks_along(bx, kTile), tiles_y = blocks_along(by, kTile);
  P3D_CUDA_TRY(launch_chained(tile_labels_kernel, dim3(tiles_x, tiles_y), dim3(kTile, kTileRowsPerPass), 0, stream,
                              features_.as<float>(), smoothed_features_.as<float>(), bx, by, params, yuv, same_grid,
                              state, labels_.as<int>(), region_sums_.as<unsigned long long>(),
                              region_counts_.as<uint32_t>(), region_max_.as<uint32_t>(), changes != nullptr));
  const ReuseSkip skip{changes != nullptr, state, params, same_grid};
  const long long vertical_pairs = static_cast<long long>(tiles_x - 1) * by;
  const long long pairs = vertical_pairs + static_cast<long long>(tiles_y - 1) * bx;
  if (pairs > 0) {
    P3D_CUDA_TRY(launch_chained(border_labels_kernel, grid_for(pairs, kThreads), kThreads, 0, stream,
                                smoothed_features_.as<float>(), bx, by, params.edge_threshold, yuv, labels_.as<int>(),
                                tiles_x, vertical_pairs, pairs, skip));
  }

  // Steps 3-4.
  P3D_CUDA_TRY(launch_chained(resolve_kernel, grid_for(n, kThreads), kThreads, 0, stream, labels_.as<int>(), n, bx, B,
                              W, H, params.hypothesis, region_sums_.as<unsigned long long>(),
                              region_counts_.as<uint32_t>(), region_max_.as<uint32_t>(), skip));

  // Steps 4-5.
  P3D_CUDA_TRY(launch_chained(block_depth_kernel, grid_for(n, kThreads), kThreads, 0, stream, labels_.as<int>(),
                              region_sums_.as<unsigned long long>(), region_counts_.as<uint32_t>(),
                              region_max_.as<uint32_t>(), features_.as<float>(), ref_features_.as<float>(),
                              block_depth_.as<float>(), state, next_state, params, same_grid, n, bx, B, W, H,
                              block_grid ? depth.cells : ImageView<float>{}));
  next_state_zeroed_ = true;

  // Step 6, for a full-size map.
  const int ew = depth.width < bx * B ? depth.width : bx * B, eh = depth.height < by * B ? depth.height : by * B;
  if (!block_grid && !depth.cells.empty()) {
    auto expand = B == 2 ? expand_kernel<2> : B == 4 ? expand_kernel<4> : B == 8 ? expand_kernel<8> : expand_kernel<0>;
    P3D_CUDA_TRY(launch_chained(expand,
                                dim3(grid_for(grid_for(ew, kExpandPixels), kExpandX), grid_for(eh, kExpandY)),
                                dim3(kExpandX, kExpandY), 0, stream, block_depth_.as<float>(), bx, B, ew, eh,
                                depth.cells));
  }

  have_state_ = true;
  bx_ = bx;
  by_ = by;
  block_ = B;
  width_ = W;
  height_ = H;
  return {};
}

CudaStatus DepthEstimatorGpu::download_labels(std::vector<int> &labels, cudaStream_t stream) const {
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));
  labels.resize(static_cast<size_t>(bx_) * by_);
  if (!labels.empty())
    P3D_CUDA_TRY(cudaMemcpy(labels.data(), labels_.get(), labels.size() * sizeof(int), cudaMemcpyDeviceToHost));
  return {};
}

CudaStatus DepthEstimatorGpu::download_block_depth(std::vector<float> &block_depth, cudaStream_t stream) const {
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));
  block_depth.resize(static_cast<size_t>(bx_) * by_);
  if (!block_depth.empty())
    P3D_CUDA_TRY(cudaMemcpy(block_depth.data(), block_depth_.get(), block_depth.size() * sizeof(float),
                            cudaMemcpyDeviceToHost));
  return {};
}

CudaStatus DepthEstimatorGpu::download_smoothed_features(std::vector<float> &smoothed, cudaStream_t stream) const {
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));
  smoothed.resize(static_cast<size_t>(bx_) * by_ * 3);
  if (!smoothed.empty())
    P3D_CUDA_TRY(cudaMemcpy(smoothed.data(), smoothed_features_.get(), smoothed.size() * sizeof(float),
                            cudaMemcpyDeviceToHost));
  return {};
}

namespace {

CudaStatus download_state(const DeviceBuffer &buf, int slot, DepthDeviceState *out, cudaStream_t stream) {
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));
  *out = DepthDeviceState{0, 0.f, static_cast<int>(TemporalDecision::Cut)};
  if (buf.get())
    P3D_CUDA_TRY(cudaMemcpy(out, buf.as<DepthDeviceState>() + slot, sizeof(DepthDeviceState), cudaMemcpyDeviceToHost));
  return {};
}

}  // namespace

CudaStatus DepthEstimatorGpu::last_decision(TemporalDecision *decision, cudaStream_t stream) const {
  DepthDeviceState s;
  P3D_CUDA_TRY_STATUS(download_state(state_, state_slot_, &s, stream));
  *decision = static_cast<TemporalDecision>(s.decision);
  return {};
}

CudaStatus DepthEstimatorGpu::last_diff(float *diff, cudaStream_t stream) const {
  DepthDeviceState s;
  P3D_CUDA_TRY_STATUS(download_state(state_, state_slot_, &s, stream));
  *diff = s.diff;
  return {};
}

CudaStatus depth_from_grey_gpu(const FrameView &grey, const YuvToRgb &m, ImageView<float> depth, cudaStream_t stream) {
  if (is_deep(grey.format)) return depth_grey_detail::launch_depth_from_grey_deep(grey, m, depth, stream);
  return depth_grey_detail::launch_depth_from_grey_of(grey, m, depth, stream);
}

}  // namespace p3d
