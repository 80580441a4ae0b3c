// CPU reference of the cross-bilateral filter (common/bilateral.h).
#include "bilateral.h"

#include <algorithm>
#include <cmath>
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

// Adjacent output pixels computed together (window_strip()).
constexpr int kStrip = 16;

// Whether every tap of the strip's windows reads one finite depth v: then
// every difference is 0, sum_wd stays +0 and each pixel's result is
// v + 0 / sum_w = v + 0 (sum_w >= 1, the centre tap's weight), whatever
// the guide, so the strip is v + 0 without its taps. The depth maps the
// estimator makes are constant over each region along a row, which is
// most of a picture for the row pass.
inline bool flat_strip(const float *tap_depth, ptrdiff_t depth_step_bytes, int dy0, int dy1, int dx0, int dx1,
                       float *out) {
  const float v = tap_depth[0];
  if (!(v - v == 0.f)) return false;  // inf or NaN: the taps' sums are not 0
  for (int dy = dy0; dy <= dy1; ++dy) {
    const float *row = reinterpret_cast<const float *>(reinterpret_cast<const char *>(tap_depth) + depth_step_bytes * dy);
    for (int dx = dx0; dx <= dx1 + kStrip - 1; ++dx)
      if (row[dx] != v) return false;
  }
  for (int k = 0; k < kStrip; ++k) out[k] = v + 0.f;
  return true;
}

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
inline void window_strip(const uint8_t *tap_guide, ptrdiff_t guide_step, const float *tap_depth,
                         ptrdiff_t depth_step_bytes, int dy0, int dy1, int dx0, int dx1, const float *space_centre,
                         int side, const float *range, float *out) {
  if (flat_strip(tap_depth, depth_step_bytes, dy0, dy1, dx0, dx1, out)) return;
  float sum_w[kStrip] = {}, sum_wd[kStrip] = {}, centre[kStrip];
  for (int k = 0; k < kStrip; ++k) centre[k] = tap_depth[k];
  for (int dy = dy0; dy <= dy1; ++dy)
    for (int dx = dx0; dx <= dx1; ++dx) {
      const uint8_t *tg = tap_guide + guide_step * dy + dx;
      const float *td =
          reinterpret_cast<const float *>(reinterpret_cast<const char *>(tap_depth) + depth_step_bytes * dy) + dx;
      const float space_w = space_centre[dy * side + dx];
#pragma GCC unroll 16
      for (int k = 0; k < kStrip; ++k) {
        const int g = static_cast<int>(tg[k]) - static_cast<int>(tap_guide[k]);
        bilateral_accumulate(space_w, range[g], td[k], centre[k], sum_w[k], sum_wd[k]);
      }
    }
  for (int k = 0; k < kStrip; ++k) out[k] = bilateral_result(centre[k], sum_w[k], sum_wd[k]);
}

// The strips' starting columns for a run [x0, x1) of at least kStrip
// pixels: every kStrip-th column, the last strip moved back to end at x1
// (its overlap is computed twice, to the same bits).
template <typename StripFn>
inline void for_each_strip(int x0, int x1, const StripFn &strip) {
  for (int x = x0; x < x1; x += kStrip) strip(x + kStrip <= x1 ? x : x1 - kStrip);
}

// The filter at full resolution of sanitised parameters p (scale 1) on the
// guide's luma (CV_8UC1), for the output pixels of `where` only; it reads
// luma and depth_in within p.radius of them. depth_in does not alias
// depth_out. mid: the Separable row pass, the picture's size.
void filter_on_luma(const BilateralParams &p, const cv::Mat &luma, ImageView<const float> depth_in,
                    ImageView<float> depth_out, const PixelRect &where, cv::Mat &mid) {
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
  // [x0, x1): the columns of `where` whose window needs no clipping in x.
  const int x0 = std::max(where.x0, std::min(r, w)), x1 = std::min(where.x1, std::max(std::min(r, w), w - r));
  const bool strips_in_row = x1 - x0 >= kStrip;
  const bool strips_down = where.x1 - where.x0 >= kStrip;
  const ptrdiff_t luma_step = static_cast<ptrdiff_t>(luma.step[0]);
  auto guide_at = [&luma](int qx, int qy) { return luma.ptr<uint8_t>(qy)[qx]; };
  auto depth_at = [&depth_in](int qx, int qy) { return depth_in.row(qy)[qx]; };
  if (p.mode == BilateralMode::Separable) {
    // Both passes in strips of kStrip pixels (window_strip) where the run
    // is long enough: along the row at the pixels whose window needs no
    // clipping, down the columns everywhere (a row's taps are clipped alike
    // for all its pixels). The other pixels take bilateral_pass_pixel().
    // The row pass covers the rows the column pass reads.
    if (mid.rows != h || mid.cols != w) mid.create(h, w, CV_32FC1);
    const PixelRect rows_read = grown(where, r, w, h);
    cv::parallel_for_(cv::Range(rows_read.y0, rows_read.y1), [&](const cv::Range &rows) {
      for (int y = rows.start; y < rows.end; ++y) {
        const uint8_t *g = luma.ptr<uint8_t>(y);
        const float *dep = depth_in.row(y);
        float *out = mid.ptr<float>(y);
        if (strips_in_row)
          for_each_strip(x0, x1, [&](int x) {
            window_strip(g + x, luma_step, dep + x, 0, 0, 0, -r, r, space_centre, side, range, out + x);
          });
        for (int x = where.x0; x < where.x1; ++x)
          if (!strips_in_row || x < x0 || x >= x1)
            out[x] = bilateral_pass_pixel(x, y, 1, 0, w, r, space.data(), range, guide_at, depth_at);
      }
    });
    auto mid_at = [&mid](int qx, int qy) { return mid.ptr<float>(qy)[qx]; };
    cv::parallel_for_(cv::Range(where.y0, where.y1), [&](const cv::Range &rows) {
      for (int y = rows.start; y < rows.end; ++y) {
        float *out = depth_out.row(y);
        if (!strips_down) {
          for (int x = where.x0; x < where.x1; ++x)
            out[x] = bilateral_pass_pixel(x, y, 0, 1, h, r, space.data(), range, guide_at, mid_at);
          continue;
        }
        const int d0 = std::max(-r, -y), d1 = std::min(r, h - 1 - y);
        for_each_strip(where.x0, where.x1, [&](int x) {
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
  cv::parallel_for_(cv::Range(where.y0, where.y1), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      float *out = depth_out.row(y);
      const uint8_t *g = luma.ptr<uint8_t>(y);
      const int dy0 = std::max(-r, -y), dy1 = std::min(r, h - 1 - y);
      if (strips_in_row)
        for_each_strip(x0, x1, [&](int x) {
          window_strip(g + x, luma_step, depth_in.row(y) + x, static_cast<ptrdiff_t>(depth_in.pitch),
                       dy0, dy1, -r, r, space_centre, side, range, out + x);
        });
      for (int x = where.x0; x < where.x1; ++x)
        if (!strips_in_row || x < x0 || x >= x1)
          out[x] = bilateral_pixel(x, y, w, h, r, space.data(), range, guide_at, depth_at);
    }
  });
}

// The guide's luma over rect r of `luma` (the picture's size).
void guide_luma_rect(const FrameView &guide, const PixelRect &r, cv::Mat &luma) {
  cv::parallel_for_(cv::Range(r.y0, r.y1), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      uint8_t *out = luma.ptr<uint8_t>(y);
      for (int x = r.x0; x < r.x1; ++x) out[x] = load_luma(guide, x, y);
    }
  });
}

// The coarse grid of step s > 1 (common/bilateral.h): guide' and depth'
// of the cells the output cells of `where` read, filtered there, each
// result spread over the pixels of `where` in its cell.
void filter_on_cells(const BilateralParams &p, int s, const FrameView &guide, ImageView<const float> depth_in,
                     ImageView<float> depth_out, const PixelRect &where, BilateralScratch &scratch) {
  const int w = depth_in.width, h = depth_in.height;
  const int cw = bilateral_cells(w, s), ch = bilateral_cells(h, s);
  const BilateralParams coarse = bilateral_coarse_params(p, s);
  const PixelRect cells{where.x0 / s, where.y0 / s, bilateral_cells(where.x1, s), bilateral_cells(where.y1, s)};
  const PixelRect read = grown(cells, coarse.radius, cw, ch);
  cv::Mat &luma = scratch.luma, &depth = scratch.cell_depth, &out = scratch.cell_out;
  if (luma.rows != ch || luma.cols != cw) {
    luma.create(ch, cw, CV_8UC1);
    depth.create(ch, cw, CV_32FC1);
    out.create(ch, cw, CV_32FC1);
  }
  cv::parallel_for_(cv::Range(read.y0, read.y1), [&](const cv::Range &rows) {
    for (int cy = rows.start; cy < rows.end; ++cy) {
      const float *src = depth_in.row(cy * s);
      for (int cx = read.x0; cx < read.x1; ++cx) {
        luma.ptr<uint8_t>(cy)[cx] = static_cast<uint8_t>(bilateral_cell_luma(guide, cx, cy, s));
        depth.ptr<float>(cy)[cx] = src[cx * s];
      }
    }
  });
  filter_on_luma(coarse, luma, as_const(float_view(depth)), float_view(out), cells, scratch.mid);
  cv::parallel_for_(cv::Range(where.y0, where.y1), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const float *cell = out.ptr<float>(y / s);
      float *dst = depth_out.row(y);
      for (int x = where.x0; x < where.x1; ++x) dst[x] = cell[x / s];
    }
  });
}

}  // namespace

void bilateral_filter_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                          ImageView<float> depth_out) {
  BilateralScratch scratch;
  bilateral_filter_cpu(params, guide, depth_in, depth_out,
                       {PixelRect{0, 0, depth_out.width, depth_out.height}}, scratch);
}

void bilateral_filter_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                          ImageView<float> depth_out, const std::vector<PixelRect> &where,
                          BilateralScratch &scratch) {
  CV_Assert(guide.width == depth_in.width && guide.height == depth_in.height);
  CV_Assert(depth_out.width == depth_in.width && depth_out.height == depth_in.height);
  if (depth_in.empty() || depth_out.empty()) return;

  const BilateralParams p = bilateral_sanitize(params);
  const int s = bilateral_effective_scale(p, depth_in.width, depth_in.height);
  const PixelRect whole{0, 0, depth_in.width, depth_in.height};
  // The filter never reads a pixel it has written: one rectangle on the
  // coarse grid reads depth_in into its own grid first, anything else
  // reads a private copy when the planes alias.
  cv::Mat in_copy;
  const bool alias = static_cast<const void *>(depth_in.data) == static_cast<const void *>(depth_out.data);
  if (alias && (s == 1 || where.size() > 1)) {
    in_copy = copy_of(depth_in);
    depth_in = as_const(float_view(in_copy));
  }
  if (s > 1) {
    for (const PixelRect &r : where)
      if (!r.empty()) filter_on_cells(p, s, guide, depth_in, depth_out, r, scratch);
    return;
  }
  const BilateralParams fine = bilateral_coarse_params(p, 1);
  cv::Mat &luma = scratch.luma;
  if (luma.rows != depth_in.height || luma.cols != depth_in.width) luma.create(depth_in.height, depth_in.width, CV_8UC1);
  for (const PixelRect &r : where)
    if (!r.empty()) guide_luma_rect(guide, grown(r, fine.radius, whole.x1, whole.y1), luma);
  for (const PixelRect &r : where)
    if (!r.empty()) filter_on_luma(fine, luma, depth_in, depth_out, r, scratch.mid);
}

bool bilateral_keeps(ImageView<const float> depth) {
  if (depth.empty()) return true;
  const float v = depth.row(0)[0];
  if (!std::isfinite(v) || (v == 0.f && std::signbit(v))) return false;
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  for (int y = 0; y < depth.height; ++y) {
    const float *row = depth.row(y);
    for (int x = 0; x < depth.width; ++x) {
      uint32_t b;
      std::memcpy(&b, &row[x], sizeof b);
      if (b != bits) return false;
    }
  }
  return true;
}

int bilateral_reach(const BilateralParams &params, int width, int height) {
  const BilateralParams p = bilateral_sanitize(params);
  const int s = bilateral_effective_scale(p, width, height);
  if (s <= 1) return p.radius;
  // An output pixel takes its cell's result, which reads the cells within
  // the coarse radius, each the pixels of its own cell.
  return (bilateral_coarse_params(p, s).radius + 1) * s;
}

// The guide's luma once per pixel: the window reads every value up to
// (2r+1)^2 times, and load_luma() of R'G'B' is a few float operations.
cv::Mat bilateral_guide_luma(const FrameView &guide) {
  cv::Mat luma(guide.height, guide.width, CV_8UC1);
  guide_luma_rect(guide, PixelRect{0, 0, guide.width, guide.height}, luma);
  return luma;
}

}  // namespace p3d
