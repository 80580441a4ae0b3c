#include "pack.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "row_convert.h"

namespace p3d {

namespace {

constexpr float kLuma[3] = {0.299f, 0.587f, 0.114f};  // rgb_luma's weights

void set_row(float *m, int row, float r, float g, float b) {
  m[3 * row] = r;
  m[3 * row + 1] = g;
  m[3 * row + 2] = b;
}
void pass_channel(float *m, int c) { m[3 * c + c] = 1.f; }
void luma_to_channel(float *m, int c) { set_row(m, c, kLuma[0], kLuma[1], kLuma[2]); }

// Dubois' least-squares projections (E. Dubois, "A projection method to
// generate anaglyph stereo images", ICASSP 2001), in their first published
// form, applied to 0..255 values.
void dubois(AnaglyphGlasses g, float *l, float *r) {
  static const float kRedCyan[2][9] = {
      {0.437f, 0.449f, 0.164f, -0.062f, -0.062f, -0.024f, -0.048f, -0.050f, -0.017f},
      {-0.011f, -0.032f, -0.007f, 0.377f, 0.761f, 0.009f, -0.026f, -0.093f, 1.234f}};
  static const float kGreenMagenta[2][9] = {
      {-0.062f, -0.158f, -0.039f, 0.284f, 0.668f, 0.143f, -0.015f, -0.027f, 0.021f},
      {0.529f, 0.705f, 0.024f, -0.016f, -0.015f, -0.065f, 0.009f, 0.075f, 0.937f}};
  static const float kAmberBlue[2][9] = {
      {1.062f, -0.205f, 0.299f, -0.026f, 0.908f, 0.068f, -0.038f, -0.173f, 0.022f},
      {-0.016f, -0.123f, -0.017f, 0.006f, 0.062f, -0.017f, 0.094f, 0.185f, 0.911f}};
  const float(*m)[9] = g == AnaglyphGlasses::GreenMagenta ? kGreenMagenta
                       : g == AnaglyphGlasses::AmberBlue  ? kAmberBlue
                                                          : kRedCyan;
  for (int i = 0; i < 9; ++i) {
    l[i] = m[0][i];
    r[i] = m[1][i];
  }
}

// The matrices of ffmpeg's (and mpv's) stereo3d filter, ana_coeff[] for
// arcd, agmd and aybd: per output channel, the left then the right eye's
// R, G, B weights in 16.16 fixed point.
void dubois_ffmpeg(AnaglyphGlasses g, float *l, float *r) {
  static const int kRedCyan[3][6] = {{29891, 32800, 11559, -2849, -5763, -102},
                                     {-2627, -2479, -1033, 24804, 48080, -1209},
                                     {-997, -1350, -358, -4729, -7403, 80373}};
  static const int kGreenMagenta[3][6] = {{-4063, -10354, -2556, 34669, 46203, 1573},
                                          {18612, 43778, 9372, -1049, -983, -4260},
                                          {-983, -1769, 1376, 590, 4915, 61407}};
  static const int kAmberBlue[3][6] = {{65535, -12650, 18451, -987, -7590, -1049},
                                       {-1604, 56032, 4196, 370, 3826, -1049},
                                       {-2345, -10676, 1358, 5801, 11416, 56217}};
  const int(*m)[6] = g == AnaglyphGlasses::GreenMagenta ? kGreenMagenta
                     : g == AnaglyphGlasses::AmberBlue  ? kAmberBlue
                                                        : kRedCyan;
  for (int row = 0; row < 3; ++row)
    for (int c = 0; c < 3; ++c) {
      l[3 * row + c] = static_cast<float>(m[row][c] / 65536.0);
      r[3 * row + c] = static_cast<float>(m[row][3 + c] / 65536.0);
    }
}

// sRGB transfer (IEC 61966-2-1), in double, for the linear-light tables.
double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

void linear_light_tables(AnaglyphMatrices *am) {
  am->linear_light = true;
  for (int v = 0; v < 256; ++v) am->to_linear[v] = static_cast<float>(srgb_to_linear(v / 255.0));
  for (int k = 0; k < 255; ++k) am->midpoints[k] = 0.5f * (am->to_linear[k] + am->to_linear[k + 1]);
}

// Channels each eye's filter passes (0 = R, 1 = G, 2 = B).
struct Filters {
  bool left[3];
  bool right[3];
  bool single_colour_left;  // which eye looks through the one-channel filter
};
Filters filters(AnaglyphGlasses g) {
  switch (g) {
    case AnaglyphGlasses::GreenMagenta: return {{false, true, false}, {true, false, true}, true};
    case AnaglyphGlasses::AmberBlue: return {{true, true, false}, {false, false, true}, false};
    case AnaglyphGlasses::RedCyan:
    default: return {{true, false, false}, {false, true, true}, true};
  }
}

// An eye's matrix built from its filter: each passed channel gets either the
// same channel (colour) or the luma.
void filter_matrix(const bool *passed, bool as_luma, float *m) {
  for (int c = 0; c < 3; ++c) {
    if (!passed[c]) continue;
    if (as_luma)
      luma_to_channel(m, c);
    else
      pass_channel(m, c);
  }
}

bool packed_rgb_valid(const FrameView &f) {
  return is_packed_rgb(f.format) && f.plane[0] != nullptr && f.width > 0 && f.height > 0 &&
         f.stride[0] >= packed_pixel_bytes(f.format) * f.width;
}

// A 4:2:0 frame with every plane present and no stride shorter than its row.
bool yuv420_valid(const FrameView &f) {
  if (is_packed_rgb(f.format) || f.width <= 0 || f.height <= 0) return false;
  for (int i = 0; i < frame_plane_count(f.format); ++i) {
    int row = 0, rows = 0;
    frame_plane_size(f.format, f.width, f.height, i, &row, &rows);
    if (f.plane[i] == nullptr || f.stride[i] < row) return false;
  }
  return true;
}

}  // namespace

// The float matrices of a method, and for the gamma mixes their 16.16
// fixed-point form (anaglyph_mix_word).
AnaglyphMatrices anaglyph_matrices(AnaglyphGlasses g, AnaglyphMethod m) {
  AnaglyphMatrices am{};
  switch (m) {
    case AnaglyphMethod::Dubois: dubois(g, am.left, am.right); break;
    case AnaglyphMethod::DuboisFfmpeg: dubois_ffmpeg(g, am.left, am.right); break;
    case AnaglyphMethod::DuboisLinear:
      dubois(g, am.left, am.right);
      linear_light_tables(&am);
      break;
    default: {
      const Filters f = filters(g);
      const bool luma_left = m == AnaglyphMethod::Gray || (m == AnaglyphMethod::HalfColor && f.single_colour_left);
      const bool luma_right = m == AnaglyphMethod::Gray || (m == AnaglyphMethod::HalfColor && !f.single_colour_left);
      filter_matrix(f.left, luma_left, am.left);
      filter_matrix(f.right, luma_right, am.right);
    }
  }
  for (int k = 0; k < 9; ++k) {
    am.left_q[k] = static_cast<int32_t>(std::lround(65536.0 * am.left[k]));
    am.right_q[k] = static_cast<int32_t>(std::lround(65536.0 * am.right[k]));
  }
  return am;
}

bool input_view_size(StereoInput input, int in_width, int in_height, int *view_width, int *view_height) {
  if (in_width <= 0 || in_height <= 0) return false;
  if (input == StereoInput::SideBySide && in_width % 2 != 0) return false;
  if (input == StereoInput::TopBottom && in_height % 2 != 0) return false;
  pack_detail::view_size(input, in_width, in_height, view_width, view_height);
  return true;
}

void pack_size(PackLayout layout, int view_width, int view_height, int *out_width, int *out_height) {
  *out_width = layout == PackLayout::SideBySide ? 2 * view_width : view_width;
  *out_height = layout == PackLayout::TopBottom ? 2 * view_height : view_height;
}

bool layout_arrangement(PackLayout layout, StereoInput *arrangement) {
  switch (layout) {
    case PackLayout::SideBySide: *arrangement = StereoInput::SideBySide; return true;
    case PackLayout::SideBySideHalf: *arrangement = StereoInput::SideBySideHalf; return true;
    case PackLayout::TopBottom: *arrangement = StereoInput::TopBottom; return true;
    case PackLayout::TopBottomHalf: *arrangement = StereoInput::TopBottomHalf; return true;
    case PackLayout::RowInterleaved: *arrangement = StereoInput::RowInterleaved; return true;
    case PackLayout::ColumnInterleaved: *arrangement = StereoInput::ColumnInterleaved; return true;
    case PackLayout::Checkerboard: *arrangement = StereoInput::Checkerboard; return true;
    default: return false;
  }
}

bool pack_is_identity(const PackParams &params) {
  StereoInput out;
  // The output's first view is the right one exactly when swap_eyes.
  return layout_arrangement(params.layout, &out) && out == params.input &&
         params.swap_eyes == params.input_right_first;
}

bool pack_args_valid(const PackParams &params, const FrameView &in, const FrameView &out) {
  if (!enum_valid(kPackLayoutNames, params.layout) || !enum_valid(kGlassesNames, params.glasses) ||
      !enum_valid(kAnaglyphMethodNames, params.method) || !enum_valid(kStereoInputNames, params.input))
    return false;
  if (!packed_rgb_valid(in)) return false;
  // The output keeps the input's depth: RGBA64 in, RGBA64 or 10-bit 4:2:0 out.
  if (!(packed_rgb_valid(out) && in.format == out.format) &&
      !(yuv420_valid(out) && is_deep(out.format) == is_deep(in.format) && params_fit(out.format, params.yuv)))
    return false;
  int vw = 0, vh = 0, w = 0, h = 0;
  if (!input_view_size(params.input, in.width, in.height, &vw, &vh)) return false;
  pack_size(params.layout, vw, vh, &w, &h);
  return out.width == w && out.height == h;
}

namespace {

#if P3D_CPU_VECTORS
// anaglyph_mix_word() of a row's pixels from 0, several at a time; returns
// where it stopped (at most w), from which the scalar loop takes over.
// Each 16.16 coefficient is split as q = 512 qh + ql (qh = q >> 9,
// ql = q & 511), so that every factor is a 16-bit lane and v_dotprod sums
// pairs of products in 32 bits: the channel's sum is 512 A + B with
// A = sum(c qh), B = sum(c ql), the same integer as the scalar sum
// (|512 A| < 512 * 6 * 255 * 256 < 2^31), shifted and clipped alike.
template <bool kBgr, bool kAlpha>
int anaglyph_pair_row_vector(const AnaglyphMatrices &am, const uint8_t *lp, const uint8_t *rp, uint8_t *o, int w) {
  using namespace cv;
  constexpr int L = v_uint8::nlanes, ri = kBgr ? 2 : 0, bi = 2 - ri;
  // Output channel k's six coefficients (left R' G' B', right R' G' B') as
  // three pairs of 16-bit lanes, high and low parts.
  v_int16 qh[3][3], ql[3][3];
  for (int k = 0; k < 3; ++k) {
    const int32_t q[6] = {am.left_q[3 * k],  am.left_q[3 * k + 1],  am.left_q[3 * k + 2],
                          am.right_q[3 * k], am.right_q[3 * k + 1], am.right_q[3 * k + 2]};
    for (int j = 0; j < 3; ++j) {
      auto lanes = [](int32_t a, int32_t b) {  // a in the even lanes, b in the odd ones
        const uint32_t pair = static_cast<uint16_t>(a) | static_cast<uint32_t>(static_cast<uint16_t>(b)) << 16;
        return v_reinterpret_as_s16(vx_setall_u32(pair));
      };
      qh[k][j] = lanes(q[2 * j] >> 9, q[2 * j + 1] >> 9);
      ql[k][j] = lanes(q[2 * j] & 511, q[2 * j + 1] & 511);
    }
  }
  const v_int32 round = vx_setall_s32(32768), zero = vx_setzero_s32(), top = vx_setall_s32(255);
  int x = 0;
  for (; x + L <= w; x += L) {
    v_uint8 l[4], r[4];
    v_load_deinterleave(lp + 4 * x, l[0], l[1], l[2], l[3]);
    v_load_deinterleave(rp + 4 * x, r[0], r[1], r[2], r[3]);
    const v_uint8 c8[6] = {l[ri], l[1], l[bi], r[ri], r[1], r[bi]};
    v_int16 c16[2][6];  // the two halves of the pixels, 16-bit lanes
    for (int i = 0; i < 6; ++i) {
      v_uint16 a, b;
      v_expand(c8[i], a, b);
      c16[0][i] = v_reinterpret_as_s16(a);
      c16[1][i] = v_reinterpret_as_s16(b);
    }
    v_int32 sums[3][4];  // channel k, quarter of the pixels
    for (int h = 0; h < 2; ++h) {
      v_int16 pairs[3][2];
      for (int j = 0; j < 3; ++j) v_zip(c16[h][2 * j], c16[h][2 * j + 1], pairs[j][0], pairs[j][1]);
      for (int k = 0; k < 3; ++k)
        for (int z = 0; z < 2; ++z) {
          const v_int32 a = v_dotprod(pairs[0][z], qh[k][0]) + v_dotprod(pairs[1][z], qh[k][1]) +
                            v_dotprod(pairs[2][z], qh[k][2]);
          const v_int32 b = v_dotprod(pairs[0][z], ql[k][0]) + v_dotprod(pairs[1][z], ql[k][1]) +
                            v_dotprod(pairs[2][z], ql[k][2]);
          sums[k][2 * h + z] = v_min(v_max(((a << 9) + b + round) >> 16, zero), top);
        }
    }
    v_uint8 c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = v_pack_u(v_pack(sums[k][0], sums[k][1]), v_pack(sums[k][2], sums[k][3]));
    const v_uint8 alpha = kAlpha ? l[3] : vx_setall_u8(255);
    v_store_interleave(o + 4 * x, c[ri], c[1], c[bi], alpha);
  }
  vx_cleanup();
  return x;
}
#endif

// The default case, the anaglyph of a side-by-side pair into packed RGB
// mixed in gamma-encoded R'G'B' (every method but DuboisLinear), a row at a
// time with the format's channel order and the views' places worked out
// once instead of per pixel: anaglyph_gamma(), anaglyph()'s own mix, on the
// channels load_rgba() would read, written where store_rgba() would write
// them, so the same output (tests/common/test_pack.cpp checks it against
// pack_pixel() for every method, format and eye order).
template <bool kBgr, bool kAlpha>
void anaglyph_pair_row(const AnaglyphMatrices &am, const uint8_t *__restrict lp, const uint8_t *__restrict rp,
                       uint8_t *__restrict o, int w) {
  constexpr int ri = kBgr ? 2 : 0, bi = 2 - ri;  // byte offsets of R' and B' (the output has the input's format)
  auto pixel = [](const uint8_t *p) { return Rgba{p[ri], p[1], p[bi], kAlpha ? p[3] : uint8_t{255}}; };
  int x = 0;
#if P3D_CPU_VECTORS
  x = anaglyph_pair_row_vector<kBgr, kAlpha>(am, lp, rp, o, w);
#endif
  for (; x < w; ++x) {
    const Rgba c = pack_detail::anaglyph_gamma(am, pixel(lp + 4 * x), pixel(rp + 4 * x));
    o[4 * x + ri] = c.r;
    o[4 * x + 1] = c.g;
    o[4 * x + bi] = c.b;
    o[4 * x + 3] = c.a;
  }
}

// The row loops of a side-by-side pair in packed RGB: row_fn(left, right,
// out) for each output row asked for (only: one flag a row, null: all),
// with the start of the left and the right view in that input row (the
// eye order applied) and of the output row; pixel_bytes: 4, or 8 for
// RGBA64.
template <class RowFn>
void side_by_side_rows(const PackParams &p, const FrameView &in, const FrameView &out,
                       const std::vector<uint8_t> *only, size_t pixel_bytes, const RowFn &row_fn) {
  const size_t left = pixel_bytes * static_cast<size_t>(pack_detail::view_slot(p, 0) * (in.width / 2));
  const size_t right = pixel_bytes * static_cast<size_t>(pack_detail::view_slot(p, 1) * (in.width / 2));
  cv::parallel_for_(cv::Range(0, out.height), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      if (only && !(*only)[y]) continue;
      const uint8_t *row = in.plane[0] + static_cast<size_t>(y) * in.stride[0];
      row_fn(row + left, row + right, out.plane[0] + static_cast<size_t>(y) * out.stride[0]);
    }
  });
}

void anaglyph_pair_rows(const PackParams &p, const AnaglyphMatrices &am, const FrameView &in, const FrameView &out,
                        const std::vector<uint8_t> *only) {
  const bool bgr = is_bgr_order(in.format), alpha = has_alpha(in.format);
  auto row_fn = bgr ? (alpha ? anaglyph_pair_row<true, true> : anaglyph_pair_row<true, false>)
                    : (alpha ? anaglyph_pair_row<false, true> : anaglyph_pair_row<false, false>);
  side_by_side_rows(p, in, out, only, 4, [&](const uint8_t *l, const uint8_t *r, uint8_t *o) {
    row_fn(am, l, r, o, in.width / 2);
  });
}

// The side-by-side-half layout of a side-by-side pair into packed RGB of
// the input's format, a row at a time: output column i of a half is
// mean2() of its view's columns 2i and 2i+1 (clamped to the view), per
// channel, which for samples stored as they are read is a lane-wise mean
// of the stored words (mean2_word()). The byte order is the same in and
// out, so no channel moves; an RGBx/BGRx padding byte becomes 255, as
// store_rgba() writes the 255 that load_rgba() reads there. A loop over
// plain words, so the compiler vectorises it (tests/common/test_pack.cpp
// checks it against pack_pixel() for every packed format, width and eye
// order).
template <class Word>
void half_pair_row(const uint8_t *view, int view_width, uint8_t *o, int n, Word set_bits) {
  auto load = [view](int i) {
    Word w;
    std::memcpy(&w, view + sizeof(Word) * static_cast<size_t>(i), sizeof w);
    return w;
  };
  const int pairs = std::min(n, view_width / 2);  // outputs whose 2i + 1 is inside the view
  for (int i = 0; i < pairs; ++i) {
    const Word w = pack_detail::mean2_word(load(2 * i), load(2 * i + 1)) | set_bits;
    std::memcpy(o + sizeof(Word) * static_cast<size_t>(i), &w, sizeof w);
  }
  for (int i = pairs; i < n; ++i) {  // an odd view's last column pairs with itself
    const Word w = load(std::min(2 * i, view_width - 1)) | set_bits;
    std::memcpy(o + sizeof(Word) * static_cast<size_t>(i), &w, sizeof w);
  }
}

template <class Word>
void half_pair_rows(const PackParams &p, const FrameView &in, const FrameView &out, const std::vector<uint8_t> *only) {
  const int w = in.width / 2, split = half_split(out.width);
  const Word set_bits = has_alpha(in.format) ? Word{0} : Word{0xff} << 24;  // the padding byte of RGBx/BGRx
  side_by_side_rows(p, in, out, only, sizeof(Word), [&](const uint8_t *l, const uint8_t *r, uint8_t *o) {
    half_pair_row<Word>(l, w, o, split, set_bits);
    half_pair_row<Word>(r, w, o + sizeof(Word) * static_cast<size_t>(split), out.width - split, set_bits);
  });
}

// The frame for input arrangement I: one loop instantiation per arrangement
// (the per-pixel function inlines into it, as in the kernel).
// only: the output rows to write (one flag a row), null: all.
// Px: Rgba, or Rgba16 for deep frames.
template <StereoInput I, class Px>
void pack_rows(const PackParams &params, const AnaglyphMatrices &am, const FrameView &in, const FrameView &out,
               const std::vector<uint8_t> *only) {
  auto wanted = [only](int y) { return !only || (*only)[y]; };
  if (!is_packed_rgb(out.format)) {  // 4:2:0: by 2x2 blocks
    const int bw = (out.width + 1) / 2, bh = (out.height + 1) / 2;
    cv::parallel_for_(cv::Range(0, bh), [&](const cv::Range &rows) {
      for (int by = rows.start; by < rows.end; ++by)
        if (wanted(2 * by) || (2 * by + 1 < out.height && wanted(2 * by + 1)))
          for (int bx = 0; bx < bw; ++bx) pack_detail::pack_block_yuv<I, Px>(params, am, in, out, bx, by);
    });
    return;
  }
  if (I == StereoInput::SideBySide && params.layout == PackLayout::Anaglyph && !am.linear_light && !is_deep(in.format))
    return anaglyph_pair_rows(params, am, in, out, only);
  if (I == StereoInput::SideBySide && params.layout == PackLayout::SideBySideHalf && in.format == out.format)
    return is_deep(in.format) ? half_pair_rows<uint64_t>(params, in, out, only)
                              : half_pair_rows<uint32_t>(params, in, out, only);
  cv::parallel_for_(cv::Range(0, out.height), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y)
      if (wanted(y))
        for (int x = 0; x < out.width; ++x)
          store_pixel(out, x, y, pack_detail::pack_pixel_for<I, Px>(params, am, in, x, y));
  });
}

// The input rows that view rows [a, b] of slot `slot` read: an interval,
// conservative (a row or two more at most).
void view_rows_read(StereoInput input, int in_height, int slot, int a, int b, int *lo, int *hi) {
  switch (input) {
    case StereoInput::TopBottom:
      *lo = a + slot * (in_height / 2);
      *hi = b + slot * (in_height / 2);
      return;
    case StereoInput::TopBottomHalf: {
      const int start = slot == 0 ? 0 : half_split(in_height);
      *lo = start + a / 2 - 1;
      *hi = start + b / 2 + 1;
      return;
    }
    case StereoInput::RowInterleaved:
    case StereoInput::Checkerboard:
      *lo = a - 1;
      *hi = b + 1;
      return;
    default:
      *lo = a;
      *hi = b;
      return;
  }
}

// The frame, one instantiation of pack_rows per arrangement.
template <class Px>
void pack_frame(const PackParams &params, const AnaglyphMatrices &am, const FrameView &in, const FrameView &out,
                const std::vector<uint8_t> *rows) {
  switch (params.input) {
    case StereoInput::SideBySideHalf: return pack_rows<StereoInput::SideBySideHalf, Px>(params, am, in, out, rows);
    case StereoInput::TopBottom: return pack_rows<StereoInput::TopBottom, Px>(params, am, in, out, rows);
    case StereoInput::TopBottomHalf: return pack_rows<StereoInput::TopBottomHalf, Px>(params, am, in, out, rows);
    case StereoInput::RowInterleaved: return pack_rows<StereoInput::RowInterleaved, Px>(params, am, in, out, rows);
    case StereoInput::ColumnInterleaved:
      return pack_rows<StereoInput::ColumnInterleaved, Px>(params, am, in, out, rows);
    case StereoInput::Checkerboard: return pack_rows<StereoInput::Checkerboard, Px>(params, am, in, out, rows);
    case StereoInput::SideBySide:
    default: return pack_rows<StereoInput::SideBySide, Px>(params, am, in, out, rows);
  }
}

}  // namespace

std::vector<uint8_t> pack_rows_reading(const PackParams &params, int in_width, int in_height,
                                       const std::vector<uint8_t> &in_rows) {
  int vw = 0, vh = 0, ow = 0, oh = 0;
  if (!input_view_size(params.input, in_width, in_height, &vw, &vh)) return {};
  pack_size(params.layout, vw, vh, &ow, &oh);
  // prefix[i]: flagged input rows before row i, so an interval is one lookup.
  std::vector<int> prefix(static_cast<size_t>(in_height) + 1, 0);
  for (int y = 0; y < in_height; ++y) prefix[y + 1] = prefix[y] + (y < static_cast<int>(in_rows.size()) && in_rows[y]);
  auto flagged = [&](int lo, int hi) {
    lo = std::max(lo, 0);
    hi = std::min(hi, in_height - 1);
    return lo <= hi && prefix[hi + 1] - prefix[lo] > 0;
  };
  std::vector<uint8_t> out(static_cast<size_t>(oh), 0);
  for (int Y = 0; Y < oh; ++Y) {
    // The view rows output row Y shows: [a, b].
    int a = Y, b = Y;
    if (params.layout == PackLayout::TopBottom && Y >= vh) a = b = Y - vh;
    if (params.layout == PackLayout::TopBottomHalf) {
      const int i = Y < half_split(vh) ? Y : Y - half_split(vh);
      a = 2 * i;
      b = std::min(2 * i + 1, vh - 1);
    }
    for (int slot = 0; slot < 2 && !out[Y]; ++slot) {
      int lo = 0, hi = 0;
      view_rows_read(params.input, in_height, slot, a, b, &lo, &hi);
      out[Y] = flagged(lo, hi);
    }
  }
  return out;
}


void pack_cpu(const PackParams &params, const FrameView &in, const FrameView &out) { pack_cpu(params, in, out, nullptr); }

void pack_cpu(const PackParams &params, const FrameView &in, const FrameView &out, const std::vector<uint8_t> *rows) {
  if (!pack_args_valid(params, in, out) || (rows && static_cast<int>(rows->size()) != out.height))
    throw std::invalid_argument("pack_cpu: frames do not match the layout (see pack_args_valid)");
  const AnaglyphMatrices am = anaglyph_matrices(params.glasses, params.method);
  if (is_deep(in.format))
    pack_frame<Rgba16>(params, am, in, out, rows);
  else
    pack_frame<Rgba>(params, am, in, out, rows);
}

}  // namespace p3d
