// Device copies of host frames and depth maps for the GPU tests: upload,
// download, compare. Device rows get a pitch different from the host's so
// kernels that ignore pitch are caught.
#pragma once

#include <cstring>
#include <vector>

#include <cuda_runtime_api.h>
#include <gtest/gtest.h>
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
  // The same with every plane starting `offset` bytes into its allocation
  // and rows `extra` bytes longer than their data: the unaligned layouts a
  // frame mapped from another allocator may have.
  static DeviceFrame upload_at(const HostFrame &h, int offset, int extra);
  HostFrame download() const;
  FrameView view() const { return view_; }

 private:
  DeviceBuffer planes_[3];
  FrameView view_;
};

// A float image in device memory (pitched): the depth of a width x height
// picture on a grid of 2^shift-pixel cells (p3d_defs.h DepthGrid; shift 0:
// a full-size map).
class DeviceDepth {
 public:
  DeviceDepth(int width, int height, int shift = 0);
  static DeviceDepth upload(const cv::Mat &depth);  // CV_32FC1
  // The cells of a full-size map at a shift: each cell takes its first
  // pixel's value (what a cell-constant map holds everywhere in the cell).
  static DeviceDepth upload_grid(const cv::Mat &depth, int shift);
  // Full-size (a grid copied out to its pixels: expand_grid).
  cv::Mat download() const;
  ImageView<float> view() const { return grid_.cells; }  // the cells: the full-size map at shift 0
  DepthGrid<float> grid() const { return grid_; }
  void poison();  // fill with NaN, so unwritten pixels show

 private:
  DeviceBuffer buf_;
  DepthGrid<float> grid_;
};

// A full-size map made constant over cells of 2^shift pixels: each pixel
// takes its cell's first pixel's value (what a stage hands on on a grid,
// DeviceDepth::upload_grid, holds).
cv::Mat cell_constant(const cv::Mat &depth, int shift);

// Asserts inside: fails the current test on a CUDA error.
void check_cuda(const CudaStatus &st);

// An output frame of a packed RGB format (RGBA64 too) in device memory
// with a chosen stride and start offset, so that the kernels' aligned
// paths (word and 16-byte stores) and their per-pixel paths (unaligned
// rows) both run, and with a guard band after the last row. Every byte of
// the allocation starts as `poison`.
class DeviceOutput {
 public:
  DeviceOutput(PixelFormat f, int w, int h, size_t stride, size_t offset, uint8_t poison) : poison_(poison) {
    bytes_ = offset + stride * static_cast<size_t>(h) + kGuard;
    check_cuda(buf_.ensure(bytes_));
    EXPECT_EQ(cudaSuccess, cudaMemset(buf_.get(), poison, bytes_));
    view_.format = f;
    view_.width = w;
    view_.height = h;
    view_.plane[0] = buf_.as<uint8_t>() + offset;
    view_.stride[0] = static_cast<int>(stride);
    offset_ = offset;
  }
  // Row-aligned like a pooled CUDA buffer: 512-byte pitch, aligned start.
  static DeviceOutput aligned(PixelFormat f, int w, int h, uint8_t poison) {
    const size_t stride = (packed_pixel_bytes(f) * static_cast<size_t>(w) + 64 + 511) / 512 * 512;
    return DeviceOutput(f, w, h, stride, 0, poison);
  }
  FrameView view() const { return view_; }

  // The pixels as a host frame, and the number of bytes outside them
  // (before the first row, row padding, guard band) that lost the poison.
  struct Result {
    HostFrame frame;
    long long writes_outside = 0;
  };
  Result download() const {
    std::vector<uint8_t> all(bytes_);
    EXPECT_EQ(cudaSuccess, cudaDeviceSynchronize());
    EXPECT_EQ(cudaSuccess, cudaMemcpy(all.data(), buf_.get(), bytes_, cudaMemcpyDeviceToHost));
    Result r{HostFrame(view_.format, view_.width, view_.height, 4)};
    const FrameView hv = r.frame.view();
    const size_t row_bytes = packed_pixel_bytes(view_.format) * static_cast<size_t>(view_.width);
    const size_t stride = view_.stride[0];
    auto count_changed = [&](size_t from, size_t to) {
      for (size_t i = from; i < to; ++i) r.writes_outside += all[i] != poison_;
    };
    count_changed(0, offset_);
    for (int y = 0; y < view_.height; ++y) {
      const size_t row = offset_ + static_cast<size_t>(y) * stride;
      std::memcpy(hv.plane[0] + static_cast<size_t>(y) * hv.stride[0], all.data() + row, row_bytes);
      count_changed(row + row_bytes, y + 1 < view_.height ? row + stride : bytes_);
    }
    return r;
  }

 private:
  static constexpr size_t kGuard = 256;
  DeviceBuffer buf_;
  FrameView view_;
  size_t bytes_ = 0, offset_ = 0;
  uint8_t poison_;
};

}  // namespace p3d::test
