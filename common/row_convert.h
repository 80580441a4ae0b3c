// A row of a frame converted to R'G'B'A words (rgba_word(load_rgba())),
// for CPU loops that convert every pixel of a row once: the warp's source
// row. 8-bit Y'CbCr 4:2:0 rows are converted several pixels at a time
// with OpenCV's universal intrinsics (SSE2 on x86-64, NEON on aarch64),
// in the operation order of chroma_terms() and yuv_rgba(), so the words
// are the same bits as the per-pixel functions give (IEEE single
// precision, no fused multiply-add: common/ is built with
// -ffp-contract=off); other formats take load_rgba_pair_words().
#pragma once

#include <cstdint>

#include <opencv2/core/hal/intrin.hpp>

#include "frame.h"

// Where the CPU loops take OpenCV's vector types: x86-64 (SSE2 and up) and
// aarch64 (NEON), whose float division is IEEE and which keep subnormals,
// as the scalar code does. 32-bit ARM's NEON divides by a reciprocal
// estimate and flushes subnormals, so it takes the scalar loops.
#if CV_SIMD && (defined(__x86_64__) || defined(__aarch64__))
#define P3D_CPU_VECTORS 1
#else
#define P3D_CPU_VECTORS 0
#endif

namespace p3d {

// words[x] = rgba_word(load_rgba(f, x, y, m)) for the x of row y in
// [x0, x1) (widened to whole 4:2:0 pairs: x0 rounded down to even, the
// pair of x1 - 1 whole; x1 at most the width).
void rgba_words_of_row(const FrameView &f, int y, const YuvToRgb &m, uint32_t *words, int x0, int x1);
inline void rgba_words_of_row(const FrameView &f, int y, const YuvToRgb &m, uint32_t *words) {
  rgba_words_of_row(f, y, m, words, 0, f.width);
}

}  // namespace p3d
