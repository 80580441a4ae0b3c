#include "test_data.h"

#include <cmath>
#include <cstdlib>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

namespace p3d::test {

std::string data_dir() {
  if (const char *env = std::getenv("P3D_DATA_DIR"); env && *env) return env;
  return P3D_DATA_DIR;
}

cv::Mat load_data_image(const std::string &name) {
  const std::string path = data_dir() + "/" + name;
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty()) ADD_FAILURE() << "missing test data " << path << " (run scripts/get-test-data.sh)";
  return m;
}

DiffStats compare_u8(const cv::Mat &a, const cv::Mat &b, int tolerance) {
  DiffStats s;
  EXPECT_EQ(a.size(), b.size());
  EXPECT_EQ(a.type(), b.type());
  if (a.size() != b.size() || a.type() != b.type()) {
    s.max_abs = 256;
    return s;
  }
  const int ch = a.channels();
  for (int y = 0; y < a.rows; ++y) {
    const uint8_t *pa = a.ptr<uint8_t>(y), *pb = b.ptr<uint8_t>(y);
    for (int i = 0; i < a.cols * ch; ++i) {
      const int d = std::abs(int(pa[i]) - int(pb[i]));
      s.max_abs = std::max(s.max_abs, d);
      s.over_tolerance += d > tolerance;
      ++s.samples;
    }
  }
  return s;
}

FloatDiff compare_f32(const cv::Mat &a, const cv::Mat &b) {
  FloatDiff s;
  EXPECT_EQ(a.size(), b.size());
  if (a.size() != b.size()) {
    s.max_abs = INFINITY;
    return s;
  }
  for (int y = 0; y < a.rows; ++y)
    for (int x = 0; x < a.cols; ++x) {
      const float va = a.at<float>(y, x), vb = b.at<float>(y, x);
      if (!std::isfinite(va) || !std::isfinite(vb)) {
        ++s.nonfinite;
        continue;
      }
      s.max_abs = std::max(s.max_abs, double(std::fabs(va - vb)));
    }
  return s;
}

const char *format_name(PixelFormat f) {
  switch (f) {
    case PixelFormat::NV12: return "NV12";
    case PixelFormat::I420: return "I420";
    case PixelFormat::RGBA: return "RGBA";
    case PixelFormat::BGRA: return "BGRA";
    case PixelFormat::RGBx: return "RGBx";
    case PixelFormat::BGRx: return "BGRx";
  }
  return "?";
}

}  // namespace p3d::test
