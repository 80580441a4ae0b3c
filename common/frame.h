// Pixel formats the plugin accepts, a format-agnostic view of one frame, and
// the per-pixel colour conversion shared by the CPU reference and the kernels.
#pragma once

#include "p3d_defs.h"

namespace p3d {

// The formats every element accepts. Packed RGB formats are 4 bytes a pixel
// in memory order given by the name (RGBx: R,G,B,unused). NV12/I420 are
// 4:2:0 with chroma sited at the top-left of each 2x2 block (nearest chroma
// is used; no interpolation), 8 bits.
enum class PixelFormat : int { NV12 = 0, I420, RGBA, BGRA, RGBx, BGRx };

P3D_HD bool is_packed_rgb(PixelFormat f) { return f != PixelFormat::NV12 && f != PixelFormat::I420; }
// Packed RGB formats whose bytes run B, G, R: their r and b trade places.
P3D_HD bool is_bgr_order(PixelFormat f) { return f == PixelFormat::BGRA || f == PixelFormat::BGRx; }
// Packed RGB formats whose fourth byte is alpha (RGBx/BGRx: padding, read as 255).
P3D_HD bool has_alpha(PixelFormat f) { return f == PixelFormat::RGBA || f == PixelFormat::BGRA; }

// The largest source frame side the stages accept (8K DCI, 8192): the GPU
// warp keeps a source row in shared memory, which bounds the width on every
// supported GPU. The stereo frames after the warp may be twice as large.
constexpr int kMaxFrameSide = 8192;

// One frame, host or device memory. Plane pointers and strides come from the
// mapped GstVideoFrame (never width*bpp). Unused planes are null.
struct FrameView {
  PixelFormat format = PixelFormat::RGBA;
  int width = 0;
  int height = 0;
  uint8_t *plane[3] = {nullptr, nullptr, nullptr};
  int stride[3] = {0, 0, 0};
};

// The part of a frame inside r (r within the frame; for 4:2:0 formats
// x0 and y0 even, so that the part starts on a chroma sample).
inline FrameView sub_frame(FrameView f, PixelRect r) {
  if (is_packed_rgb(f.format)) {
    f.plane[0] += static_cast<size_t>(r.y0) * f.stride[0] + 4 * r.x0;
  } else {
    f.plane[0] += static_cast<size_t>(r.y0) * f.stride[0] + r.x0;
    const size_t chroma_row = static_cast<size_t>(r.y0 / 2);
    if (f.format == PixelFormat::NV12) {
      f.plane[1] += chroma_row * f.stride[1] + r.x0;  // x0/2 pairs of 2 bytes
    } else {
      f.plane[1] += chroma_row * f.stride[1] + r.x0 / 2;
      f.plane[2] += chroma_row * f.stride[2] + r.x0 / 2;
    }
  }
  f.width = r.width();
  f.height = r.height();
  return f;
}

// Whether every row of plane `plane` starts `bytes`-aligned (its start and
// its stride are multiples of it): the host-side check the kernels' word
// and vector paths take once per launch.
inline bool rows_aligned(const FrameView &f, int plane, int bytes) {
  return reinterpret_cast<uintptr_t>(f.plane[plane]) % bytes == 0 && f.stride[plane] % bytes == 0;
}

// 4-byte aligned, so that a whole pixel in shared memory or a host array
// can move as one 32-bit word. Kernels that move whole words or 16-byte
// vectors through global frame rows check the rows' alignment once per
// launch (cuda/warp.cu, cuda/pack.cu) and keep these byte accesses for the
// rest; a per-pixel alignment check measured slower than bytes.
struct alignas(4) Rgba {
  uint8_t r, g, b, a;
};

// Y'CbCr -> R'G'B' for 8-bit samples. Built from Kr/Kb and the range by
// yuv_to_rgb_params() (colour.cpp); the gst layer takes Kr/Kb from the
// caps' colorimetry.
//   Yn = (Y - y_offset) * y_scale,  Cb = (U - 128) * c_scale, Cr = (V - 128) * c_scale
//   R = Yn + rv*Cr,  G = Yn + gu*Cb + gv*Cr,  B = Yn + bu*Cb      (all in 0..255 units)
struct YuvToRgb {
  float y_offset = 16.f, y_scale = 255.f / 219.f, c_scale = 255.f / 224.f;
  float rv = 1.402f, gu = -0.344136f, gv = -0.714136f, bu = 1.772f;
};

YuvToRgb yuv_to_rgb_params(double kr, double kb, bool full_range);
inline bool operator==(const YuvToRgb &a, const YuvToRgb &b) {
  return a.y_offset == b.y_offset && a.y_scale == b.y_scale && a.c_scale == b.c_scale && a.rv == b.rv &&
         a.gu == b.gu && a.gv == b.gv && a.bu == b.bu;
}
inline bool operator!=(const YuvToRgb &a, const YuvToRgb &b) { return !(a == b); }

// R'G'B' -> Y'CbCr for 8-bit output (the inverse of YuvToRgb), built by
// rgb_to_yuv_params() (colour.cpp) from the output caps' colorimetry:
//   Yl = kr R + kg G + kb B,  Cb = (B - Yl) * cb,  Cr = (R - Yl) * cr     (0..255 units)
//   Y = to_u8(y_offset + Yl * y_scale),  U = to_u8(128 + Cb * c_scale),  V likewise
// Defaults: BT.709, limited range (what GStreamer picks for HD YUV).
struct RgbToYuv {
  float kr = 0.2126f, kg = 0.7152f, kb = 0.0722f;
  float cb = 0.538909f, cr = 0.635075f;  // 1 / (2 (1 - kb)), 1 / (2 (1 - kr))
  float y_offset = 16.f, y_scale = 219.f / 255.f, c_scale = 224.f / 255.f;
};

RgbToYuv rgb_to_yuv_params(double kr, double kb, bool full_range);
inline bool operator==(const RgbToYuv &a, const RgbToYuv &b) {
  return a.kr == b.kr && a.kg == b.kg && a.kb == b.kb && a.cb == b.cb && a.cr == b.cr && a.y_offset == b.y_offset &&
         a.y_scale == b.y_scale && a.c_scale == b.c_scale;
}

// Luma weights of the guide image and of depth read from grey pictures
// (BT.601; only used on R'G'B' values, so it is colorimetry independent).
P3D_HD float rgb_luma(float r, float g, float b) { return 0.299f * r + 0.587f * g + 0.114f * b; }

// The Cb/Cr sample (u, v) of pixel (x, y) of a 4:2:0 frame (NV12 or I420):
// the pixels 2k and 2k + 1 of rows 2j and 2j + 1 share it.
P3D_HD void load_chroma(const FrameView &f, int x, int y, int *u, int *v) {
  if (f.format == PixelFormat::NV12) {
    const uint8_t *c = f.plane[1] + static_cast<size_t>(y / 2) * f.stride[1] + 2 * (x / 2);
    *u = c[0];
    *v = c[1];
  } else {
    *u = f.plane[1][static_cast<size_t>(y / 2) * f.stride[1] + x / 2];
    *v = f.plane[2][static_cast<size_t>(y / 2) * f.stride[2] + x / 2];
  }
}

// The chroma products of one Cb/Cr sample (YuvToRgb's rv Cr, gu Cb, gv Cr,
// bu Cb), which the pixels sharing the sample share: yuv_rgba() adds them
// to each pixel's Yn in the order load_rgba() always did, so a pixel pair
// converted with one ChromaTerms has the bytes of two load_rgba() calls.
struct ChromaTerms {
  float r, gu, gv, b;
};
P3D_HD ChromaTerms chroma_terms(int u, int v, const YuvToRgb &m) {
  const float cb = (static_cast<float>(u) - 128.f) * m.c_scale;
  const float cr = (static_cast<float>(v) - 128.f) * m.c_scale;
  return ChromaTerms{m.rv * cr, m.gu * cb, m.gv * cr, m.bu * cb};
}
P3D_HD Rgba yuv_rgba(int luma, const ChromaTerms &c, const YuvToRgb &m) {
  const float yn = (static_cast<float>(luma) - m.y_offset) * m.y_scale;
  return Rgba{to_u8(yn + c.r), to_u8(yn + c.gu + c.gv), to_u8(yn + c.b), 255};
}

// Read pixel (x, y) of any supported format as R'G'B'A (alpha 255 where the
// format has none).
P3D_HD Rgba load_rgba(const FrameView &f, int x, int y, const YuvToRgb &m) {
  if (is_packed_rgb(f.format)) {
    const uint8_t *p = f.plane[0] + static_cast<size_t>(y) * f.stride[0] + 4 * x;
    const bool bgr = is_bgr_order(f.format), alpha = has_alpha(f.format);
    return Rgba{bgr ? p[2] : p[0], p[1], bgr ? p[0] : p[2], alpha ? p[3] : static_cast<uint8_t>(255)};
  }
  int u, v;
  load_chroma(f, x, y, &u, &v);
  return yuv_rgba(f.plane[0][static_cast<size_t>(y) * f.stride[0] + x], chroma_terms(u, v, m), m);
}

// Rgba as a little-endian word r | g << 8 | b << 16 | a << 24 (Rgba's
// memory order) and back: rows of converted pixels are kept as words so
// that a pixel moves, and two channels are multiplied, in one operation.
P3D_HD uint32_t rgba_word(Rgba c) {
  return static_cast<uint32_t>(c.r) | static_cast<uint32_t>(c.g) << 8 | static_cast<uint32_t>(c.b) << 16 |
         static_cast<uint32_t>(c.a) << 24;
}
P3D_HD Rgba word_rgba(uint32_t w) {
  return Rgba{static_cast<uint8_t>(w), static_cast<uint8_t>(w >> 8), static_cast<uint8_t>(w >> 16),
              static_cast<uint8_t>(w >> 24)};
}

// A word with its first and third bytes traded: rgba_word() of a pixel as
// the BGR orders store it (store_rgba()'s byte order, in one word). The
// device has a byte-permute instruction for it.
P3D_HD uint32_t swap_rb_word(uint32_t w) {
#ifdef __CUDA_ARCH__
  return __byte_perm(w, 0u, 0x3012);
#else
  return (w & 0xff00ff00u) | (w >> 16 & 0xffu) | (w & 0xffu) << 16;
#endif
}

// rgba_word(load_rgba()) of pixels x and x + 1 of row y into w[0] and w[1]
// (x even; x + 1 == width: w[0] only). A 4:2:0 pair shares its chroma
// sample, read and multiplied once: the warp converts each source row this
// way (common/warp.cpp, cuda/warp_rows.cu).
P3D_HD void load_rgba_pair_words(const FrameView &f, int x, int y, const YuvToRgb &m, uint32_t *w) {
  const bool second = x + 1 < f.width;
  if (is_packed_rgb(f.format)) {
    w[0] = rgba_word(load_rgba(f, x, y, m));
    if (second) w[1] = rgba_word(load_rgba(f, x + 1, y, m));
    return;
  }
  int u, v;
  load_chroma(f, x, y, &u, &v);
  const ChromaTerms c = chroma_terms(u, v, m);
  const uint8_t *luma = f.plane[0] + static_cast<size_t>(y) * f.stride[0] + x;
  w[0] = rgba_word(yuv_rgba(luma[0], c, m));
  if (second) w[1] = rgba_word(yuv_rgba(luma[1], c, m));
}

// Write an R'G'B'A pixel into a packed RGB frame (other formats: no-op).
P3D_HD void store_rgba(const FrameView &f, int x, int y, Rgba c) {
  if (!is_packed_rgb(f.format)) return;
  uint8_t *p = f.plane[0] + static_cast<size_t>(y) * f.stride[0] + 4 * x;
  const bool bgr = is_bgr_order(f.format);
  p[0] = bgr ? c.b : c.r;
  p[1] = c.g;
  p[2] = bgr ? c.r : c.b;
  p[3] = c.a;  // RGBx/BGRx: the padding byte gets c.a (255 for any converted pixel): defined, never garbage
}

// Writes the 2x2 block of a 4:2:0 frame (NV12 or I420) whose top-left
// pixel is (2 bx, 2 by): px[] are its pixels in row order (top-left,
// top-right, bottom-left, bottom-right); those outside the frame (the last
// column or row of an odd size) are left out. Each pixel gets its own Y'; the
// block's Cb/Cr are those of the mean R'G'B' of its pixels (chroma centred
// on the block, as a 2x2 box filter puts it).
P3D_HD void store_yuv420_block(const FrameView &f, int bx, int by, const Rgba px[4], const RgbToYuv &m) {
  int n = 0, sr = 0, sg = 0, sb = 0;
  for (int k = 0; k < 4; ++k) {
    const int x = 2 * bx + (k & 1), y = 2 * by + (k >> 1);
    if (x >= f.width || y >= f.height) continue;
    const float r = px[k].r, g = px[k].g, b = px[k].b;
    const float yl = m.kr * r + m.kg * g + m.kb * b;
    f.plane[0][static_cast<size_t>(y) * f.stride[0] + x] = to_u8(m.y_offset + yl * m.y_scale);
    sr += px[k].r;
    sg += px[k].g;
    sb += px[k].b;
    ++n;
  }
  if (n == 0) return;
  const float fn = static_cast<float>(n);
  const float r = static_cast<float>(sr) / fn, g = static_cast<float>(sg) / fn, b = static_cast<float>(sb) / fn;
  const float yl = m.kr * r + m.kg * g + m.kb * b;
  const uint8_t u = to_u8(128.f + (b - yl) * m.cb * m.c_scale);
  const uint8_t v = to_u8(128.f + (r - yl) * m.cr * m.c_scale);
  if (f.format == PixelFormat::NV12) {
    uint8_t *c = f.plane[1] + static_cast<size_t>(by) * f.stride[1] + 2 * bx;
    c[0] = u;
    c[1] = v;
  } else {
    f.plane[1][static_cast<size_t>(by) * f.stride[1] + bx] = u;
    f.plane[2][static_cast<size_t>(by) * f.stride[2] + bx] = v;
  }
}

// The 8-bit guide value of pixel (x, y): the Y' plane for YUV formats, the
// BT.601 luma of R'G'B' otherwise.
P3D_HD uint8_t load_luma(const FrameView &f, int x, int y) {
  if (!is_packed_rgb(f.format)) return f.plane[0][static_cast<size_t>(y) * f.stride[0] + x];
  const YuvToRgb unused;
  const Rgba c = load_rgba(f, x, y, unused);
  return to_u8(rgb_luma(c.r, c.g, c.b));
}

// Three 8-bit colour channels of pixel (x, y) in the frame's own space
// (Y'UV for YUV formats, R'G'B' otherwise): what region grouping compares.
P3D_HD void load_native3(const FrameView &f, int x, int y, int out[3]) {
  if (is_packed_rgb(f.format)) {
    const YuvToRgb unused;
    const Rgba c = load_rgba(f, x, y, unused);
    out[0] = c.r;
    out[1] = c.g;
    out[2] = c.b;
    return;
  }
  out[0] = f.plane[0][static_cast<size_t>(y) * f.stride[0] + x];
  load_chroma(f, x, y, &out[1], &out[2]);
}

// Helpers for host code: number of planes and the size of plane i.
int frame_plane_count(PixelFormat f);
void frame_plane_size(PixelFormat f, int width, int height, int plane, int *bytes_per_row, int *rows);

}  // namespace p3d
