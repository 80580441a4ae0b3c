// Cross-bilateral filter kernel. A block of 32x8 threads computes 32x32
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
#include "bilateral_gpu.h"

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
constexpr int kRangeSym = 2 * kBilateralRangeTableSize - 1;
constexpr int kRangeMid = kBilateralRangeTableSize - 1;

// Depth and luma of one pixel side by side: one 64-bit shared load per tap.
struct alignas(8) Texel {
  float depth;
  int luma;
};

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

// Tile row t of the thread's window column holds tap row dy = t - j of its
// output j. One row: each texel is loaded once and serves every output
// whose window contains that row (j in [J0, J1]).
template <int R, int J0, int J1>
__device__ __forceinline__ void accumulate_row(const Texel *row, int t, const float *space,
                                               const float *const range_c[kRowsPerThread],
                                               float sum_w[kRowsPerThread], float sum_wd[kRowsPerThread]) {
  constexpr int kSide = Geometry<R>::kSide;
#pragma unroll
  for (int dx = 0; dx < kSide; ++dx) {
    const Texel q = row[dx];
#pragma unroll
    for (int j = J0; j <= J1; ++j)
      bilateral_accumulate(space[(t - j) * kSide + dx], range_c[j][q.luma], q.depth, sum_w[j], sum_wd[j]);
  }
}

// Rows T .. TEnd-1 one by one, each with the outputs it reaches known at
// compile time (j in [max(0, T-2R), min(K-1, T)]).
template <int R, int T, int TEnd>
__device__ __forceinline__ void unroll_rows(const Texel *row, const float *space,
                                            const float *const range_c[kRowsPerThread],
                                            float sum_w[kRowsPerThread], float sum_wd[kRowsPerThread]) {
  if constexpr (T < TEnd) {
    constexpr int J0 = T - 2 * R > 0 ? T - 2 * R : 0;
    constexpr int J1 = T < kRowsPerThread - 1 ? T : kRowsPerThread - 1;
    accumulate_row<R, J0, J1>(row + T * Geometry<R>::kTileW, T, space, range_c, sum_w, sum_wd);
    unroll_rows<R, T + 1, TEnd>(row, space, range_c, sum_w, sum_wd);
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
  const float *range_c[K];
  float sum_w[K], sum_wd[K];
#pragma unroll
  for (int j = 0; j < K; ++j) {
    range_c[j] = range_sym + kRangeMid - row[(R + j) * G::kTileW + R].luma;  // index by neighbour luma
    sum_w[j] = sum_wd[j] = 0.f;
  }
  // Rows 0 .. K-2: outputs 0 .. t (and dy = t - j <= 2R).
  unroll_rows<R, 0, K - 1>(row, space, range_c, sum_w, sum_wd);
  // Rows K-1 .. 2R: every output.
#pragma unroll 1
  for (int t = K - 1; t <= kLastDy; ++t)
    accumulate_row<R, 0, K - 1>(row + t * G::kTileW, t, space, range_c, sum_w, sum_wd);
  // Rows max(2R+1, K-1) .. 2R+K-1: outputs t-2R .. K-1.
  constexpr int kDownStart = kLastDy + 1 > K - 1 ? kLastDy + 1 : K - 1;
  unroll_rows<R, kDownStart, kLastDy + K>(row, space, range_c, sum_w, sum_wd);
#pragma unroll
  for (int j = 0; j < K; ++j) out[j] = sum_wd[j] / sum_w[j];
}

template <int R>
__global__ void __launch_bounds__(kThreads) bilateral_kernel(FrameView guide, ImageView<const float> depth_in,
                                                            ImageView<float> depth_out,
                                                            const float *__restrict__ tables) {
  using G = Geometry<R>;
  extern __shared__ __align__(8) unsigned char smem[];
  Texel *tile = reinterpret_cast<Texel *>(smem);
  float *s_tables = reinterpret_cast<float *>(tile + G::kTexels);
  const float *s_range_sym = s_tables;
  const float *s_space = s_tables + kRangeSym;

  const int tid = threadIdx.y * kBlockX + threadIdx.x;
  for (int i = tid; i < G::kTables; i += kThreads) s_tables[i] = tables[i];

  const int w = depth_in.width, h = depth_in.height;
  const int ox = blockIdx.x * kBlockX - R, oy = blockIdx.y * kOutY - R;  // tile origin in the image
  // Row-major over the tile, so a warp reads consecutive pixels of a row.
  // Texels outside the image stay unset: the clipped window never reads them.
  for (int i = tid; i < G::kTexels; i += kThreads) {
    const int ty = i / G::kTileW, tx = i - ty * G::kTileW;
    const int gx = ox + tx, gy = oy + ty;
    if (gx >= 0 && gx < w && gy >= 0 && gy < h) tile[i] = Texel{depth_in.row(gy)[gx], load_luma(guide, gx, gy)};
  }
  __syncthreads();

  const int x = blockIdx.x * kBlockX + threadIdx.x;
  const int y0 = blockIdx.y * kOutY + threadIdx.y * kRowsPerThread;
  if (x >= w || y0 >= h) return;
  const bool unclipped = ox >= 0 && oy >= 0 && ox + G::kTileW <= w && oy + G::kTileH <= h;  // whole block
  if (unclipped) {
    float out[kRowsPerThread];
    filter_unclipped<R>(tile, s_range_sym, s_space, out);
#pragma unroll
    for (int j = 0; j < kRowsPerThread; ++j) depth_out.row(y0 + j)[x] = out[j];
    return;
  }
  auto at = [=](int qx, int qy) { return tile[(qy - oy) * G::kTileW + (qx - ox)]; };
  auto guide_at = [=](int qx, int qy) { return at(qx, qy).luma; };
  auto depth_at = [=](int qx, int qy) { return at(qx, qy).depth; };
  for (int y = y0; y < y0 + kRowsPerThread && y < h; ++y)
    depth_out.row(y)[x] = bilateral_pixel(x, y, w, h, R, s_space, s_range_sym + kRangeMid, guide_at, depth_at);
}

// Separable mode: one 1-D pass (along x when step_x, else along y), a
// thread per pixel, bilateral_pass_pixel() straight from global memory (the
// CPU reference's own function on the same tables: bit-identical).
__global__ void separable_pass_kernel(FrameView guide, ImageView<const float> in, ImageView<float> out,
                                      const float *tables, int radius, int step_x) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= in.width || y >= in.height) return;
  const float *range = tables + kRangeMid;  // range[|g|], the centre of the symmetric table
  const float *space = tables + kRangeSym;
  auto guide_at = [&guide](int qx, int qy) { return load_luma(guide, qx, qy); };
  auto depth_at = [&in](int qx, int qy) { return in.row(qy)[qx]; };
  out.row(y)[x] = bilateral_pass_pixel(x, y, step_x, 1 - step_x, step_x ? in.width : in.height, radius, space, range,
                                       guide_at, depth_at);
}

using KernelFn = void (*)(FrameView, ImageView<const float>, ImageView<float>, const float *);
struct KernelEntry {
  KernelFn fn;
  size_t shared_bytes;
};

template <int... R>
constexpr auto make_kernels(std::integer_sequence<int, R...>) {
  return std::array<KernelEntry, sizeof...(R)>{KernelEntry{bilateral_kernel<R>, Geometry<R>::kSharedBytes}...};
}

const auto kKernels = make_kernels(std::make_integer_sequence<int, kMaxBilateralRadius + 1>{});

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
  for (int g = 1; g <= kRangeMid; ++g) range_sym[kRangeMid - g] = range_sym[kRangeMid + g];
  P3D_CUDA_TRY(cudaMemcpyAsync(tables_.get(), host_tables_.data(), sizeof(float) * host_tables_.size(),
                               cudaMemcpyHostToDevice, stream));
  uploaded_ = s;
  return {};
}

CudaStatus BilateralFilterGpu::run(const BilateralParams &params, const FrameView &guide,
                                   ImageView<const float> depth_in, ImageView<float> depth_out, cudaStream_t stream) {
  if (guide.width != depth_in.width || guide.height != depth_in.height)
    return invalid("BilateralFilterGpu::run: guide and depth sizes differ", __LINE__);
  if (depth_out.width != depth_in.width || depth_out.height != depth_in.height)
    return invalid("BilateralFilterGpu::run: depth_in and depth_out sizes differ", __LINE__);
  if (depth_in.empty() || depth_out.empty()) return {};
  if (static_cast<const void *>(depth_in.data) == static_cast<const void *>(depth_out.data))
    return invalid("BilateralFilterGpu::run: depth_in aliases depth_out", __LINE__);
  if (guide.plane[0] == nullptr) return invalid("BilateralFilterGpu::run: guide has no plane 0", __LINE__);

  const BilateralParams s = bilateral_sanitize(params);
  if (s.radius != uploaded_.radius || s.sigma_space != uploaded_.sigma_space ||
      s.sigma_range != uploaded_.sigma_range)
    P3D_CUDA_TRY_STATUS(upload_tables(s, stream));

  if (s.mode == BilateralMode::Separable) {
    const int w = depth_in.width, h = depth_in.height;
    P3D_CUDA_TRY_STATUS(mid_.ensure_2d(sizeof(float) * static_cast<size_t>(w), static_cast<size_t>(h)));
    const ImageView<float> mid{mid_.as<float>(), w, h, mid_.pitch()};
    const dim3 block(kBlockX, kBlockY), grid((w + kBlockX - 1) / kBlockX, (h + kBlockY - 1) / kBlockY);
    separable_pass_kernel<<<grid, block, 0, stream>>>(guide, depth_in, mid, tables_.as<const float>(), s.radius, 1);
    P3D_CUDA_TRY_LAUNCH(separable_pass_kernel);
    separable_pass_kernel<<<grid, block, 0, stream>>>(guide, as_const(mid), depth_out, tables_.as<const float>(),
                                                      s.radius, 0);
    P3D_CUDA_TRY_LAUNCH(separable_pass_kernel);
    return {};
  }
  const KernelEntry &k = kKernels[s.radius];
  const dim3 block(kBlockX, kBlockY);
  const dim3 grid((depth_in.width + kBlockX - 1) / kBlockX, (depth_in.height + kOutY - 1) / kOutY);
  k.fn<<<grid, block, k.shared_bytes, stream>>>(guide, depth_in, depth_out, tables_.as<const float>());
  P3D_CUDA_TRY_LAUNCH(bilateral_kernel);
  return {};
}

}  // namespace p3d
