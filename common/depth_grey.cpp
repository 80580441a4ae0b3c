#include "depth_grey.h"

#include <algorithm>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace p3d {

float import_depth_sample(const DepthImportParams &p, uint32_t s, uint32_t smax) {
  switch (p.convention) {
    case DepthConvention::NearDark: return 1.f - static_cast<float>(s) / static_cast<float>(smax);
    case DepthConvention::Metric: {
      if (s == 0) return 0.f;  // nothing seen there
      const float inv = 1.f / static_cast<float>(s), inv_near = 1.f / p.near, inv_far = 1.f / p.far;
      return std::clamp((inv - inv_far) / (inv_near - inv_far), 0.f, 1.f);
    }
    case DepthConvention::NearWhite:
    default: return static_cast<float>(s) / static_cast<float>(smax);
  }
}

void import_depth_cpu(const DepthImportParams &p, const ImageView<const uint8_t> &src, int bits,
                      ImageView<float> out) {
  const uint32_t smax = bits == 8 ? 255u : 65535u;
  // One table for every sample value: 256 or 65536 entries, cheaper than
  // the per-pixel arithmetic and the same numbers.
  std::vector<float> lut(smax + 1);
  for (uint32_t s = 0; s <= smax; ++s) lut[s] = import_depth_sample(p, s, smax);
  cv::Mat converted(src.height, src.width, CV_32FC1);
  for (int y = 0; y < src.height; ++y) {
    const uint8_t *row = src.row(y);
    float *d = converted.ptr<float>(y);
    if (bits == 8) {
      for (int x = 0; x < src.width; ++x) d[x] = lut[row[x]];
    } else {
      const auto *row16 = reinterpret_cast<const uint16_t *>(row);
      for (int x = 0; x < src.width; ++x) d[x] = lut[row16[x]];
    }
  }
  cv::Mat dst(out.height, out.width, CV_32FC1, out.data, out.pitch);
  if (converted.size() == dst.size())
    converted.copyTo(dst);
  else
    cv::resize(converted, dst, dst.size(), 0, 0, cv::INTER_NEAREST_EXACT);  // see the header
}

uint32_t export_depth_sample(float d, uint32_t smax) {
  if (!(d > 0.f)) return 0;  // also NaN
  if (d >= 1.f) return smax;
  return static_cast<uint32_t>(d * static_cast<float>(smax) + 0.5f);
}

void export_depth_cpu(const ImageView<const float> &depth, int bits, ImageView<uint8_t> out) {
  const uint32_t smax = bits == 8 ? 255u : 65535u;
  for (int y = 0; y < depth.height; ++y) {
    const float *d = depth.row(y);
    uint8_t *row = out.row(y);
    if (bits == 8) {
      for (int x = 0; x < depth.width; ++x) row[x] = static_cast<uint8_t>(export_depth_sample(d[x], smax));
    } else {
      auto *row16 = reinterpret_cast<uint16_t *>(row);
      for (int x = 0; x < depth.width; ++x) row16[x] = static_cast<uint16_t>(export_depth_sample(d[x], smax));
    }
  }
}

}  // namespace p3d
