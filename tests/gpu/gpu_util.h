// Device copies of host frames and depth maps for the GPU tests: upload,
// download, compare. Device rows get a pitch different from the host's so
// kernels that ignore pitch are caught.
#pragma once

#include <opencv2/core.hpp>

#include "device_buffer.h"
#include "frame.h"
#include "host_frame.h"

namespace p3d::test {

// A frame in device memory with the planes of a HostFrame's format and size.
class DeviceFrame {
 public:
  DeviceFrame(PixelFormat format, int width, int height);
  static DeviceFrame upload(const HostFrame &h);
  HostFrame download() const;
  FrameView view() const { return view_; }

 private:
  DeviceBuffer planes_[3];
  FrameView view_;
};

// A float image in device memory (pitched).
class DeviceDepth {
 public:
  DeviceDepth(int width, int height);
  static DeviceDepth upload(const cv::Mat &depth);  // CV_32FC1
  cv::Mat download() const;
  ImageView<float> view() const { return view_; }
  void poison();  // fill with NaN, so unwritten pixels show

 private:
  DeviceBuffer buf_;
  ImageView<float> view_;
};

// Asserts inside: fails the current test on a CUDA error.
void check_cuda(const CudaStatus &st);

}  // namespace p3d::test
