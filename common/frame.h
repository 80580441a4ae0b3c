// Pixel formats the plugin accepts, a format-agnostic view of one frame, and
// the per-pixel colour conversion shared by the CPU reference and the kernels.
#pragma once

#include "p3d_defs.h"

namespace p3d {

// The formats the stages accept (CUDA memory: all but RGBA64). The 8-bit
// packed RGB formats are 4 bytes a pixel in memory order given by the name
// (RGBx: R,G,B,unused). NV12/I420 are
// 4:2:0 with chroma sited at the top-left of each 2x2 block (nearest chroma
// is used; no interpolation), 8 bits. The deep formats hold 16-bit
// little-endian samples: P010 (GStreamer's P010_10LE) is NV12's layout with
// a 10-bit code in each sample's high bits, I420_10 (I420_10LE) I420's
// layout with the code in the low bits, RGBA64 (RGBA64_LE) R, G, B, A of
// 16 bits each.
enum class PixelFormat : int { NV12 = 0, I420, RGBA, BGRA, RGBx, BGRx, P010, I420_10, RGBA64 };

// Formats of 16-bit samples. Kernels are built for one depth: a
// translation unit of 8-bit kernels sees no format as deep in device code,
// so the deep branches of the shared code below compile away and those
// kernels carry the 8-bit code alone; the unit of deep kernels
// (cuda/kernels_deep.cu) defines P3D_DEVICE_DEEP before any include, so its
// device code reads every format. Host code always sees every format.
P3D_HD bool is_deep(PixelFormat f) {
#if defined(__CUDA_ARCH__) && !defined(P3D_DEVICE_DEEP)
  (void)f;
  return false;
#else
  return f == PixelFormat::P010 || f == PixelFormat::I420_10 || f == PixelFormat::RGBA64;
#endif
}
// The 16-bit packed RGB format.
P3D_HD bool is_rgba64(PixelFormat f) { return is_deep(f) && f == PixelFormat::RGBA64; }
// 4:2:0 Y'CbCr formats; every other format is packed RGB.
P3D_HD bool is_yuv420(PixelFormat f) {
  return f == PixelFormat::NV12 || f == PixelFormat::I420 || (is_deep(f) && !is_rgba64(f));
}
P3D_HD bool is_packed_rgb(PixelFormat f) { return !is_yuv420(f); }
// 4:2:0 formats whose second plane interleaves Cb and Cr (NV12, P010).
P3D_HD bool is_semi_planar(PixelFormat f) { return f == PixelFormat::NV12 || (is_deep(f) && f == PixelFormat::P010); }
// Bytes of one sample (one channel of a pixel, one Y', Cb or Cr).
P3D_HD int sample_bytes(PixelFormat f) { return is_deep(f) ? 2 : 1; }
// Bytes of one packed RGB pixel.
P3D_HD int packed_pixel_bytes(PixelFormat f) { return is_rgba64(f) ? 8 : 4; }
// Packed RGB formats whose bytes run B, G, R: their r and b trade places.
P3D_HD bool is_bgr_order(PixelFormat f) { return f == PixelFormat::BGRA || f == PixelFormat::BGRx; }
// Packed RGB formats whose fourth sample is alpha (RGBx/BGRx: padding, read as 255).
P3D_HD bool has_alpha(PixelFormat f) {
  return f == PixelFormat::RGBA || f == PixelFormat::BGRA || is_rgba64(f);
}

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
  const size_t sb = static_cast<size_t>(sample_bytes(f.format));
  if (is_packed_rgb(f.format)) {
    f.plane[0] += static_cast<size_t>(r.y0) * f.stride[0] + static_cast<size_t>(packed_pixel_bytes(f.format)) * r.x0;
  } else {
    f.plane[0] += static_cast<size_t>(r.y0) * f.stride[0] + sb * r.x0;
    const size_t chroma_row = static_cast<size_t>(r.y0 / 2);
    if (is_semi_planar(f.format)) {
      f.plane[1] += chroma_row * f.stride[1] + sb * r.x0;  // x0/2 pairs of 2 samples
    } else {
      f.plane[1] += chroma_row * f.stride[1] + sb * (r.x0 / 2);
      f.plane[2] += chroma_row * f.stride[2] + sb * (r.x0 / 2);
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

// A pixel of the deep formats' pictures: R'G'B'A of 16 bits each (0..65535).
struct alignas(8) Rgba16 {
  uint16_t r, g, b, a;
};
// An 8-bit level as 16 bits (v * 257: 255 -> 65535), and the high byte of
// a 16-bit one: what the 8-bit stages read of deep frames.
P3D_HD Rgba16 widen(Rgba c) {
  return Rgba16{static_cast<uint16_t>(c.r * 257), static_cast<uint16_t>(c.g * 257), static_cast<uint16_t>(c.b * 257),
                static_cast<uint16_t>(c.a * 257)};
}
P3D_HD Rgba narrow(Rgba16 c) {
  return Rgba{static_cast<uint8_t>(c.r >> 8), static_cast<uint8_t>(c.g >> 8), static_cast<uint8_t>(c.b >> 8),
              static_cast<uint8_t>(c.a >> 8)};
}

// Y'CbCr -> R'G'B'. Built from Kr/Kb, the range and the sample depth by
// yuv_to_rgb_params() (colour.cpp); the gst layer takes Kr/Kb from the
// caps' colorimetry. On codes of the samples' depth (8 or 10 bits):
//   Yn = (Y - y_offset) * y_scale,  Cb = (U - c_offset) * c_scale, Cr = (V - c_offset) * c_scale
//   R = Yn + rv*Cr,  G = Yn + gu*Cb + gv*Cr,  B = Yn + bu*Cb      (in 0..top units)
// top is 255 for 8-bit samples (8-bit R'G'B' out) and 65535 for 10-bit
// ones (16-bit R'G'B' out, Rgba16).
struct YuvToRgb {
  float y_offset = 16.f, y_scale = 255.f / 219.f, c_scale = 255.f / 224.f;
  float rv = 1.402f, gu = -0.344136f, gv = -0.714136f, bu = 1.772f;
  float c_offset = 128.f;
  int top = 255;
};

YuvToRgb yuv_to_rgb_params(double kr, double kb, bool full_range, int bits = 8);
inline bool operator==(const YuvToRgb &a, const YuvToRgb &b) {
  return a.y_offset == b.y_offset && a.y_scale == b.y_scale && a.c_scale == b.c_scale && a.rv == b.rv &&
         a.gu == b.gu && a.gv == b.gv && a.bu == b.bu && a.c_offset == b.c_offset && a.top == b.top;
}
inline bool operator!=(const YuvToRgb &a, const YuvToRgb &b) { return !(a == b); }

// R'G'B' -> Y'CbCr (the inverse of YuvToRgb), built by rgb_to_yuv_params()
// (colour.cpp) from the output caps' colorimetry and depth:
//   Yl = kr R + kg G + kb B,  Cb = (B - Yl) * cb,  Cr = (R - Yl) * cr  (R'G'B' in 0..255, or 0..65535 for 10 bits)
//   Y = level(y_offset + Yl * y_scale),  U = level(c_offset + Cb * c_scale),  V likewise
// level() rounds and clamps to 0..top (255, or 1023 for 10-bit codes).
// Defaults: BT.709, limited range, 8 bits (what GStreamer picks for HD YUV).
struct RgbToYuv {
  float kr = 0.2126f, kg = 0.7152f, kb = 0.0722f;
  float cb = 0.538909f, cr = 0.635075f;  // 1 / (2 (1 - kb)), 1 / (2 (1 - kr))
  float y_offset = 16.f, y_scale = 219.f / 255.f, c_scale = 224.f / 255.f;
  float c_offset = 128.f;
  int top = 255;
};

RgbToYuv rgb_to_yuv_params(double kr, double kb, bool full_range, int bits = 8);
inline bool operator==(const RgbToYuv &a, const RgbToYuv &b) {
  return a.kr == b.kr && a.kg == b.kg && a.kb == b.kb && a.cb == b.cb && a.cr == b.cr && a.y_offset == b.y_offset &&
         a.y_scale == b.y_scale && a.c_scale == b.c_scale && a.c_offset == b.c_offset && a.top == b.top;
}

// Whether conversion parameters suit a format: 10-bit ones (top 65535 /
// 1023) for the deep formats, 8-bit ones for the others (packed RGB
// formats never convert, so any parameters suit them).
P3D_HD bool yuv_params_fit(PixelFormat f, int top, int deep_top) {
  return !is_yuv420(f) || (top == deep_top) == is_deep(f);
}
P3D_HD bool params_fit(PixelFormat f, const YuvToRgb &m) { return yuv_params_fit(f, m.top, 65535); }
P3D_HD bool params_fit(PixelFormat f, const RgbToYuv &m) { return yuv_params_fit(f, m.top, 1023); }

// 16-bit little-endian sample i of a row.
P3D_HD int load_u16(const uint8_t *row, int i) { return row[2 * i] | row[2 * i + 1] << 8; }
P3D_HD void store_u16(uint8_t *row, int i, int v) {
  row[2 * i] = static_cast<uint8_t>(v);
  row[2 * i + 1] = static_cast<uint8_t>(v >> 8);
}

// The code of sample i of row y of plane p of a 4:2:0 frame: the byte of
// the 8-bit formats, the 10-bit code of the deep ones (P010's high bits,
// I420_10's low bits).
P3D_HD int load_code(const FrameView &f, int p, int y, int i) {
  const uint8_t *row = f.plane[p] + static_cast<size_t>(y) * f.stride[p];
  if (!is_deep(f.format)) return row[i];
  const int v = load_u16(row, i);
  return f.format == PixelFormat::P010 ? v >> 6 : v & 0x3ff;
}
P3D_HD void store_code(const FrameView &f, int p, int y, int i, int code) {
  uint8_t *row = f.plane[p] + static_cast<size_t>(y) * f.stride[p];
  if (!is_deep(f.format)) {
    row[i] = static_cast<uint8_t>(code);
    return;
  }
  store_u16(row, i, f.format == PixelFormat::P010 ? code << 6 : code);
}

// Luma weights of the guide image and of depth read from grey pictures
// (BT.601; only used on R'G'B' values, so it is colorimetry independent).
P3D_HD float rgb_luma(float r, float g, float b) { return 0.299f * r + 0.587f * g + 0.114f * b; }

// The Cb/Cr codes (u, v) of pixel (x, y) of a 4:2:0 frame: the pixels
// 2k and 2k + 1 of rows 2j and 2j + 1 share them.
P3D_HD void load_chroma(const FrameView &f, int x, int y, int *u, int *v) {
  if (is_semi_planar(f.format)) {
    *u = load_code(f, 1, y / 2, 2 * (x / 2));
    *v = load_code(f, 1, y / 2, 2 * (x / 2) + 1);
  } else {
    *u = load_code(f, 1, y / 2, x / 2);
    *v = load_code(f, 2, y / 2, x / 2);
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
  const float cb = (static_cast<float>(u) - m.c_offset) * m.c_scale;
  const float cr = (static_cast<float>(v) - m.c_offset) * m.c_scale;
  return ChromaTerms{m.rv * cr, m.gu * cb, m.gv * cr, m.bu * cb};
}
P3D_HD Rgba yuv_rgba(int luma, const ChromaTerms &c, const YuvToRgb &m) {
  const float yn = (static_cast<float>(luma) - m.y_offset) * m.y_scale;
  return Rgba{to_u8(yn + c.r), to_u8(yn + c.gu + c.gv), to_u8(yn + c.b), 255};
}
// The same in 16 bits, for 10-bit codes and parameters (top 65535).
P3D_HD Rgba16 yuv_rgba16(int luma, const ChromaTerms &c, const YuvToRgb &m) {
  const float yn = (static_cast<float>(luma) - m.y_offset) * m.y_scale;
  return Rgba16{static_cast<uint16_t>(to_level(yn + c.r, 65535)), static_cast<uint16_t>(to_level(yn + c.gu + c.gv, 65535)),
                static_cast<uint16_t>(to_level(yn + c.b, 65535)), 65535};
}

// Pixel (x, y) of a packed RGB frame: its four samples as stored (RGBx and
// BGRx: alpha 255).
P3D_HD Rgba load_packed(const FrameView &f, int x, int y) {
  const uint8_t *p = f.plane[0] + static_cast<size_t>(y) * f.stride[0] + 4 * x;
  const bool bgr = is_bgr_order(f.format), alpha = has_alpha(f.format);
  return Rgba{bgr ? p[2] : p[0], p[1], bgr ? p[0] : p[2], alpha ? p[3] : static_cast<uint8_t>(255)};
}
// In device code an 8-byte aligned RGBA64 pixel (every pair buffer the
// stages allocate) moves as one 64-bit word: the 8 byte accesses it takes
// otherwise bound the 16-bit pack and fill kernels by their load and store
// instructions. Other addresses keep the byte accesses, so no frame can
// make the device access memory misaligned.
P3D_HD Rgba16 load_packed16(const FrameView &f, int x, int y) {
  const uint8_t *p = f.plane[0] + static_cast<size_t>(y) * f.stride[0];
#ifdef __CUDA_ARCH__
  if (reinterpret_cast<uintptr_t>(p + 8 * static_cast<size_t>(x)) % 8 == 0) {
    const uint64_t w = *reinterpret_cast<const uint64_t *>(p + 8 * static_cast<size_t>(x));
    return Rgba16{static_cast<uint16_t>(w), static_cast<uint16_t>(w >> 16), static_cast<uint16_t>(w >> 32),
                  static_cast<uint16_t>(w >> 48)};
  }
#endif
  return Rgba16{static_cast<uint16_t>(load_u16(p, 4 * x)), static_cast<uint16_t>(load_u16(p, 4 * x + 1)),
                static_cast<uint16_t>(load_u16(p, 4 * x + 2)), static_cast<uint16_t>(load_u16(p, 4 * x + 3))};
}

// Read pixel (x, y) of any supported format as 16-bit R'G'B'A: RGBA64 as
// stored, the 10-bit Y'CbCr formats converted with 10-bit parameters
// (params_fit), the 8-bit formats' load_rgba() widened.
P3D_HD Rgba load_rgba(const FrameView &f, int x, int y, const YuvToRgb &m);
P3D_HD Rgba16 load_rgba16(const FrameView &f, int x, int y, const YuvToRgb &m) {
  if (is_rgba64(f.format)) return load_packed16(f, x, y);
  if (!is_deep(f.format)) return widen(load_rgba(f, x, y, m));
  int u, v;
  load_chroma(f, x, y, &u, &v);
  return yuv_rgba16(load_code(f, 0, y, x), chroma_terms(u, v, m), m);
}

// Read pixel (x, y) of any supported format as 8-bit R'G'B'A (alpha 255
// where the format has none). The deep formats give their high bits:
// RGBA64 its samples' high bytes; P010/I420_10 narrow(load_rgba16()) with
// 10-bit parameters, or, given 8-bit ones, their codes' high 8 bits
// converted as 8-bit samples.
P3D_HD Rgba load_rgba(const FrameView &f, int x, int y, const YuvToRgb &m) {
  if (is_rgba64(f.format)) return narrow(load_packed16(f, x, y));
  if (is_packed_rgb(f.format)) return load_packed(f, x, y);
  if (is_deep(f.format) && m.top == 65535) return narrow(load_rgba16(f, x, y, m));
  const int shift = is_deep(f.format) ? 2 : 0;
  int u, v;
  load_chroma(f, x, y, &u, &v);
  return yuv_rgba(load_code(f, 0, y, x) >> shift, chroma_terms(u >> shift, v >> shift, m), m);
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
// Rgba16 likewise, 16 bits a channel (RGBA64's memory order).
P3D_HD uint64_t rgba_word(Rgba16 c) {
  return static_cast<uint64_t>(c.r) | static_cast<uint64_t>(c.g) << 16 | static_cast<uint64_t>(c.b) << 32 |
         static_cast<uint64_t>(c.a) << 48;
}
P3D_HD Rgba16 word_rgba(uint64_t w) {
  return Rgba16{static_cast<uint16_t>(w), static_cast<uint16_t>(w >> 16), static_cast<uint16_t>(w >> 32),
                static_cast<uint16_t>(w >> 48)};
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
// way (common/warp.cpp, cuda/warp_rows.cuh).
P3D_HD void load_rgba_pair_words(const FrameView &f, int x, int y, const YuvToRgb &m, uint32_t *w) {
  const bool second = x + 1 < f.width;
  if (is_packed_rgb(f.format) || is_deep(f.format)) {
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
// The same in 16 bits: rgba_word(load_rgba16()) of the pair.
P3D_HD void load_rgba_pair_words(const FrameView &f, int x, int y, const YuvToRgb &m, uint64_t *w) {
  const bool second = x + 1 < f.width;
  if (!is_deep(f.format) || is_packed_rgb(f.format)) {
    w[0] = rgba_word(load_rgba16(f, x, y, m));
    if (second) w[1] = rgba_word(load_rgba16(f, x + 1, y, m));
    return;
  }
  int u, v;
  load_chroma(f, x, y, &u, &v);
  const ChromaTerms c = chroma_terms(u, v, m);
  w[0] = rgba_word(yuv_rgba16(load_code(f, 0, y, x), c, m));
  if (second) w[1] = rgba_word(yuv_rgba16(load_code(f, 0, y, x + 1), c, m));
}

// Write an R'G'B'A pixel into a packed RGB frame (other formats: no-op;
// RGBA64 gets it widened).
P3D_HD void store_rgba16(const FrameView &f, int x, int y, Rgba16 c);
P3D_HD void store_rgba(const FrameView &f, int x, int y, Rgba c) {
  if (is_rgba64(f.format)) return store_rgba16(f, x, y, widen(c));
  if (!is_packed_rgb(f.format)) return;
  uint8_t *p = f.plane[0] + static_cast<size_t>(y) * f.stride[0] + 4 * x;
  const bool bgr = is_bgr_order(f.format);
  p[0] = bgr ? c.b : c.r;
  p[1] = c.g;
  p[2] = bgr ? c.r : c.b;
  p[3] = c.a;  // RGBx/BGRx: the padding byte gets c.a (255 for any converted pixel): defined, never garbage
}
// The same for 16-bit pixels: RGBA64 as they are, the 8-bit packed formats
// their high bytes.
P3D_HD void store_rgba16(const FrameView &f, int x, int y, Rgba16 c) {
  if (!is_rgba64(f.format)) return store_rgba(f, x, y, narrow(c));
  uint8_t *p = f.plane[0] + static_cast<size_t>(y) * f.stride[0];
#ifdef __CUDA_ARCH__
  if (reinterpret_cast<uintptr_t>(p + 8 * static_cast<size_t>(x)) % 8 == 0) {  // as load_packed16
    *reinterpret_cast<uint64_t *>(p + 8 * static_cast<size_t>(x)) =
        c.r | static_cast<uint64_t>(c.g) << 16 | static_cast<uint64_t>(c.b) << 32 | static_cast<uint64_t>(c.a) << 48;
    return;
  }
#endif
  store_u16(p, 4 * x, c.r);
  store_u16(p, 4 * x + 1, c.g);
  store_u16(p, 4 * x + 2, c.b);
  store_u16(p, 4 * x + 3, c.a);
}

// Packed RGB pixels by their type, for the code that works on either
// depth (the warp's and the pack's templates): Rgba through load_rgba /
// store_rgba, Rgba16 through load_rgba16 / store_rgba16, and an 8-bit
// colour as either.
P3D_HD void load_pixel(const FrameView &f, int x, int y, Rgba *c) {
  const YuvToRgb packed;  // packed RGB: never applied
  *c = load_rgba(f, x, y, packed);
}
P3D_HD void load_pixel(const FrameView &f, int x, int y, Rgba16 *c) {
  const YuvToRgb packed;
  *c = load_rgba16(f, x, y, packed);
}
P3D_HD void store_pixel(const FrameView &f, int x, int y, Rgba c) { store_rgba(f, x, y, c); }
P3D_HD void store_pixel(const FrameView &f, int x, int y, Rgba16 c) { store_rgba16(f, x, y, c); }
template <class Px>
P3D_HD Px colour_as(Rgba c);
template <>
P3D_HD Rgba colour_as<Rgba>(Rgba c) {
  return c;
}
template <>
P3D_HD Rgba16 colour_as<Rgba16>(Rgba c) {
  return widen(c);
}

// Writes the 2x2 block of a 4:2:0 frame whose top-left pixel is (2 bx,
// 2 by): px[] are its pixels in row order (top-left, top-right,
// bottom-left, bottom-right); those outside the frame (the last column or
// row of an odd size) are left out. Each pixel gets its own Y'; the
// block's Cb/Cr are those of the mean R'G'B' of its pixels (chroma centred
// on the block, as a 2x2 box filter puts it). Px is Rgba for the 8-bit
// formats and Rgba16 for the deep ones, with parameters of the frame's
// depth (params_fit).
template <class Px>
P3D_HD void store_yuv420_block(const FrameView &f, int bx, int by, const Px px[4], const RgbToYuv &m) {
  const int top = is_deep(f.format) ? m.top : 255;  // a constant in the kernels (8-bit only)
  int n = 0;
  unsigned int sr = 0, sg = 0, sb = 0;
  for (int k = 0; k < 4; ++k) {
    const int x = 2 * bx + (k & 1), y = 2 * by + (k >> 1);
    if (x >= f.width || y >= f.height) continue;
    const float r = px[k].r, g = px[k].g, b = px[k].b;
    const float yl = m.kr * r + m.kg * g + m.kb * b;
    store_code(f, 0, y, x, to_level(m.y_offset + yl * m.y_scale, top));
    sr += px[k].r;
    sg += px[k].g;
    sb += px[k].b;
    ++n;
  }
  if (n == 0) return;
  const float fn = static_cast<float>(n);
  const float r = static_cast<float>(sr) / fn, g = static_cast<float>(sg) / fn, b = static_cast<float>(sb) / fn;
  const float yl = m.kr * r + m.kg * g + m.kb * b;
  const int u = to_level(m.c_offset + (b - yl) * m.cb * m.c_scale, top);
  const int v = to_level(m.c_offset + (r - yl) * m.cr * m.c_scale, top);
  if (is_semi_planar(f.format)) {
    store_code(f, 1, by, 2 * bx, u);
    store_code(f, 1, by, 2 * bx + 1, v);
  } else {
    store_code(f, 1, by, bx, u);
    store_code(f, 2, by, bx, v);
  }
}

// The 8-bit guide value of pixel (x, y): the Y' code for YUV formats (its
// high 8 bits for the deep ones), the BT.601 luma of R'G'B' otherwise.
P3D_HD uint8_t load_luma(const FrameView &f, int x, int y) {
  if (!is_packed_rgb(f.format)) return static_cast<uint8_t>(load_code(f, 0, y, x) >> (is_deep(f.format) ? 2 : 0));
  const YuvToRgb unused;
  const Rgba c = load_rgba(f, x, y, unused);
  return to_u8(rgb_luma(c.r, c.g, c.b));
}

// Three 8-bit colour channels of pixel (x, y) in the frame's own space
// (Y'UV for YUV formats, R'G'B' otherwise; the deep formats' high 8 bits):
// what region grouping compares.
P3D_HD void load_native3(const FrameView &f, int x, int y, int out[3]) {
  if (is_packed_rgb(f.format)) {
    const YuvToRgb unused;
    const Rgba c = load_rgba(f, x, y, unused);
    out[0] = c.r;
    out[1] = c.g;
    out[2] = c.b;
    return;
  }
  const int shift = is_deep(f.format) ? 2 : 0;
  out[0] = load_code(f, 0, y, x) >> shift;
  load_chroma(f, x, y, &out[1], &out[2]);
  out[1] >>= shift;
  out[2] >>= shift;
}

// The 8-bit format whose samples are a deep format's high 8 bits: NV12 for
// P010, I420 for I420_10, RGBA for RGBA64; an 8-bit format is its own.
P3D_HD PixelFormat high_byte_format(PixelFormat f) {
  if (!is_deep(f)) return f;
  return is_rgba64(f) ? PixelFormat::RGBA : is_semi_planar(f) ? PixelFormat::NV12 : PixelFormat::I420;
}

// The high 8 bits of a deep format's 16-bit sample v: a 10-bit code >> 2
// (P010 keeps its code in the high bits, I420_10 in the low ones), an
// RGBA64 sample >> 8. A deep frame's samples narrowed so, plane by plane,
// make the frame of high_byte_format() that load_luma() and
// load_native3() read as they read the deep frame, so the 8-bit depth
// estimate and the filter's guide of that copy are those of the deep frame
// (high_byte_copy_cpu, cuda/high_bytes_gpu.h).
P3D_HD uint8_t high_byte(PixelFormat f, int v) {
  return static_cast<uint8_t>(f == PixelFormat::I420_10 ? (v & 0x3ff) >> 2 : v >> 8);
}

// Helpers for host code: number of planes and the size of plane i.
int frame_plane_count(PixelFormat f);
void frame_plane_size(PixelFormat f, int width, int height, int plane, int *bytes_per_row, int *rows);
// high_byte() of every sample of every plane of deep frame src into out
// (high_byte_format(src.format), src's size).
void high_byte_copy_cpu(const FrameView &src, const FrameView &out);

}  // namespace p3d
