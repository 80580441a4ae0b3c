#include "test_data.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <cstdlib>

#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

namespace p3d::test {

std::string data_dir() {
  if (const char *env = std::getenv("P3D_DATA_DIR"); env && *env) return env;
  return P3D_DATA_DIR;
}

bool write_raw_image(const std::string &path, const cv::Mat &m) {
  std::ofstream f(path, std::ios::binary);
  f << "P3DRAW " << m.cols << " " << m.rows << " " << m.type() << "\n";
  for (int y = 0; y < m.rows; ++y) f.write(m.ptr<char>(y), static_cast<std::streamsize>(m.cols * m.elemSize()));
  return static_cast<bool>(f);
}

cv::Mat read_raw_image(const std::string &path) {
  std::ifstream f(path, std::ios::binary);
  std::string magic;
  int cols = 0, rows = 0, type = 0;
  if (!(f >> magic >> cols >> rows >> type) || magic != "P3DRAW" || cols <= 0 || rows <= 0) return cv::Mat();
  f.get();  // the newline
  cv::Mat m(rows, cols, type);
  f.read(m.ptr<char>(), static_cast<std::streamsize>(m.total() * m.elemSize()));
  return f ? m : cv::Mat();
}

cv::Mat load_data_image(const std::string &name) {
  const std::string path = data_dir() + "/" + name;
  cv::Mat m = read_raw_image(path + ".p3draw");
  if (m.empty()) m = read_image_file(path);
  if (m.empty()) ADD_FAILURE() << "missing test data " << path << " (or its .p3draw dump; run scripts/get-test-data.sh)";
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

cv::Mat deep_picture(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  cv::Mat m(h, w, CV_16UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      m.at<cv::Vec3w>(y, x) = cv::Vec3w(static_cast<uint16_t>((x * 65535) / w ^ (rng() & 0x3f)),
                                        static_cast<uint16_t>((y * 65535) / h ^ (rng() & 0x3f)),
                                        static_cast<uint16_t>(rng() & 0xffff));
  for (int k = 0; k < 4; ++k) {
    const int x0 = static_cast<int>(rng() % static_cast<uint32_t>(std::max(1, w / 2)));
    const int y0 = static_cast<int>(rng() % static_cast<uint32_t>(std::max(1, h / 2)));
    m(cv::Rect(x0, y0, std::max(1, w / 4), std::max(1, h / 4))) =
        cv::Scalar(rng() & 0xffff, rng() & 0xffff, rng() & 0xffff);
  }
  return m;
}

const char *format_name(PixelFormat f) {
  switch (f) {
    case PixelFormat::NV12: return "NV12";
    case PixelFormat::I420: return "I420";
    case PixelFormat::RGBA: return "RGBA";
    case PixelFormat::BGRA: return "BGRA";
    case PixelFormat::RGBx: return "RGBx";
    case PixelFormat::BGRx: return "BGRx";
    case PixelFormat::P010: return "P010_10LE";
    case PixelFormat::I420_10: return "I420_10LE";
    case PixelFormat::RGBA64: return "RGBA64_LE";
  }
  return "?";
}

}  // namespace p3d::test
