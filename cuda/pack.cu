// GPU stereo packing (cuda/pack_gpu.h): the 8-bit pictures' kernels, with
// the vectorised paths, and the dispatch of 16-bit ones to
// cuda/kernels_deep.cu.
#include <cstdint>

#include "pack_gpu.h"
#include "pack_kernels.cuh"

namespace p3d {
namespace pack_detail {
namespace {

// Pixels per thread on the vectorised path: four 4-byte pixels make one
// 16-byte store.
constexpr int kVec = 4;

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
      store_rgba(kp.out, x, y, pack_pixel_for<I>(kp.p, kp.am, kp.in, x, y));
    return;
  }
  uint4 packed;
  FrameView reg = kp.out;
  reg.plane[0] = reinterpret_cast<uint8_t *>(&packed);
  reg.stride[0] = 4 * kVec;
#pragma unroll
  for (int i = 0; i < kVec; ++i) store_rgba(reg, i, 0, pack_pixel_for<I>(kp.p, kp.am, kp.in, x0 + i, y));
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
    eye[e] = *reinterpret_cast<const uint4 *>(row + 4 * static_cast<size_t>(x0 + view_slot(kp.p, e) * w));
  uint32_t out[kVec];
#pragma unroll
  for (int i = 0; i < kVec; ++i) {
    uint32_t c;
    if (kp.am.linear_light) {
      c = rgba_word(anaglyph(kp.am, view_word_rgba<kBgr, kAlpha>(word_at(eye[0], i)),
                                          view_word_rgba<kBgr, kAlpha>(word_at(eye[1], i))));
    } else {  // anaglyph()'s gamma mix on the words as load_rgba() reads them
      c = anaglyph_mix_word(kp.am.left_q, kp.am.right_q,
                                         rgba_word(view_word_rgba<kBgr, kAlpha>(word_at(eye[0], i))),
                                         rgba_word(view_word_rgba<kBgr, kAlpha>(word_at(eye[1], i))));
    }
    out[i] = kBgr ? swap_rb_word(c) : c;  // store_rgba()'s bytes
  }
  *reinterpret_cast<uint4 *>(kp.out.plane[0] + static_cast<size_t>(y) * kp.out.stride[0] + 4 * x0) =
      make_uint4(out[0], out[1], out[2], out[3]);
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
  } else if (vector_stores) {
    const int threads_x = (kp.out.width + kVec - 1) / kVec;
    const dim3 grid((threads_x + kBlockX - 1) / kBlockX, (kp.out.height + kBlockY - 1) / kBlockY);
    P3D_CUDA_TRY(launch_chained(pack_kernel_vec<I>, grid, block, 0, stream, kp));
  } else {
    return launch_plain<I, Rgba>(kp, stream);
  }
  return {};
}

}  // namespace
}  // namespace pack_detail

CudaStatus pack_gpu(const PackParams &params, const FrameView &in, const FrameView &out, cudaStream_t stream,
                    StageGate gate) {
  using namespace pack_detail;
  if (!pack_args_valid(params, in, out))
    return CudaStatus{cudaErrorInvalidValue, "pack_gpu: pack_args_valid(params, in, out)", __FILE__, __LINE__};
  const PackKernelParams kp{params, anaglyph_matrices(params.glasses, params.method), in, out, gate};
  if (is_deep(in.format)) return launch_pack_deep(kp, stream);
  const bool vec = use_vector_stores(params, out);
  return with_input(params.input, [&](auto input) { return launch<decltype(input)::value>(kp, vec, stream); });
}

}  // namespace p3d
