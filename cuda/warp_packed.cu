// WarpRendererGpu::render_packed (cuda/warp_gpu.h): the pair rendered and
// packed in one, and the kernel that finishes the anaglyph fused into the
// row kernel (the fused pack: cuda/warp_device.cuh says how the work is
// shared between the row kernel, the sums kernel and this one).
#include "chained_launch.cuh"
#include "pack_gpu.h"
#include "warp_device.cuh"
#include "warp_gpu.h"
#include "warp_internal.h"

namespace p3d {
namespace warp_detail {
namespace {

// The fused anaglyph's pixels that the row kernel left in the pair (pair:
// render_packed's scratch, 2W x H, both eyes' colours final): the holes of
// the listed tiles, either eye's (the sums kernel has filled them, and the
// other eye's colour is in the pair, written by the row kernel or filled
// too), then every pixel of the rows from tail_y0 on, whose blocks render
// one eye each. A pixel that both eyes' tiles (or a tile and its tail row)
// hold is written twice with the same bytes.
// Its time is load latency (the tile count, the list, the states, the
// pair): the work is kPatchPerThread pixels of one row an item (a quarter
// of a tile's row, or of a tail row), every item of the frame shared out
// over one wave of resident threads, each issuing the loads of all its
// pixels before it uses any, which beats a block a listed tile plus a
// block a tail row, and two waves of blocks a tile or a quarter of a tail
// row (measured: docs/benchmarks.md, Design measurements, "Fused pack").
__device__ uint32_t pair_word(const FrameView &pair, int col, int y) {
  const uint32_t w = reinterpret_cast<const uint32_t *>(pair.plane[0] + static_cast<size_t>(y) * pair.stride[0])[col];
  return is_bgr_order(pair.format) ? swap_rb_word(w) : w;  // store_rgba()'s bytes back in rgba_word order
}

__global__ void fused_anaglyph_patch_kernel(FrameView pair, FusedAnaglyph f, SmoothScratch sc, int tail_y0,
                                            StageGate gate) {
  chained_kernel_start();
  if (gate.closed()) return;
  const int W = pair.width / 2, H = pair.height, chunks = row_chunks(W);
  constexpr int kItemsARow = kSmoothTileW / kPatchPerThread;
  // 32-bit counts (a 64-bit division costs more than the rest of an item):
  // at most 2 x 256 x 8192 tile rows of 8 items (all listed at 8K), and
  // 8192 rows of 2048.
  const unsigned per_tile = static_cast<unsigned>(sc.tile_rows) * kItemsARow;
  const unsigned tile_items = *sc.tile_count * per_tile;
  const unsigned tail_row_items = static_cast<unsigned>(W + kPatchPerThread - 1) / kPatchPerThread;
  const unsigned items = tile_items + static_cast<unsigned>(H - tail_y0) * tail_row_items;
  const bool pair_alpha = has_alpha(pair.format);
  for (unsigned item = blockIdx.x * blockDim.x + threadIdx.x; item < items; item += gridDim.x * blockDim.x) {
    int x0, y;
    bool mix[kPatchPerThread];
    if (item < tile_items) {
      const int k = static_cast<int>(item % per_tile);
      const unsigned t = sc.tile_list[item / per_tile];
      const int tx = static_cast<int>(t % sc.tiles_x), rest = static_cast<int>(t / sc.tiles_x);
      const int ty = rest % sc.tiles_y, eye = rest / sc.tiles_y;
      y = ty * sc.tile_rows + k / kItemsARow;
      x0 = tx * kSmoothTileW + (k % kItemsARow) * kPatchPerThread;
      // The row kernel writes states only in chunks with holes; the others
      // hold a past frame's (initialised) bytes, loaded with the flag and
      // dropped.
      const bool in_rows = y < H;
      const size_t eye_row = static_cast<size_t>(eye) * H + (in_rows ? y : 0);  // of the eyes' planes' rows
      const bool flag = in_rows && sc.chunk_holes[eye_row * chunks + tx];
      uint8_t state[kPatchPerThread];
#pragma unroll
      for (int i = 0; i < kPatchPerThread; ++i) state[i] = x0 + i < W ? sc.state[eye_row * W + x0 + i] : 0;
#pragma unroll
      for (int i = 0; i < kPatchPerThread; ++i) mix[i] = flag && (state[i] & kStateHole);
    } else {
      const unsigned k = item - tile_items;
      y = tail_y0 + static_cast<int>(k / tail_row_items);
      x0 = static_cast<int>(k % tail_row_items) * kPatchPerThread;
#pragma unroll
      for (int i = 0; i < kPatchPerThread; ++i) mix[i] = x0 + i < W;
    }
    uint32_t w[kPatchPerThread][2];
#pragma unroll
    for (int i = 0; i < kPatchPerThread; ++i)
      if (mix[i]) {
        w[i][0] = pair_word(pair, x0 + i, y);
        w[i][1] = pair_word(pair, W + x0 + i, y);
      }
#pragma unroll
    for (int i = 0; i < kPatchPerThread; ++i)
      if (mix[i]) store_aligned_word(f.out, x0 + i, y, fused_anaglyph_word(f, w[i][0], w[i][1], pair_alpha));
  }
}

}  // namespace

CudaStatus launch_fused_patch(const FrameView &pair, const FusedAnaglyph &f, const SmoothScratch &sc,
                              const SmoothPlan &plan, int tail_y0, cudaStream_t stream, int *resident_blocks,
                              StageGate gate) {
  if (*resident_blocks < 0) {
    int dev = 0, sms = 0, threads = 0;
    P3D_CUDA_TRY(cudaGetDevice(&dev));
    P3D_CUDA_TRY(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev));
    P3D_CUDA_TRY(cudaDeviceGetAttribute(&threads, cudaDevAttrMaxThreadsPerMultiProcessor, dev));
    *resident_blocks = patch_resident_blocks(sms, threads);
  }
  const int W = pair.width / 2, H = pair.height;
  const unsigned blocks = patch_blocks(plan, W, H, tail_y0, *resident_blocks);
  P3D_CUDA_TRY(launch_chained(fused_anaglyph_patch_kernel, blocks, kPatchThreads, 0, stream, pair, f, sc,
                              min(tail_y0, H), gate));
  return {};
}

}  // namespace warp_detail

using namespace warp_detail;

CudaStatus WarpRendererGpu::render_packed(const WarpParams &params, const PackParams &pack, const FrameView &src,
                                          const YuvToRgb &m, DepthGrid<const float> depth, const FrameView &out,
                                          cudaStream_t stream, bool *fused_out, StageGate gate) {
  if (fused_out) *fused_out = false;
  PackParams pp = pack;
  pp.input = StereoInput::SideBySide;
  pp.input_right_first = false;
  // The pair in the output's packed format (pack's input and output share
  // one), or RGBA (RGBA64 for 16-bit samples) for a 4:2:0 output.
  const PixelFormat pair_format = is_packed_rgb(out.format) ? out.format
                                  : is_deep(out.format)     ? PixelFormat::RGBA64
                                                            : PixelFormat::RGBA;
  // The rows of the gate are rendered into the pair kept here; an output
  // that is the pair, or written by the fused pack, keeps no rows.
  if (pack_is_identity(pp) && out.format == pair_format)
    return render_pair(params, src, m, depth, out, nullptr, stream, nullptr, nullptr, gate.every_row());
  if (src.width <= 0 || src.height <= 0 || src.width > kMaxFrameSide || src.height > kMaxFrameSide)
    return invalid_frames();
  const int W = src.width, H = src.height;
  const int pair_stride = 2 * W * packed_pixel_bytes(pair_format);
  const size_t had_pair = pair_.size();
  P3D_CUDA_TRY_STATUS(pair_.ensure(static_cast<size_t>(pair_stride) * H));
  if (pair_.size() != had_pair) gate = gate.every_row();  // a new pair holds no rows
  FrameView pair{};
  pair.format = pair_format;
  pair.width = 2 * W;
  pair.height = H;
  pair.plane[0] = pair_.as<uint8_t>();
  pair.stride[0] = pair_stride;
  if (!pack_args_valid(pp, pair, out))
    return CudaStatus{cudaErrorInvalidValue, "render_packed: pack_args_valid(pack, pair, out)", __FILE__, __LINE__};
  // The gamma mixes of 8-bit pictures fuse (dubois-linear mixes in linear
  // light, in float; the fused kernels move 32-bit pixels).
  FusedAnaglyph fused{};
  const bool fusable = !is_deep(out.format) && pp.layout == PackLayout::Anaglyph &&
                       pp.method != AnaglyphMethod::DuboisLinear &&
                       out.format == pair_format && rows_aligned(out, 0, 4);
  if (fusable) {
    const AnaglyphMatrices am = anaglyph_matrices(pp.glasses, pp.method);
    fused.out = out;
    for (int k = 0; k < 9; ++k) {
      fused.left[k] = am.left_q[k];
      fused.right[k] = am.right_q[k];
    }
    fused.swap = pp.swap_eyes;
  }
  if (fusable) gate = gate.every_row();
  bool used = false;
  P3D_CUDA_TRY_STATUS(
      render_pair(params, src, m, depth, pair, fusable ? &fused : nullptr, stream, nullptr, &used, gate));
  if (fused_out) *fused_out = used;
  if (used) return {};
  return pack_gpu(pp, pair, out, stream, gate);
}

}  // namespace p3d
