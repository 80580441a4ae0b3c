// GPU DIBR warp (cuda/warp_gpu.h): kernels and the host launcher. Every
// per-pixel decision calls the P3D_HD helpers of common/warp.h.
//
// Rows are independent for everything but NeighborAverage, so one block
// renders one output row, both eyes, from start to end: the source row is
// converted to RGBA once into shared memory, the z-buffer lives in shared
// memory (global memory only for rows too wide for it), scatter, resolve and
// the Background fill follow each other behind __syncthreads, and nothing
// but the depth row, the source row and the output row touches DRAM.
#include "warp_gpu.h"

#include <climits>
#include <utility>

namespace p3d {
namespace {

constexpr unsigned kFullMask = 0xffffffffu;
constexpr int kBlockX = 32;  // NeighborAverage kernels: one warp = one row segment
constexpr int kBlockY = 8;

// The eyes' shift factors (0: copy the source).
struct EyeShifts {
  float shift[2];
};

// Layout of counters_: total hole count, then the per-step fill counts of
// one NeighborAverage batch.
constexpr size_t kTotalOffset = 0;
constexpr size_t kFilledOffset = sizeof(unsigned long long);
constexpr size_t kCountersBytes = kFilledOffset + sizeof(unsigned) * kWarpFillBatch;

// Dynamic shared memory of the row kernel: [keys: W x u64 when in shared
// memory] [the source row, W x RGBA] [four int arrays of one entry per
// 32-pixel chunk].
__host__ __device__ int row_chunks(int W) { return (W + 31) / 32; }
size_t row_smem_bytes(int W, bool shared_keys) {
  return (shared_keys ? sizeof(unsigned long long) * W : 0) + 4 * static_cast<size_t>(W) +
         4 * sizeof(int) * static_cast<size_t>(row_chunks(W));
}

// Per-chunk first and last non-hole (INT_MAX / -1: none), one warp per chunk.
__device__ void chunk_extremes(const unsigned long long *keys, int W, int chunks, int *first, int *last) {
  const int lane = threadIdx.x & 31, warps = blockDim.x >> 5;
  for (int c = threadIdx.x >> 5; c < chunks; c += warps) {
    const int X = c * 32 + lane;
    const unsigned nonhole = __ballot_sync(kFullMask, X < W && keys[X] != 0);
    if (lane == 0) {
      first[c] = nonhole ? c * 32 + __ffs(nonhole) - 1 : INT_MAX;
      last[c] = nonhole ? c * 32 + 31 - __clz(nonhole) : -1;
    }
  }
}

// Warp 0: before[c] = last non-hole of the chunks left of c (-1: none),
// after[c] = first non-hole of the chunks right of c (-1: none). Warp-wide
// inclusive scans over 32 chunks at a time, carrying between them.
__device__ void chunk_neighbours(int chunks, const int *first, const int *last, int *before, int *after) {
  const int lane = threadIdx.x & 31;
  int carry = -1;
  for (int base = 0; base < chunks; base += 32) {
    const int c = base + lane;
    int v = c < chunks ? last[c] : -1;
    for (int o = 1; o < 32; o <<= 1) {
      const int n = __shfl_up_sync(kFullMask, v, o);
      if (lane >= o) v = max(v, n);
    }
    v = max(v, carry);
    int excl = __shfl_up_sync(kFullMask, v, 1);
    if (lane == 0) excl = carry;
    if (c < chunks) before[c] = excl;
    carry = __shfl_sync(kFullMask, v, 31);
  }
  carry = INT_MAX;
  for (int top = chunks - 1; top >= 0; top -= 32) {
    const int c = top - lane;
    int v = c >= 0 ? first[c] : INT_MAX;
    for (int o = 1; o < 32; o <<= 1) {
      const int n = __shfl_up_sync(kFullMask, v, o);
      if (lane >= o) v = min(v, n);
    }
    v = min(v, carry);
    int excl = __shfl_up_sync(kFullMask, v, 1);
    if (lane == 0) excl = carry;
    if (c >= 0) after[c] = excl == INT_MAX ? -1 : excl;
    carry = __shfl_sync(kFullMask, v, 31);
  }
}

// Background fill of one row whose keys are final and whose non-hole
// colours are in `out`: each hole's nearest non-holes come from its chunk's
// ballot or, past the chunk, from before/after.
__device__ void background_fill_row(const FrameView &out, int col0, int y, const unsigned long long *keys, int W,
                                    int chunks, const int *before, const int *after) {
  const YuvToRgb packed;
  const int lane = threadIdx.x & 31, warps = blockDim.x >> 5;
  for (int c = threadIdx.x >> 5; c < chunks; c += warps) {
    const int X = c * 32 + lane;
    const bool in = X < W;
    const unsigned long long key = in ? keys[X] : 0ull;
    const unsigned nonhole = __ballot_sync(kFullMask, in && key != 0);
    if (!in || key != 0) continue;
    const unsigned below = nonhole & ((1u << lane) - 1u);
    const unsigned above = nonhole & ~((2u << lane) - 1u);
    const int xl = below ? c * 32 + 31 - __clz(below) : before[c];
    const int xr = above ? c * 32 + __ffs(above) - 1 : after[c];
    const int pick = background_source(X, xl, xl >= 0 ? keys[xl] : 0ull, xr, xr >= 0 ? keys[xr] : 0ull);
    store_rgba(out, col0 + X, y, pick >= 0 ? load_rgba(out, col0 + pick, y, packed) : kFillBlack);
  }
}

// What one block works on: output row y, its converted source row in shared
// memory, its z-buffer, the chunk arrays of the Background fill.
struct RowJob {
  FrameView out;
  FrameView row;  // the source row as RGBA bytes in shared memory (y = 0)
  EyeShifts eyes;
  float D, convergence;
  HoleFill fill;
  const float *depth_row;
  unsigned long long *keys;
  int *first, *last, *before, *after;
  uint8_t *mask;  // NeighborAverage masks (2 eyes x H x W), or null
  uint32_t *zbits;  // BackgroundSmooth: smooth_zbits() of every pixel (2 eyes x H x W), or null
  unsigned long long *total;
  int y, W, H, chunks;
};

// Renders one eye of the row; every thread of the block calls it.
__device__ void render_eye(const RowJob &j, int eye, int *row_holes) {
  const int col0 = eye * j.W;
  const float shift = j.eyes.shift[eye];
  const YuvToRgb packed;  // j.row is RGBA
  uint8_t *mask_row = j.mask ? j.mask + (static_cast<size_t>(eye) * j.H + j.y) * j.W : nullptr;
  if (shift == 0.f) {  // this eye is the source
    for (int x = threadIdx.x; x < j.W; x += blockDim.x) {
      store_rgba(j.out, col0 + x, j.y, load_rgba(j.row, x, 0, packed));
      if (mask_row) mask_row[x] = 0;
    }
    return;
  }
  __syncthreads();  // the previous eye is done with keys and row_holes
  if (threadIdx.x == 0) *row_holes = 0;
  for (int X = threadIdx.x; X < j.W; X += blockDim.x) j.keys[X] = 0ull;
  __syncthreads();

  for (int x = threadIdx.x; x < j.W; x += blockDim.x) {
    const WarpSource s = warp_source(j.depth_row, x, j.W, shift, j.D, j.convergence);
    const WarpSpan span = warp_span(s, j.W);
    for (int X = span.first; X <= span.last; ++X) atomicMax(j.keys + X, warp_key_at(s, X, j.W));
  }
  __syncthreads();

  // j.row holds the load_rgba() values of the source row, as the CPU's
  // SourceRow does; sample_row reads them as Rgba.
  int holes = 0;
  for (int X = threadIdx.x; X < j.W; X += blockDim.x) {
    const unsigned long long key = j.keys[X];
    if (key != 0) {
      store_rgba(j.out, col0 + X, j.y, sample_row(reinterpret_cast<const Rgba *>(j.row.plane[0]), j.W, key));
    } else {
      ++holes;
      if (j.fill == HoleFill::None) store_rgba(j.out, col0 + X, j.y, kHoleColour);
    }
    if (mask_row) mask_row[X] = key == 0 ? 1 : 0;
    if (j.zbits) j.zbits[(static_cast<size_t>(eye) * j.H + j.y) * j.W + X] = smooth_zbits(key);
  }
  if (holes) atomicAdd(row_holes, holes);
  __syncthreads();  // also publishes this row's colours to the fill below
  const int row_total = *row_holes;
  if (row_total == 0) return;  // block-uniform
  if (threadIdx.x == 0) atomicAdd(j.total, static_cast<unsigned long long>(row_total));
  if (j.fill != HoleFill::Background) return;

  chunk_extremes(j.keys, j.W, j.chunks, j.first, j.last);
  __syncthreads();
  if (threadIdx.x < 32) chunk_neighbours(j.chunks, j.first, j.last, j.before, j.after);
  __syncthreads();
  background_fill_row(j.out, col0, j.y, j.keys, j.W, j.chunks, j.before, j.after);
}

// One block = output row blockIdx.x, both eyes one after the other, so the
// source row is converted once. kSharedKeys: the z-buffer in shared memory,
// else in global_keys (one W-key row per block).
// At most 512 threads, 3 blocks per SM: 40 registers a thread (42 without
// the bound, no spills with it), so that three rows (49 KB of shared memory
// each at 4K) run at once instead of two; launch_rows asks for the largest
// shared-memory carveout. The kernel is instruction bound (ncu: SM 61 %,
// DRAM 9 %), and the third row per SM took the 4K warp from 0.286 to
// 0.230 ms on an H100 (8K, whose rows need 92 KB, is unchanged).
constexpr int kRowThreadsMax = 512;
template <bool kSharedKeys>
__global__ void __launch_bounds__(kRowThreadsMax, 3) warp_row_kernel(FrameView src, YuvToRgb m, ImageView<const float> depth, FrameView out,
                                EyeShifts eyes, float D, float convergence, HoleFill fill,
                                unsigned long long *global_keys, uint8_t *mask, uint32_t *zbits,
                                unsigned long long *total) {
  extern __shared__ unsigned long long smem[];
  __shared__ int row_holes;
  RowJob j;
  j.y = blockIdx.x;
  j.W = src.width;
  j.H = src.height;
  j.chunks = row_chunks(j.W);
  j.out = out;
  j.eyes = eyes;
  j.D = D;
  j.convergence = convergence;
  j.fill = fill;
  j.depth_row = depth.row(j.y);
  j.keys = kSharedKeys ? smem : global_keys + static_cast<size_t>(j.y) * j.W;
  uint8_t *rgba = reinterpret_cast<uint8_t *>(kSharedKeys ? smem + j.W : smem);
  j.first = reinterpret_cast<int *>(rgba + 4 * static_cast<size_t>(j.W));
  j.last = j.first + j.chunks;
  j.before = j.last + j.chunks;
  j.after = j.before + j.chunks;
  j.mask = mask;
  j.zbits = zbits;
  j.total = total;
  j.row.format = PixelFormat::RGBA;
  j.row.width = j.W;
  j.row.height = 1;
  j.row.plane[0] = rgba;
  j.row.stride[0] = 4 * j.W;

  for (int x = threadIdx.x; x < j.W; x += blockDim.x) store_rgba(j.row, x, 0, load_rgba(src, x, j.y, m));
  __syncthreads();
  render_eye(j, 0, &row_holes);
  render_eye(j, 1, &row_holes);
}

// One Jacobi step of NeighborAverage over both eyes: reads mask_in and the
// colours of pixels that mask_in says are filled (never written in this
// step), writes the new mask for every pixel.
__global__ void neighbour_average_kernel(FrameView out, int W, int H, const uint8_t *mask_in, uint8_t *mask_out,
                                         unsigned *filled) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int eye = blockIdx.z;
  bool done = false;
  if (x < W && y < H) {
    const size_t plane = static_cast<size_t>(W) * H;
    const size_t i = eye * plane + static_cast<size_t>(y) * W + x;
    uint8_t still = 0;
    if (mask_in[i]) {
      Rgba c;
      if (neighbour_average(out, eye * W, mask_in + eye * plane, W, W, H, x, y, &c)) {
        store_rgba(out, eye * W + x, y, c);
        done = true;
      } else {
        still = 1;
      }
    }
    mask_out[i] = still;
  }
  const unsigned ballot = __ballot_sync(kFullMask, done);  // every lane gets here
  if ((threadIdx.x & 31) == 0 && ballot != 0) atomicAdd(filled, static_cast<unsigned>(__popc(ballot)));
}

// ---- BackgroundSmooth (common/warp.h): three kernels after the row kernel,
// which wrote smooth_zbits() of every pixel of the warped eyes. Scratch per
// eye (W x H each): zbits (uint32), state (uint8 flags below; 0: not in F),
// anchor (Rgba), column sums V (SmoothSum). Integer sums throughout, so
// every reduction order gives the CPU's result.

// Predicate bits of a row pixel for the anchor search.
constexpr uint8_t kNonHole = 1, kClean = 2;
// State flags of a pixel: in F (hole or ring), has an anchor, is a hole (so
// the row pass reads one byte per pixel instead of the zbits).
constexpr uint8_t kStateInF = 1, kStateAnchor = 2, kStateHole = 4;

// Per-chunk first and last pixel whose predicate has `bit` (INT_MAX / -1:
// none), one warp per chunk.
__device__ void chunk_extremes_bit(const uint8_t *pred, uint8_t bit, int W, int chunks, int *first, int *last) {
  const int lane = threadIdx.x & 31, warps = blockDim.x >> 5;
  for (int c = threadIdx.x >> 5; c < chunks; c += warps) {
    const int X = c * 32 + lane;
    const unsigned set = __ballot_sync(kFullMask, X < W && (pred[X] & bit));
    if (lane == 0) {
      first[c] = set ? c * 32 + __ffs(set) - 1 : INT_MAX;
      last[c] = set ? c * 32 + 31 - __clz(set) : -1;
    }
  }
}

// Anchors of one row of one eye (block = row blockIdx.x, eye blockIdx.y).
// Dynamic shared memory: hole flags of rows y-1, y, y+1 (3 W bytes), the
// predicate row (W bytes), then 8 int arrays of one entry per chunk; each
// part starts 16-byte aligned (smooth_anchor_smem()).
__host__ __device__ size_t align16(size_t n) { return (n + 15) & ~static_cast<size_t>(15); }
size_t smooth_anchor_smem(int W) {
  return align16(3 * static_cast<size_t>(W)) + align16(W) + 8 * sizeof(int) * static_cast<size_t>(row_chunks(W));
}
__global__ void smooth_anchor_kernel(FrameView out, int W, int H, EyeShifts eyes, const uint32_t *zbits,
                                     uint8_t *state, Rgba *anchor) {
  extern __shared__ unsigned char smem_bytes[];
  const int y = blockIdx.x, eye = blockIdx.y;
  if (eyes.shift[eye] == 0.f) return;  // a copied eye has no holes
  const size_t plane = static_cast<size_t>(W) * H;
  const uint32_t *z = zbits + eye * plane;
  uint8_t *rows = smem_bytes;  // [0, W): row y-1, [W, 2W): row y, [2W, 3W): row y+1
  uint8_t *pred = rows + align16(3 * static_cast<size_t>(W));
  const int chunks = row_chunks(W);
  int *arrays = reinterpret_cast<int *>(pred + align16(W));
  int *first_any = arrays, *last_any = arrays + chunks, *before_any = arrays + 2 * chunks,
      *after_any = arrays + 3 * chunks;
  int *first_clean = arrays + 4 * chunks, *last_clean = arrays + 5 * chunks, *before_clean = arrays + 6 * chunks,
      *after_clean = arrays + 7 * chunks;
  for (int X = threadIdx.x; X < W; X += blockDim.x)
    for (int r = 0; r < 3; ++r) {
      const int yy = y - 1 + r;
      rows[r * W + X] = yy >= 0 && yy < H && smooth_zbits_hole(z[static_cast<size_t>(yy) * W + X]) ? 1 : 0;
    }
  __syncthreads();
  const uint8_t *up = y > 0 ? rows : nullptr, *row = rows + W, *down = y + 1 < H ? rows + 2 * W : nullptr;
  for (int X = threadIdx.x; X < W; X += blockDim.x) {
    const bool ring = smooth_is_ring(up, row, down, X, W);
    pred[X] = row[X] ? 0 : static_cast<uint8_t>(kNonHole | (ring ? 0 : kClean));
  }
  __syncthreads();
  chunk_extremes_bit(pred, kNonHole, W, chunks, first_any, last_any);
  chunk_extremes_bit(pred, kClean, W, chunks, first_clean, last_clean);
  __syncthreads();
  if (threadIdx.x < 32)
    chunk_neighbours(chunks, first_any, last_any, before_any, after_any);
  else if (threadIdx.x < 64)
    chunk_neighbours(chunks, first_clean, last_clean, before_clean, after_clean);
  __syncthreads();
  const YuvToRgb packed;
  const int lane = threadIdx.x & 31, warps = blockDim.x >> 5;
  const uint32_t *zrow = z + static_cast<size_t>(y) * W;
  for (int c = threadIdx.x >> 5; c < chunks; c += warps) {
    const int X = c * 32 + lane;
    const bool in = X < W;
    const uint8_t p = in ? pred[X] : 0;
    const unsigned any = __ballot_sync(kFullMask, in && (p & kNonHole));
    const unsigned clean = __ballot_sync(kFullMask, in && (p & kClean));
    if (!in) continue;
    const size_t i = eye * plane + static_cast<size_t>(y) * W + X;
    const bool in_f = row[X] || !(p & kClean);  // a hole or a ring pixel
    if (!in_f) {
      state[i] = 0;
      continue;
    }
    const unsigned below = (1u << lane) - 1u, above = ~((2u << lane) - 1u);
    const int l_any = (any & below) ? c * 32 + 31 - __clz(any & below) : before_any[c];
    const int l_clean = (clean & below) ? c * 32 + 31 - __clz(clean & below) : before_clean[c];
    const int r_any = (any & above) ? c * 32 + __ffs(any & above) - 1 : after_any[c];
    const int r_clean = (clean & above) ? c * 32 + __ffs(clean & above) - 1 : after_clean[c];
    const int xl = smooth_side(l_clean, l_any), xr = smooth_side(r_clean, r_any);
    const int pick = background_source(X, xl, xl >= 0 ? smooth_zbits_key(zrow[xl]) : 0ull, xr,
                                       xr >= 0 ? smooth_zbits_key(zrow[xr]) : 0ull);
    state[i] = static_cast<uint8_t>(kStateInF | (pick >= 0 ? kStateAnchor : 0) | (row[X] ? kStateHole : 0));
    if (pick >= 0) anchor[i] = load_rgba(out, eye * W + pick, y, packed);
  }
}

// Column sums V: one thread per column, segment of rows and eye slides the
// window [max(a, y - R), min(b, y + R)] down its segment, a..b being the run
// of F that holds y. A segment starts by walking up to R rows back to find
// where the window begins, so a pixel costs about 2 + (2R + 1) / segment
// loads, and the columns are split into H / segment independent threads.
// The walk is latency bound, so short segments (more threads) win although
// they load more: at 4K, 3 % (R = 29) on an H100 the whole warp took 1.7 ms
// with one thread per column, 0.623 with segments of 2R rows and 0.565 with
// R / 2 (a thread per pixel, walking its own window: 0.565 too).
int smooth_column_segment(int R) { return R < 32 ? 16 : R / 2; }
__global__ void smooth_column_kernel(int W, int H, int segment, EyeShifts eyes, int2 radius, const uint8_t *state,
                                     const Rgba *anchor, SmoothSum *column) {
  const int X = blockIdx.x * blockDim.x + threadIdx.x, eye = blockIdx.z;
  if (X >= W || eyes.shift[eye] == 0.f) return;
  const int R = eye == 0 ? radius.x : radius.y;
  const int y0 = blockIdx.y * segment;
  const int y1 = min(H, y0 + segment);
  const size_t plane = static_cast<size_t>(W) * H, base = eye * plane + X;
  auto at = [&](int y) { return base + static_cast<size_t>(y) * W; };
  int lo = y0;  // the first row of y0's window: its run's start, at most R rows up
  while (lo > 0 && lo > y0 - R && state[at(lo - 1)]) --lo;
  int hi = lo - 1;  // the window holds the F rows lo..hi of the current run
  SmoothSum s = SmoothSum{0, 0, 0, 0, 0};
  for (int y = y0; y < y1; ++y) {
    if (!state[at(y)]) {
      s = SmoothSum{0, 0, 0, 0, 0};
      lo = y + 1;
      hi = y;
      continue;
    }
    while (hi < y + R && hi + 1 < H && state[at(hi + 1)]) {
      ++hi;
      if (state[at(hi)] & kStateAnchor) smooth_add(s, anchor[at(hi)]);
    }
    while (lo < y - R) {
      if (state[at(lo)] & kStateAnchor) {
        const Rgba c = anchor[at(lo)];
        s = smooth_window(s, SmoothSum{c.r, c.g, c.b, c.a, 1u});
      }
      ++lo;
    }
    column[at(y)] = s;
  }
}

// Every hole: the mean of V over its row's run of F within +-Rx.
__global__ void smooth_row_kernel(FrameView out, int W, int H, EyeShifts eyes, int2 radius_x, const uint8_t *state,
                                  const SmoothSum *column) {
  const int X = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y, eye = blockIdx.z;
  if (X >= W || eyes.shift[eye] == 0.f) return;
  const size_t row = eye * static_cast<size_t>(W) * H + static_cast<size_t>(y) * W;
  if (!(state[row + X] & kStateHole)) return;
  const int Rx = eye == 0 ? radius_x.x : radius_x.y;
  SmoothSum s = column[row + X];
  for (int t = X - 1; t >= 0 && t >= X - Rx && state[row + t]; --t) smooth_add(s, column[row + t]);
  for (int t = X + 1; t < W && t <= X + Rx && state[row + t]; ++t) smooth_add(s, column[row + t]);
  store_rgba(out, eye * W + X, y, smooth_mean(s));
}

__global__ void paint_holes_kernel(FrameView out, int W, int H, const uint8_t *mask) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int eye = blockIdx.z;
  if (x >= W || y >= H) return;
  if (mask[(static_cast<size_t>(eye) * H + y) * W + x]) store_rgba(out, eye * W + x, y, kFillBlack);
}

dim3 pixel_grid(int W, int H) { return dim3((W + kBlockX - 1) / kBlockX, (H + kBlockY - 1) / kBlockY, 2); }

struct RowLaunch {
  FrameView src;
  YuvToRgb m;
  ImageView<const float> depth;
  FrameView out;
  EyeShifts eyes;
  float D, convergence;
  HoleFill fill;
  unsigned long long *global_keys;
  uint8_t *mask;
  uint32_t *zbits;
  unsigned long long *total;
  size_t smem;
  cudaStream_t stream;
};

template <bool kSharedKeys>
CudaStatus launch_rows(const RowLaunch &l) {
  if (l.smem > 48 * 1024)  // the default dynamic shared memory limit
    P3D_CUDA_TRY(cudaFuncSetAttribute(warp_row_kernel<kSharedKeys>, cudaFuncAttributeMaxDynamicSharedMemorySize,
                                      static_cast<int>(l.smem)));
  P3D_CUDA_TRY(cudaFuncSetAttribute(warp_row_kernel<kSharedKeys>, cudaFuncAttributePreferredSharedMemoryCarveout,
                                    static_cast<int>(cudaSharedmemCarveoutMaxShared)));
  const int threads = l.src.width > 1024 ? kRowThreadsMax : 256;
  warp_row_kernel<kSharedKeys><<<l.src.height, threads, l.smem, l.stream>>>(
      l.src, l.m, l.depth, l.out, l.eyes, l.D, l.convergence, l.fill, l.global_keys, l.mask, l.zbits, l.total);
  P3D_CUDA_TRY_LAUNCH(warp_row_kernel);
  return {};
}

CudaStatus invalid_frames() {
  return CudaStatus{cudaErrorInvalidValue, "warp_frames_fit(src, depth, out)", __FILE__, __LINE__};
}

}  // namespace

CudaStatus WarpRendererGpu::render(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                                   ImageView<const float> depth, const FrameView &out, cudaStream_t stream,
                                   long long *holes_out) {
  if (!warp_frames_fit(src, depth, out)) return invalid_frames();
  const WarpParams p = warp_sanitize(params);
  const int W = src.width, H = src.height;
  const float D = disparity_scale(p, W);
  const EyeShifts eyes{{warp_eye_shift(p, D, 0), warp_eye_shift(p, D, 1)}};
  const bool average = p.fill == HoleFill::NeighborAverage;
  const bool smooth = p.fill == HoleFill::BackgroundSmooth;

  if (smem_optin_ < 0) {
    int dev = 0;
    P3D_CUDA_TRY(cudaGetDevice(&dev));
    P3D_CUDA_TRY(cudaDeviceGetAttribute(&smem_optin_, cudaDevAttrMaxSharedMemoryPerBlockOptin, dev));
  }
  // 64 bytes: room for the kernel's static __shared__ counter.
  const bool shared_keys = row_smem_bytes(W, true) + 64 <= static_cast<size_t>(smem_optin_);
  const size_t smem = row_smem_bytes(W, shared_keys);
  if (smem + 64 > static_cast<size_t>(smem_optin_))  // rows wider than ~50000 pixels on Hopper
    return CudaStatus{cudaErrorInvalidValue, "row_smem_bytes(W) <= cudaDevAttrMaxSharedMemoryPerBlockOptin", __FILE__,
                      __LINE__};
  if (!shared_keys) P3D_CUDA_TRY_STATUS(keys_.ensure(static_cast<size_t>(W) * H * sizeof(unsigned long long)));
  if (average) P3D_CUDA_TRY_STATUS(scratch_.ensure(2 * 2 * static_cast<size_t>(W) * H));  // two masks, both eyes
  const size_t plane = 2 * static_cast<size_t>(W) * H;                                      // both eyes
  if (smooth) P3D_CUDA_TRY_STATUS(smooth_.ensure(plane * kSmoothBytesPerPixel));
  P3D_CUDA_TRY_STATUS(counters_.ensure(kCountersBytes));
  uint8_t *counters = counters_.as<uint8_t>();
  auto *total = reinterpret_cast<unsigned long long *>(counters + kTotalOffset);
  P3D_CUDA_TRY(cudaMemsetAsync(counters, 0, kCountersBytes, stream));

  uint8_t *mask = average ? scratch_.as<uint8_t>() : nullptr;
  // BackgroundSmooth scratch, both eyes each: column sums, anchors, zbits, states.
  SmoothSum *column = smooth ? smooth_.as<SmoothSum>() : nullptr;
  Rgba *anchor = smooth ? reinterpret_cast<Rgba *>(column + plane) : nullptr;
  uint32_t *zbits = smooth ? reinterpret_cast<uint32_t *>(anchor + plane) : nullptr;
  uint8_t *state = smooth ? reinterpret_cast<uint8_t *>(zbits + plane) : nullptr;
  const RowLaunch launch{src, m, depth, out, eyes, D, p.convergence, p.fill, keys_.as<unsigned long long>(), mask,
                         zbits, total, smem, stream};
  P3D_CUDA_TRY_STATUS(shared_keys ? launch_rows<true>(launch) : launch_rows<false>(launch));
  if (average) P3D_CUDA_TRY_STATUS(neighbour_average(out, W, H, stream));
  if (smooth) P3D_CUDA_TRY_STATUS(background_smooth(out, W, H, eyes.shift, D, zbits, state, anchor, column, stream));

  if (holes_out) {
    unsigned long long h = 0;
    P3D_CUDA_TRY(cudaMemcpyAsync(&h, total, sizeof(h), cudaMemcpyDeviceToHost, stream));
    P3D_CUDA_TRY(cudaStreamSynchronize(stream));
    *holes_out = static_cast<long long>(h);
  }
  return {};
}

// BackgroundSmooth driver: anchors (a block per row and eye), column sums (a
// thread per column segment and eye), row means (a thread per pixel). No
// host sync.
CudaStatus WarpRendererGpu::background_smooth(const FrameView &out, int W, int H, const float shift[2], float D,
                                              const uint32_t *zbits, uint8_t *state, Rgba *anchor, SmoothSum *column,
                                              cudaStream_t stream) {
  const EyeShifts eyes{{shift[0], shift[1]}};
  const int R0 = smooth_fill_radius(shift[0], D), R1 = smooth_fill_radius(shift[1], D);
  const size_t smem = smooth_anchor_smem(W);
  if (smem > 48 * 1024)
    P3D_CUDA_TRY(cudaFuncSetAttribute(smooth_anchor_kernel, cudaFuncAttributeMaxDynamicSharedMemorySize,
                                      static_cast<int>(smem)));
  // 256 threads: twice the resident blocks of 512 for this latency-bound
  // kernel (4K on an H100: 0.623 against 0.643 ms for the whole warp).
  smooth_anchor_kernel<<<dim3(H, 2), 256, smem, stream>>>(out, W, H, eyes, zbits, state, anchor);
  P3D_CUDA_TRY_LAUNCH(smooth_anchor_kernel);
  constexpr int kColumnThreads = 128;
  // Both eyes share the grid; the smaller radius of a warped eye sets the
  // segment (shorter segments: more threads, a little more overlap).
  const int R_small = shift[0] == 0.f ? R1 : shift[1] == 0.f ? R0 : (R0 < R1 ? R0 : R1);
  const int segment = smooth_column_segment(R_small);
  smooth_column_kernel<<<dim3((W + kColumnThreads - 1) / kColumnThreads, (H + segment - 1) / segment, 2),
                         kColumnThreads, 0, stream>>>(W, H, segment, eyes, make_int2(R0, R1), state, anchor, column);
  P3D_CUDA_TRY_LAUNCH(smooth_column_kernel);
  constexpr int kRowThreads = 128;
  smooth_row_kernel<<<dim3((W + kRowThreads - 1) / kRowThreads, H, 2), kRowThreads, 0, stream>>>(
      out, W, H, eyes, make_int2(smooth_fill_radius_x(R0), smooth_fill_radius_x(R1)), state, column);
  P3D_CUDA_TRY_LAUNCH(smooth_row_kernel);
  return {};
}

// NeighborAverage driver: batches of kWarpFillBatch Jacobi steps; the host
// reads the batch's per-step fill counts (one stream sync per batch) and
// stops once no hole is left or a step filled nothing. Steps after such a
// step are no-ops (masks copied), so running the rest of a batch is harmless.
CudaStatus WarpRendererGpu::neighbour_average(const FrameView &out, int W, int H, cudaStream_t stream) {
  uint8_t *counters = counters_.as<uint8_t>();
  auto *filled = reinterpret_cast<unsigned *>(counters + kFilledOffset);
  unsigned long long total = 0;
  P3D_CUDA_TRY(cudaMemcpyAsync(&total, counters + kTotalOffset, sizeof(total), cudaMemcpyDeviceToHost, stream));
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));

  const size_t masks = 2 * static_cast<size_t>(W) * H;
  uint8_t *cur = scratch_.as<uint8_t>(), *next = cur + masks;
  long long remaining = static_cast<long long>(total);
  bool stuck = false;
  while (remaining > 0 && !stuck) {
    P3D_CUDA_TRY(cudaMemsetAsync(filled, 0, sizeof(unsigned) * kWarpFillBatch, stream));
    for (int i = 0; i < kWarpFillBatch; ++i) {
      neighbour_average_kernel<<<pixel_grid(W, H), dim3(kBlockX, kBlockY), 0, stream>>>(out, W, H, cur, next,
                                                                                      filled + i);
      P3D_CUDA_TRY_LAUNCH(neighbour_average_kernel);
      std::swap(cur, next);
    }
    unsigned counts[kWarpFillBatch] = {};
    P3D_CUDA_TRY(cudaMemcpyAsync(counts, filled, sizeof(counts), cudaMemcpyDeviceToHost, stream));
    P3D_CUDA_TRY(cudaStreamSynchronize(stream));
    for (int i = 0; i < kWarpFillBatch && !stuck; ++i) {
      remaining -= counts[i];
      stuck = counts[i] == 0;
    }
  }
  if (remaining > 0) {
    paint_holes_kernel<<<pixel_grid(W, H), dim3(kBlockX, kBlockY), 0, stream>>>(out, W, H, cur);
    P3D_CUDA_TRY_LAUNCH(paint_holes_kernel);
  }
  return {};
}

}  // namespace p3d
