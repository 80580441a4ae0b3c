#include "host_frame.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

namespace p3d {

HostFrame::HostFrame(PixelFormat format, int width, int height, int row_padding) {
  view_.format = format;
  view_.width = width;
  view_.height = height;
  size_t offsets[3] = {0, 0, 0}, total = 0;
  for (int i = 0; i < frame_plane_count(format); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(format, width, height, i, &row_bytes, &rows);
    view_.stride[i] = row_bytes + row_padding;
    offsets[i] = total;
    total += static_cast<size_t>(view_.stride[i]) * rows;
  }
  storage_.assign(total + 1, 0);  // +1: never empty, even for 0 x 0
  for (int i = 0; i < frame_plane_count(format); ++i) view_.plane[i] = storage_.data() + offsets[i];
}

HostFrame::HostFrame(const HostFrame &o) : storage_(o.storage_), view_(o.view_) {
  for (int i = 0; i < 3; ++i)
    if (o.view_.plane[i]) view_.plane[i] = storage_.data() + (o.view_.plane[i] - o.storage_.data());
}

HostFrame &HostFrame::operator=(const HostFrame &o) {
  if (this != &o) *this = HostFrame(o);
  return *this;
}

void HostFrame::fill_random(uint32_t seed) {
  std::mt19937 rng(seed);
  for (auto &b : storage_) b = static_cast<uint8_t>(rng() >> 24);
}

void HostFrame::fill(uint8_t value) { std::fill(storage_.begin(), storage_.end(), value); }

HostFrame HostFrame::from_bgr(const cv::Mat &bgr_in, PixelFormat format, int row_padding) {
  cv::Mat bgr;
  if (bgr_in.channels() == 4)
    cv::cvtColor(bgr_in, bgr, cv::COLOR_BGRA2BGR);
  else
    bgr = bgr_in;
  if (is_deep(format)) {
    cv::Mat wide;
    bgr.convertTo(wide, CV_16UC3, 257.0);
    return from_bgr16(wide, format, row_padding);
  }
  HostFrame h(format, bgr.cols, bgr.rows, row_padding);
  const FrameView v = h.view();
  if (is_packed_rgb(format)) {
    for (int y = 0; y < bgr.rows; ++y)
      for (int x = 0; x < bgr.cols; ++x) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
        store_rgba(v, x, y, Rgba{p[2], p[1], p[0], 255});
      }
    return h;
  }
  // OpenCV's 4:2:0 conversion needs even sizes: convert a padded copy.
  const int ew = (bgr.cols + 1) & ~1, eh = (bgr.rows + 1) & ~1;
  cv::Mat padded;
  cv::copyMakeBorder(bgr, padded, 0, eh - bgr.rows, 0, ew - bgr.cols, cv::BORDER_REPLICATE);
  cv::Mat i420;
  cv::cvtColor(padded, i420, cv::COLOR_BGR2YUV_I420);  // Y plane, then U, then V, contiguous
  const uint8_t *Y = i420.data, *U = Y + ew * eh, *V = U + (ew / 2) * (eh / 2);
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) v.plane[0][y * v.stride[0] + x] = Y[y * ew + x];
  for (int y = 0; y < (bgr.rows + 1) / 2; ++y)
    for (int x = 0; x < (bgr.cols + 1) / 2; ++x) {
      const uint8_t u = U[y * (ew / 2) + x], vv = V[y * (ew / 2) + x];
      if (format == PixelFormat::NV12) {
        v.plane[1][y * v.stride[1] + 2 * x] = u;
        v.plane[1][y * v.stride[1] + 2 * x + 1] = vv;
      } else {
        v.plane[1][y * v.stride[1] + x] = u;
        v.plane[2][y * v.stride[2] + x] = vv;
      }
    }
  return h;
}

HostFrame HostFrame::from_bgr16(const cv::Mat &bgr, PixelFormat format, int row_padding) {
  HostFrame h(format, bgr.cols, bgr.rows, row_padding);
  const FrameView v = h.view();
  auto rgb = [&](int x, int y, double c[3]) {
    const cv::Vec3w p = bgr.at<cv::Vec3w>(std::min(y, bgr.rows - 1), std::min(x, bgr.cols - 1));
    for (int k = 0; k < 3; ++k) c[k] = p[2 - k] / 65535.0;  // R, G, B in 0..1
  };
  auto code = [](double v) { return static_cast<int>(std::lround(std::clamp(v, 0.0, 1023.0))); };
  if (is_packed_rgb(format)) {
    for (int y = 0; y < bgr.rows; ++y)
      for (int x = 0; x < bgr.cols; ++x) {
        const cv::Vec3w p = bgr.at<cv::Vec3w>(y, x);
        store_rgba16(v, x, y, Rgba16{p[2], p[1], p[0], 65535});
      }
    return h;
  }
  auto luma = [](const double c[3]) { return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]; };
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) {
      double c[3];
      rgb(x, y, c);
      store_code(v, 0, y, x, code(64.0 + 876.0 * luma(c)));
    }
  for (int by = 0; by < (bgr.rows + 1) / 2; ++by)
    for (int bx = 0; bx < (bgr.cols + 1) / 2; ++bx) {
      double m[3] = {0, 0, 0};
      for (int k = 0; k < 4; ++k) {
        double c[3];
        rgb(2 * bx + (k & 1), 2 * by + (k >> 1), c);
        for (int i = 0; i < 3; ++i) m[i] += c[i] / 4.0;
      }
      const double yl = luma(m);
      const int u = code(512.0 + 896.0 * (m[2] - yl) / 1.772), vv = code(512.0 + 896.0 * (m[0] - yl) / 1.402);
      if (is_semi_planar(format)) {
        store_code(v, 1, by, 2 * bx, u);
        store_code(v, 1, by, 2 * bx + 1, vv);
      } else {
        store_code(v, 1, by, bx, u);
        store_code(v, 2, by, bx, vv);
      }
    }
  return h;
}

cv::Mat HostFrame::to_bgra(const YuvToRgb &m) const {
  cv::Mat out(view_.height, view_.width, CV_8UC4);
  for (int y = 0; y < view_.height; ++y)
    for (int x = 0; x < view_.width; ++x) {
      const Rgba c = load_rgba(view_, x, y, m);
      out.at<cv::Vec4b>(y, x) = cv::Vec4b(c.b, c.g, c.r, c.a);
    }
  return out;
}

FrameView frame_view_of(const cv::Mat &m, PixelFormat format) {
  FrameView v;
  v.format = format;
  v.width = m.cols;
  v.height = m.rows;
  v.plane[0] = const_cast<uint8_t *>(m.ptr<uint8_t>());
  v.stride[0] = static_cast<int>(m.step[0]);
  return v;
}

ImageView<float> depth_view_of(cv::Mat &m) { return ImageView<float>{m.ptr<float>(), m.cols, m.rows, m.step[0]}; }
ImageView<const float> depth_view_of(const cv::Mat &m) {
  return ImageView<const float>{m.ptr<float>(), m.cols, m.rows, m.step[0]};
}

}  // namespace p3d
