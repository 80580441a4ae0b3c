// CPU reference of the cross-bilateral filter (common/bilateral.h).
#include "bilateral.h"

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

}  // namespace

void bilateral_filter_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                          ImageView<float> depth_out) {
  CV_Assert(guide.width == depth_in.width && guide.height == depth_in.height);
  CV_Assert(depth_out.width == depth_in.width && depth_out.height == depth_in.height);
  if (depth_in.empty() || depth_out.empty()) return;

  cv::Mat in_copy;
  if (static_cast<const void *>(depth_in.data) == static_cast<const void *>(depth_out.data)) {
    in_copy = copy_of(depth_in);
    depth_in = ImageView<const float>{in_copy.ptr<float>(), in_copy.cols, in_copy.rows, in_copy.step[0]};
  }

  const BilateralParams p = bilateral_sanitize(params);
  std::vector<float> space(bilateral_space_table_size(p.radius)), range(kBilateralRangeTableSize);
  bilateral_tables(p, space.data(), range.data());
  const cv::Mat luma = bilateral_guide_luma(guide);

  const int w = depth_in.width, h = depth_in.height;
  auto guide_at = [&luma](int qx, int qy) { return luma.ptr<uint8_t>(qy)[qx]; };
  auto depth_at = [&depth_in](int qx, int qy) { return depth_in.row(qy)[qx]; };
  if (p.mode == BilateralMode::Separable) {
    cv::Mat mid(h, w, CV_32FC1);
    auto mid_at = [&mid](int qx, int qy) { return mid.ptr<float>(qy)[qx]; };
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
      for (int y = rows.start; y < rows.end; ++y) {
        float *out = mid.ptr<float>(y);
        for (int x = 0; x < w; ++x)
          out[x] = bilateral_pass_pixel(x, y, 1, 0, w, p.radius, space.data(), range.data(), guide_at, depth_at);
      }
    });
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
      for (int y = rows.start; y < rows.end; ++y) {
        float *out = depth_out.row(y);
        for (int x = 0; x < w; ++x)
          out[x] = bilateral_pass_pixel(x, y, 0, 1, h, p.radius, space.data(), range.data(), guide_at, mid_at);
      }
    });
    return;
  }
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      float *out = depth_out.row(y);
      for (int x = 0; x < w; ++x)
        out[x] = bilateral_pixel(x, y, w, h, p.radius, space.data(), range.data(), guide_at, depth_at);
    }
  });
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
