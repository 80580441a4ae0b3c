// The exact cross-bilateral window (bilateral_filter_cpu, mode Exact)
// against faster variants: the Separable mode of common/bilateral.h (a row
// pass then a column pass) and, as a study only, a stride-2 window written
// here. Error against the exact result and time, on the estimator's depth of
// aloeL and on the GT depth (which also goes through the warp).
#include <cstdio>
#include <limits>

#include "metrics.h"
#include "quality.h"

namespace p3d::quality {
namespace {

struct FilterTables {
  BilateralParams p;
  std::vector<float> space, range;
  explicit FilterTables(const BilateralParams &params)
      : p(bilateral_sanitize(params)),
        space(bilateral_space_table_size(p.radius)),
        range(kBilateralRangeTableSize) {
    bilateral_tables(p, space.data(), range.data());
  }
  float space_at(int dx, int dy) const { return space[(dy + p.radius) * (2 * p.radius + 1) + (dx + p.radius)]; }
};

// Stride-2 window: only the taps with even dx and dy (about a quarter of
// them, the centre included so the weight sum stays >= 1). Same weights as
// the exact filter; a thin structure between two taps is what it can miss.
cv::Mat bilateral_stride2(const BilateralParams &params, const FrameView &guide, const cv::Mat &depth) {
  const FilterTables t(params);
  const cv::Mat luma = bilateral_guide_luma(guide);
  const int w = depth.cols, h = depth.rows, r = t.p.radius & ~1;  // the largest even offset
  cv::Mat out(depth.size(), CV_32FC1);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const uint8_t *gc = luma.ptr<uint8_t>(y);
      float *o = out.ptr<float>(y);
      for (int x = 0; x < w; ++x) {
        const int centre = gc[x];
        const float centre_depth = depth.ptr<float>(y)[x];
        float sum_w = 0.f, sum_wd = 0.f;
        for (int dy = -r; dy <= r; dy += 2) {
          const int qy = y + dy;
          if (qy < 0 || qy >= h) continue;
          const uint8_t *g = luma.ptr<uint8_t>(qy);
          const float *d = depth.ptr<float>(qy);
          for (int dx = -r; dx <= r; dx += 2) {
            const int qx = x + dx;
            if (qx < 0 || qx >= w) continue;
            const int diff = static_cast<int>(g[qx]) - centre;
            bilateral_accumulate(t.space_at(dx, dy), t.range[diff < 0 ? -diff : diff], d[qx], centre_depth, sum_w,
                                 sum_wd);
          }
        }
        o[x] = bilateral_result(centre_depth, sum_w, sum_wd);
      }
    }
  });
  return out;
}

cv::Mat bilateral_exact(const BilateralParams &bp, const FrameView &guide, const cv::Mat &depth) {
  BilateralParams p = bp;
  p.mode = BilateralMode::Exact;
  return filter_depth(p, guide, depth);
}

cv::Mat bilateral_separable(const BilateralParams &bp, const FrameView &guide, const cv::Mat &depth) {
  BilateralParams p = bp;
  p.mode = BilateralMode::Separable;
  return filter_depth(p, guide, depth);
}

}  // namespace

void measure_filter_variants(Writer &w, const Aloe &a, int runs) {
  using Variant = std::function<cv::Mat(const BilateralParams &, const FrameView &, const cv::Mat &)>;
  const std::vector<std::pair<const char *, Variant>> variants = {
      {"exact", bilateral_exact}, {"stride2", bilateral_stride2}, {"separable", bilateral_separable}};
  const std::vector<std::pair<const char *, cv::Mat>> inputs = {
      {"estimated", estimated_depth(DepthParams(), a.left_frame.view())}, {"ground-truth", a.gt_depth}};
  const FrameView guide = a.left_frame.view();
  // One timing group for all of them, so that the speed-ups compare runs
  // taken side by side.
  struct Case {
    size_t input, variant;
    int radius;
  };
  std::vector<Case> cases;
  for (size_t i = 0; i < inputs.size(); ++i)
    for (const int radius : {5, 10})
      for (size_t v = 0; v < variants.size(); ++v) cases.push_back({i, v, radius});
  std::vector<cv::Mat> results(cases.size());
  std::vector<std::function<void()>> jobs;
  for (size_t k = 0; k < cases.size(); ++k)
    jobs.push_back([&, k] {
      // The element's default (sigma_space 3) at radius 5; 0.6 r at radius 10.
      const Case &c = cases[k];
      results[k] = variants[c.variant].second(study_filter(c.radius), guide, inputs[c.input].second);
    });
  const std::vector<Timing> t = time_interleaved(runs, jobs);

  HostFrame out(PixelFormat::BGRA, 2 * a.left.cols, a.left.rows);
  for (size_t k = 0; k < cases.size(); ++k) {
    const Case &c = cases[k];
    const char *variant = variants[c.variant].first, *input = inputs[c.input].first;
    const BilateralParams bp = study_filter(c.radius);
    const cv::Mat &exact = results[k - c.variant];  // variant 0 of the same input and radius
    const MapError e = map_error(exact, results[k]);
    JsonLine j;
    j.str("kind", "filter_variant").str("variant", variant).str("input", input).integer("radius", c.radius);
    j.num("sigma_space", bp.sigma_space).num("sigma_range", bp.sigma_range);
    j.num("time_ms", t[k].median_ms()).num("min_ms", t[k].min_ms());
    j.num("max_abs", e.max_abs).num("mean_abs", e.mean_abs).num("psnr_vs_exact", e.psnr);
    if (std::string(input) == "ground-truth") {
      render_right(a, results[k], HoleFill::BackgroundSmooth, out);
      const cv::Mat synth = right_half_bgr(out);
      j.num("synth_psnr", psnr(synth, a.right)).num("synth_ssim", ssim(synth, a.right));
    }
    w.emit(j);
    std::printf("filter     %-9s %-12s radius %2d  %8.1f ms  max %.4f  mean %.5f  PSNR %6.2f dB\n", variant, input,
                c.radius, t[k].median_ms(), e.max_abs, e.mean_abs, e.psnr);
    std::fflush(stdout);
  }
}

}  // namespace p3d::quality
