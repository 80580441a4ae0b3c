// BackgroundSmooth's sums (common/warp.h), after the row kernel
// (cuda/warp_rows.cu) wrote every hole's anchor and state and listed the
// tiles with holes: a block (256 threads, 512 where shared memory bounds
// the tiles an SM holds anyway) per listed tile of 32 columns x up to 32
// rows and eye copies the states and anchors of its rows and R more above
// and below into shared memory, slides the +-R window down the column runs
// of holes (column sums V for its columns and Rx more either side) and
// sums V over +-Rx along each hole's row run. No host sync. Integer sums
// throughout, so every reduction order gives the CPU's result. The tiles,
// V's width and the block size are cuda/warp_plan.h's (plan_smooth,
// choose_smooth_threads). Templates on the anchors' pixel type: Rgba
// (cuda/warp_smooth.cu), Rgba16 (cuda/kernels_deep.cu).
#pragma once

#include <vector>

#include "chained_launch.cuh"
#include "launch_bounds.cuh"
#include "warp_device.cuh"
#include "warp_internal.h"

namespace p3d {
namespace warp_detail {
namespace {

// Column and row sums in one kernel: a block takes a tile of one eye,
// kSmoothTileW columns x S rows. It computes V of the tile's rows for the
// tile's columns and Rx more on either side into shared memory (sliding
// the +-R window down segments of kSmoothSub rows, as smooth_column_sums
// does on the CPU), then every hole of the tile sums V along its row run.
// The walks are serial, so they read a copy of the states and anchors of
// rows y0 - R .. y0 + S + R - 1 in shared memory when it fits (global
// memory otherwise: very wide windows only); a tile without a hole returns
// at once.
constexpr int kSmoothSub = 8;
constexpr int kSmoothCopyBatch = 4;  // pixels a thread copies at once (smooth_tile)

// V in shared memory: wide sums of Sum, or narrow ones of SmoothSum
// (kSmoothNarrowRMax, cuda/warp_plan.h), smooth_v_bytes' layout.
template <bool kNarrow, class Sum>
struct TileSums {
  Sum *v;
  __device__ TileSums(unsigned char *smem, size_t) : v(reinterpret_cast<Sum *>(smem)) {}
  __device__ void put(size_t i, const Sum &s) { v[i] = s; }
  __device__ Sum get(size_t i) const { return v[i]; }
};
template <>
struct TileSums<true, SmoothSum> {
  static_assert(sizeof(uint2) == 2 * sizeof(uint32_t) && sizeof(unsigned short) == sizeof(uint16_t),
                "smooth_v_bytes' narrow layout");
  uint2 *rgba;
  unsigned short *n;
  __device__ TileSums(unsigned char *smem, size_t count)
      : rgba(reinterpret_cast<uint2 *>(smem)),
        n(reinterpret_cast<unsigned short *>(smem + align16(count * sizeof(uint2)))) {}
  __device__ void put(size_t i, const SmoothSum &s) {
    rgba[i] = make_uint2(s.r | (s.g << 16), s.b | (s.a << 16));
    n[i] = static_cast<unsigned short>(s.n);
  }
  __device__ SmoothSum get(size_t i) const {
    const uint2 p = rgba[i];
    return SmoothSum{p.x & 0xffffu, p.x >> 16, p.y & 0xffffu, p.y >> 16, n[i]};
  }
};

// One listed tile of one eye (tile column tx = chunk tx, tile row ty):
// every thread of the block calls it. kStaged: the walks read the copy in
// shared memory (a template parameter, so that they compile to
// shared-memory loads, not generic ones).
template <bool kNarrow, bool kStaged, class Px>
__device__ void smooth_tile(unsigned char *smem_bytes, const FrameView &out, int W, int H, int R,
                            const SmoothScratch &sc, int eye, int tx, int ty) {
  using Sum = typename SmoothSumFor<Px>::Type;
  const int S = sc.tile_rows, Rx = smooth_fill_radius_x(R);
  const int x0 = tx * kSmoothTileW, y0 = ty * S;
  const size_t plane = static_cast<size_t>(W) * H;
  const uint8_t *st_eye = sc.state + eye * plane;
  const Px *an_eye = static_cast<const Px *>(sc.anchor) + eye * plane;
  const int chunks = row_chunks(W);
  const uint8_t *ch_eye = sc.chunk_holes + eye * static_cast<size_t>(H) * chunks;

  const int nc = smooth_tile_columns(Rx), cx0 = x0 - Rx;  // V columns cx0 .. cx0 + nc - 1
  TileSums<kNarrow, Sum> V(smem_bytes, static_cast<size_t>(nc) * S);  // row r of the tile: r * nc + column - cx0
  const uint8_t *st = st_eye;
  const Px *an = an_eye;
  size_t pitch = W;
  int sy0 = 0, sx0 = 0;
  if (kStaged) {
    Px *an_copy = reinterpret_cast<Px *>(smem_bytes + smooth_tile_v_bytes(kNarrow, Rx, S, sizeof(Px)));
    uint8_t *st_copy = reinterpret_cast<uint8_t *>(an_copy + smooth_tile_copy_pixels(R, Rx, S));
    uint8_t *flags = st_copy + smooth_tile_copy_pixels(R, Rx, S);
    sy0 = max(0, y0 - R);
    sx0 = max(0, cx0);
    const int rows = min(H, y0 + S + R) - sy0, cols = min(W, cx0 + nc) - sx0;
    // The chunk flags of the copied rows, then the states and anchors of
    // the chunks with holes (zeros elsewhere, nothing read; an anchor is
    // loaded with its state and kept where the state names one): holes
    // are sparse, so most of the copy costs no load. The block works
    // through each copy as one flat range, kSmoothCopyBatch pixels a thread
    // at a time whose loads are all issued before any is used: a listed
    // tile's time is mostly these loads' latency, which a warp a row, each
    // row waiting for the last, would serialise (measured:
    // docs/benchmarks.md, Design measurements, "Warp: the smooth fill's
    // sums").
    const int fc0 = sx0 / 32, fcn = (sx0 + cols - 1) / 32 - fc0 + 1;
    for (int i = threadIdx.x; i < rows * fcn; i += blockDim.x) {
      const int r = i / fcn;
      flags[i] = ch_eye[static_cast<size_t>(sy0 + r) * chunks + fc0 + (i - r * fcn)];
    }
    __syncthreads();
    // Pixel i of the range is row i / cols, column i % cols; a thread's
    // pixels are blockDim.x apart, so it steps its row and column by the
    // block's quotient and remainder instead of dividing for each (a
    // division a pixel would be a third of the copy's instructions, which
    // are a third of the kernel's; measured: docs/benchmarks.md, Design
    // measurements, "Warp: the smooth fill's sums").
    const int count = rows * cols, step = static_cast<int>(blockDim.x);
    const int step_rows = step / cols, step_cols = step - step_rows * cols;
    int r = static_cast<int>(threadIdx.x) / cols, c = static_cast<int>(threadIdx.x) - r * cols;
    for (int i0 = threadIdx.x; i0 < count; i0 += kSmoothCopyBatch * step) {
      int at_copy[kSmoothCopyBatch];  // the pixel's place in the copy, -1: none
      uint8_t state[kSmoothCopyBatch];
      Px anchor[kSmoothCopyBatch];  // loaded with its state: stale (and dropped) where it has no anchor
#pragma unroll
      for (int k = 0; k < kSmoothCopyBatch; ++k) {
        const bool in = i0 + k * step < count;
        at_copy[k] = in ? r * nc + c : -1;
        state[k] = 0;
        if (in && flags[r * fcn + ((sx0 + c) >> 5) - fc0]) {
          const size_t g = static_cast<size_t>(sy0 + r) * W + sx0 + c;
          state[k] = st_eye[g];
          anchor[k] = an_eye[g];
        }
        r += step_rows;
        c += step_cols;
        if (c >= cols) {
          c -= cols;
          ++r;
        }
      }
#pragma unroll
      for (int k = 0; k < kSmoothCopyBatch; ++k) {
        if (at_copy[k] < 0) continue;
        st_copy[at_copy[k]] = state[k];
        if (state[k] & kStateAnchor) an_copy[at_copy[k]] = anchor[k];
      }
    }
    st = st_copy;
    an = an_copy;
    pitch = nc;
    __syncthreads();
  }
  auto at = [&](int y, int X) { return static_cast<size_t>(y - sy0) * pitch + (X - sx0); };
  // A pixel's state: the row kernel wrote the states of chunks with holes
  // only, so outside the copy a chunk without a flag reads as no hole.
  auto hole_state = [&](int y, int X) -> uint8_t {
    if (kStaged) return st[at(y, X)];
    return ch_eye[static_cast<size_t>(y) * chunks + (X >> 5)] ? st[at(y, X)] : 0;
  };

  const int subs = (S + kSmoothSub - 1) / kSmoothSub;
  for (int item = threadIdx.x; item < nc * subs; item += blockDim.x) {
    const int ci = item % nc, X = cx0 + ci;
    if (X < 0 || X >= W) continue;
    const int ya = y0 + (item / nc) * kSmoothSub, yb = min(min(H, y0 + S), ya + kSmoothSub);
    if (ya >= yb) continue;  // a segment past the picture's last row (its walk would read row H)
    int lo = ya;  // the first row of ya's window: its run's start, at most R rows up
    while (lo > 0 && lo > ya - R && hole_state(lo - 1, X)) --lo;
    int hi = lo - 1;  // the window holds the rows lo..hi of the current run
    Sum s = Sum{0, 0, 0, 0, 0};
    for (int y = ya; y < yb; ++y) {
      if (!hole_state(y, X)) {
        s = Sum{0, 0, 0, 0, 0};
        lo = y + 1;
        hi = y;
        continue;
      }
      while (hi < y + R && hi + 1 < H && hole_state(hi + 1, X)) {
        ++hi;
        if (hole_state(hi, X) & kStateAnchor) smooth_add(s, an[at(hi, X)]);
      }
      while (lo < y - R) {
        if (hole_state(lo, X) & kStateAnchor) {
          const Px c = an[at(lo, X)];
          s = smooth_window(s, Sum{c.r, c.g, c.b, c.a, 1u});
        }
        ++lo;
      }
      V.put(static_cast<size_t>(y - y0) * nc + ci, s);
    }
  }
  __syncthreads();

  for (int i = threadIdx.x; i < kSmoothTileW * S; i += blockDim.x) {
    const int X = x0 + i % kSmoothTileW, y = y0 + i / kSmoothTileW;
    if (X >= W || y >= H || !hole_state(y, X)) continue;
    const size_t v0 = static_cast<size_t>(y - y0) * nc - cx0;  // V of column t in row y: v0 + t
    Sum s = V.get(v0 + X);
    for (int t = X - 1; t >= 0 && t >= X - Rx && hole_state(y, t); --t) smooth_add(s, V.get(v0 + t));
    for (int t = X + 1; t < W && t <= X + Rx && hole_state(y, t); ++t) smooth_add(s, V.get(v0 + t));
    store_pixel(out, eye * W + X, y, smooth_mean(s));
  }
}

// The sums kernel: block b sums listed tiles b, b + gridDim.x, ...; the
// grid has a block for every kSmoothTilesPerBlock tiles the frame may list
// (launch_smooth), so a frame whose every tile has a hole (noise depth,
// GpuWarp.AllModesRandomDepth) takes each block through several tiles.
// A 4K frame lists about 900 of its 32400 tiles. A block for every 8
// tiles beats a block for every tile (4 to 16 measure alike; 32 leave a
// 1080p frame's few tiles to too few blocks), and a grid of only as many
// blocks as the GPU holds is slower than either, chained or not: tiles
// differ in cost, and many short-lived blocks balance them better
// (measured: docs/benchmarks.md, Design measurements, "Warp: the smooth
// fill's sums").
// kTight: blocks of kSmoothTileThreads, as many as an SM holds threads for
// (at most 32 registers a thread on Hopper; ptxas: no spills in the
// staged narrow kernel, 12 to 24 bytes in the others), else
// kSmoothTileThreadsMax with no register bound; choose_smooth_threads()
// takes the one that keeps more threads resident.
template <bool kNarrow, bool kStaged, bool kTight, class Px>
__global__ void __launch_bounds__(kTight ? kSmoothTileThreads : kSmoothTileThreadsMax,
                                  kTight ? P3D_MAX_THREADS_PER_SM / kSmoothTileThreads : 1)
    smooth_tile_kernel(FrameView out, int W, int H, int2 radius, SmoothScratch sc) {
  chained_kernel_start();
  extern __shared__ unsigned char smem_bytes[];
  const unsigned count = *sc.tile_count;
  for (unsigned i = blockIdx.x; i < count; i += gridDim.x) {  // block-uniform
    if (i != blockIdx.x) __syncthreads();  // the last tile's row sums are done with shared memory
    const unsigned t = sc.tile_list[i];
    const int tx = static_cast<int>(t % sc.tiles_x), rest = static_cast<int>(t / sc.tiles_x);
    const int ty = rest % sc.tiles_y, eye = rest / sc.tiles_y;
    smooth_tile<kNarrow, kStaged, Px>(smem_bytes, out, W, H, eye == 0 ? radius.x : radius.y, sc, eye, tx, ty);
  }
}

// The sums kernel's block size for a kernel and its shared memory
// (choose_smooth_threads), asked of the device once for each.
CudaStatus smooth_tile_threads(const void *loose, const void *tight, size_t smem, SmoothSumsLaunch *cache) {
  if (cache->kernel == loose && cache->smem == smem) return {};
  int tiles = 0, tiles_max = 0, tiles_tight = 0;
  P3D_CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&tiles, loose, kSmoothTileThreads, smem));
  P3D_CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&tiles_max, loose, kSmoothTileThreadsMax, smem));
  P3D_CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&tiles_tight, tight, kSmoothTileThreads, smem));
  const SmoothThreads choice = choose_smooth_threads(tiles, tiles_max, tiles_tight);
  cache->kernel = loose;
  cache->smem = smem;
  cache->launch = choice.tight ? tight : loose;
  cache->threads = choice.threads;
  return {};
}

// The sums kernel of a plan's V width and staging, with or without the
// register bound (kTight). 16-bit anchors take wide sums only.
template <bool kTight, class Px>
auto smooth_kernel_for(const SmoothPlan &plan) -> decltype(&smooth_tile_kernel<false, true, kTight, Px>) {
  if constexpr (sizeof(Px) == sizeof(Rgba)) {
    if (plan.narrow)
      return plan.staged ? smooth_tile_kernel<true, true, kTight, Px> : smooth_tile_kernel<true, false, kTight, Px>;
  }
  return plan.staged ? smooth_tile_kernel<false, true, kTight, Px> : smooth_tile_kernel<false, false, kTight, Px>;
}

// BackgroundSmooth sums, after the row kernel wrote the states and anchors
// and listed the tiles with holes: one smooth_tile_kernel, a block for every
// kSmoothTilesPerBlock tiles the list may hold (the host does not read the
// count). No host sync.
template <class Px>
CudaStatus launch_smooth_of(const SmoothPlan &plan, const SmoothScratch &sc, const FrameView &out, int W, int H,
                            cudaStream_t stream, int smem_optin, std::vector<const void *> *attributes_set,
                            SmoothSumsLaunch *threads_cache) {
  using Kernel = decltype(&smooth_tile_kernel<false, true, false, Px>);
  const Kernel loose = smooth_kernel_for<false, Px>(plan), tight = smooth_kernel_for<true, Px>(plan);
  P3D_CUDA_TRY_STATUS(allow_shared_memory(reinterpret_cast<const void *>(loose), smem_optin, attributes_set));
  P3D_CUDA_TRY_STATUS(allow_shared_memory(reinterpret_cast<const void *>(tight), smem_optin, attributes_set));
  P3D_CUDA_TRY_STATUS(smooth_tile_threads(reinterpret_cast<const void *>(loose), reinterpret_cast<const void *>(tight),
                                          plan.smem, threads_cache));
  const Kernel kernel = reinterpret_cast<Kernel>(const_cast<void *>(threads_cache->launch));
  // Chained (cuda/chained_launch.cuh): its blocks start while the row
  // kernel's last ones run. That gains with a block for every
  // kSmoothTilesPerBlock tiles; with a block for every tile (32400 at 4K),
  // mostly returning at once, it would cost more than it gains (measured:
  // docs/benchmarks.md, Design measurements, "Warp: the smooth fill's
  // sums" and "Chained launches").
  const unsigned blocks = static_cast<unsigned>((plan.tiles() + kSmoothTilesPerBlock - 1) / kSmoothTilesPerBlock);
  P3D_CUDA_TRY(launch_chained(kernel, blocks, threads_cache->threads, plan.smem, stream, out, W, H,
                              make_int2(plan.radius[0], plan.radius[1]), sc));
  return {};
}

}  // namespace
}  // namespace warp_detail
}  // namespace p3d
