// Stereo conversion: a stereo frame in (the warp's full side-by-side pair,
// or any frame holding a pair as side-by-side, top-bottom, interleaved or
// checkerboard, at full or half resolution, either eye first) and a display
// or delivery format out. CPU reference; cuda/pack_gpu.h computes the same
// function. The input is a packed RGB frame; the output is packed RGB of the
// input's format, or 4:2:0 Y'CbCr (NV12, I420) converted from the packed
// pixels by store_yuv420_block() with PackParams::yuv, so that an encoder
// takes the frame as it is (no CPU conversion, a third of the bytes to
// download). An RGBA64 input is packed with the same rules on its 16-bit
// samples (Rgba16: the means in 16 bits, the gamma anaglyphs' fixed point
// in 64 bits; DuboisLinear on the nearest 8-bit codes, widened) into
// RGBA64 or 10-bit 4:2:0 (P010, I420_10), on the CPU.
//
// Input. PackParams::input says how the input frame (Win x Hin) holds the
// two views, input_right_first whether the right view comes first (left
// half, top half, even rows/columns, (X + Y) even). Each view is read at its
// full display size W x H (input_view_size()):
//   SideBySide        W = Win / 2, H = Hin       the half of the frame
//   TopBottom         W = Win, H = Hin / 2       the half of the frame
//   SideBySideHalf    W = Win, H = Hin           the first view's samples are
//                     columns [0, half_split(W)), the second's the rest; view
//                     column X comes from sample i = X / 2 of the view's n
//                     samples and its neighbour j = i - 1 (X even) or i + 1
//                     (X odd), clamped to the view: (3 s_i + s_j + 2) / 4 per
//                     channel (linear interpolation between sample centres;
//                     it inverts the half formats' pair means up to
//                     rounding); past the last sample (i >= n, the shorter
//                     view of an odd width) the last sample itself
//   TopBottomHalf     likewise along rows
//   RowInterleaved    W = Win, H = Hin; the first view owns the even rows:
//                     a row the view owns is read as is, any other row is the
//                     rounded mean (a + b + 1) / 2 of the rows above and below
//                     (one of them at the frame's edge)
//   ColumnInterleaved likewise along columns
//   Checkerboard      the first view owns (X + Y) even; any other pixel is the
//                     rounded mean (sum + n / 2) / n of its n in-frame
//                     4-neighbours (which the view owns)
// A frame too small to hold a view's sample (a one-row row-interleaved
// frame...) reads the nearest sample there is.
//
// Output. Let L(x, y) and R(x, y) be the left and right views (W x H each),
// exchanged when swap_eyes. Output pixel (X, Y) for each layout:
//   SideBySide        2W x H   L | R
//   SideBySideHalf    W  x H   L squeezed into columns [0, half_split(W)), R into
//                              the rest; output column i of a half is the rounded
//                              mean (a + b + 1) / 2 of its view's columns 2i and
//                              2i+1 (clamped to W-1), per channel
//   TopBottom         W  x 2H  L over R
//   TopBottomHalf     W  x H   likewise along rows: L in rows [0, half_split(H)), R below
//   RowInterleaved    W  x H   even rows from L, odd rows from R
//   ColumnInterleaved W  x H   even columns from L, odd from R
//   Checkerboard      W  x H   (X + Y) even from L, odd from R
//   Left / Right      W  x H   one view
//   Anaglyph          W  x H   per pixel: out = Ml * L + Mr * R (3x3 matrices
//                              on 0..255 R'G'B', in 16.16 fixed point, rounded
//                              and clipped to 0..255; below), alpha from L.
// An output in the input's own arrangement and eye order is the input itself
// (pack_is_identity(): the element passes such buffers through).
//
// Anaglyph matrices (anaglyph_matrices()):
//   Dubois        Dubois' least-squares projections for red-cyan,
//                 green-magenta and amber-blue glasses (E. Dubois, "A
//                 projection method to generate anaglyph stereo images",
//                 ICASSP 2001), as first published, applied to the
//                 gamma-encoded R'G'B' values and clipped;
//   DuboisFfmpeg  the matrices of ffmpeg's and mpv's stereo3d filter (arcd,
//                 agmd, aybd: Dubois' later revision, 16.16 fixed point in
//                 their source, used here as those fractions), applied the
//                 same way, for output that matches theirs;
//   DuboisLinear  the Dubois matrices applied in linear light, as Dubois
//                 specifies: sRGB-decode both views (to_linear table), mix,
//                 clip to [0, 1], and sRGB-encode by picking the 8-bit code
//                 whose linear value is nearest (midpoint table);
//   Color: each eye's channels pass through its filter (red-cyan: R from L,
//   G and B from R); HalfColor: the left eye's channel is L's luma, the
//   other eye in colour (for red-cyan; for the others the eye behind the
//   single-channel filter gets luma: green-magenta the left, amber-blue the
//   right eye); Gray: both eyes as luma.
// Color/HalfColor/Gray are matrices too (luma rows: rgb_luma's BT.601
// weights), so every anaglyph takes the one path out = Ml * L + Mr * R: in
// 16.16 fixed point, each coefficient round(65536 m), each channel's sum
// of products plus 2^15 shifted down 16 bits and clipped (anaglyph_mix_word;
// within one code of the float mix, equal to it but where the float sum
// lies within about 2^-16 of a half: the integers cost a pixel 18
// multiply-adds where floats take about 60 instructions, and the GPU's
// fused anaglyph is bound by its instructions); DuboisLinear in float:
// (Ml row . L) + (Mr row . R) on linear values, each dot left to right.
// Anaglyphs keep colour detail only in full-resolution chroma: encode them
// as RGB or 4:4:4 (4:2:0 smears the red channel over two pixels).
#pragma once

#include "enum_name.h"
#include "frame.h"

#if !defined(__CUDACC__)
#include <vector>
#endif

namespace p3d {

enum class PackLayout : int {
  Anaglyph = 0,
  SideBySide,
  SideBySideHalf,
  TopBottom,
  TopBottomHalf,
  RowInterleaved,
  ColumnInterleaved,
  Checkerboard,
  Left,
  Right,
};
enum class AnaglyphGlasses : int { RedCyan = 0, GreenMagenta, AmberBlue };
enum class AnaglyphMethod : int { Dubois = 0, Color, HalfColor, Gray, DuboisFfmpeg, DuboisLinear };
// How an input frame holds the pair (see the header comment).
enum class StereoInput : int {
  SideBySide = 0,
  SideBySideHalf,
  TopBottom,
  TopBottomHalf,
  RowInterleaved,
  ColumnInterleaved,
  Checkerboard,
};

inline constexpr EnumName<PackLayout> kPackLayoutNames[] = {
    {PackLayout::Anaglyph, "anaglyph", "Anaglyph (see glasses and anaglyph-method)"},
    {PackLayout::SideBySide, "side-by-side", "Side by side, full resolution (2W x H)"},
    {PackLayout::SideBySideHalf, "side-by-side-half", "Side by side, half width (anamorphic)"},
    {PackLayout::TopBottom, "top-bottom", "Top and bottom, full resolution (W x 2H)"},
    {PackLayout::TopBottomHalf, "top-bottom-half", "Top and bottom, half height (anamorphic)"},
    {PackLayout::RowInterleaved, "row-interleaved", "Even rows left view, odd rows right view"},
    {PackLayout::ColumnInterleaved, "column-interleaved", "Even columns left, odd columns right"},
    {PackLayout::Checkerboard, "checkerboard", "Checkerboard of the two views"},
    {PackLayout::Left, "left", "Left view only"},
    {PackLayout::Right, "right", "Right view only"},
};
P3D_CHECK_ENUM_NAMES(kPackLayoutNames);

inline constexpr EnumName<AnaglyphGlasses> kGlassesNames[] = {
    {AnaglyphGlasses::RedCyan, "red-cyan", "Red (left) / cyan (right)"},
    {AnaglyphGlasses::GreenMagenta, "green-magenta", "Green (left) / magenta (right)"},
    {AnaglyphGlasses::AmberBlue, "amber-blue", "Amber (left) / blue (right)"},
};
P3D_CHECK_ENUM_NAMES(kGlassesNames);

inline constexpr EnumName<AnaglyphMethod> kAnaglyphMethodNames[] = {
    {AnaglyphMethod::Dubois, "dubois",
     "Dubois least squares, the first published matrices, on gamma-encoded values (least ghosting)"},
    {AnaglyphMethod::Color, "color", "Full colour through the filters"},
    {AnaglyphMethod::HalfColor, "half-color", "Half colour (luma behind the single-colour filter)"},
    {AnaglyphMethod::Gray, "gray", "Grey (luma for both eyes)"},
    {AnaglyphMethod::DuboisFfmpeg, "dubois-ffmpeg",
     "Dubois, the revised matrices of ffmpeg's and mpv's stereo3d (arcd, agmd, aybd)"},
    {AnaglyphMethod::DuboisLinear, "dubois-linear", "Dubois in linear light (sRGB decoded, mixed, clipped, encoded)"},
};
P3D_CHECK_ENUM_NAMES(kAnaglyphMethodNames);

// How input frames hold a pair (pseudo3dpack's input-layout, whose GStreamer
// enum adds "from-caps" before these).
inline constexpr EnumName<StereoInput> kStereoInputNames[] = {
    {StereoInput::SideBySide, "side-by-side", "Side by side, full resolution"},
    {StereoInput::SideBySideHalf, "side-by-side-half", "Side by side, each view squeezed to half width"},
    {StereoInput::TopBottom, "top-bottom", "Top and bottom, full resolution"},
    {StereoInput::TopBottomHalf, "top-bottom-half", "Top and bottom, each view squeezed to half height"},
    {StereoInput::RowInterleaved, "row-interleaved", "Rows alternate between the views"},
    {StereoInput::ColumnInterleaved, "column-interleaved", "Columns alternate between the views"},
    {StereoInput::Checkerboard, "checkerboard", "Checkerboard of the two views"},
};
P3D_CHECK_ENUM_NAMES(kStereoInputNames);

struct PackParams {
  PackLayout layout = PackLayout::Anaglyph;
  AnaglyphGlasses glasses = AnaglyphGlasses::RedCyan;
  AnaglyphMethod method = AnaglyphMethod::Dubois;
  bool swap_eyes = false;
  StereoInput input = StereoInput::SideBySide;  // pseudo3dwarp's output
  bool input_right_first = false;
  RgbToYuv yuv;  // NV12/I420 output: the output caps' colorimetry
};

// Field by field: an adaptive stage repacks everything when they differ.
inline bool operator==(const PackParams &a, const PackParams &b) {
  return a.layout == b.layout && a.glasses == b.glasses && a.method == b.method && a.swap_eyes == b.swap_eyes &&
         a.input == b.input && a.input_right_first == b.input_right_first && a.yuv == b.yuv;
}
inline bool operator!=(const PackParams &a, const PackParams &b) { return !(a == b); }

// Row-major 3x3 matrices: out.r = m[0]*c.r + m[1]*c.g + m[2]*c.b, ...
// left_q / right_q: the same in 16.16 fixed point, round(65536 m), which
// every method but DuboisLinear mixes with (anaglyph_mix_word).
// With linear_light the views are mixed in linear light (DuboisLinear):
// to_linear[v] is the linear value of sRGB code v, and the output code is
// the number of midpoints[k] = (to_linear[k] + to_linear[k + 1]) / 2,
// k = 0..254, below the clipped linear value.
struct AnaglyphMatrices {
  float left[9];
  float right[9];
  int32_t left_q[9];
  int32_t right_q[9];
  bool linear_light;
  float to_linear[256];
  float midpoints[255];
};
AnaglyphMatrices anaglyph_matrices(AnaglyphGlasses g, AnaglyphMethod m);

// Size of each view of an input frame of in_width x in_height holding the
// pair as `input`; false when it cannot (a full side-by-side frame of odd
// width, a full top-bottom one of odd height, an empty frame).
bool input_view_size(StereoInput input, int in_width, int in_height, int *view_width, int *view_height);
// Output size for views of view_width x view_height.
void pack_size(PackLayout layout, int view_width, int view_height, int *out_width, int *out_height);
// The arrangement an output layout writes, or false for anaglyph and single views.
bool layout_arrangement(PackLayout layout, StereoInput *arrangement);
// Whether the output equals the input (same arrangement and eye order).
bool pack_is_identity(const PackParams &params);

// Width of the left half in the half formats: ceil(W/2) (the right half
// gets the rest, so odd widths lose no column of the output frame).
P3D_HD int half_split(int n) { return (n + 1) / 2; }

// Output pixel (X, Y) of the input frame `in`. Defined in this header
// (below) so the kernel calls the very same code.
P3D_HD Rgba pack_pixel(const PackParams &p, const AnaglyphMatrices &am, const FrameView &in, int X, int Y);

// Whether pack_cpu/pack_gpu accept these arguments: enums in range, in
// packed RGB, out packed RGB of in's format or NV12/I420, in holding views
// of input_view_size(), out of pack_size()'s size for them, and no stride
// shorter than its row.
bool pack_args_valid(const PackParams &params, const FrameView &in, const FrameView &out);

// Whole frame. out must have pack_size()'s size and the input's format
// (or NV12/I420); throws std::invalid_argument (writing nothing) when pack_args_valid() fails.
void pack_cpu(const PackParams &params, const FrameView &in, const FrameView &out);
#if !defined(__CUDACC__)
// The output rows flagged in `rows` (one flag a row of out) only; the
// others are left as they are.
void pack_cpu(const PackParams &params, const FrameView &in, const FrameView &out, const std::vector<uint8_t> *rows);
// The output rows (one flag a row) that read an input row flagged in
// in_rows (one flag a row of an in_width x in_height input): what the
// adaptive stages pack again when those rows changed. Conservative: a row
// or two beyond the exact set where interleaved or squeezed views mix rows.
std::vector<uint8_t> pack_rows_reading(const PackParams &params, int in_width, int in_height,
                                       const std::vector<uint8_t> &in_rows);
#endif

// ---- per-pixel implementation ----------------------------------------------

namespace pack_detail {

// Pixel (x, y) of the packed input: Px is Rgba for the 8-bit formats and
// Rgba16 for RGBA64, whose 16-bit samples every layout keeps.
template <class Px = Rgba>
P3D_HD Px pixel_at(const FrameView &in, int x, int y) {
  Px c;
  load_pixel(in, x, y, &c);
  return c;
}

// Rounded per-channel mean: what the half formats store for a pair of samples.
P3D_HD uint8_t mean2(uint8_t a, uint8_t b) { return static_cast<uint8_t>((a + b + 1) / 2); }
P3D_HD uint16_t mean2(uint16_t a, uint16_t b) { return static_cast<uint16_t>((a + b + 1) / 2); }
template <class Px>
P3D_HD Px mean2(Px a, Px b) {
  return Px{mean2(a.r, b.r), mean2(a.g, b.g), mean2(a.b, b.b), mean2(a.a, b.a)};
}
// mean2() of every lane of two words of 8-bit lanes (uint32_t: one Rgba
// word) or 16-bit lanes (uint64_t: one Rgba16 word), in word operations:
// per lane a + b = 2 (a & b) + (a ^ b), so (a + b + 1) / 2 = (a & b) +
// ceil((a ^ b) / 2) = (a | b) - floor((a ^ b) / 2). The shifted XOR is
// masked to its own lane, and never exceeds a | b there, so no lane
// borrows from the next.
template <class Word>
P3D_HD Word mean2_word(Word a, Word b) {
  constexpr Word kLaneLow = static_cast<Word>(sizeof(Word) == 4 ? 0x7f7f7f7full : 0x7fff7fff7fff7fffull);
  return (a | b) - (((a ^ b) >> 1) & kLaneLow);
}
// (3a + b + 2) / 4: a quarter of the way from sample a towards sample b.
P3D_HD uint8_t mix31(uint8_t a, uint8_t b) { return static_cast<uint8_t>((3 * a + b + 2) / 4); }
P3D_HD uint16_t mix31(uint16_t a, uint16_t b) { return static_cast<uint16_t>((3 * a + b + 2) / 4); }
template <class Px>
P3D_HD Px mix31(Px a, Px b) {
  return Px{mix31(a.r, b.r), mix31(a.g, b.g), mix31(a.b, b.b), mix31(a.a, b.a)};
}

P3D_HD int clamp_index(int i, int n) { return i < 0 ? 0 : (i >= n ? n - 1 : i); }

// Along an axis of n frame samples holding two squeezed views: the first
// view's samples are [0, half_split(n)), the second's the rest. Display
// position X of view `slot`: the two sample indices to mix (mix31).
P3D_HD void unsqueeze(int X, int n, int slot, int *s0, int *s1) {
  const int split = half_split(n);
  int start = slot == 0 ? 0 : split, count = slot == 0 ? split : n - split;
  if (count <= 0) {  // a one-sample axis has no second view: read the first
    start = 0;
    count = split;
  }
  if (X / 2 >= count) {  // past the view's last sample (the shorter view of an odd axis): repeat it
    *s0 = *s1 = start + count - 1;
    return;
  }
  const int i = X / 2;
  const int j = clamp_index((X & 1) ? i + 1 : i - 1, count);
  *s0 = start + i;
  *s1 = start + j;
}

// Interleaved along an axis of n samples: view `slot` owns the indices of
// its parity. Sets the indices to average for display position X (both the
// same when the view owns X, or at the frame's edge).
P3D_HD void deinterleave(int X, int n, int slot, int *s0, int *s1) {
  if ((X & 1) == slot || n == 1) {
    *s0 = *s1 = clamp_index(X, n);
    return;
  }
  // X belongs to the other view; its neighbours belong to this one.
  int a = X - 1, b = X + 1;
  if (a < 0) a = b;
  if (b >= n) b = a;
  *s0 = clamp_index(a, n);
  *s1 = clamp_index(b, n);
}

// View `slot` of a checkerboard frame at (x, y).
template <class Px = Rgba>
P3D_HD Px checker_pixel(const FrameView &in, int slot, int x, int y) {
  using C = decltype(Px{}.r);
  if (((x + y) & 1) == slot) return pixel_at<Px>(in, x, y);
  const int dx[4] = {-1, 1, 0, 0}, dy[4] = {0, 0, -1, 1};
  int n = 0, r = 0, g = 0, b = 0, a = 0;
  for (int k = 0; k < 4; ++k) {
    const int xx = x + dx[k], yy = y + dy[k];
    if (xx < 0 || yy < 0 || xx >= in.width || yy >= in.height) continue;
    const Px c = pixel_at<Px>(in, xx, yy);
    r += c.r;
    g += c.g;
    b += c.b;
    a += c.a;
    ++n;
  }
  if (n == 0) return pixel_at<Px>(in, x, y);  // a 1x1 frame
  return Px{static_cast<C>((r + n / 2) / n), static_cast<C>((g + n / 2) / n), static_cast<C>((b + n / 2) / n),
            static_cast<C>((a + n / 2) / n)};
}

// Where the output's left (eye 0) or right (eye 1) view lies in the input
// frame: 0 first (left half, top half, even rows or columns, (X + Y) even),
// 1 second. swap_eyes and input_right_first each exchange the two.
P3D_HD int view_slot(const PackParams &p, int eye) {
  const int view = eye ^ (p.swap_eyes ? 1 : 0);
  return view ^ (p.input_right_first ? 1 : 0);
}

// Pixel (x, y) of the left (eye 0) or right (eye 1) view as the output
// shows it (swap_eyes exchanges them), read from the input arrangement I
// (a template argument, so the kernel of the common case, a side-by-side
// pair, carries no code for the others).
template <StereoInput I, class Px = Rgba>
P3D_HD Px view_pixel(const PackParams &p, const FrameView &in, int eye, int x, int y) {
  const int slot = view_slot(p, eye);
  int a = 0, b = 0;
  switch (I) {
    case StereoInput::TopBottom: return pixel_at<Px>(in, x, y + slot * (in.height / 2));
    case StereoInput::SideBySideHalf:
      unsqueeze(x, in.width, slot, &a, &b);
      return mix31(pixel_at<Px>(in, a, y), pixel_at<Px>(in, b, y));
    case StereoInput::TopBottomHalf:
      unsqueeze(y, in.height, slot, &a, &b);
      return mix31(pixel_at<Px>(in, x, a), pixel_at<Px>(in, x, b));
    case StereoInput::RowInterleaved:
      deinterleave(y, in.height, slot, &a, &b);
      return mean2(pixel_at<Px>(in, x, a), pixel_at<Px>(in, x, b));
    case StereoInput::ColumnInterleaved:
      deinterleave(x, in.width, slot, &a, &b);
      return mean2(pixel_at<Px>(in, a, y), pixel_at<Px>(in, b, y));
    case StereoInput::Checkerboard: return checker_pixel<Px>(in, slot, x, y);
    case StereoInput::SideBySide:
    default: return pixel_at<Px>(in, x + slot * (in.width / 2), y);
  }
}

// Row `row` of a 3x3 matrix times (r, g, b). One fixed evaluation order, so
// the host (-ffp-contract=off) and the device (-fmad=false) round alike.
P3D_HD float mat_row(const float *m, int row, float r, float g, float b) {
  return m[3 * row] * r + m[3 * row + 1] * g + m[3 * row + 2] * b;
}

// The 8-bit sRGB code of a linear value: the count of midpoints below it
// (binary search; the midpoints increase).
P3D_HD uint8_t linear_to_code(const AnaglyphMatrices &am, float v) {
  int lo = 0, hi = 255;  // answer in [lo, hi]
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (v > am.midpoints[mid])
      lo = mid + 1;
    else
      hi = mid;
  }
  return static_cast<uint8_t>(lo);
}

// The mix on gamma-encoded R'G'B' (every method but DuboisLinear), on the
// pixels' words (rgba_word order; the alpha is l's) with the matrices in
// 16.16 fixed point (AnaglyphMatrices::left_q, right_q): per channel the
// sum of the six products plus 2^15, shifted down 16 bits (rounded to the
// nearest, halves up) and clipped to 0..255. Integer arithmetic, so the
// CPU and every GPU kernel agree without care for operation order; a pixel
// is 18 multiply-adds where the float mix takes about 60 instructions,
// which counts in the warp's fused anaglyph (cuda/warp_rows.cuh), a kernel bound
// by its instructions (measured: docs/benchmarks.md, Design measurements,
// "Fused pack"). |q| < 2^17 and 6 * 255 * 2^17 < 2^31: no
// overflow. Against the float mix it differs by at most one code, where
// the float sum lies within about 2^-16 of a half (tests/common/test_pack.cpp).
P3D_HD uint32_t anaglyph_mix_word(const int32_t *left, const int32_t *right, uint32_t l, uint32_t r) {
  const int lr = static_cast<int>(l & 0xffu), lg = static_cast<int>((l >> 8) & 0xffu),
            lb = static_cast<int>((l >> 16) & 0xffu);
  const int rr = static_cast<int>(r & 0xffu), rg = static_cast<int>((r >> 8) & 0xffu),
            rb = static_cast<int>((r >> 16) & 0xffu);
  uint32_t out = l & 0xff000000u;
  for (int k = 0; k < 3; ++k) {
    const int v = (left[3 * k] * lr + left[3 * k + 1] * lg + left[3 * k + 2] * lb + right[3 * k] * rr +
                   right[3 * k + 1] * rg + right[3 * k + 2] * rb + 32768) >>
                  16;
    out |= static_cast<uint32_t>(v < 0 ? 0 : (v > 255 ? 255 : v)) << (8 * k);
  }
  return out;
}
P3D_HD Rgba anaglyph_gamma(const AnaglyphMatrices &am, Rgba l, Rgba r) {
  return word_rgba(anaglyph_mix_word(am.left_q, am.right_q, rgba_word(l), rgba_word(r)));
}

// The gamma mix of 16-bit pixels: anaglyph_mix_word()'s sums on 16-bit
// channels c, sum = sum(q * c) + 2^15, shifted down 16 bits and clipped
// to 0..65535. The sum needs 36 bits (6 * 65535 * 2^17 > 2^31), but the GPU
// has no 64-bit multiply-add, and 64-bit sums made the 16-bit anaglyph
// pack kernel bound by its instructions. So the sum is split: with
// c = 256 h + l (its high and low bytes), sum = 256 A + B + 2^15 with
// A = sum(q * h) and B = sum(q * l), each |.| < 6 * 2^17 * 255 < 2^31; with
// A = 256 a1 + a0 (a1 = A >> 8, a0 = A & 255),
// sum >> 16 = a1 + ((256 a0 + B + 2^15) >> 16): the 64-bit result, in
// 32-bit integers (tests/common/test_deep.cpp checks it against the sum in
// 64 bits).
P3D_HD int mix16_channel(const int32_t *lq, const int32_t *rq, const int lc[3], const int rc[3]) {
  int a = 0, b = 0;
  for (int i = 0; i < 3; ++i) {
    a += lq[i] * (lc[i] >> 8) + rq[i] * (rc[i] >> 8);
    b += lq[i] * (lc[i] & 255) + rq[i] * (rc[i] & 255);
  }
  const int q = (a >> 8) + ((((a & 255) << 8) + b + 32768) >> 16);
  return q < 0 ? 0 : (q > 65535 ? 65535 : q);
}
P3D_HD Rgba16 anaglyph_gamma16(const AnaglyphMatrices &am, Rgba16 l, Rgba16 r) {
  const int lc[3] = {l.r, l.g, l.b}, rc[3] = {r.r, r.g, r.b};
  return Rgba16{static_cast<uint16_t>(mix16_channel(am.left_q, am.right_q, lc, rc)),
                static_cast<uint16_t>(mix16_channel(am.left_q + 3, am.right_q + 3, lc, rc)),
                static_cast<uint16_t>(mix16_channel(am.left_q + 6, am.right_q + 6, lc, rc)), l.a};
}

// The 8-bit code nearest a 16-bit level (round(v / 257)).
P3D_HD uint8_t nearest_code8(uint16_t v) { return static_cast<uint8_t>((v * 255u + 32767u) / 65535u); }
P3D_HD Rgba nearest_codes8(Rgba16 c) {
  return Rgba{nearest_code8(c.r), nearest_code8(c.g), nearest_code8(c.b), nearest_code8(c.a)};
}

P3D_HD Rgba anaglyph(const AnaglyphMatrices &am, Rgba l, Rgba r);
// 16-bit views: the gamma methods mix the 16-bit values; DuboisLinear,
// whose tables hold the 256 sRGB codes, mixes the views' nearest 8-bit
// codes and widens the result (alpha: L's 16 bits).
P3D_HD Rgba16 anaglyph(const AnaglyphMatrices &am, Rgba16 l, Rgba16 r) {
  if (am.linear_light) {
    Rgba16 o = widen(anaglyph(am, nearest_codes8(l), nearest_codes8(r)));
    o.a = l.a;  // alpha from L, as every method keeps it
    return o;
  }
  return anaglyph_gamma16(am, l, r);
}

P3D_HD Rgba anaglyph(const AnaglyphMatrices &am, Rgba l, Rgba r) {
  if (am.linear_light) {
    Rgba o;
    o.a = l.a;
    const float lr = am.to_linear[l.r], lg = am.to_linear[l.g], lb = am.to_linear[l.b];
    const float rr = am.to_linear[r.r], rg = am.to_linear[r.g], rb = am.to_linear[r.b];
    float c[3];
    for (int k = 0; k < 3; ++k) {
      const float v = mat_row(am.left, k, lr, lg, lb) + mat_row(am.right, k, rr, rg, rb);
      c[k] = v < 0.f ? 0.f : (v > 1.f ? 1.f : v);
    }
    o.r = linear_to_code(am, c[0]);
    o.g = linear_to_code(am, c[1]);
    o.b = linear_to_code(am, c[2]);
    return o;
  }
  return anaglyph_gamma(am, l, r);
}

// A half format along one axis: output index i of an axis of n samples per
// view holds eye 0 below half_split(n), eye 1 above; returns the eye and sets
// the two source indices whose mean is taken (the second clamped to n - 1).
P3D_HD int half_source(int i, int n, int *s0, int *s1) {
  const int split = half_split(n);
  const int eye = i < split ? 0 : 1;
  const int j = eye == 0 ? i : i - split;
  *s0 = 2 * j;
  *s1 = 2 * j + 1 < n ? 2 * j + 1 : n - 1;
  return eye;
}

// Display size of the views of an input frame (input_view_size() without the checks).
P3D_HD void view_size(StereoInput input, int in_width, int in_height, int *w, int *h) {
  *w = input == StereoInput::SideBySide ? in_width / 2 : in_width;
  *h = input == StereoInput::TopBottom ? in_height / 2 : in_height;
}

// pack_pixel for input arrangement I (p.input must be I).
template <StereoInput I, class Px = Rgba>
P3D_HD Px pack_pixel_for(const PackParams &p, const AnaglyphMatrices &am, const FrameView &in, int X, int Y) {
  int w = 0, h = 0;
  view_size(I, in.width, in.height, &w, &h);
  switch (p.layout) {
    case PackLayout::SideBySide:
      return X < w ? view_pixel<I, Px>(p, in, 0, X, Y) : view_pixel<I, Px>(p, in, 1, X - w, Y);
    case PackLayout::TopBottom:
      return Y < h ? view_pixel<I, Px>(p, in, 0, X, Y) : view_pixel<I, Px>(p, in, 1, X, Y - h);
    case PackLayout::SideBySideHalf: {
      int x0, x1;
      const int eye = half_source(X, w, &x0, &x1);
      return mean2(view_pixel<I, Px>(p, in, eye, x0, Y), view_pixel<I, Px>(p, in, eye, x1, Y));
    }
    case PackLayout::TopBottomHalf: {
      int y0, y1;
      const int eye = half_source(Y, h, &y0, &y1);
      return mean2(view_pixel<I, Px>(p, in, eye, X, y0), view_pixel<I, Px>(p, in, eye, X, y1));
    }
    case PackLayout::RowInterleaved:
      return view_pixel<I, Px>(p, in, Y & 1, X, Y);
    case PackLayout::ColumnInterleaved:
      return view_pixel<I, Px>(p, in, X & 1, X, Y);
    case PackLayout::Checkerboard:
      return view_pixel<I, Px>(p, in, (X + Y) & 1, X, Y);
    case PackLayout::Left:
      return view_pixel<I, Px>(p, in, 0, X, Y);
    case PackLayout::Right:
      return view_pixel<I, Px>(p, in, 1, X, Y);
    case PackLayout::Anaglyph:
    default:
      return anaglyph(am, view_pixel<I, Px>(p, in, 0, X, Y), view_pixel<I, Px>(p, in, 1, X, Y));
  }
}

// The 2x2 block (bx, by) of a 4:2:0 output frame for input arrangement I:
// its pixels packed as pack_pixel_for gives them, then converted.
template <StereoInput I, class Px = Rgba>
P3D_HD void pack_block_yuv(const PackParams &p, const AnaglyphMatrices &am, const FrameView &in, const FrameView &out,
                           int bx, int by) {
  Px px[4];
  for (int k = 0; k < 4; ++k) {
    const int x = 2 * bx + (k & 1), y = 2 * by + (k >> 1);
    px[k] = x < out.width && y < out.height ? pack_pixel_for<I, Px>(p, am, in, x, y) : Px{0, 0, 0, 0};
  }
  store_yuv420_block(out, bx, by, px, p.yuv);
}

}  // namespace pack_detail

P3D_HD Rgba pack_pixel(const PackParams &p, const AnaglyphMatrices &am, const FrameView &in, int X, int Y) {
  switch (p.input) {
    case StereoInput::SideBySideHalf: return pack_detail::pack_pixel_for<StereoInput::SideBySideHalf>(p, am, in, X, Y);
    case StereoInput::TopBottom: return pack_detail::pack_pixel_for<StereoInput::TopBottom>(p, am, in, X, Y);
    case StereoInput::TopBottomHalf: return pack_detail::pack_pixel_for<StereoInput::TopBottomHalf>(p, am, in, X, Y);
    case StereoInput::RowInterleaved: return pack_detail::pack_pixel_for<StereoInput::RowInterleaved>(p, am, in, X, Y);
    case StereoInput::ColumnInterleaved:
      return pack_detail::pack_pixel_for<StereoInput::ColumnInterleaved>(p, am, in, X, Y);
    case StereoInput::Checkerboard: return pack_detail::pack_pixel_for<StereoInput::Checkerboard>(p, am, in, X, Y);
    case StereoInput::SideBySide:
    default: return pack_detail::pack_pixel_for<StereoInput::SideBySide>(p, am, in, X, Y);
  }
}

}  // namespace p3d
