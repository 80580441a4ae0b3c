// Device code that several of the warp's kernels share (cuda/warp_rows.cuh,
// warp_smooth.cuh, warp_neighbour.cuh, warp_packed.cu; built by warp_rows.cu,
// warp_smooth.cu, warp_neighbour.cu and kernels_deep.cu): each translation unit
// compiles its own copy (no -rdc).
#pragma once

#include <cstdint>

#include "../common/frame.h"
#include "../common/pack.h"
#include "warp_internal.h"

namespace p3d {
namespace warp_detail {

constexpr unsigned kFullMask = 0xffffffffu;

// BackgroundSmooth's state flags of a pixel (SmoothScratch::state): a hole
// (0: not one, so not summed), has an anchor.
constexpr uint8_t kStateHole = 1, kStateAnchor = 2;

// ---- Pack fused into the warp (WarpRendererGpu::render_packed) -------------
// An anaglyph pixel needs both eyes' colours at one target, which the
// RowsTogether kernel holds at once: where neither eye has a hole there it
// writes the anaglyph pixel itself, and the pair (render_packed's scratch)
// gets only the colours next to holes. The sums kernel then fills the
// holes in the pair, and a last kernel (fused_anaglyph_patch_kernel,
// cuda/warp_packed.cu) mixes the pixels where either eye had a hole, and
// the tail rows, whose blocks render one eye each. The 4K pair (66 MB) is
// then neither written whole nor read back by a pack kernel.

// The anaglyph of the pair's words w0 (left eye) and w1 (rgba_word order)
// as pack's anaglyph() mixes them after load_rgba() reads them back from a
// pair of `pair_alpha` (alpha 255 in the formats without one), as a word.
__device__ inline uint32_t fused_anaglyph_word(const FusedAnaglyph &f, uint32_t w0, uint32_t w1, bool pair_alpha) {
  const uint32_t l = f.swap ? w1 : w0, r = f.swap ? w0 : w1;
  return pack_detail::anaglyph_mix_word(f.left, f.right, pair_alpha ? l : l | 0xff000000u, r);
}

// Pixel (col, y) of a frame with 4-byte aligned rows from a word in
// rgba_word order: store_rgba()'s bytes in one store.
__device__ inline void store_aligned_word(const FrameView &out, int col, int y, uint32_t w) {
  reinterpret_cast<uint32_t *>(out.plane[0] + static_cast<size_t>(y) * out.stride[0])[col] =
      is_bgr_order(out.format) ? swap_rb_word(w) : w;
}

}  // namespace warp_detail
}  // namespace p3d
