// CPU reference of the cross-bilateral filter (common/bilateral.h).
#include "bilateral.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>

namespace p3d {

void bilateral_tables(const BilateralParams &p, float *space, float *range) {
  const BilateralParams s = bilateral_sanitize(p);
  const int r = s.radius, side = 2 * r + 1;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) space[(dy + r) * side + (dx + r)] = bilateral_space_weight(s, dx, dy);
  for (int g = 0; g < kBilateralRangeTableSize; ++g) range[g] = bilateral_range_weight(s, g);
}

namespace {


// A private copy of the input when it aliases the output, so that the
// filter never reads pixels it has already written.
cv::Mat copy_of(ImageView<const float> v) {
  cv::Mat m(v.height, v.width, CV_32FC1);
  for (int y = 0; y < v.height; ++y) std::memcpy(m.ptr<float>(y), v.row(y), sizeof(float) * v.width);
  return m;
}

// A CV_32FC1 matrix as the filter's image view.
ImageView<float> float_view(cv::Mat &m) { return ImageView<float>{m.ptr<float>(), m.cols, m.rows, m.step[0]}; }

// kStrip adjacent output pixels of one window at once: the taps (dx, dy)
// for dy from dy0 to dy1 (outer) and dx from dx0 to dx1 (inner), the order
// of bilateral_pixel() and bilateral_pass_pixel(), each through
// bilateral_accumulate(), so every pixel's sums round exactly as there
// (tests/common/test_bilateral.cpp pins this bit for bit). The exact window
// is dy and dx over -r..r, the Separable row pass dy = 0, its column pass
// dx = 0. tap_guide / tap_depth point at the strip's first pixel; a row down
// is guide_step and depth_step_bytes bytes away; space_centre points at
// space(0, 0) of the (2r+1)^2 table, `side` = 2r+1 per row; `range` is
// the mirrored table's centre, indexed by the signed guide difference, so no
// branch on its sign. The strip keeps
// kStrip independent sums in registers, which the compiler vectorises,
// instead of one pixel's chain of dependent additions at a time, which is
// several times faster than a pixel at a time (row pass) or row sweeps
// (column pass) (measured: docs/benchmarks.md, Design measurements,
// "Filter").
constexpr int kStrip = 16;

inline void window_strip(const uint8_t *tap_guide, ptrdiff_t guide_step, const float *tap_depth,
                         ptrdiff_t depth_step_bytes, int dy0, int dy1, int dx0, int dx1, const float *space_centre,
                         int side, const float *range, float *out) {
  float sum_w[kStrip] = {}, sum_wd[kStrip] = {};
  for (int dy = dy0; dy <= dy1; ++dy)
    for (int dx = dx0; dx <= dx1; ++dx) {
      const uint8_t *tg = tap_guide + guide_step * dy + dx;
      const float *td =
          reinterpret_cast<const float *>(reinterpret_cast<const char *>(tap_depth) + depth_step_bytes * dy) + dx;
      const float space_w = space_centre[dy * side + dx];
#pragma GCC unroll 16
      for (int k = 0; k < kStrip; ++k) {
        const int g = static_cast<int>(tg[k]) - static_cast<int>(tap_guide[k]);
        bilateral_accumulate(space_w, range[g], td[k], sum_w[k], sum_wd[k]);
      }
    }
  for (int k = 0; k < kStrip; ++k) out[k] = sum_wd[k] / sum_w[k];
}

// The strips' starting columns for a run [x0, x1) of at least kStrip
// pixels: every kStrip-th column, the last strip moved back to end at x1
// (its overlap is computed twice, to the same bits).
template <typename StripFn>
inline void for_each_strip(int x0, int x1, const StripFn &strip) {
  for (int x = x0; x < x1; x += kStrip) strip(x + kStrip <= x1 ? x : x1 - kStrip);
}

// The filter at full resolution of sanitised parameters p (scale 1) on the
// guide's luma (CV_8UC1); depth_in does not alias depth_out.
void filter_on_luma(const BilateralParams &p, const cv::Mat &luma, ImageView<const float> depth_in,
                    ImageView<float> depth_out) {
  // The range table mirrored (bilateral_mirror_range): `range` points at its
  // centre, so range[g] is the weight of a guide difference g in -255..255,
  // and range[|g|] (what bilateral_pixel reads) the same value.
  std::vector<float> space(bilateral_space_table_size(p.radius)), signed_range(kBilateralSignedRangeSize);
  float *range = signed_range.data() + kBilateralRangeTableSize - 1;
  bilateral_tables(p, space.data(), range);
  bilateral_mirror_range(signed_range.data());

  const int w = depth_in.width, h = depth_in.height;
  const int r = p.radius, side = 2 * r + 1;
  const float *space_centre = space.data() + r * side + r;  // space(0, 0)
  const int x0 = std::min(r, w), x1 = std::max(x0, w - r);  // [x0, x1): the window needs no clipping in x
  const bool strips_in_row = x1 - x0 >= kStrip;
  const ptrdiff_t luma_step = static_cast<ptrdiff_t>(luma.step[0]);
  auto guide_at = [&luma](int qx, int qy) { return luma.ptr<uint8_t>(qy)[qx]; };
  auto depth_at = [&depth_in](int qx, int qy) { return depth_in.row(qy)[qx]; };
  if (p.mode == BilateralMode::Separable) {
    // Both passes in strips of kStrip pixels (window_strip) where the row is
    // long enough: along the row at the pixels whose window needs no
    // clipping, down the columns everywhere (a row's taps are clipped alike
    // for all its pixels). The other pixels take bilateral_pass_pixel().
    cv::Mat mid(h, w, CV_32FC1);
    const bool strips_down = w >= kStrip;
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
      for (int y = rows.start; y < rows.end; ++y) {
        const uint8_t *g = luma.ptr<uint8_t>(y);
        const float *dep = depth_in.row(y);
        float *out = mid.ptr<float>(y);
        if (strips_in_row)
          for_each_strip(x0, x1, [&](int x) {
            window_strip(g + x, luma_step, dep + x, 0, 0, 0, -r, r, space_centre, side, range, out + x);
          });
        for (int x = 0; x < w; ++x)
          if (!strips_in_row || x < x0 || x >= x1)
            out[x] = bilateral_pass_pixel(x, y, 1, 0, w, r, space.data(), range, guide_at, depth_at);
      }
    });
    auto mid_at = [&mid](int qx, int qy) { return mid.ptr<float>(qy)[qx]; };
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
      for (int y = rows.start; y < rows.end; ++y) {
        float *out = depth_out.row(y);
        if (!strips_down) {
          for (int x = 0; x < w; ++x)
            out[x] = bilateral_pass_pixel(x, y, 0, 1, h, r, space.data(), range, guide_at, mid_at);
          continue;
        }
        const int d0 = std::max(-r, -y), d1 = std::min(r, h - 1 - y);
        for_each_strip(0, w, [&](int x) {
          const uint8_t *g = luma.ptr<uint8_t>(y) + x;
          window_strip(g, luma_step, mid.ptr<float>(y) + x, static_cast<ptrdiff_t>(mid.step[0]), d0,
                       d1, 0, 0, space_centre, side, range, out + x);
        });
      }
    });
    return;
  }
  // The exact window: strips where it needs no clipping in x (its rows are
  // clipped alike for the whole row), per pixel elsewhere.
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      float *out = depth_out.row(y);
      const uint8_t *g = luma.ptr<uint8_t>(y);
      const int dy0 = std::max(-r, -y), dy1 = std::min(r, h - 1 - y);
      if (strips_in_row)
        for_each_strip(x0, x1, [&](int x) {
          window_strip(g + x, luma_step, depth_in.row(y) + x, static_cast<ptrdiff_t>(depth_in.pitch),
                       dy0, dy1, -r, r, space_centre, side, range, out + x);
        });
      for (int x = 0; x < w; ++x)
        if (!strips_in_row || x < x0 || x >= x1)
          out[x] = bilateral_pixel(x, y, w, h, r, space.data(), range, guide_at, depth_at);
    }
  });
}

// The coarse grid of step s > 1 (common/bilateral.h): guide' and depth'
// per cell, filtered there, each result spread over its cell.
void filter_on_cells(const BilateralParams &p, int s, const FrameView &guide, ImageView<const float> depth_in,
                     ImageView<float> depth_out) {
  const int w = depth_in.width, h = depth_in.height;
  const int cw = bilateral_cells(w, s), ch = bilateral_cells(h, s);
  cv::Mat luma(ch, cw, CV_8UC1), depth(ch, cw, CV_32FC1), out(ch, cw, CV_32FC1);
  cv::parallel_for_(cv::Range(0, ch), [&](const cv::Range &rows) {
    for (int cy = rows.start; cy < rows.end; ++cy) {
      const float *src = depth_in.row(cy * s);
      for (int cx = 0; cx < cw; ++cx) {
        luma.ptr<uint8_t>(cy)[cx] = static_cast<uint8_t>(bilateral_cell_luma(guide, cx, cy, s));
        depth.ptr<float>(cy)[cx] = src[cx * s];
      }
    }
  });
  filter_on_luma(bilateral_coarse_params(p, s), luma, as_const(float_view(depth)), float_view(out));
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const float *cell = out.ptr<float>(y / s);
      float *dst = depth_out.row(y);
      for (int x = 0; x < w; ++x) dst[x] = cell[x / s];
    }
  });
}

}  // namespace

void bilateral_filter_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                          ImageView<float> depth_out) {
  CV_Assert(guide.width == depth_in.width && guide.height == depth_in.height);
  CV_Assert(depth_out.width == depth_in.width && depth_out.height == depth_in.height);
  if (depth_in.empty() || depth_out.empty()) return;

  const BilateralParams p = bilateral_sanitize(params);
  const int s = bilateral_effective_scale(p, depth_in.width, depth_in.height);
  if (s > 1) {  // reads depth_in into its own grid first, so it may alias depth_out
    filter_on_cells(p, s, guide, depth_in, depth_out);
    return;
  }
  cv::Mat in_copy;
  if (static_cast<const void *>(depth_in.data) == static_cast<const void *>(depth_out.data)) {
    in_copy = copy_of(depth_in);
    depth_in = as_const(float_view(in_copy));
  }
  filter_on_luma(bilateral_coarse_params(p, 1), bilateral_guide_luma(guide), depth_in, depth_out);
}

// The guide's luma once per pixel: the window reads every value up to
// (2r+1)^2 times, and load_luma() of R'G'B' is a few float operations.
cv::Mat bilateral_guide_luma(const FrameView &guide) {
  cv::Mat luma(guide.height, guide.width, CV_8UC1);
  cv::parallel_for_(cv::Range(0, guide.height), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      uint8_t *out = luma.ptr<uint8_t>(y);
      for (int x = 0; x < guide.width; ++x) out[x] = load_luma(guide, x, y);
    }
  });
  return luma;
}

}  // namespace p3d
