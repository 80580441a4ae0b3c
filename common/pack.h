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
// for the others the eye behind the single-channel filter gets luma);
// Gray: both eyes as luma.
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

// Whole frame. out must have pack_size()'s size and the input's format.
void pack_cpu(const PackParams &params, const FrameView &in, const FrameView &out);

}  // namespace p3d
