// Packing a full-resolution side-by-side stereo pair (the warp's output) into
// a display or delivery format. CPU reference; cuda/pack_gpu.h computes the
// same function. Input and output are packed RGB frames of one format.
//
// Let L(x, y) and R(x, y) be the left and right views (W x H each) of the
// input (left in columns [0, W) and right in [W, 2W), swapped when
// swap_eyes). Output pixel (X, Y) for each layout:
//   SideBySide        2W x H   L | R                 (the input itself unless swap_eyes)
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
//                              on 0..255 R'G'B', then to_u8), alpha from L.
// Anaglyph matrices (anaglyph_matrices()): Dubois' least-squares matrices for
// red-cyan, green-magenta and amber-blue glasses; Color: each eye's channels
// pass through its filter (red-cyan: R from L, G and B from R); HalfColor:
// the left eye's channel is L's luma, the other eye in colour (for red-cyan;
// for the others the eye behind the single-channel filter gets luma:
// green-magenta the left, amber-blue the right eye); Gray: both eyes as luma.
// Color/HalfColor/Gray are matrices too (luma rows: rgb_luma's BT.601
// weights), so every anaglyph takes the one path out = Ml * L + Mr * R,
// evaluated as (Ml row . L) + (Mr row . R), each dot left to right.
#pragma once

#include "frame.h"

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
enum class AnaglyphMethod : int { Dubois = 0, Color, HalfColor, Gray };

struct PackParams {
  PackLayout layout = PackLayout::Anaglyph;
  AnaglyphGlasses glasses = AnaglyphGlasses::RedCyan;
  AnaglyphMethod method = AnaglyphMethod::Dubois;
  bool swap_eyes = false;
};

// Row-major 3x3 matrices: out.r = m[0]*c.r + m[1]*c.g + m[2]*c.b, ...
struct AnaglyphMatrices {
  float left[9];
  float right[9];
};
AnaglyphMatrices anaglyph_matrices(AnaglyphGlasses g, AnaglyphMethod m);

// Output size for an input pair of width 2*view_width.
void pack_size(PackLayout layout, int view_width, int view_height, int *out_width, int *out_height);

// Width of the left half in the half formats: ceil(W/2) (the right half
// gets the rest, so odd widths lose no column of the output frame).
P3D_HD int half_split(int n) { return (n + 1) / 2; }

// Output pixel (X, Y). `in` is the 2W x H pair, W = in.width / 2. Defined
// in this header (below) so the kernel calls the very same code.
P3D_HD Rgba pack_pixel(const PackParams &p, const AnaglyphMatrices &am, const FrameView &in, int X, int Y);

// Whether pack_cpu/pack_gpu accept these arguments: enums in range, in and
// out packed RGB of one format, in of even width >= 2 and height >= 1, out of
// pack_size()'s size, and no view's stride shorter than its rows.
bool pack_args_valid(const PackParams &params, const FrameView &in, const FrameView &out);

// Whole frame. out must have pack_size()'s size and the input's format;
// throws std::invalid_argument (writing nothing) when pack_args_valid() fails.
void pack_cpu(const PackParams &params, const FrameView &in, const FrameView &out);

// ---- per-pixel implementation ----------------------------------------------

namespace pack_detail {

// Pixel (x, y) of the left (eye 0) or right (eye 1) view of the pair.
P3D_HD Rgba view_pixel(const FrameView &in, bool swap_eyes, int eye, int x, int y) {
  const int w = in.width / 2;
  const bool right_half = (eye == 1) != swap_eyes;
  const YuvToRgb unused;  // packed RGB only: the conversion is never applied
  return load_rgba(in, right_half ? x + w : x, y, unused);
}

// Rounded per-channel mean: what the half formats store for a pair of samples.
P3D_HD uint8_t mean2(uint8_t a, uint8_t b) { return static_cast<uint8_t>((a + b + 1) / 2); }
P3D_HD Rgba mean2(Rgba a, Rgba b) { return Rgba{mean2(a.r, b.r), mean2(a.g, b.g), mean2(a.b, b.b), mean2(a.a, b.a)}; }

// Row `row` of a 3x3 matrix times (r, g, b). One fixed evaluation order, so
// the host (-ffp-contract=off) and the device (-fmad=false) round alike.
P3D_HD float mat_row(const float *m, int row, float r, float g, float b) {
  return m[3 * row] * r + m[3 * row + 1] * g + m[3 * row + 2] * b;
}

P3D_HD Rgba anaglyph(const AnaglyphMatrices &am, Rgba l, Rgba r) {
  const float lr = l.r, lg = l.g, lb = l.b, rr = r.r, rg = r.g, rb = r.b;
  Rgba o;
  o.r = to_u8(mat_row(am.left, 0, lr, lg, lb) + mat_row(am.right, 0, rr, rg, rb));
  o.g = to_u8(mat_row(am.left, 1, lr, lg, lb) + mat_row(am.right, 1, rr, rg, rb));
  o.b = to_u8(mat_row(am.left, 2, lr, lg, lb) + mat_row(am.right, 2, rr, rg, rb));
  o.a = l.a;
  return o;
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

}  // namespace pack_detail

P3D_HD Rgba pack_pixel(const PackParams &p, const AnaglyphMatrices &am, const FrameView &in, int X, int Y) {
  using namespace pack_detail;
  const int w = in.width / 2, h = in.height;
  const bool sw = p.swap_eyes;
  switch (p.layout) {
    case PackLayout::SideBySide:
      return X < w ? view_pixel(in, sw, 0, X, Y) : view_pixel(in, sw, 1, X - w, Y);
    case PackLayout::TopBottom:
      return Y < h ? view_pixel(in, sw, 0, X, Y) : view_pixel(in, sw, 1, X, Y - h);
    case PackLayout::SideBySideHalf: {
      int x0, x1;
      const int eye = half_source(X, w, &x0, &x1);
      return mean2(view_pixel(in, sw, eye, x0, Y), view_pixel(in, sw, eye, x1, Y));
    }
    case PackLayout::TopBottomHalf: {
      int y0, y1;
      const int eye = half_source(Y, h, &y0, &y1);
      return mean2(view_pixel(in, sw, eye, X, y0), view_pixel(in, sw, eye, X, y1));
    }
    case PackLayout::RowInterleaved:
      return view_pixel(in, sw, Y & 1, X, Y);
    case PackLayout::ColumnInterleaved:
      return view_pixel(in, sw, X & 1, X, Y);
    case PackLayout::Checkerboard:
      return view_pixel(in, sw, (X + Y) & 1, X, Y);
    case PackLayout::Left:
      return view_pixel(in, sw, 0, X, Y);
    case PackLayout::Right:
      return view_pixel(in, sw, 1, X, Y);
    case PackLayout::Anaglyph:
    default:
      return anaglyph(am, view_pixel(in, sw, 0, X, Y), view_pixel(in, sw, 1, X, Y));
  }
}

}  // namespace p3d
