#include "row_convert.h"

#include <algorithm>

#include <opencv2/core.hpp>

namespace p3d {
namespace {

#if P3D_CPU_VECTORS
// The pixels [x0, end) of row y of an 8-bit NV12 or I420 frame (x0
// even), 4L at a time (L = float lanes: 2L chroma pairs); end <= x1, where
// the caller's per-pair loop takes over. The bytes are widened with
// vector loads of whole lanes (v_load_expand reads 2L bytes as a vector,
// never a misaligned int).
int yuv420_words_vector(const FrameView &f, int y, const YuvToRgb &m, int x0, int x1, uint32_t *words) {
  using namespace cv;
  constexpr int L = v_float32::nlanes;
  const uint8_t *luma = f.plane[0] + static_cast<size_t>(y) * f.stride[0];
  const uint8_t *chroma = f.plane[1] + static_cast<size_t>(y / 2) * f.stride[1];
  const uint8_t *cr_plane = f.format == PixelFormat::I420 ? f.plane[2] + static_cast<size_t>(y / 2) * f.stride[2] : nullptr;
  const v_float32 y_offset = vx_setall_f32(m.y_offset), y_scale = vx_setall_f32(m.y_scale);
  const v_float32 c_offset = vx_setall_f32(m.c_offset), c_scale = vx_setall_f32(m.c_scale);
  const v_float32 rv = vx_setall_f32(m.rv), gu = vx_setall_f32(m.gu), gv = vx_setall_f32(m.gv), bu = vx_setall_f32(m.bu);
  const v_float32 zero = vx_setzero_f32(), top = vx_setall_f32(255.f), half = vx_setall_f32(0.5f);
  const v_uint32 alpha = vx_setall_u32(0xff000000u);
  const v_uint16 low_byte = vx_setall_u16(0xff);
  // to_u8(): clamped to [0, 255], then v + 0.5 truncated.
  auto level = [&](const v_float32 &v) { return v_reinterpret_as_u32(v_trunc(v_min(v_max(v, zero), top) + half)); };
  auto as_float = [](const v_uint32 &v) { return v_cvt_f32(v_reinterpret_as_s32(v)); };
  int x = x0;
  for (; x + 4 * L <= x1; x += 4 * L) {
    // The codes of the 2L pairs x / 2 ... (load_chroma()): NV12 holds them
    // interleaved, a 16-bit lane a pair (Cb in its low byte).
    v_uint16 cb16, cr16;
    if (cr_plane) {
      cb16 = vx_load_expand(chroma + x / 2);
      cr16 = vx_load_expand(cr_plane + x / 2);
    } else {
      const v_uint16 pairs = v_reinterpret_as_u16(vx_load(chroma + x));
      cb16 = pairs & low_byte;
      cr16 = pairs >> 8;
    }
    v_uint32 cb32[2], cr32[2];
    v_expand(cb16, cb32[0], cb32[1]);
    v_expand(cr16, cr32[0], cr32[1]);
    for (int g = 0; g < 2; ++g) {  // pairs g L ..., pixels 2 g L ...
      // chroma_terms(), one lane a pair, then each term twice: a lane a pixel.
      const v_float32 cb = (as_float(cb32[g]) - c_offset) * c_scale;
      const v_float32 cr = (as_float(cr32[g]) - c_offset) * c_scale;
      v_float32 r_term[2], gu_term[2], gv_term[2], b_term[2];
      v_zip(rv * cr, rv * cr, r_term[0], r_term[1]);
      v_zip(gu * cb, gu * cb, gu_term[0], gu_term[1]);
      v_zip(gv * cr, gv * cr, gv_term[0], gv_term[1]);
      v_zip(bu * cb, bu * cb, b_term[0], b_term[1]);
      v_uint32 luma32[2];
      v_expand(vx_load_expand(luma + x + 2 * g * L), luma32[0], luma32[1]);
      for (int h = 0; h < 2; ++h) {  // yuv_rgba() of pixels x + (2 g + h) L ...
        const v_float32 yn = (as_float(luma32[h]) - y_offset) * y_scale;
        const v_uint32 r = level(yn + r_term[h]), gr = level(yn + gu_term[h] + gv_term[h]), b = level(yn + b_term[h]);
        v_store(words + x + (2 * g + h) * L, r | (gr << 8) | (b << 16) | alpha);
      }
    }
  }
  vx_cleanup();
  return x;
}
#endif

}  // namespace

void rgba_words_of_row(const FrameView &f, int y, const YuvToRgb &m, uint32_t *words, int x0, int x1) {
  int x = x0 & ~1;  // whole 4:2:0 pairs
  x1 = std::min(x1, f.width);
#if P3D_CPU_VECTORS
  if (f.format == PixelFormat::NV12 || f.format == PixelFormat::I420) x = yuv420_words_vector(f, y, m, x, x1, words);
#endif
  for (; x < x1; x += 2) load_rgba_pair_words(f, x, y, m, words + x);
}

}  // namespace p3d
