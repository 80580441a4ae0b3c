// Cross (joint) bilateral filter of a depth map guided by the frame's luma,
// so that depth edges follow image edges. CPU reference;
// cuda/bilateral_gpu.h computes the same function.
//
// out(p) = sum_q w(p,q) * depth(q) / sum_q w(p,q), q over the
// (2*radius+1)^2 window clipped to the image (no padding), with
//   w(p,q) = space_weight(|p-q|^2) * range_weight(guide(p) - guide(q)),
//   space_weight(d2) = exp(-d2 / (2 sigma_space^2)),
//   range_weight(g)  = exp(-g^2 / (2 sigma_range^2)), and for sigma_range == 0:
//                      1 where g == 0, else 0;
// either weight under kBilateralMinWeight (2^-60) is 0.
// The centre weight is exactly 1, so the sum never underflows to 0 and the
// result of finite depth is never NaN. It is computed as depth(p) + sum_q w(p,q) *
// (depth(q) - depth(p)) / sum_q w(p,q) (bilateral_accumulate): a window of
// one depth value, and so a constant depth map, comes back bit for bit.
// sigma_range -> 0 averages only over pixels with the centre's exact guide
// value.
// guide(p) is load_luma() of the frame (8-bit). radius 0 is the identity (the
// element passes the buffer through).
//
// Out-of-range parameters (bilateral_sanitize(), applied by both the CPU and
// the GPU filter) are mapped to the nearest meaningful filter, never to NaN:
//   radius < 0 -> 0 (identity), radius > kMaxBilateralRadius -> kMaxBilateralRadius;
//   sigma_space <= 0 or NaN -> radius 0 (the identity, the sigma_space -> 0 limit);
//   sigma_range < 0 or NaN -> 0 (exact guide match only);
//   tiny sigmas whose square underflows act as their -> 0 limit and huge
//   ones (up to +inf) as a plain box / range-blind average;
//   a mode other than Separable -> Exact;
//   scale < 0 -> 1, scale > kMaxBilateralScale -> kMaxBilateralScale (0
//   stays automatic).
// Summation order (both sides, bit-identical results): dy outer from -r to r,
// dx inner from -r to r, window clipped to the image.
//
// mode = Separable: an approximation (Pham & van Vliet 2005) in two 1-D
// passes of 2r+1 taps each instead of (2r+1)^2, with the same weights:
//   mid(p) = sum_dx w(p, p+(dx,0)) depth(p+(dx,0)) / sum_dx w(p, p+(dx,0)),
//   out(p) = sum_dy w(p, p+(0,dy)) mid(p+(0,dy))  / sum_dy w(p, p+(0,dy)),
// dx (dy) from -r to r clipped to the image, w as above (the centre's guide
// against the tap's). Where depth and guide vary along one axis only it
// equals the exact filter up to float rounding (the window factorises);
// elsewhere a pixel reaches a diagonal neighbour only through an L-shaped
// path, so single pixels at depth corners can differ from the exact filter by
// tens of levels, the mean by tenths of a level (docs/quality.md). Its time
// grows linearly with the radius, the exact window's quadratically.
//
// scale = s > 1: the filter above runs on a grid s times coarser in each
// direction, and each of its results is spread over its s x s cell:
//   cells:   W' = ceil(W / s), H' = ceil(H / s); cell (X, Y) holds the
//            pixels sX..sX+s-1 x sY..sY+s-1 that lie inside the image;
//   guide':  the mean of the cell's guide lumas, rounded (integer:
//            (sum + n / 2) / n over its n pixels; bilateral_cell_luma());
//   depth':  the depth of the cell's first pixel, depth(sX, sY): exact for
//            the estimator's piecewise-constant map when s divides its block
//            (bilateral_auto_scale() does at 4K and 8K);
//   filter:  either mode above on (guide', depth') with radius ceil(r / s)
//            and sigma_space / s (bilateral_coarse_params()): the same reach
//            in the picture;
//   out(x, y) = out'(x / s, y / s).
// Depth edges then follow image edges to a cell, not a pixel; the filter
// does about s^2 times less work (more where the radius rounds down). The
// quality cost at 4K and 8K is measured in docs/quality.md. Radius 0 is the
// identity at every scale. scale 0 is automatic (bilateral_auto_scale()).
#pragma once

#include "frame.h"
#include "enum_name.h"

namespace p3d {

constexpr int kMaxBilateralRadius = 16;
constexpr int kBilateralRangeTableSize = 256;  // |guide difference| 0..255

enum class BilateralMode : int { Exact = 0, Separable = 1 };

inline constexpr EnumName<BilateralMode> kFilterModeNames[] = {
    {BilateralMode::Exact, "exact", "Every pixel of the (2r+1) x (2r+1) window"},
    {BilateralMode::Separable, "separable", "A row pass, then a column pass: 2 (2r+1) taps"},
};
P3D_CHECK_ENUM_NAMES(kFilterModeNames);

// The mode pseudo3dfilter and the tools run by default. Separable: a few
// times faster than Exact on the CPU and the GPU (docs/benchmarks.md,
// Design measurements, "Filter"), and its measured quality is within noise
// of Exact's (Aloe right view through the warp, depth rank, vtest.avi
// static-background flicker; docs/quality.md). BilateralParams() itself
// stays Exact: the definition the references and their tests start from.
constexpr BilateralMode kDefaultFilterMode = BilateralMode::Separable;

constexpr int kMaxBilateralScale = 8;
// scale 0 (automatic): step 1 (every pixel) below kAutoFilterGridRows rows
// of the picture's shorter side, kAutoFilterStep from there: cells of 4 x 4
// pixels at 4K and at 8K. At 4K that is depth_estimate.h's automatic block
// (one per 540 rows), at 8K half of it, so there a cell never straddles
// two of the estimator's blocks where both are automatic. Step 4 rather
// than 2 at 4K: the filter is cheaper and the warp's row groups share one
// scatter between 4 rows, and the quality on Aloe enlarged to 4K is no
// worse than step 2's (measured: docs/quality.md, "The filter on a coarser
// grid"; docs/benchmarks.md, Design measurements, "Filter").
constexpr int kAutoFilterGridRows = 2160;
constexpr int kAutoFilterStep = 4;

struct BilateralParams {
  int radius = 5;             // 0..kMaxBilateralRadius, in pixels of the picture
  float sigma_space = 3.f;    // pixels of the picture, > 0
  float sigma_range = 12.f;   // 8-bit guide levels, >= 0
  BilateralMode mode = BilateralMode::Exact;
  int scale = 1;              // 1..kMaxBilateralScale: the grid step; 0 = bilateral_auto_scale()
};

// Field by field: an adaptive stage recomputes everything when they differ.
inline bool operator==(const BilateralParams &a, const BilateralParams &b) {
  return a.radius == b.radius && a.sigma_space == b.sigma_space && a.sigma_range == b.sigma_range &&
         a.mode == b.mode && a.scale == b.scale;
}
inline bool operator!=(const BilateralParams &a, const BilateralParams &b) { return !(a == b); }

// The grid step the filter takes at a picture size (scale 0) on a frame of
// width x height.
P3D_HD int bilateral_auto_scale(int width, int height) {
  return (width < height ? width : height) < kAutoFilterGridRows ? 1 : kAutoFilterStep;
}

// pseudo3dfilter's defaults: BilateralParams() in kDefaultFilterMode at the
// automatic scale (full resolution up to 1080p, as before the scale existed).
// The element and the tools that stand for it (pseudo3d-bench,
// pseudo3d-quality) start from these.
inline BilateralParams default_filter_params() {
  BilateralParams p;
  p.mode = kDefaultFilterMode;
  p.scale = 0;
  return p;
}

// The parameters the filter really runs with (see the header comment).
inline BilateralParams bilateral_sanitize(const BilateralParams &p) {
  BilateralParams s = p;
  s.radius = clamp_value(p.radius, 0, kMaxBilateralRadius);
  if (!(p.sigma_space > 0.f)) {
    s.radius = 0;
    s.sigma_space = 1.f;  // unused at radius 0; canonical so equal inputs compare equal
  }
  if (!(p.sigma_range > 0.f)) s.sigma_range = 0.f;
  if (p.mode != BilateralMode::Separable) s.mode = BilateralMode::Exact;
  s.scale = p.scale == 0 ? 0 : clamp_value(p.scale, 1, kMaxBilateralScale);
  return s;
}

// The grid step of sanitised parameters on a width x height frame: 1 at
// radius 0 (the identity needs no grid).
P3D_HD int bilateral_effective_scale(const BilateralParams &sanitised, int width, int height) {
  if (sanitised.radius == 0) return 1;
  return sanitised.scale == 0 ? bilateral_auto_scale(width, height) : sanitised.scale;
}

// The grid (p3d_defs.h DepthGrid) that holds the filter's output with one
// value a cell: log2 s where the step s is a power of two above 1 (the
// automatic 4 from 2160 rows up; not a step of 3), else 0, the full-size
// map.
P3D_HD int bilateral_grid_shift(const BilateralParams &sanitised, int width, int height) {
  const int s = step_shift(bilateral_effective_scale(sanitised, width, height));
  return s > 0 ? s : 0;
}

// The parameters the coarse grid's filter runs with at step s (see the
// header comment): the same reach in the picture, scale 1. At s = 1 the
// sanitised parameters themselves, at scale 1.
inline BilateralParams bilateral_coarse_params(const BilateralParams &sanitised, int s) {
  BilateralParams c = sanitised;
  c.scale = 1;
  if (s <= 1) return c;
  c.radius = (sanitised.radius + s - 1) / s;
  c.sigma_space = sanitised.sigma_space / static_cast<float>(s);
  return bilateral_sanitize(c);
}

// Cells of a grid of step s along an axis of `pixels`.
P3D_HD int bilateral_cells(int pixels, int s) { return (pixels + s - 1) / s; }

// guide' of cell (cx, cy) at step s (>= 1): the rounded mean of the luma of
// its pixels inside the image; load_luma() itself at s = 1.
P3D_HD int bilateral_cell_luma(const FrameView &guide, int cx, int cy, int s) {
  if (s == 1) return load_luma(guide, cx, cy);
  const int x0 = cx * s, y0 = cy * s;
  const int x1 = x0 + s < guide.width ? x0 + s : guide.width;
  const int y1 = y0 + s < guide.height ? y0 + s : guide.height;
  int sum = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) sum += load_luma(guide, x, y);
  const int n = (x1 - x0) * (y1 - y0);
  return (sum + n / 2) / n;
}

// Number of floats of the space table for a (sanitised) radius.
inline int bilateral_space_table_size(int radius) { return (2 * radius + 1) * (2 * radius + 1); }

// Weight helpers shared with the kernel. The kernel may tabulate
// space_weight per (dx, dy) and range_weight per |g| in 0..255 (the tables
// are computed by these same functions on the host), so both sides use
// identical weights. The zero-distance weights are returned as exactly 1
// without evaluating d/(2 sigma^2), which would be 0/0 when sigma^2
// underflows to 0.
//
// A weight under kBilateralMinWeight counts as 0, so that a product of two
// table weights is 0 or at least 2^-120, a normal float: on x86 CPUs an
// operation on a subnormal float costs many times a normal one, and
// strong guide edges (luma steps of 159 to 173 levels at the default
// sigma_range 12) would give subnormal range weights. The dropped weights
// (at most 33 x 33 of them, each under 2^-60 of the centre's 1) move a
// result by less than 2^-48 of the window's depth range, far under
// float's resolution of depths near 1.
constexpr float kBilateralMinWeight = 0x1p-60f;
inline float bilateral_kept_weight(float w) { return w < kBilateralMinWeight ? 0.f : w; }
inline float bilateral_space_weight(const BilateralParams &p, int dx, int dy) {
  const int d2 = dx * dx + dy * dy;
  if (d2 == 0) return 1.f;
  const float denom = 2.f * p.sigma_space * p.sigma_space;
  if (!(denom > 0.f)) return 0.f;
  return bilateral_kept_weight(expf(-static_cast<float>(d2) / denom));
}
inline float bilateral_range_weight(const BilateralParams &p, int absdiff) {
  if (absdiff == 0) return 1.f;
  if (!(p.sigma_range > 0.f)) return 0.f;
  const float denom = 2.f * p.sigma_range * p.sigma_range;
  if (!(denom > 0.f)) return 0.f;
  return bilateral_kept_weight(expf(-static_cast<float>(absdiff * absdiff) / denom));
}

// Tables the filter uses (host side): space[(dy+r)*(2r+1)+(dx+r)], range[0..255],
// for r = bilateral_sanitize(p).radius (space needs
// bilateral_space_table_size(r) floats, range kBilateralRangeTableSize).
void bilateral_tables(const BilateralParams &p, float *space, float *range);

// The range table mirrored, so that a lookup by the signed guide difference
// g in -255..255 needs no |g| (no branch on its sign): the
// kBilateralSignedRangeSize floats at signed_range hold range[|g|] at index
// g + kBilateralRangeTableSize - 1. Fill the upper half, from that index on,
// with the 256-entry range table (bilateral_tables writes it there), then
// call this to mirror it into the lower half. Both the CPU strips and the
// GPU kernels look the weights up this way.
constexpr int kBilateralSignedRangeSize = 2 * kBilateralRangeTableSize - 1;
inline void bilateral_mirror_range(float *signed_range) {
  float *centre = signed_range + kBilateralRangeTableSize - 1;
  for (int g = 1; g < kBilateralRangeTableSize; ++g) centre[-g] = centre[g];
}

// One tap of the window: the float operations every path performs, in this
// order, so that all of them round alike. The tap's depth enters as its
// difference from the centre pixel's (`centre`), and the output is the
// centre plus the weighted mean difference (bilateral_result): a window of
// one depth value sums differences of exactly 0 and returns that value,
// bit for bit, whatever the weights, so the filter leaves a constant depth
// map (a flat scene) as it is and a stage may skip it there.
P3D_HD void bilateral_accumulate(float space_w, float range_w, float depth, float centre, float &sum_w,
                                 float &sum_wd) {
  const float w = space_w * range_w;
  sum_w += w;
  sum_wd += w * (depth - centre);
}
P3D_HD float bilateral_result(float centre, float sum_w, float sum_wd) { return centre + sum_wd / sum_w; }

// One output pixel: the shared per-pixel maths of the CPU loop and the kernel.
// guide(qx, qy) returns the 8-bit guide value and depth(qx, qy) the input
// depth of an image pixel (the kernel reads both from shared-memory tiles);
// (x, y) is inside the width x height image. The kernel's fast path for
// windows that need no clipping (cuda/bilateral.cu) visits the same taps in
// the same order through bilateral_accumulate().
template <typename GuideFn, typename DepthFn>
P3D_HD float bilateral_pixel(int x, int y, int width, int height, int radius, const float *space,
                             const float *range, const GuideFn &guide, const DepthFn &depth) {
  const int side = 2 * radius + 1;
  const int centre = guide(x, y);
  const int y0 = y - radius < 0 ? 0 : y - radius;
  const int y1 = y + radius > height - 1 ? height - 1 : y + radius;
  const int x0 = x - radius < 0 ? 0 : x - radius;
  const int x1 = x + radius > width - 1 ? width - 1 : x + radius;
  const float centre_depth = depth(x, y);
  float sum_w = 0.f, sum_wd = 0.f;
  for (int qy = y0; qy <= y1; ++qy) {
    const float *space_row = space + (qy - y + radius) * side + radius;  // index by qx - x
    for (int qx = x0; qx <= x1; ++qx) {
      const int g = static_cast<int>(guide(qx, qy)) - centre;
      bilateral_accumulate(space_row[qx - x], range[g < 0 ? -g : g], depth(qx, qy), centre_depth, sum_w, sum_wd);
    }
  }
  return bilateral_result(centre_depth, sum_w, sum_wd);
}

// One pass of the Separable mode at (x, y): taps along x (step_x 1, step_y 0,
// `length` = width) or along y (0, 1, `length` = height), clipped to
// 0..length-1, in ascending order. `space` is the (2r+1)^2 table; the 1-D
// weights are its centre row, space(d, 0) = space(0, d). guide(qx, qy) and
// depth(qx, qy) as for bilateral_pixel.
template <typename GuideFn, typename DepthFn>
P3D_HD float bilateral_pass_pixel(int x, int y, int step_x, int step_y, int length, int radius, const float *space,
                                  const float *range, const GuideFn &guide, const DepthFn &depth) {
  const int centre = guide(x, y);
  const int pos = step_x ? x : y;
  const int d0 = pos - radius < 0 ? -pos : -radius;
  const int d1 = pos + radius > length - 1 ? length - 1 - pos : radius;
  const float *space_row = space + radius * (2 * radius + 1) + radius;  // index by d
  const float centre_depth = depth(x, y);
  float sum_w = 0.f, sum_wd = 0.f;
  for (int d = d0; d <= d1; ++d) {
    const int qx = x + d * step_x, qy = y + d * step_y;
    const int g = static_cast<int>(guide(qx, qy)) - centre;
    bilateral_accumulate(space_row[d], range[g < 0 ? -g : g], depth(qx, qy), centre_depth, sum_w, sum_wd);
  }
  return bilateral_result(centre_depth, sum_w, sum_wd);
}

// depth_in and depth_out may alias (the CPU copies the input first; the GPU
// filter refuses). params.mode picks the exact window or the separable
// passes (the CPU holds the row pass in a scratch image). guide has the depth map's size (checked: cv::Exception
// otherwise). Empty images are a no-op.
void bilateral_filter_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                          ImageView<float> depth_out);

// Whether the filter returns `depth` itself, bit for bit, whatever the
// guide and the parameters: a map of one finite value (every window sums
// differences of 0; bilateral_accumulate) other than -0 (to which the +0
// difference adds up as +0; an infinite centre gives inf - inf = NaN).
// An adaptive stage passes such a map on unfiltered: a flat scene costs
// the filter one read of the map. The scan stops at the first value that
// differs.
bool bilateral_keeps(ImageView<const float> depth);

// How far, in pixels across and down, a change of the guide or of the
// depth can move the filter's output (the adaptive stages recompute the
// tiles within this reach of a changed one): the radius, or at a grid
// step s the coarse radius plus one cell, in pixels.
int bilateral_reach(const BilateralParams &params, int width, int height);

}  // namespace p3d

#if !defined(__CUDACC__)
#include <vector>

#include <opencv2/core.hpp>

#include "change_map.h"

namespace p3d {
// The guide's 8-bit luma (load_luma) of every pixel, computed once: the
// window reads each value up to (2r+1)^2 times. Host code only (OpenCV).
cv::Mat bilateral_guide_luma(const FrameView &guide);

// The CPU filter's working images, kept by a caller that filters a stream
// so that a frame allocates nothing.
struct BilateralScratch {
  cv::Mat luma, mid, cell_depth, cell_out;
};
// The filter's output over the rectangles `where` only; the rest of
// depth_out is left as it is. Each pixel gets the bits that the call over
// the whole picture gives it.
void bilateral_filter_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                          ImageView<float> depth_out, const std::vector<PixelRect> &where, BilateralScratch &scratch);
}  // namespace p3d
#endif
