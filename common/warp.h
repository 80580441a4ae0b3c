// DIBR: render a left and a right view from a frame plus its depth by forward
// warping with depth ordering, then fill the disocclusion holes. CPU
// reference; cuda/warp_gpu.h computes the same function.
//
// Conventions (docs/architecture.md): parallax p = D * (depth - convergence),
// D = max_disparity_percent * width / 100. A view with shift factor s puts
// source pixel x at t(x) = x + s * p(x): s = +1/2 (left) and -1/2 (right) for
// view=both; view=right: left view is the source, right s = -1; view=left:
// right view is the source, left s = +1.
//
// Rendering one view, row by row (rows are independent):
//  * Each source pixel x covers the target integers X with
//      t(x) - 0.5 <= X < t(x) + 0.5                  (its own footprint), and,
//    when it is connected to x+1 (x+1 < W and 0 < t(x+1) - t(x) <= 1 + kMaxStretch),
//      t(x) <= X < t(x+1)                            (the surface between them).
//  * For a covered X the source position is
//      u = x + (X - t(x)) * (1 / (t(x+1) - t(x)))  for X >= t(x) on a connected span,
//      u = x + (X - t(x))                          otherwise,
//    clamped to [0, W-1], and the depth there is depth(x) + (u - x) * (depth(x+1) - depth(x))
//    on a connected span, depth(x) otherwise.
//  * Z-buffer: a covered X gets a WarpHit of two codes, the depth
//    round(65535 d) (d clamped to [0, 1]) and the source position
//    round(256 u) + 1; the target keeps the hit with the larger depth code
//    (the nearest surface), between equal depth codes the larger u code.
//    Nothing landed = hole. A key word orders like (depth code, u code):
//    WideKeys (64 bits) for any row, NarrowKeys (32 bits, u relative to X)
//    where every hit lies within 127 pixels of its target
//    (warp_narrow_keys_fit); 0 is the hole in both. The max is order
//    independent, so the GPU's atomicMax and the CPU's sequential max
//    agree exactly, whichever word holds the keys.
//  * Colour: bilinear along the row between floor(u) and floor(u)+1 of the
//    source (load_rgba), per channel to_u8(a + (b - a) * f) (sample_row, in
//    exact integer arithmetic).
// All float maths is written once in the P3D_HD helpers below; cuda/ is
// compiled with -fmad=false so the host and the device round identically.
// A deep source (P010, I420_10, RGBA64) renders 16-bit views into RGBA64
// with the same rules on 16-bit channels (Rgba16; the smooth fill's sums
// in 64 bits), on the CPU.
//
// Precise reading of the rules above (warp_source / warp_span / warp_hit_at):
//  * "X >= t(x) on a connected span" means t(x) <= X < t(x+1): a footprint
//    target past t(x+1) (possible when t(x+1) - t(x) < 0.5) takes the
//    unit-slope u, so u never runs past the span's far end.
//  * The colour is sampled at the u code of the winning hit (1/256 pixel
//    steps), because that is all the GPU's atomicMax keeps. The depth code
//    has 16 bits so that a 32-bit key holds it beside u: two surfaces
//    nearer than 1/65535 in depth are ordered by u, as one surface is.
//  * The gap's reciprocal is taken once per source pixel (warp_link), so a
//    target costs a multiply where it cost an IEEE division (both sides
//    round it alike: -fmad=false, IEEE reciprocal).
//  * Depth is read through warp_depth(): NaN and values below 0 count as 0
//    (far), values above 1 as 1, so every target is finite.
//  * WarpParams are read through warp_sanitize(): max_disparity clamped to
//    0..kMaxDisparityPercent and convergence to 0..1 (NaN -> 0). With
//    D == 0 both views are the source, copied.
//
// Hole filling (only pixels with key 0 are touched):
//  * BackgroundSmooth (default): the background side of each row, averaged down the
//    column, over the holes. Per rendered view:
//     - Clean pixel: a non-hole with no hole within kSmoothClean pixels of it
//       in its row (smooth_is_clean). The warp's pixels beside a hole mix the
//       colours of both surfaces (bilinear sampling across the depth edge,
//       the source's own anti-aliasing), so anchors are taken a few pixels
//       into the surface (docs/quality.md: Aloe 24.30 / 24.45 / 24.51 /
//       24.54 dB for 1 / 2 / 3 / 4 pixels).
//     - Anchor of every hole X in row y: CL = the nearest clean pixel left of
//       X, or, when the row has none left of X, the nearest non-hole left of
//       X; CR likewise to the right (-1: none). The anchor is the colour
//       (rendered view, before filling) of background_source(X, CL, depth
//       code of CL, CR, depth code of CR): the farther side, as for
//       Background. No non-hole on either side: the hole has no anchor.
//     - Column sums: every hole (X, y) gets V(X, y), the per-channel sums and
//       the count of the anchors of its column's run of holes: the holes
//       (X, y') with |y' - y| <= R such that every pixel from y to y' is a
//       hole. R = smooth_fill_radius(): 1 + floor(|s| D / 2) rows, where s
//       is the eye's shift factor (holes are at most |s| D pixels wide, so
//       the averaging grows with them).
//     - Every hole (X, y) becomes the per-channel rounded mean
//       (sum + n/2) / n of the sums V(X', y) over its row's run of holes: the
//       holes (X', y) with |X' - X| <= Rx = R / 4 (integer division) such
//       that every pixel from X to X' is a hole; n is the total count.
//       n = 0: kFillBlack. Integer sums (uint32, no overflow for the
//       largest R): the result does not depend on the order of summation.
//    Compared with Background, one noisy pixel does not streak along a
//    row, and the colour of a disocclusion is the local mean of the
//    background next to it (docs/quality.md). Everything but the column
//    and row sums is row-local, so the GPU finds the anchors in the warp's
//    row kernel, where the row's keys are at hand.
//  * Background: take the nearest non-hole pixel to the left (XL)
//    and to the right (XR) in the same row of the rendered view; copy the
//    colour of the farther one (smaller depth code; equal depth: the nearer in
//    distance, then XL). One side missing: the other. Neither: black.
//  * NeighborAverage (the paper's inpainting): Jacobi iterations; in each,
//    every remaining hole with at least one non-hole pixel among its 8
//    neighbours (as of the previous iteration) becomes the per-channel
//    rounded mean (sum + n/2) / n of those neighbours, and stops being a hole.
//    Repeat until no hole is left or an iteration changes nothing (then the
//    rest becomes black). Neighbours are read back from the output view
//    (load_rgba of the packed output), never across into the other view.
//  * None: holes are painted kHoleColour (magenta) so they can be seen.
// "Black" is kFillBlack (alpha 255). Fill colours
// are read back from the rendered output (load_rgba), so an RGBx/BGRx output
// carries alpha 255 into the fill, like the GPU.
#pragma once

#include <cstdint>
#include <vector>

#include "change_map.h"
#include "enum_name.h"
#include "frame.h"

namespace p3d {

enum class StereoView : int { Both = 0, Left = 1, Right = 2 };
enum class HoleFill : int { Background = 0, NeighborAverage = 1, None = 2, BackgroundSmooth = 3 };

inline constexpr EnumName<StereoView> kStereoViewNames[] = {
    {StereoView::Both, "both", "Synthesize both views, half the parallax each"},
    {StereoView::Left, "left", "Input is the right view; synthesize the left"},
    {StereoView::Right, "right", "Input is the left view; synthesize the right"},
};
P3D_CHECK_ENUM_NAMES(kStereoViewNames);

inline constexpr EnumName<HoleFill> kHoleFillNames[] = {
    {HoleFill::Background, "background",
     "Extend the background side of each row (depth-aware; cheapest, streaks along rows)"},
    {HoleFill::NeighborAverage, "neighbor-average", "Iterative neighbour-average inpainting"},
    {HoleFill::None, "none", "Leave holes, painted magenta (diagnostics)"},
    {HoleFill::BackgroundSmooth, "background-smooth",
     "Background side of each row, averaged across rows (depth-aware; best quality; costs more than background: "
     "docs/benchmarks.md)"},
};
P3D_CHECK_ENUM_NAMES(kHoleFillNames);

constexpr float kMaxStretch = 2.f;  // a gap wider than 1 + this many pixels is a disocclusion
constexpr Rgba kHoleColour = {255, 0, 255, 255};
constexpr float kMaxDisparityPercent = 25.f;
constexpr Rgba kFillBlack = {0, 0, 0, 255};

struct WarpParams {
  float max_disparity = 3.f;   // percent of frame width, 0..kMaxDisparityPercent
  float convergence = 0.5f;    // depth that lands on the screen plane, 0..1
  StereoView view = StereoView::Both;
  // BackgroundSmooth is the default: the best quality of the fills
  // (docs/quality.md), for a cost on the GPU and the CPU measured in
  // docs/benchmarks.md, Design measurements, "Default fill".
  HoleFill fill = HoleFill::BackgroundSmooth;
};

// Field by field: an adaptive stage recomputes everything when they differ.
inline bool operator==(const WarpParams &a, const WarpParams &b) {
  return a.max_disparity == b.max_disparity && a.convergence == b.convergence && a.view == b.view && a.fill == b.fill;
}
inline bool operator!=(const WarpParams &a, const WarpParams &b) { return !(a == b); }

// Disparity scale D in pixels for a frame width.
P3D_HD float disparity_scale(const WarpParams &p, int width) { return p.max_disparity * static_cast<float>(width) / 100.f; }

// Shift factor of the left (eye 0) and right (eye 1) view; 0 means "the
// source, copied".
P3D_HD float view_shift(StereoView v, int eye) {
  if (v == StereoView::Both) return eye == 0 ? 0.5f : -0.5f;
  if (v == StereoView::Right) return eye == 0 ? 0.f : -1.f;
  return eye == 0 ? 1.f : 0.f;
}

P3D_HD float warp_target(int x, float depth, float shift, float D, float convergence) {
  const float p = D * (depth - convergence);
  return static_cast<float>(x) + shift * p;
}

// A covered target's z-buffer entry: the depth code round(65535 d), d
// clamped to [0, 1], and the source position code round(256 u) + 1 (0 is
// never a u code, so a zero key is a hole). Larger depth codes are nearer.
struct WarpHit {
  unsigned int depth, u;
};
P3D_HD unsigned int warp_depth_code(float d) {
  return static_cast<unsigned int>(clamp_value(d, 0.f, 1.f) * 65535.f + 0.5f);
}
P3D_HD unsigned int warp_u_code(float u) { return static_cast<unsigned int>(u * 256.f + 0.5f) + 1u; }
// The u a code stands for (a multiple of 1/256).
P3D_HD float warp_u_of(unsigned int u_code) { return static_cast<float>(u_code - 1u) / 256.f; }

// Key words: the hit's depth code over its u code, so that the larger word
// is the larger (depth, u) pair, and 0 is the hole.
//  * WideKeys, 64 bits: any row (the CPU's z-buffer, and the GPU's where
//    warp_narrow_keys_fit() does not hold).
//  * NarrowKeys, 32 bits: the u code relative to the target, u - 256 X +
//    32768, in the low 16 bits. For |u code - 256 X| <= 32767 that is
//    1..65535 and orders like u at a fixed X; warp_narrow_keys_fit() says
//    when every hit of a frame is that near. On the GPU a 32-bit key is one
//    shared-memory atomicMax instruction, where 64 bits are a
//    compare-and-swap loop, and it takes half the shared memory.
struct WideKeys {
  using Word = unsigned long long;
  static P3D_HD Word key(WarpHit h, int) { return static_cast<Word>(h.depth) << 32 | h.u; }
  static P3D_HD unsigned int depth(Word k) { return static_cast<unsigned int>(k >> 32); }
  static P3D_HD unsigned int u(Word k, int) { return static_cast<unsigned int>(k); }
};
struct NarrowKeys {
  using Word = unsigned int;
  static P3D_HD Word key(WarpHit h, int X) {
    return h.depth << 16 | ((h.u - 256u * static_cast<unsigned int>(X) + 32768u) & 0xffffu);
  }
  static P3D_HD unsigned int depth(Word k) { return k >> 16; }
  static P3D_HD unsigned int u(Word k, int X) { return (k & 0xffffu) + 256u * static_cast<unsigned int>(X) - 32768u; }
};

// The depth code of a row's key at X, 0 for none (X < 0): what
// background_source() compares.
template <class Keys>
P3D_HD unsigned int key_depth_at(const typename Keys::Word *keys, int X) {
  return X >= 0 ? Keys::depth(keys[X]) : 0u;
}

// Bilinear colour at the source position of a u code (u = q / 256,
// q = u_code - 1), from a source row
// already converted to R'G'B'A (load_rgba of each pixel): both the CPU and
// the GPU convert the row once and render both eyes from it. Per channel the
// colour is to_u8(a + (b - a) * f) between x0 = floor(u) and x0 + 1 (x0
// alone at the row's end), f = u - x0. Because u is a multiple of 1/256 and
// lies in [0, width - 1] (warp_hit_at clamps it), f = k / 256 with k = q & 255,
// and every float step of that formula is exact: (b - a) * k / 256 has at
// most 16 significant bits, a plus it at most 17, so to_u8's floor(v + 0.5)
// equals the integer (256 a + (b - a) k + 128) >> 8, which is what this
// computes (tests/common/test_warp.cpp checks every a, b and k against the
// float formula).
P3D_HD int sample_channel(int a, int b, int k) { return (256 * a + (b - a) * k + 128) >> 8; }
// Px: Rgba, or Rgba16 for the deep formats (16-bit channels: the same
// integers, at most 65535 * 256 + 128 < 2^31).
template <class Px>
P3D_HD Px sample_row(const Px *row, int width, unsigned int u_code) {
  using C = decltype(row->r);
  const unsigned int q = u_code - 1u;
  const int x0 = static_cast<int>(q >> 8);
  if (x0 >= width - 1) return row[width - 1];  // u = width - 1 exactly: k is 0
  const int k = static_cast<int>(q & 255u);
  const Px a = row[x0], b = row[x0 + 1];
  Px o;
  o.r = static_cast<C>(sample_channel(a.r, b.r, k));
  o.g = static_cast<C>(sample_channel(a.g, b.g, k));
  o.b = static_cast<C>(sample_channel(a.b, b.b, k));
  o.a = static_cast<C>(sample_channel(a.a, b.a, k));
  return o;
}

// sample_row() on words: per channel (a (256 - k) + b k + 128) >> 8, which
// is sample_channel()'s (256 a + (b - a) k + 128) >> 8 with no negative
// term, and at most 255 * 256 + 128 < 2^16, so the two 16-bit fields of
// each product never carry into each other (tests/common/test_warp.cpp
// compares it with sample_row()).
P3D_HD uint32_t sample_word(const uint32_t *row, int width, unsigned int u_code) {
  const unsigned q = u_code - 1u;
  const int x0 = static_cast<int>(q >> 8);
  if (x0 >= width - 1) return row[width - 1];
  const unsigned k = q & 255u, k0 = 256u - k;
  const uint32_t a = row[x0], b = row[x0 + 1];
  const uint32_t rb = (((a & 0xff00ffu) * k0 + (b & 0xff00ffu) * k + 0x800080u) >> 8) & 0xff00ffu;
  const uint32_t ga = (((a >> 8) & 0xff00ffu) * k0 + ((b >> 8) & 0xff00ffu) * k + 0x800080u) & 0xff00ff00u;
  return rb | ga;
}
// The same on the 16-bit channels' words (rgba_word of Rgba16): channel by
// channel, as sample_row().
P3D_HD uint64_t sample_word(const uint64_t *row, int width, unsigned int u_code) {
  const unsigned q = u_code - 1u;
  const int x0 = static_cast<int>(q >> 8);
  if (x0 >= width - 1) return row[width - 1];
  const Rgba16 pair[2] = {word_rgba(row[x0]), word_rgba(row[x0 + 1])};
  return rgba_word(sample_row(pair, 2, (q & 255u) + 1u));
}

// ---- Helpers shared by warp_render_cpu and WarpRendererGpu -------------

// The parameters the warp really runs with (see the header comment).
P3D_HD WarpParams warp_sanitize(const WarpParams &p) {
  WarpParams s = p;
  s.max_disparity = p.max_disparity >= 0.f ? (p.max_disparity <= kMaxDisparityPercent ? p.max_disparity
                                                                                       : kMaxDisparityPercent)
                                           : 0.f;
  s.convergence = p.convergence >= 0.f ? (p.convergence <= 1.f ? p.convergence : 1.f) : 0.f;
  return s;
}

// Depth as the warp reads it: NaN and < 0 -> 0, > 1 -> 1.
P3D_HD float warp_depth(float d) { return d >= 0.f ? (d <= 1.f ? d : 1.f) : 0.f; }

// Shift factor an eye is rendered with: 0 (copy the source) for the eye that
// view_shift() leaves alone and for every eye when D == 0.
P3D_HD float warp_eye_shift(const WarpParams &sanitized, float D, int eye) {
  return D > 0.f ? view_shift(sanitized.view, eye) : 0.f;
}

// Source pixel x of one row, placed in a view: its target t(x), its depth,
// and the next pixel's, with whether the two are connected.
struct WarpSource {
  int x;
  float t0, d0;  // pixel x
  float t1, d1;  // pixel x+1 (= x's own values at the row's end)
  float inv_gap;  // 1 / (t1 - t0) when connected, else 0
  bool connected;
};

// The same from pixel x's and x+1's read depth (warp_depth) and target
// (warp_target); has_next is x + 1 < width. Callers that already hold every
// pixel's target (the CPU row) link neighbours without computing them twice.
P3D_HD WarpSource warp_link(int x, float d0, float t0, float d1, float t1, bool has_next) {
  WarpSource s;
  s.x = x;
  s.d0 = d0;
  s.t0 = t0;
  s.t1 = has_next ? t1 : t0;
  s.d1 = has_next ? d1 : d0;
  const float gap = t1 - t0;
  s.connected = has_next && gap > 0.f && gap <= 1.f + kMaxStretch;
  s.inv_gap = s.connected ? 1.f / gap : 0.f;
  return s;
}

// Source pixel x placed in a view with shift factor `shift` from its own and
// its right neighbour's read depths d0, d1 (d1 unused without one): where
// every caller places a source pixel, so that a renderer that reads the
// depths once for both eyes places it as warp_source() does.
P3D_HD WarpSource warp_place(int x, float d0, float d1, bool has_next, float shift, float D, float convergence) {
  const float t0 = warp_target(x, d0, shift, D, convergence);
  const float t1 = has_next ? warp_target(x + 1, d1, shift, D, convergence) : t0;
  return warp_link(x, d0, t0, d1, t1, has_next);
}

P3D_HD WarpSource warp_source(const float *depth_row, int x, int width, float shift, float D, float convergence) {
  const bool has_next = x + 1 < width;
  const float d0 = warp_depth(depth_row[x]);
  return warp_place(x, d0, has_next ? warp_depth(depth_row[x + 1]) : d0, has_next, shift, D, convergence);
}

// Whether x covers target X (footprint or connected span), the rule above
// evaluated in float: a reading for tests. t0 + 0.5f is not always exact
// (t0 = 0.50000006 gives 1), so this can miss the footprint's integer at
// such a boundary; the renderers on both devices take warp_span(), which
// finds it as ceil(t0 - 0.5).
P3D_HD bool warp_covers(const WarpSource &s, int X) {
  const float xf = static_cast<float>(X);
  if (xf >= s.t0 - 0.5f && xf < s.t0 + 0.5f) return true;
  return s.connected && xf >= s.t0 && xf < s.t1;
}

// The targets x covers, clipped to the view: first..last inclusive (empty
// when first > last). The footprint holds the one integer X0 = ceil(t0 - 0.5);
// a connected span adds the integers X with t0 <= X < t1, which start at
// ceil(t0) <= X0 + 1, so the covered set is the run from X0 to
// max(X0, ceil(t1) - 1), at most 2 + 1 + kMaxStretch targets long
// (tests/common/test_warp.cpp checks this against warp_covers() on targets
// where its float reading is exact).
struct WarpSpan {
  int first, last;
};

P3D_HD WarpSpan warp_span(const WarpSource &s, int width) {
  const int X0 = ceil_to_int(s.t0 - 0.5f);
  int last = X0;
  if (s.connected) {
    const int end = ceil_to_int(s.t1) - 1;
    if (end > last) last = end;
  }
  WarpSpan r;
  r.first = X0 < 0 ? 0 : X0;
  r.last = last > width - 1 ? width - 1 : last;
  return r;
}

// The hit x offers target X (X covered by x).
P3D_HD WarpHit warp_hit_at(const WarpSource &s, int X, int width) {
  const float xf = static_cast<float>(X);
  const float x = static_cast<float>(s.x);
  const float hi = static_cast<float>(width - 1);
  if (s.connected && xf >= s.t0 && xf < s.t1) {
    const float u = clamp_value(x + (xf - s.t0) * s.inv_gap, 0.f, hi);
    return WarpHit{warp_depth_code(s.d0 + (u - x) * (s.d1 - s.d0)), warp_u_code(u)};
  }
  const float u = clamp_value(x + (xf - s.t0), 0.f, hi);
  return WarpHit{warp_depth_code(s.d0), warp_u_code(u)};
}

// Whether NarrowKeys hold every hit of a frame: |u - X| < 128 for every
// covered X, with a margin. A footprint target has u - X = x - t(x) =
// -s p(x) (clamping u to the row only brings it nearer X), a connected
// span's u lies in [x, x + 1] for X in [t(x), t(x+1)) (an ulp past x + 1
// at most, through the reciprocal: inside the margin), so |u - X| <= |s| D
// max(c, 1 - c) + 1 for shift factor s, parallax p = D (d - c), d in
// [0, 1]; the u code is then within 256 |u - X| + 2 of 256 X. Read for
// the sanitised parameters and both eyes' shift factors.
P3D_HD bool warp_narrow_keys_fit(float shift0, float shift1, float D, float convergence) {
  const float s0 = shift0 < 0.f ? -shift0 : shift0, s1 = shift1 < 0.f ? -shift1 : shift1;
  const float c = convergence > 0.5f ? convergence : 1.f - convergence;
  return (s0 > s1 ? s0 : s1) * D * c <= 120.f;
}

// Background fill of hole X: xl / xr are the nearest non-holes to its left /
// right in the row (-1: none) with their depth codes. Returns the column whose
// colour fills X, or -1 for black.
P3D_HD int background_source(int X, int xl, unsigned int depth_l, int xr, unsigned int depth_r) {
  if (xl < 0) return xr;
  if (xr < 0) return xl;
  if (depth_l != depth_r) return depth_l < depth_r ? xl : xr;
  return xr - X < X - xl ? xr : xl;
}

// One NeighborAverage (Jacobi) step at hole (X, y) of a view W x H that
// starts at column col0 of the packed output `out`. mask (W x H, row pitch
// mask_pitch bytes) is the hole mask before this step (non-zero = hole).
// Returns false when no neighbour is filled yet; else *c is the rounded mean.
// Neighbours are visited dy outer, dx inner (integer sums: order free).
template <class Px>
P3D_HD bool neighbour_average(const FrameView &out, int col0, const uint8_t *mask, size_t mask_pitch, int width,
                              int height, int X, int y, Px *c) {
  using C = decltype(c->r);
  unsigned int n = 0, r = 0, g = 0, b = 0, a = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    const int yy = y + dy;
    if (yy < 0 || yy >= height) continue;
    const uint8_t *mrow = mask + static_cast<size_t>(yy) * mask_pitch;
    for (int dx = -1; dx <= 1; ++dx) {
      const int xx = X + dx;
      if ((dx == 0 && dy == 0) || xx < 0 || xx >= width || mrow[xx]) continue;
      Px p;
      load_pixel(out, col0 + xx, yy, &p);
      r += p.r;
      g += p.g;
      b += p.b;
      a += p.a;
      ++n;
    }
  }
  if (n == 0) return false;
  c->r = static_cast<C>((r + n / 2) / n);
  c->g = static_cast<C>((g + n / 2) / n);
  c->b = static_cast<C>((b + n / 2) / n);
  c->a = static_cast<C>((a + n / 2) / n);
  return true;
}

// ---- BackgroundSmooth ------------------------------------------------------

// Vertical half-window R of BackgroundSmooth for an eye with shift factor
// `shift` and disparity scale D (both sanitised, so |shift| D <= 0.25 * 8192
// and R <= 1025); the horizontal half-window is smooth_fill_radius_x(R).
P3D_HD int smooth_fill_radius(float shift, float D) {
  const float w = (shift < 0.f ? -shift : shift) * D;
  return 1 + static_cast<int>(w * 0.5f);
}
P3D_HD int smooth_fill_radius_x(int R) { return R / 4; }

// Whether pixel X of a row (hole mask `row`, non-zero = hole, `width`
// pixels) is clean: not a hole, and no hole within kSmoothClean pixels.
constexpr int kSmoothClean = 4;
P3D_HD bool smooth_is_clean(const uint8_t *row, int X, int width) {
  const int x0 = X > kSmoothClean ? X - kSmoothClean : 0;
  const int x1 = X + kSmoothClean < width ? X + kSmoothClean : width - 1;
  for (int x = x0; x <= x1; ++x)
    if (row[x]) return false;
  return true;
}

// Side of an anchor: the nearest clean pixel (neither hole nor ring) on that
// side if there is one, else the nearest non-hole (-1: none).
P3D_HD int smooth_side(int clean, int any) { return clean >= 0 ? clean : any; }

// Integer sums of anchors (per channel) and their count. At most
// (2 Rx + 1)(2 R + 1) < 2^21 anchors of 255 each: no uint32 overflows; the
// 16-bit channels of Rgba16 anchors sum in 64 bits (SmoothSum16).
template <class Acc>
struct SmoothSumOf {
  Acc r, g, b, a;
  unsigned int n;
};
using SmoothSum = SmoothSumOf<unsigned int>;
using SmoothSum16 = SmoothSumOf<unsigned long long>;
// One anchor (Rgba into SmoothSum, Rgba16 into SmoothSum16).
template <class Acc, class Px>
P3D_HD void smooth_add(SmoothSumOf<Acc> &s, Px c) {
  s.r += c.r;
  s.g += c.g;
  s.b += c.b;
  s.a += c.a;
  s.n += 1u;
}
template <class Acc>
P3D_HD void smooth_add(SmoothSumOf<Acc> &s, const SmoothSumOf<Acc> &o) {
  s.r += o.r;
  s.g += o.g;
  s.b += o.b;
  s.a += o.a;
  s.n += o.n;
}
// The sums of prefix[hi] minus prefix[lo] (a window of prefix sums).
template <class Acc>
P3D_HD SmoothSumOf<Acc> smooth_window(const SmoothSumOf<Acc> &hi, const SmoothSumOf<Acc> &lo) {
  return SmoothSumOf<Acc>{hi.r - lo.r, hi.g - lo.g, hi.b - lo.b, hi.a - lo.a, hi.n - lo.n};
}
// The rounded mean of a sum; kFillBlack for an empty one.
template <class Px, class Acc>
P3D_HD Px smooth_mean_of(const SmoothSumOf<Acc> &s) {
  using C = decltype(Px{}.r);
  if (s.n == 0u) return colour_as<Px>(kFillBlack);
  const Acc h = s.n / 2u;
  Px c;
  c.r = static_cast<C>((s.r + h) / s.n);
  c.g = static_cast<C>((s.g + h) / s.n);
  c.b = static_cast<C>((s.b + h) / s.n);
  c.a = static_cast<C>((s.a + h) / s.n);
  return c;
}
P3D_HD Rgba smooth_mean(const SmoothSum &s) { return smooth_mean_of<Rgba>(s); }
P3D_HD Rgba16 smooth_mean(const SmoothSum16 &s) { return smooth_mean_of<Rgba16>(s); }
// The sum type of a pixel type's anchors.
template <class Px>
struct SmoothSumFor {
  using Type = SmoothSum;
};
template <>
struct SmoothSumFor<Rgba16> {
  using Type = SmoothSum16;
};

// Whether the frames fit together: src W x H (W, H > 0), depth W x H (a
// DepthGrid, the GPU's input, of that picture with cells that fit it), out
// packed RGB 2W x H. A deep source renders 16-bit views (Rgba16) into an
// RGBA64 output; the 8-bit formats render Rgba into 8-bit packed RGB.
inline bool warp_frames_fit(const FrameView &src, const DepthGrid<const float> &depth, const FrameView &out) {
  return src.width > 0 && src.height > 0 && src.plane[0] && depth.cells.data && depth.width == src.width &&
         depth.height == src.height && grid_fits(depth) && out.plane[0] && is_packed_rgb(out.format) &&
         out.width == 2 * src.width && out.height == src.height && is_deep(src.format) == is_deep(out.format);
}
inline bool warp_frames_fit(const FrameView &src, ImageView<const float> depth, const FrameView &out) {
  return warp_frames_fit(src, full_grid(depth), out);
}

// Renders the stereo pair side by side into `out` (packed RGB, 2W x H: left
// view in columns [0, W), right in [W, 2W)). A view with shift 0 is the
// source converted (load_rgba), no warping. Returns the number of hole pixels
// the warp left before filling, both views together (0: the fill pass did
// not run), or -1 when the frames do not fit (warp_frames_fit; nothing is
// written).
long long warp_render_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &out);

// What the CPU warp keeps from one frame to the next: BackgroundSmooth's
// per-pixel state and anchor planes (5 bytes a pixel and eye, 20 MB at
// 1080p). Allocated per frame they cost page faults worth more than the
// fill itself, so a caller that renders a stream keeps one and passes it
// to every frame (one call at a time); the overload above uses a fresh one.
struct WarpCpuScratch {
  std::vector<uint8_t> smooth_state[2];
  std::vector<Rgba> smooth_anchor[2];
  std::vector<Rgba16> smooth_anchor16[2];  // deep frames' anchors
};
long long warp_render_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &out, WarpCpuScratch &scratch);

// The adaptive warp: changed[y] (one span a source row, null: every row
// whole) holds the columns of row y whose source or depth changed since
// the previous call with this scratch, the same parameters and the same
// frame geometry; `out` holds that call's output. In each changed row the
// warp renders again the targets those columns can reach (their spans'
// reach, and for BackgroundSmooth out to a clean pixel on either side
// that the change cannot touch; Background and NeighborAverage: the whole
// row, NeighborAverage every row), and the fill runs over what those
// reach (BackgroundSmooth: R rows and Rx columns more); every other pixel
// of out and of scratch is left as it is, which is what a call over
// everything would write there. Returns the holes of the rendered
// targets, or -1 as above (also when changed has not one span a row or a
// span leaves the picture).
long long warp_render_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &out, WarpCpuScratch &scratch,
                          const std::vector<ColumnSpan> *changed);
// The output rows of both views that the adaptive warp rewrites when the
// spans `changed` changed: those within warp_rows_reach() of a changed row.
std::vector<uint8_t> warp_rows_written(const WarpParams &params, int width, const std::vector<ColumnSpan> &changed);
// How many rows up and down a changed source row reaches in the output of
// a width x height picture (the source and depth of a row only reach
// targets in that row): BackgroundSmooth's smooth_fill_radius(),
// NeighborAverage the whole picture (its steps cross it), 0 for the fills
// that stay in the row. The adaptive warp on CUDA memory renders the rows
// within it of a changed tile's rows again.
int warp_rows_reach(const WarpParams &params, int width, int height);

}  // namespace p3d
