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
//      u = x + (X - t(x)) / (t(x+1) - t(x))  for X >= t(x) on a connected span,
//      u = x + (X - t(x))                    otherwise,
//    clamped to [0, W-1], and the depth there is depth(x) + (u - x) * (depth(x+1) - depth(x))
//    on a connected span, depth(x) otherwise.
//  * Z-buffer: warp_key(depth, u) packs (float bits of depth) << 32 | fixed(u)+1;
//    the target keeps the largest key (the nearest surface; ties: larger u).
//    Key 0 = nothing landed = hole. The max is order independent, so the
//    GPU's atomicMax and the CPU's sequential max agree exactly.
//  * Colour: bilinear along the row between floor(u) and floor(u)+1 of the
//    source (load_rgba), per channel to_u8(a + (b - a) * f).
// All float maths is written once in the P3D_HD helpers below; cuda/ is
// compiled with -fmad=false so the host and the device round identically.
//
// Hole filling (only pixels with key 0 are touched):
//  * Background (default): take the nearest non-hole pixel to the left (XL)
//    and to the right (XR) in the same row of the rendered view; copy the
//    colour of the farther one (smaller key depth; equal depth: the nearer in
//    distance, then XL). One side missing: the other. Neither: black.
//  * NeighborAverage (the paper's inpainting): Jacobi iterations; in each,
//    every remaining hole with at least one non-hole pixel among its 8
//    neighbours (as of the previous iteration) becomes the per-channel
//    rounded mean (sum + n/2) / n of those neighbours, and stops being a hole.
//    Repeat until no hole is left or an iteration changes nothing (then the
//    rest becomes black).
//  * None: holes are painted kHoleColour (magenta) so they can be seen.
#pragma once

#include <cstdint>

#include "frame.h"

namespace p3d {

enum class StereoView : int { Both = 0, Left = 1, Right = 2 };
enum class HoleFill : int { Background = 0, NeighborAverage = 1, None = 2 };

constexpr float kMaxStretch = 2.f;  // a gap wider than 1 + this many pixels is a disocclusion
constexpr Rgba kHoleColour = {255, 0, 255, 255};
constexpr float kMaxDisparityPercent = 25.f;

struct WarpParams {
  float max_disparity = 3.f;   // percent of frame width, 0..kMaxDisparityPercent
  float convergence = 0.5f;    // depth that lands on the screen plane, 0..1
  StereoView view = StereoView::Both;
  HoleFill fill = HoleFill::Background;
};

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

P3D_HD unsigned long long warp_key(float depth, float u) {
  // depth >= 0, so its IEEE bits order like the value. +1 keeps key 0 free.
  union {
    float f;
    unsigned int i;
  } bits;
  bits.f = depth < 0.f ? 0.f : depth;
  const unsigned int uq = static_cast<unsigned int>(u * 256.f + 0.5f) + 1u;
  return (static_cast<unsigned long long>(bits.i) << 32) | uq;
}
P3D_HD float warp_key_depth(unsigned long long key) {
  union {
    float f;
    unsigned int i;
  } bits;
  bits.i = static_cast<unsigned int>(key >> 32);
  return bits.f;
}
P3D_HD float warp_key_u(unsigned long long key) {
  return static_cast<float>(static_cast<unsigned int>(key & 0xffffffffu) - 1u) / 256.f;
}

// Bilinear colour at source position u of row y.
P3D_HD Rgba sample_row(const FrameView &src, float u, int y, const YuvToRgb &m) {
  int x0 = static_cast<int>(floorf(u));
  x0 = clamp_value(x0, 0, src.width - 1);
  const int x1 = x0 + 1 < src.width ? x0 + 1 : x0;
  const float f = u - static_cast<float>(x0);
  const Rgba a = load_rgba(src, x0, y, m), b = load_rgba(src, x1, y, m);
  Rgba o;
  o.r = to_u8(a.r + (static_cast<float>(b.r) - a.r) * f);
  o.g = to_u8(a.g + (static_cast<float>(b.g) - a.g) * f);
  o.b = to_u8(a.b + (static_cast<float>(b.b) - a.b) * f);
  o.a = to_u8(a.a + (static_cast<float>(b.a) - a.a) * f);
  return o;
}

// Renders the stereo pair side by side into `out` (packed RGB, 2W x H: left
// view in columns [0, W), right in [W, 2W)). A view with shift 0 is the
// source converted (load_rgba), no warping. Returns the number of hole pixels
// the warp left before filling (0: the fill pass did not run).
long long warp_render_cpu(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                          ImageView<const float> depth, const FrameView &out);

}  // namespace p3d
