// A frame in host memory that owns its planes, in any supported format, with
// optional row padding (so code is exercised with stride > width * bpp).
// Used by tests, benchmarks and the CPU fallback paths; no GStreamer.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "frame.h"

namespace p3d {

class HostFrame {
 public:
  HostFrame() = default;
  // row_padding: extra bytes at the end of every row of every plane.
  HostFrame(PixelFormat format, int width, int height, int row_padding = 0);
  // Copies own their planes: the view is re-pointed into the copy's storage.
  HostFrame(const HostFrame &o);
  HostFrame &operator=(const HostFrame &o);
  HostFrame(HostFrame &&o) noexcept = default;  // vector storage moves, pointers stay valid
  HostFrame &operator=(HostFrame &&o) noexcept = default;

  FrameView view() const { return view_; }
  PixelFormat format() const { return view_.format; }
  int width() const { return view_.width; }
  int height() const { return view_.height; }
  bool empty() const { return storage_.empty(); }

  void fill_random(uint32_t seed);
  void fill(uint8_t value);

  // From an 8-bit BGR (CV_8UC3) or BGRA image: R'G'B' formats take the
  // pixels as they are; YUV formats get BT.601 limited-range Y'CbCr
  // (OpenCV's conversion), which the default YuvToRgb reads back.
  // The deep formats take the 8-bit image widened (v * 257), as from_bgr16.
  static HostFrame from_bgr(const cv::Mat &bgr, PixelFormat format, int row_padding = 0);
  // From a 16-bit BGR image (CV_16UC3) into a deep format: RGBA64 takes the
  // pixels as they are; P010/I420_10 get BT.601 limited-range 10-bit
  // Y'CbCr (each 2 x 2 block's chroma from its mean R'G'B'), which
  // yuv_to_rgb_params(0.299, 0.114, false, 10) reads back.
  static HostFrame from_bgr16(const cv::Mat &bgr16, PixelFormat format, int row_padding = 0);

  // The frame as 8-bit BGRA through load_rgba() (for metrics and PNG output).
  cv::Mat to_bgra(const YuvToRgb &m = YuvToRgb()) const;

 private:
  std::vector<uint8_t> storage_;
  FrameView view_;
};

// A view of a packed-RGB frame with the bytes of cv::Mat `m` (CV_8UC4).
FrameView frame_view_of(const cv::Mat &m, PixelFormat format);
// A depth ImageView over a CV_32FC1 matrix.
ImageView<float> depth_view_of(cv::Mat &m);
ImageView<const float> depth_view_of(const cv::Mat &m);

}  // namespace p3d
