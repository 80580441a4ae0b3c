// Cross (joint) bilateral filter of a depth map guided by the frame's luma,
// so that depth edges follow image edges. CPU reference;
// cuda/bilateral_gpu.h computes the same function.
//
// out(p) = sum_q w(p,q) * depth(q) / sum_q w(p,q), q over the
// (2*radius+1)^2 window clipped to the image (no padding), with
//   w(p,q) = space_weight(|p-q|^2) * range_weight(guide(p) - guide(q)),
//   space_weight(d2) = exp(-d2 / (2 sigma_space^2)),
//   range_weight(g)  = exp(-g^2 / (2 sigma_range^2)), and for sigma_range == 0:
//                      1 where g == 0, else 0.
// The centre weight is exactly 1, so the sum never underflows to 0 and the
// result is never NaN; a constant depth map comes back unchanged (up to float
// rounding of the normalisation), and sigma_range -> 0 averages only over
// pixels with the centre's exact guide value.
// guide(p) is load_luma() of the frame (8-bit). radius 0 is the identity (the
// element passes the buffer through).
#pragma once

#include "frame.h"

namespace p3d {

constexpr int kMaxBilateralRadius = 16;

struct BilateralParams {
  int radius = 5;             // 0..kMaxBilateralRadius
  float sigma_space = 3.f;    // pixels, > 0
  float sigma_range = 12.f;   // 8-bit guide levels, >= 0
};

// Weight helpers shared with the kernel. The kernel may tabulate
// space_weight per (dx, dy) and range_weight per |g| in 0..255 (the tables
// are computed by these same functions on the host), so both sides use
// identical weights.
inline float bilateral_space_weight(const BilateralParams &p, int dx, int dy) {
  return expf(-static_cast<float>(dx * dx + dy * dy) / (2.f * p.sigma_space * p.sigma_space));
}
inline float bilateral_range_weight(const BilateralParams &p, int absdiff) {
  if (p.sigma_range <= 0.f) return absdiff == 0 ? 1.f : 0.f;
  return expf(-static_cast<float>(absdiff * absdiff) / (2.f * p.sigma_range * p.sigma_range));
}

// Tables the filter uses (host side): space[(dy+r)*(2r+1)+(dx+r)], range[0..255].
void bilateral_tables(const BilateralParams &p, float *space, float *range);

// depth_in and depth_out must not alias. guide has the depth map's size.
void bilateral_filter_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                          ImageView<float> depth_out);

}  // namespace p3d
