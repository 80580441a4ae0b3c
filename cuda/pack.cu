#include "chained_launch.cuh"
#include "pack_gpu.h"

#include <cstdint>

namespace p3d {

namespace {

// Everything a launch needs, by value: no device state shared between
// elements, nothing to upload per frame.
struct PackKernelParams {
  PackParams p;
  AnaglyphMatrices am;
  FrameView in;
  FrameView out;
  StageGate gate;  // closed: the adaptive stage keeps this frame (cuda/change_gpu.h)
};

constexpr int kBlockX = 32, kBlockY = 8;
// Pixels per thread on the vectorised path: four 4-byte pixels make one
// 16-byte store.
constexpr int kVec = 4;

// One instantiation per input arrangement: the common side-by-side input
// runs without the code of the others.
template <StereoInput I>
__global__ void pack_kernel(const PackKernelParams kp) {
  chained_kernel_start();
  if (kp.gate.closed()) return;
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = (gridDim.y - 1 - blockIdx.y) * blockDim.y + threadIdx.y;  // bottom up, as pack_anaglyph_pair_vec
  if (x >= kp.out.width || y >= kp.out.height) return;
  store_rgba(kp.out, x, y, pack_detail::pack_pixel_for<I>(kp.p, kp.am, kp.in, x, y));
}

// kVec pixels per thread. The pixels are laid out in memory order by
// store_rgba itself (into registers), then written with one 16-byte store;
// the ragged end of a row falls back to per-pixel stores. Needs 16-byte
// aligned rows (checked by the launcher).
template <StereoInput I>
__global__ void pack_kernel_vec(const PackKernelParams kp) {
  chained_kernel_start();
  if (kp.gate.closed()) return;
  const int x0 = (blockIdx.x * blockDim.x + threadIdx.x) * kVec;
  const int y = (gridDim.y - 1 - blockIdx.y) * blockDim.y + threadIdx.y;  // bottom up, as pack_anaglyph_pair_vec
  if (x0 >= kp.out.width || y >= kp.out.height) return;
  if (x0 + kVec > kp.out.width) {
    for (int x = x0; x < kp.out.width; ++x)
      store_rgba(kp.out, x, y, pack_detail::pack_pixel_for<I>(kp.p, kp.am, kp.in, x, y));
    return;
  }
  uint4 packed;
  FrameView reg = kp.out;
  reg.plane[0] = reinterpret_cast<uint8_t *>(&packed);
  reg.stride[0] = 4 * kVec;
#pragma unroll
  for (int i = 0; i < kVec; ++i) store_rgba(reg, i, 0, pack_detail::pack_pixel_for<I>(kp.p, kp.am, kp.in, x0 + i, y));
  *reinterpret_cast<uint4 *>(kp.out.plane[0] + static_cast<size_t>(y) * kp.out.stride[0] + 4 * x0) = packed;
}

// The default case, an anaglyph of a side-by-side pair into packed RGB, with
// kVec pixels a thread: each eye's kVec input pixels come in one 16-byte
// load (the launcher checks that the rows are 16-byte aligned and the view
// width is a multiple of kVec, so no thread has a ragged end), then
// anaglyph() per pixel (for the gamma mixes anaglyph_mix_word on the words
// themselves, which is cheaper than anaglyph_gamma()'s Rgba round trip) on
// the words as load_rgba() reads them and store_rgba() writes them. The
// format's byte order and alpha are template parameters (kBgr, kAlpha: one
// kernel a packed format), so a pixel costs no format test: the kernel is
// bound by instructions rather than by memory, and reading the format at
// run time through pixel_at() and store_rgba() on registers costs several
// hundred instructions a pixel (measured: docs/benchmarks.md, Design
// measurements, "Pack").
template <bool kBgr, bool kAlpha>
__device__ Rgba view_word_rgba(uint32_t w) {
  Rgba c = word_rgba(kBgr ? swap_rb_word(w) : w);  // load_rgba()'s channels
  if (!kAlpha) c.a = 255;
  return c;
}
__device__ uint32_t word_at(const uint4 &v, int i) { return i == 0 ? v.x : i == 1 ? v.y : i == 2 ? v.z : v.w; }

// Rows go bottom to top (in every pack kernel): the warp before it wrote
// its last rows last, and those may still be in L2 (the 4K pair is 66 MB,
// Hopper's L2 50 MB), so the pack meets them first; on a pair not just
// written the order makes no difference (measured: docs/benchmarks.md,
// Design measurements, "Pack").
template <bool kBgr, bool kAlpha>
__global__ void pack_anaglyph_pair_vec(const PackKernelParams kp) {
  chained_kernel_start();
  if (kp.gate.closed()) return;
  const int x0 = (blockIdx.x * blockDim.x + threadIdx.x) * kVec;
  const int y = (gridDim.y - 1 - blockIdx.y) * blockDim.y + threadIdx.y;
  if (x0 >= kp.out.width || y >= kp.out.height) return;
  const int w = kp.in.width / 2;
  const uint8_t *row = kp.in.plane[0] + static_cast<size_t>(y) * kp.in.stride[0];
  uint4 eye[2];
  for (int e = 0; e < 2; ++e)
    eye[e] = *reinterpret_cast<const uint4 *>(row + 4 * static_cast<size_t>(x0 + pack_detail::view_slot(kp.p, e) * w));
  uint32_t out[kVec];
#pragma unroll
  for (int i = 0; i < kVec; ++i) {
    uint32_t c;
    if (kp.am.linear_light) {
      c = rgba_word(pack_detail::anaglyph(kp.am, view_word_rgba<kBgr, kAlpha>(word_at(eye[0], i)),
                                          view_word_rgba<kBgr, kAlpha>(word_at(eye[1], i))));
    } else {  // anaglyph()'s gamma mix on the words as load_rgba() reads them
      c = pack_detail::anaglyph_mix_word(kp.am.left_q, kp.am.right_q,
                                         rgba_word(view_word_rgba<kBgr, kAlpha>(word_at(eye[0], i))),
                                         rgba_word(view_word_rgba<kBgr, kAlpha>(word_at(eye[1], i))));
    }
    out[i] = kBgr ? swap_rb_word(c) : c;  // store_rgba()'s bytes
  }
  *reinterpret_cast<uint4 *>(kp.out.plane[0] + static_cast<size_t>(y) * kp.out.stride[0] + 4 * x0) =
      make_uint4(out[0], out[1], out[2], out[3]);
}

// 4:2:0 output: one thread per 2x2 block (its four pixels, one chroma pair).
template <StereoInput I>
__global__ void pack_kernel_yuv(const PackKernelParams kp) {
  chained_kernel_start();
  if (kp.gate.closed()) return;
  const int bx = blockIdx.x * blockDim.x + threadIdx.x;
  const int by = (gridDim.y - 1 - blockIdx.y) * blockDim.y + threadIdx.y;  // bottom up, as pack_anaglyph_pair_vec
  if (2 * bx >= kp.out.width || 2 * by >= kp.out.height) return;
  pack_detail::pack_block_yuv<I>(kp.p, kp.am, kp.in, kp.out, bx, by);
}

// Vectorised (16-byte) stores into packed RGB with 16-byte aligned rows,
// for every layout but SideBySideHalf, whose thread would read 8
// neighbouring input pixels byte by byte, which costs more than the stores
// save (measured: docs/benchmarks.md, Design measurements, "Pack").
bool use_vector_stores(const PackParams &p, const FrameView &out) {
  return p.layout != PackLayout::SideBySideHalf && is_packed_rgb(out.format) && rows_aligned(out, 0, 16);
}

// pack_anaglyph_pair_vec's conditions (besides the side-by-side input).
bool anaglyph_pair_vec(const PackParams &p, const FrameView &in, const FrameView &out) {
  return p.layout == PackLayout::Anaglyph && is_packed_rgb(out.format) && (in.width / 2) % kVec == 0 &&
         rows_aligned(in, 0, 16) && rows_aligned(out, 0, 16);
}

template <StereoInput I>
CudaStatus launch(const PackKernelParams &kp, bool vector_stores, cudaStream_t stream) {
  const dim3 block(kBlockX, kBlockY);
  if (I == StereoInput::SideBySide && anaglyph_pair_vec(kp.p, kp.in, kp.out)) {
    const dim3 grid((kp.out.width / kVec + kBlockX - 1) / kBlockX, (kp.out.height + kBlockY - 1) / kBlockY);
    const bool bgr = is_bgr_order(kp.out.format), alpha = has_alpha(kp.out.format);
    const auto kernel = bgr ? (alpha ? pack_anaglyph_pair_vec<true, true> : pack_anaglyph_pair_vec<true, false>)
                            : (alpha ? pack_anaglyph_pair_vec<false, true> : pack_anaglyph_pair_vec<false, false>);
    P3D_CUDA_TRY(launch_chained(kernel, grid, block, 0, stream, kp));
  } else if (!is_packed_rgb(kp.out.format)) {
    const int bw = (kp.out.width + 1) / 2, bh = (kp.out.height + 1) / 2;
    const dim3 grid((bw + kBlockX - 1) / kBlockX, (bh + kBlockY - 1) / kBlockY);
    P3D_CUDA_TRY(launch_chained(pack_kernel_yuv<I>, grid, block, 0, stream, kp));
  } else if (vector_stores) {
    const int threads_x = (kp.out.width + kVec - 1) / kVec;
    const dim3 grid((threads_x + kBlockX - 1) / kBlockX, (kp.out.height + kBlockY - 1) / kBlockY);
    P3D_CUDA_TRY(launch_chained(pack_kernel_vec<I>, grid, block, 0, stream, kp));
  } else {
    const dim3 grid((kp.out.width + kBlockX - 1) / kBlockX, (kp.out.height + kBlockY - 1) / kBlockY);
    P3D_CUDA_TRY(launch_chained(pack_kernel<I>, grid, block, 0, stream, kp));
  }
  return {};
}

}  // namespace

CudaStatus pack_gpu(const PackParams &params, const FrameView &in, const FrameView &out, cudaStream_t stream,
                    StageGate gate) {
  if (!pack_args_valid(params, in, out) || !kernels_take(in.format) || !kernels_take(out.format))
    return CudaStatus{cudaErrorInvalidValue, "pack_gpu: pack_args_valid(params, in, out), 8-bit formats", __FILE__,
                      __LINE__};
  const PackKernelParams kp{params, anaglyph_matrices(params.glasses, params.method), in, out, gate};
  const bool vec = use_vector_stores(params, out);
  switch (params.input) {
    case StereoInput::SideBySideHalf: return launch<StereoInput::SideBySideHalf>(kp, vec, stream);
    case StereoInput::TopBottom: return launch<StereoInput::TopBottom>(kp, vec, stream);
    case StereoInput::TopBottomHalf: return launch<StereoInput::TopBottomHalf>(kp, vec, stream);
    case StereoInput::RowInterleaved: return launch<StereoInput::RowInterleaved>(kp, vec, stream);
    case StereoInput::ColumnInterleaved: return launch<StereoInput::ColumnInterleaved>(kp, vec, stream);
    case StereoInput::Checkerboard: return launch<StereoInput::Checkerboard>(kp, vec, stream);
    case StereoInput::SideBySide:
    default: return launch<StereoInput::SideBySide>(kp, vec, stream);
  }
}

}  // namespace p3d
