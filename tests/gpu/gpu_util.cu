#include "gpu_util.h"

#include <cstring>

#include <gtest/gtest.h>

namespace p3d::test {

void check_cuda(const CudaStatus &st) { ASSERT_TRUE(st.ok()) << st.message(); }

DeviceFrame::DeviceFrame(PixelFormat format, int width, int height) {
  view_.format = format;
  view_.width = width;
  view_.height = height;
  for (int i = 0; i < frame_plane_count(format); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(format, width, height, i, &row_bytes, &rows);
    const CudaStatus st = planes_[i].ensure_2d(row_bytes + 64, rows);  // +64: pitch != host stride
    EXPECT_TRUE(st.ok()) << st.message();
    view_.plane[i] = planes_[i].as<uint8_t>();
    view_.stride[i] = static_cast<int>(planes_[i].pitch());
    cudaMemset(view_.plane[i], 0xA5, planes_[i].size());  // poison
  }
}

DeviceFrame DeviceFrame::upload(const HostFrame &h) {
  DeviceFrame d(h.format(), h.width(), h.height());
  const FrameView hv = h.view();
  for (int i = 0; i < frame_plane_count(h.format()); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(h.format(), h.width(), h.height(), i, &row_bytes, &rows);
    EXPECT_EQ(cudaSuccess, cudaMemcpy2D(d.view_.plane[i], d.view_.stride[i], hv.plane[i], hv.stride[i], row_bytes,
                                        rows, cudaMemcpyHostToDevice));
  }
  return d;
}

DeviceFrame DeviceFrame::upload_at(const HostFrame &h, int offset, int extra) {
  DeviceFrame d(h.format(), h.width(), h.height());
  const FrameView hv = h.view();
  for (int i = 0; i < frame_plane_count(h.format()); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(h.format(), h.width(), h.height(), i, &row_bytes, &rows);
    const size_t stride = static_cast<size_t>(row_bytes) + extra;
    const CudaStatus st = d.planes_[i].ensure(stride * rows + offset);
    EXPECT_TRUE(st.ok()) << st.message();
    d.view_.plane[i] = d.planes_[i].as<uint8_t>() + offset;
    d.view_.stride[i] = static_cast<int>(stride);
    EXPECT_EQ(cudaSuccess, cudaMemcpy2D(d.view_.plane[i], stride, hv.plane[i], hv.stride[i], row_bytes, rows,
                                        cudaMemcpyHostToDevice));
  }
  return d;
}

HostFrame DeviceFrame::download() const {
  HostFrame h(view_.format, view_.width, view_.height, 8);
  const FrameView hv = h.view();
  EXPECT_EQ(cudaSuccess, cudaDeviceSynchronize());
  for (int i = 0; i < frame_plane_count(view_.format); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(view_.format, view_.width, view_.height, i, &row_bytes, &rows);
    EXPECT_EQ(cudaSuccess, cudaMemcpy2D(hv.plane[i], hv.stride[i], view_.plane[i], view_.stride[i], row_bytes, rows,
                                        cudaMemcpyDeviceToHost));
  }
  return h;
}

DeviceDepth::DeviceDepth(int width, int height, int shift) {
  const int w = grid_cells(width, shift), h = grid_cells(height, shift);
  const CudaStatus st = buf_.ensure_2d(static_cast<size_t>(w) * sizeof(float) + 128, h);
  EXPECT_TRUE(st.ok()) << st.message();
  grid_ = DepthGrid<float>{ImageView<float>{buf_.as<float>(), w, h, buf_.pitch()}, width, height, shift};
  poison();
}

void DeviceDepth::poison() { cudaMemset(buf_.get(), 0xFF, buf_.size()); }  // 0xFFFFFFFF is a NaN

cv::Mat cell_constant(const cv::Mat &depth, int shift) {
  cv::Mat out(depth.size(), CV_32FC1);
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x)
      out.at<float>(y, x) = depth.at<float>(y >> shift << shift, x >> shift << shift);
  return out;
}

DeviceDepth DeviceDepth::upload(const cv::Mat &depth) { return upload_grid(depth, 0); }

DeviceDepth DeviceDepth::upload_grid(const cv::Mat &depth, int shift) {
  DeviceDepth d(depth.cols, depth.rows, shift);
  const ImageView<float> &c = d.grid_.cells;
  cv::Mat cells(c.height, c.width, CV_32FC1);
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) cells.at<float>(y, x) = depth.at<float>(y << shift, x << shift);
  EXPECT_EQ(cudaSuccess, cudaMemcpy2D(c.data, c.pitch, cells.data, cells.step, c.width * sizeof(float), c.height,
                                      cudaMemcpyHostToDevice));
  return d;
}

cv::Mat DeviceDepth::download() const {
  const ImageView<float> &c = grid_.cells;
  cv::Mat cells(c.height, c.width, CV_32FC1);
  EXPECT_EQ(cudaSuccess, cudaDeviceSynchronize());
  EXPECT_EQ(cudaSuccess, cudaMemcpy2D(cells.data, cells.step, c.data, c.pitch, c.width * sizeof(float), c.height,
                                      cudaMemcpyDeviceToHost));
  cv::Mat m(grid_.height, grid_.width, CV_32FC1);
  expand_grid(DepthGrid<const float>{ImageView<const float>{reinterpret_cast<const float *>(cells.data), c.width,
                                                             c.height, cells.step},
                                     grid_.width, grid_.height, grid_.shift},
              ImageView<float>{reinterpret_cast<float *>(m.data), m.cols, m.rows, m.step});
  return m;
}

}  // namespace p3d::test
