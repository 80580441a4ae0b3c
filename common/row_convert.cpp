#include "row_convert.h"

#include <opencv2/core.hpp>

namespace p3d {
namespace {

#if P3D_CPU_VECTORS
// The pixels [0, end) of row y of an 8-bit NV12 or I420 frame, 2L at a
// time (L = float lanes: L chroma pairs); returns end (even), where the
// caller's per-pair loop takes over.
int yuv420_words_vector(const FrameView &f, int y, const YuvToRgb &m, uint32_t *words) {
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
  // to_u8(): clamped to [0, 255], then v + 0.5 truncated.
  auto level = [&](const v_float32 &v) { return v_reinterpret_as_u32(v_trunc(v_min(v_max(v, zero), top) + half)); };
  // The codes widened into aligned ints first: OpenCV's byte-widening
  // loads read 4 bytes as one int, which is undefined at an odd address.
  alignas(64) int u_code[L], v_code[L], luma_code[2 * L];
  int x = 0;
  for (; x + 2 * L <= f.width; x += 2 * L) {
    for (int i = 0; i < L; ++i) {  // load_chroma() of pair x / 2 + i
      const int pair = x / 2 + i;
      u_code[i] = cr_plane ? chroma[pair] : chroma[2 * pair];
      v_code[i] = cr_plane ? cr_plane[pair] : chroma[2 * pair + 1];
    }
    for (int i = 0; i < 2 * L; ++i) luma_code[i] = luma[x + i];
    // chroma_terms(), one lane a pair, then each term twice: a lane a pixel.
    const v_float32 cb = (v_cvt_f32(vx_load(u_code)) - c_offset) * c_scale;
    const v_float32 cr = (v_cvt_f32(vx_load(v_code)) - c_offset) * c_scale;
    v_float32 r_term[2], gu_term[2], gv_term[2], b_term[2];
    v_zip(rv * cr, rv * cr, r_term[0], r_term[1]);
    v_zip(gu * cb, gu * cb, gu_term[0], gu_term[1]);
    v_zip(gv * cr, gv * cr, gv_term[0], gv_term[1]);
    v_zip(bu * cb, bu * cb, b_term[0], b_term[1]);
    for (int h = 0; h < 2; ++h) {  // yuv_rgba() of pixels x + h L ...
      const v_float32 codes = v_cvt_f32(vx_load(luma_code + h * L));
      const v_float32 yn = (codes - y_offset) * y_scale;
      const v_uint32 r = level(yn + r_term[h]), g = level(yn + gu_term[h] + gv_term[h]), b = level(yn + b_term[h]);
      v_store(words + x + h * L, r | (g << 8) | (b << 16) | alpha);
    }
  }
  vx_cleanup();
  return x;
}
#endif

}  // namespace

void rgba_words_of_row(const FrameView &f, int y, const YuvToRgb &m, uint32_t *words) {
  int x = 0;
#if P3D_CPU_VECTORS
  if (f.format == PixelFormat::NV12 || f.format == PixelFormat::I420) x = yuv420_words_vector(f, y, m, words);
#endif
  for (; x < f.width; x += 2) load_rgba_pair_words(f, x, y, m, words + x);
}

}  // namespace p3d
