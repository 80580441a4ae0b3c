// Cross-bilateral filter kernels: bilateral_kernel (the exact window) and
// separable_kernel (both Separable passes, further down). A block of 32x8 threads computes 32x32
// outputs, each thread a column of kRowsPerThread vertically adjacent
// pixels, so that a tap's shared-memory load serves all of them (the kernel
// is bound by shared-memory bandwidth). Each block stages its tile of
// (depth, guide luma) with an apron of R pixels, plus the weight tables, in
// shared memory; the kernel is instantiated per radius (0..16) so tile
// geometry and the inner loop are compile-time constants. Blocks whose
// windows all lie inside the image (almost all of them) take the register-
// blocked loop; border blocks run bilateral_pixel(), the CPU reference's own
// function. Every output accumulates its taps in the reference's order (dy
// outer, dx inner) through bilateral_accumulate() on the same host-made
// weights, so the result is bit-identical to the CPU's.
//
// At a grid step s > 1 (BilateralParams::scale) the kernels' cell
// instances (GridIo) run on the coarse grid: the tile's texels are cells
// (the rounded mean luma of the cell's pixels, the depth of its first
// pixel: bilateral_cell_luma(), as on the CPU) and each output is written
// to its s x s cell (store_cell), or once to an output grid of the cells'
// size (the depth handoff on grids, docs/architecture.md), so the coarse
// picture never goes through global memory. The step is a template
// parameter, not a run-time branch in every instance, so the step-1
// kernels carry no code for other steps (measured: docs/benchmarks.md,
// Design measurements, "Filter").
#include "chained_launch.cuh"
#include "bilateral_gpu.h"
#include "launch_bounds.cuh"

#include <array>
#include <cstdint>
#include <utility>

namespace p3d {

namespace {

constexpr int kBlockX = 32;
constexpr int kBlockY = 8;
constexpr int kThreads = kBlockX * kBlockY;
constexpr int kRowsPerThread = 4;
constexpr int kOutY = kBlockY * kRowsPerThread;  // output rows per block
// Range weights indexed by g_q - g_p + 255 (symmetric copy of the 256-entry
// table): the fast loop then needs no |.| per tap.
constexpr int kRangeSym = kBilateralSignedRangeSize;
constexpr int kRangeMid = kBilateralRangeTableSize - 1;

// Depth and luma of one pixel side by side: one 64-bit shared load per tap.
// The luma is kept as the byte offset of its entry in a float table (luma
// * 4), so that a tap's range weight is one add and one load from a table
// pointer that already holds the centre's offset (range_weight), where an
// index would take an add, a shift-add and the load (measured:
// docs/benchmarks.md, Design measurements, "Filter").
struct alignas(8) Texel {
  float depth;
  int luma4;
  __device__ int luma() const { return luma4 >> 2; }
};
constexpr int kLumaBytes = static_cast<int>(sizeof(float));

// The range weight of a tap with luma offset luma4, from range_c: the
// symmetric table's centre moved back by the window centre's luma offset.
__device__ __forceinline__ float range_weight(const unsigned char *range_c, int luma4) {
  return *reinterpret_cast<const float *>(range_c + luma4);
}
// range_c for a window centre with luma offset centre4.
__device__ __forceinline__ const unsigned char *range_centred(const float *range_sym, int centre4) {
  return reinterpret_cast<const unsigned char *>(range_sym + kRangeMid) - centre4;
}

template <int R>
struct Geometry {
  static constexpr int kSide = 2 * R + 1;
  static constexpr int kSpace = kSide * kSide;
  static constexpr int kTables = kRangeSym + kSpace;  // floats: range (symmetric) then space
  static constexpr int kTileW = kBlockX + 2 * R;
  static constexpr int kTileH = kOutY + 2 * R;
  static constexpr int kTexels = kTileW * kTileH;
  // Texels first (8-byte aligned), then the tables. R = 16: 39168 bytes,
  // inside the 48 KiB that need no opt-in.
  static constexpr size_t kSharedBytes = sizeof(Texel) * kTexels + sizeof(float) * kTables;
};
static_assert(Geometry<kMaxBilateralRadius>::kSharedBytes <= 48 * 1024, "tile too large for default shared memory");

// Device table layout for every radius: symmetric range table, then the space table.
constexpr size_t kMaxTableFloats = Geometry<kMaxBilateralRadius>::kTables;

// The grid the kernels filter: cells of s x s pixels (s = 1: the pixels),
// w x h of them.
struct Cells {
  int w, h, s;
};

// The grid a kernel instance filters, and how its depth comes in and goes
// out (a template parameter, so that the cell instances that run
// full-size maps carry none of the grids' run-time shifts, which make the
// step-2 kernel spill (measured: docs/benchmarks.md, Design measurements,
// "Filter"); the step-1 instances read through the shift whatever the
// map, which costs them nothing measurable on grids):
//  * kPixelGrid: the pixels (step 1); the depth read through its grid's
//    shift (the estimator's blocks), the output full-size;
//  * kCellsFullSize: the cells of a step s > 1, the depth read from a
//    full-size map at each cell's first pixel and each result written to
//    the cell's s x s pixels;
//  * kCellsOnGrids: the same with the depth read through its grid's shift
//    and each result written once to an output grid of the cells' own size
//    (shift log2 s), or to the s x s pixels of a full-size output.
enum GridIo : int { kPixelGrid = 0, kCellsFullSize = 1, kCellsOnGrids = 2 };

// The grid's size: the cells' (kCells) or the image's.
template <bool kCells>
__device__ __forceinline__ int grid_width(const DepthGrid<const float> &depth_in, const Cells &cells) {
  return kCells ? cells.w : depth_in.width;
}
template <bool kCells>
__device__ __forceinline__ int grid_height(const DepthGrid<const float> &depth_in, const Cells &cells) {
  return kCells ? cells.h : depth_in.height;
}

// bilateral_cell_luma() with every load of a whole 4:2:0 cell at steps 2
// and 4 issued before any is added (a loop over a run-time step waits for
// each byte in turn, and the staging is bound by those waits); integer
// sums, so the same value in any order.
// Where the cell's rows start 2-byte aligned (step 2) or 4-byte aligned
// (step 4), a row is one 16- or 32-bit load, its bytes added by shifts or
// one byte dot product (__dp4a with ones): the same integer sum with half
// or a quarter of the loads (at step 4, byte loads would be most of a
// cell's staging).
template <int S>
__device__ __forceinline__ int whole_cell_luma(const uint8_t *p, int stride) {
  unsigned sum = 0;
  const uintptr_t align = reinterpret_cast<uintptr_t>(p) | static_cast<uintptr_t>(stride);
  if (S == 4 && (align & 3u) == 0) {
#pragma unroll
    for (int y = 0; y < S; ++y)
      sum = __dp4a(*reinterpret_cast<const unsigned *>(p + static_cast<size_t>(y) * stride), 0x01010101u, sum);
  } else if (S == 2 && (align & 1u) == 0) {
#pragma unroll
    for (int y = 0; y < S; ++y) {
      const unsigned w = *reinterpret_cast<const uint16_t *>(p + static_cast<size_t>(y) * stride);
      sum += (w & 0xffu) + (w >> 8);
    }
  } else {
#pragma unroll
    for (int y = 0; y < S; ++y)
#pragma unroll
      for (int x = 0; x < S; ++x) sum += p[static_cast<size_t>(y) * stride + x];
  }
  return static_cast<int>((sum + S * S / 2) / (S * S));
}
__device__ __forceinline__ int cell_luma(const FrameView &guide, int cx, int cy, int s) {
  const int x0 = cx * s, y0 = cy * s;
  if (!is_packed_rgb(guide.format) && x0 + s <= guide.width && y0 + s <= guide.height) {
    const uint8_t *p = guide.plane[0] + static_cast<size_t>(y0) * guide.stride[0] + x0;
    if (s == 2) return whole_cell_luma<2>(p, guide.stride[0]);
    if (s == 4) return whole_cell_luma<4>(p, guide.stride[0]);
  }
  return bilateral_cell_luma(guide, cx, cy, s);
}

// Stages the block's tables and its tile of (depth, luma) texels whose
// origin is (ox, oy) in the grid, row-major so a warp reads consecutive
// texels of a row. Texels outside the grid stay unset: the clipped windows
// never read them. A thread loads all its texels before it stores any, so
// their loads are in flight together (one store after each load leaves the
// staging waiting on each texel's loads in turn; measured:
// docs/benchmarks.md, Design measurements, "Filter").
template <int kTileW, int kTexels, int kTables, GridIo kIo>
__device__ __forceinline__ void stage_tile(const FrameView &guide, const DepthGrid<const float> &depth_in,
                                           const Cells &cells, int ox, int oy, const float *__restrict__ tables,
                                           Texel *tile, float *s_tables) {
  const int tid = threadIdx.y * kBlockX + threadIdx.x;
  for (int i = tid; i < kTables; i += kThreads) s_tables[i] = tables[i];
  constexpr bool kCells = kIo != kPixelGrid;
  const int w = grid_width<kCells>(depth_in, cells), h = grid_height<kCells>(depth_in, cells);
  constexpr int kPerThread = (kTexels + kThreads - 1) / kThreads;
  Texel t[kPerThread];
  bool in[kPerThread];
#pragma unroll
  for (int k = 0; k < kPerThread; ++k) {
    const int i = tid + k * kThreads;
    const int ty = i / kTileW, tx = i - ty * kTileW;
    const int gx = ox + tx, gy = oy + ty;
    in[k] = i < kTexels && gx >= 0 && gx < w && gy >= 0 && gy < h;
    if (!in[k]) continue;
    if constexpr (kIo == kCellsFullSize)  // shift 0
      t[k] = Texel{depth_in.cells.row(gy * cells.s)[gx * cells.s], kLumaBytes * cell_luma(guide, gx, gy, cells.s)};
    else if constexpr (kIo == kCellsOnGrids)
      t[k] = Texel{depth_in.at(gx * cells.s, gy * cells.s), kLumaBytes * cell_luma(guide, gx, gy, cells.s)};
    else
      t[k] = Texel{depth_in.at(gx, gy), kLumaBytes * load_luma(guide, gx, gy)};
  }
#pragma unroll
  for (int k = 0; k < kPerThread; ++k)
    if (in[k]) tile[tid + k * kThreads] = t[k];
  __syncthreads();
}

// Output v of cell (cx, cy): its s x s pixels inside the image; at s = 2 a
// row's two as one 8-byte store where the address allows. kOnGrids: an
// output grid of the cells' own size (out.shift = log2 s, checked by the
// launcher) takes the value itself.
template <bool kOnGrids>
__device__ __forceinline__ void store_cell(const DepthGrid<float> &out, int s, int cx, int cy, float v) {
  if (kOnGrids && out.shift > 0) {
    out.cells.at(cx, cy) = v;
    return;
  }
  const int x0 = cx * s, y0 = cy * s;
  const int x1 = min(x0 + s, out.width), y1 = min(y0 + s, out.height);
  for (int y = y0; y < y1; ++y) {
    float *r = out.cells.row(y);
    if (s == 2 && x1 == x0 + 2 && (reinterpret_cast<uintptr_t>(r + x0) & 7) == 0) {
      *reinterpret_cast<float2 *>(r + x0) = make_float2(v, v);
      continue;
    }
    for (int x = x0; x < x1; ++x) r[x] = v;
  }
}

// Output v of grid point (x, y): a pixel, or a cell (store_cell).
template <GridIo kIo>
__device__ __forceinline__ void store_output(const DepthGrid<float> &out, const Cells &cells, int x, int y, float v) {
  if constexpr (kIo == kPixelGrid)
    out.cells.row(y)[x] = v;  // shift 0 at step 1 (the launcher checks)
  else
    store_cell<kIo == kCellsOnGrids>(out, cells.s, x, y, v);
}

// Adaptive (BilateralFilterGpu::run with dirty tiles): a block whose
// outputs, cells (cx0, cy0) .. (cx1, cy1) of step s, lie in no dirty tile
// computes the same values as the frame before, so it copies them from the
// kept output (of out's geometry) instead. True when it did.
__device__ __forceinline__ bool kept_block(const TileFlags &dirty, const DepthGrid<const float> &kept,
                                           const DepthGrid<float> &out, int s, int cx0, int cy0, int cx1, int cy1) {
  if (dirty.any_in(PixelRect{cx0 * s, cy0 * s, cx1 * s, cy1 * s})) return false;
  const int sh = out.shift, x0 = (cx0 * s) >> sh, y0 = (cy0 * s) >> sh;
  const int x1 = min(out.cells.width, ((cx1 * s) + (1 << sh) - 1) >> sh);
  const int y1 = min(out.cells.height, ((cy1 * s) + (1 << sh) - 1) >> sh);
  const int tid = threadIdx.y * blockDim.x + threadIdx.x, cols = x1 - x0;
  for (int i = tid; cols > 0 && i < cols * (y1 - y0); i += blockDim.x * blockDim.y) {
    const int y = y0 + i / cols, x = x0 + i % cols;
    out.cells.at(x, y) = kept.cells.at(x, y);
  }
  return true;
}

// Tile row t of the thread's window column holds tap row dy = t - j of its
// output j. One row: each texel is loaded once and serves every output
// whose window contains that row (j in [J0, J1]).
template <int R, int J0, int J1>
__device__ __forceinline__ void accumulate_row(const Texel *row, int t, const float *space,
                                               const unsigned char *const range_c[kRowsPerThread],
                                               const float centre[kRowsPerThread], float sum_w[kRowsPerThread],
                                               float sum_wd[kRowsPerThread]) {
  constexpr int kSide = Geometry<R>::kSide;
#pragma unroll
  for (int dx = 0; dx < kSide; ++dx) {
    const Texel q = row[dx];
#pragma unroll
    for (int j = J0; j <= J1; ++j)
      bilateral_accumulate(space[(t - j) * kSide + dx], range_weight(range_c[j], q.luma4), q.depth, centre[j],
                           sum_w[j], sum_wd[j]);
  }
}

// Rows T .. TEnd-1 one by one, each with the outputs it reaches known at
// compile time (j in [max(0, T-2R), min(K-1, T)]).
template <int R, int T, int TEnd>
__device__ __forceinline__ void unroll_rows(const Texel *row, const float *space,
                                            const unsigned char *const range_c[kRowsPerThread],
                                            const float centre[kRowsPerThread], float sum_w[kRowsPerThread],
                                            float sum_wd[kRowsPerThread]) {
  if constexpr (T < TEnd) {
    constexpr int J0 = T - 2 * R > 0 ? T - 2 * R : 0;
    constexpr int J1 = T < kRowsPerThread - 1 ? T : kRowsPerThread - 1;
    accumulate_row<R, J0, J1>(row + T * Geometry<R>::kTileW, T, space, range_c, centre, sum_w, sum_wd);
    unroll_rows<R, T + 1, TEnd>(row, space, range_c, centre, sum_w, sum_wd);
  }
}

// The thread's kRowsPerThread outputs, none of whose windows is clipped.
// Walking the tile rows upwards, and dx inside each, keeps every output's
// own order (dy outer, dx inner). The first and last kRowsPerThread - 1
// rows reach only some outputs; they are unrolled so that which ones is
// known at compile time and the steady loop in between has no conditions.
template <int R>
__device__ void filter_unclipped(const Texel *tile, const float *range_sym, const float *space,
                                 float out[kRowsPerThread]) {
  using G = Geometry<R>;
  constexpr int K = kRowsPerThread, kLastDy = 2 * R;
  const Texel *row = tile + threadIdx.y * K * G::kTileW + threadIdx.x;  // tap (-R, -R) of output 0
  const unsigned char *range_c[K];
  float centre[K], sum_w[K], sum_wd[K];
#pragma unroll
  for (int j = 0; j < K; ++j) {
    const Texel c = row[(R + j) * G::kTileW + R];
    range_c[j] = range_centred(range_sym, c.luma4);  // index by neighbour luma
    centre[j] = c.depth;
    sum_w[j] = sum_wd[j] = 0.f;
  }
  // Rows 0 .. K-2: outputs 0 .. t (and dy = t - j <= 2R).
  unroll_rows<R, 0, K - 1>(row, space, range_c, centre, sum_w, sum_wd);
  // Rows K-1 .. 2R: every output.
#pragma unroll 1
  for (int t = K - 1; t <= kLastDy; ++t)
    accumulate_row<R, 0, K - 1>(row + t * G::kTileW, t, space, range_c, centre, sum_w, sum_wd);
  // Rows max(2R+1, K-1) .. 2R+K-1: outputs t-2R .. K-1.
  constexpr int kDownStart = kLastDy + 1 > K - 1 ? kLastDy + 1 : K - 1;
  unroll_rows<R, kDownStart, kLastDy + K>(row, space, range_c, centre, sum_w, sum_wd);
#pragma unroll
  for (int j = 0; j < K; ++j) out[j] = bilateral_result(centre[j], sum_w[j], sum_wd[j]);
}

template <int R, GridIo kIo>
__global__ void __launch_bounds__(kThreads) bilateral_kernel(FrameView guide, DepthGrid<const float> depth_in,
                                                            DepthGrid<float> depth_out,
                                                            const float *__restrict__ tables, Cells cells,
                                                            TileFlags dirty, DepthGrid<const float> kept) {
  chained_kernel_start();
  if (kept_block(dirty, kept, depth_out, cells.s, blockIdx.x * kBlockX, blockIdx.y * kOutY, (blockIdx.x + 1) * kBlockX,
                 (blockIdx.y + 1) * kOutY))
    return;
  constexpr bool kCells = kIo != kPixelGrid;
  using G = Geometry<R>;
  extern __shared__ __align__(8) unsigned char smem[];
  Texel *tile = reinterpret_cast<Texel *>(smem);
  float *s_tables = reinterpret_cast<float *>(tile + G::kTexels);
  const float *s_range_sym = s_tables;
  const float *s_space = s_tables + kRangeSym;

  const int w = grid_width<kCells>(depth_in, cells), h = grid_height<kCells>(depth_in, cells);
  const int ox = blockIdx.x * kBlockX - R, oy = blockIdx.y * kOutY - R;  // tile origin in the grid
  stage_tile<G::kTileW, G::kTexels, G::kTables, kIo>(guide, depth_in, cells, ox, oy, tables, tile, s_tables);

  const int x = blockIdx.x * kBlockX + threadIdx.x;
  const int y0 = blockIdx.y * kOutY + threadIdx.y * kRowsPerThread;
  if (x >= w || y0 >= h) return;
  const bool unclipped = ox >= 0 && oy >= 0 && ox + G::kTileW <= w && oy + G::kTileH <= h;  // whole block
  if (unclipped) {
    float out[kRowsPerThread];
    filter_unclipped<R>(tile, s_range_sym, s_space, out);
#pragma unroll
    for (int j = 0; j < kRowsPerThread; ++j) store_output<kIo>(depth_out, cells, x, y0 + j, out[j]);
    return;
  }
  auto at = [=](int qx, int qy) { return tile[(qy - oy) * G::kTileW + (qx - ox)]; };
  auto guide_at = [=](int qx, int qy) { return at(qx, qy).luma(); };
  auto depth_at = [=](int qx, int qy) { return at(qx, qy).depth; };
  for (int y = y0; y < y0 + kRowsPerThread && y < h; ++y)
    store_output<kIo>(depth_out, cells, x, y,
                         bilateral_pixel(x, y, w, h, R, s_space, s_range_sym + kRangeMid, guide_at, depth_at));
}

// Separable mode, both passes in one kernel. The block stages the same
// tile as bilateral_kernel (its 32 x 32 outputs with an apron of R), runs
// the row pass for its 32 columns over every tile row into shared memory
// (mid), then the column pass from mid: the intermediate plane never goes
// through global memory, and each tap reads shared memory or registers. Every
// value is bilateral_pass_pixel()'s (the CPU reference's function, on the
// same tables, taps in its order), so bit-identical; windows that need no
// clipping take the same taps through a loop whose bounds are constants.
template <int R>
struct SeparableGeometry {
  static constexpr int kSide = 2 * R + 1;
  static constexpr int kTables = kRangeSym + kSide * kSide;  // as uploaded: range (symmetric), space
  static constexpr int kTileW = kBlockX + 2 * R;
  static constexpr int kTileH = kOutY + 2 * R;
  static constexpr int kTexels = kTileW * kTileH;
  static constexpr int kMid = kBlockX * kTileH;  // the row pass at the block's columns, every tile row
  // R = 16: 32768 + 8192 + 6400 = 47360 bytes, inside the 48 KiB that need no opt-in.
  static constexpr size_t kSharedBytes = sizeof(Texel) * kTexels + sizeof(float) * (kMid + kTables);
};
static_assert(SeparableGeometry<kMaxBilateralRadius>::kSharedBytes <= 48 * 1024,
              "separable tile too large for default shared memory");

// Taps d = -R..R of one unclipped 1-D window, ascending, as bilateral_pass_pixel.
// luma4(d) / depth(d) read the tap d away from the centre (luma as Texel::luma4).
// space_1d holds the 1-D weights in registers (index d + R).
template <int R, typename LumaFn, typename DepthFn>
__device__ __forceinline__ float pass_unclipped(int centre4, const float (&space_1d)[2 * R + 1], const float *range_sym,
                                                const LumaFn &luma4, const DepthFn &depth) {
  float sum_w = 0.f, sum_wd = 0.f;
  const unsigned char *range_c = range_centred(range_sym, centre4);
  const float centre = depth(0);
#pragma unroll
  for (int d = -R; d <= R; ++d)
    bilateral_accumulate(space_1d[d + R], range_weight(range_c, luma4(d)), depth(d), centre, sum_w, sum_wd);
  return bilateral_result(centre, sum_w, sum_wd);
}

// As many blocks as an SM holds threads for (6 from sm_80 up, 4 on sm_75;
// cuda/launch_bounds.cuh): at most 40 registers a thread. Unbounded, the
// compiler takes more registers and fewer blocks run an SM, which is
// slower, as is a bound of 5 blocks (measured: docs/benchmarks.md, Design
// measurements, "Filter").
template <int R, GridIo kIo>
__global__ void __launch_bounds__(kThreads, P3D_THREADS_PER_SM / kThreads)
    separable_kernel(FrameView guide, DepthGrid<const float> depth_in, DepthGrid<float> depth_out,
                     const float *__restrict__ tables, Cells cells, TileFlags dirty, DepthGrid<const float> kept) {
  chained_kernel_start();
  if (kept_block(dirty, kept, depth_out, cells.s, blockIdx.x * kBlockX, blockIdx.y * kOutY, (blockIdx.x + 1) * kBlockX,
                 (blockIdx.y + 1) * kOutY))
    return;
  constexpr bool kCells = kIo != kPixelGrid;
  using G = SeparableGeometry<R>;
  extern __shared__ __align__(8) unsigned char smem[];
  Texel *tile = reinterpret_cast<Texel *>(smem);
  float *mid = reinterpret_cast<float *>(tile + G::kTexels);
  float *s_tables = mid + G::kMid;
  const float *s_range_sym = s_tables;
  const float *s_space = s_tables + kRangeSym;

  const int w = grid_width<kCells>(depth_in, cells), h = grid_height<kCells>(depth_in, cells);
  const int bx = blockIdx.x * kBlockX, by = blockIdx.y * kOutY;  // the block's first output
  const int ox = bx - R, oy = by - R;                             // tile origin in the grid
  stage_tile<G::kTileW, G::kTexels, G::kTables, kIo>(guide, depth_in, cells, ox, oy, tables, tile, s_tables);
  const int tid = threadIdx.y * kBlockX + threadIdx.x;
  // The 1-D space weights space(d, 0) in registers: the unclipped taps
  // index them by compile-time constants instead of loading them from
  // shared memory.
  float space_1d[G::kSide];
#pragma unroll
  for (int d = 0; d < G::kSide; ++d) space_1d[d] = s_space[R * G::kSide + d];

  auto at = [=](int qx, int qy) { return tile[(qy - oy) * G::kTileW + (qx - ox)]; };
  auto guide_at = [=](int qx, int qy) { return at(qx, qy).luma(); };
  auto depth_at = [=](int qx, int qy) { return at(qx, qy).depth; };
  const float *range = s_range_sym + kRangeMid;  // range[|g|]
  const bool rows_unclipped = ox >= 0 && ox + G::kTileW <= w;   // every row window of the block
  const bool cols_unclipped = oy >= 0 && oy + G::kTileH <= h;   // every column window
  // Row pass: mid(x, y) for the block's columns x and every tile row y in the image.
  for (int i = tid; i < G::kMid; i += kThreads) {
    const int ty = i / kBlockX, tx = i - ty * kBlockX;
    const int gx = bx + tx, gy = oy + ty;
    if (gx >= w || gy < 0 || gy >= h) continue;
    if (rows_unclipped) {
      const Texel *c = tile + ty * G::kTileW + R + tx;
      mid[i] = pass_unclipped<R>(c->luma4, space_1d, s_range_sym, [c](int d) { return c[d].luma4; },
                                 [c](int d) { return c[d].depth; });
    } else {
      mid[i] = bilateral_pass_pixel(gx, gy, 1, 0, w, R, s_space, range, guide_at, depth_at);
    }
  }
  __syncthreads();

  // Column pass: the thread's kRowsPerThread outputs down its column.
  const int x = bx + threadIdx.x;
  if (x >= w) return;
  const int ly0 = threadIdx.y * kRowsPerThread;  // the thread's first output row in the block
  if (cols_unclipped) {
    // Its windows cover kRowsPerThread + 2R tile rows, which it loads once
    // into registers (luma and the row pass's value) for all its outputs,
    // instead of 2R + 1 loads of each per output.
    constexpr int kRun = kRowsPerThread + 2 * R;
    const Texel *c = tile + ly0 * G::kTileW + R + threadIdx.x;  // tap -R of output 0
    const float *m = mid + ly0 * kBlockX + threadIdx.x;
    int luma4[kRun];
    float value[kRun];
#pragma unroll
    for (int t = 0; t < kRun; ++t) {
      luma4[t] = c[t * G::kTileW].luma4;
      value[t] = m[t * kBlockX];
    }
    if constexpr (kCells) {
      float out[kRowsPerThread];  // all first: the loaded run is dead before the cells' stores
#pragma unroll
      for (int j = 0; j < kRowsPerThread; ++j)
        out[j] = pass_unclipped<R>(luma4[j + R], space_1d, s_range_sym, [&](int d) { return luma4[j + R + d]; },
                                   [&](int d) { return value[j + R + d]; });
#pragma unroll
      for (int j = 0; j < kRowsPerThread; ++j)
        store_cell<kIo == kCellsOnGrids>(depth_out, cells.s, x, by + ly0 + j, out[j]);
    } else {
#pragma unroll
      for (int j = 0; j < kRowsPerThread; ++j)
        depth_out.cells.row(by + ly0 + j)[x] =
            pass_unclipped<R>(luma4[j + R], space_1d, s_range_sym, [&](int d) { return luma4[j + R + d]; },
                              [&](int d) { return value[j + R + d]; });
    }
    return;
  }
  auto mid_at = [=](int qx, int qy) { return mid[(qy - oy) * kBlockX + (qx - bx)]; };
  for (int j = 0; j < kRowsPerThread; ++j) {
    const int y = by + ly0 + j;
    if (y >= h) return;
    store_output<kIo>(depth_out, cells, x, y,
                         bilateral_pass_pixel(x, y, 0, 1, h, R, s_space, range, guide_at, mid_at));
  }
}

using KernelFn = void (*)(FrameView, DepthGrid<const float>, DepthGrid<float>, const float *, Cells, TileFlags,
                          DepthGrid<const float>);
struct KernelEntry {
  KernelFn fn;
  size_t shared_bytes;
};

template <GridIo kIo, int... R>
constexpr auto make_kernels(std::integer_sequence<int, R...>) {
  return std::array<KernelEntry, sizeof...(R)>{
      KernelEntry{bilateral_kernel<R, kIo>, Geometry<R>::kSharedBytes}...};
}
template <GridIo kIo, int... R>
constexpr auto make_separable_kernels(std::integer_sequence<int, R...>) {
  return std::array<KernelEntry, sizeof...(R)>{
      KernelEntry{separable_kernel<R, kIo>, SeparableGeometry<R>::kSharedBytes}...};
}

// Every radius at step 1; on a grid of step s >= 2 the radius is
// ceil(r / s) <= ceil(kMaxBilateralRadius / 2).
constexpr int kMaxCellRadius = (kMaxBilateralRadius + 1) / 2;
const auto kKernels = make_kernels<kPixelGrid>(std::make_integer_sequence<int, kMaxBilateralRadius + 1>{});
const auto kSeparableKernels =
    make_separable_kernels<kPixelGrid>(std::make_integer_sequence<int, kMaxBilateralRadius + 1>{});
const auto kCellKernels = make_kernels<kCellsFullSize>(std::make_integer_sequence<int, kMaxCellRadius + 1>{});
const auto kCellSeparableKernels =
    make_separable_kernels<kCellsFullSize>(std::make_integer_sequence<int, kMaxCellRadius + 1>{});
const auto kCellGridKernels = make_kernels<kCellsOnGrids>(std::make_integer_sequence<int, kMaxCellRadius + 1>{});
const auto kCellGridSeparableKernels =
    make_separable_kernels<kCellsOnGrids>(std::make_integer_sequence<int, kMaxCellRadius + 1>{});

CudaStatus invalid(const char *what, int line) { return CudaStatus{cudaErrorInvalidValue, what, __FILE__, line}; }

}  // namespace

CudaStatus BilateralFilterGpu::upload_tables(const BilateralParams &s, cudaStream_t stream) {
  // Sized for the largest radius once, so a parameter change never frees
  // (and thereby synchronises) the buffer a queued kernel still reads.
  P3D_CUDA_TRY_STATUS(tables_.ensure(sizeof(float) * kMaxTableFloats));
  host_tables_.assign(kRangeSym + bilateral_space_table_size(s.radius), 0.f);
  float *range_sym = host_tables_.data();
  // The reference's range table at the centre of the symmetric one, space after it.
  bilateral_tables(s, range_sym + kRangeSym, range_sym + kRangeMid);
  bilateral_mirror_range(range_sym);
  P3D_CUDA_TRY(cudaMemcpyAsync(tables_.get(), host_tables_.data(), sizeof(float) * host_tables_.size(),
                               cudaMemcpyHostToDevice, stream));
  uploaded_ = s;
  return {};
}

CudaStatus BilateralFilterGpu::run(const BilateralParams &params, const FrameView &guide,
                                   ImageView<const float> depth_in, ImageView<float> depth_out, cudaStream_t stream) {
  return run(params, guide, full_grid(depth_in), full_grid(depth_out), stream);
}

CudaStatus BilateralFilterGpu::run(const BilateralParams &params, const FrameView &guide_in,
                                   DepthGrid<const float> depth_in, DepthGrid<float> depth_out, cudaStream_t stream,
                                   const TileFlags &dirty, DepthGrid<const float> kept) {
  if (guide_in.width != depth_in.width || guide_in.height != depth_in.height)
    return invalid("BilateralFilterGpu::run: guide and depth sizes differ", __LINE__);
  if (depth_out.width != depth_in.width || depth_out.height != depth_in.height)
    return invalid("BilateralFilterGpu::run: depth_in and depth_out sizes differ", __LINE__);
  if (depth_in.empty() || depth_out.empty()) return {};
  if (!grid_fits(depth_in) || !grid_fits(depth_out))
    return invalid("BilateralFilterGpu::run: a depth grid's cells do not fit its picture and shift", __LINE__);
  if (static_cast<const void *>(depth_in.cells.data) == static_cast<const void *>(depth_out.cells.data))
    return invalid("BilateralFilterGpu::run: depth_in aliases depth_out", __LINE__);
  if (guide_in.plane[0] == nullptr) return invalid("BilateralFilterGpu::run: guide has no plane 0", __LINE__);
  FrameView guide;  // the guide, or its high bytes (a deep frame)
  P3D_CUDA_TRY_STATUS(high_bytes_.of(guide_in, stream, &guide, true));  // the guide is load_luma() alone
  if (dirty.flags && (kept.width != depth_out.width || kept.height != depth_out.height ||
                      kept.shift != depth_out.shift || kept.cells.width != depth_out.cells.width ||
                      kept.cells.height != depth_out.cells.height))
    return invalid("BilateralFilterGpu::run: the kept output has the output's geometry", __LINE__);

  const BilateralParams sanitised = bilateral_sanitize(params);
  const int step = bilateral_effective_scale(sanitised, depth_in.width, depth_in.height);
  const BilateralParams s = bilateral_coarse_params(sanitised, step);  // what the grid's filter runs
  if (depth_out.shift != 0 && depth_out.shift != bilateral_grid_shift(sanitised, depth_in.width, depth_in.height))
    return invalid("BilateralFilterGpu::run: depth_out's shift is neither 0 nor bilateral_grid_shift()", __LINE__);
  if (s.radius != uploaded_.radius || s.sigma_space != uploaded_.sigma_space ||
      s.sigma_range != uploaded_.sigma_range)
    P3D_CUDA_TRY_STATUS(upload_tables(s, stream));

  const Cells cells{bilateral_cells(depth_in.width, step), bilateral_cells(depth_in.height, step), step};
  const bool separable = s.mode == BilateralMode::Separable;
  if (step > 1 && s.radius > kMaxCellRadius)  // bilateral_coarse_params() rules it out
    return invalid("BilateralFilterGpu::run: grid radius beyond the cell kernels", __LINE__);
  const bool grids = depth_in.shift > 0 || depth_out.shift > 0;
  const KernelEntry &k =
      step == 1 ? (separable ? kSeparableKernels[s.radius] : kKernels[s.radius])
      : grids   ? (separable ? kCellGridSeparableKernels[s.radius] : kCellGridKernels[s.radius])
                : (separable ? kCellSeparableKernels[s.radius] : kCellKernels[s.radius]);
  const dim3 block(kBlockX, kBlockY);
  const dim3 grid((cells.w + kBlockX - 1) / kBlockX, (cells.h + kOutY - 1) / kOutY);
  P3D_CUDA_TRY(launch_chained(k.fn, grid, block, k.shared_bytes, stream, guide, depth_in, depth_out,
                              tables_.as<const float>(), cells, dirty, kept));
  return {};
}

}  // namespace p3d
