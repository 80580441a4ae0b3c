// Frames and depth grids in device memory for pseudo3d-bench's GPU runs
// (bench_gpu.cu, scene_chain_gpu.cpp): host code on the CUDA runtime API.
#pragma once

#include <cuda_runtime_api.h>

#include "cuda_check.h"
#include "device_buffer.h"
#include "frame.h"
#include "host_frame.h"

namespace p3d::bench {

// A frame in device memory, planes pitched by the driver.
struct DevFrame {
  DeviceBuffer planes[3];
  FrameView view;

  CudaStatus allocate(PixelFormat format, int width, int height) {
    view.format = format;
    view.width = width;
    view.height = height;
    for (int i = 0; i < frame_plane_count(format); ++i) {
      int row_bytes = 0, rows = 0;
      frame_plane_size(format, width, height, i, &row_bytes, &rows);
      P3D_CUDA_TRY_STATUS(planes[i].ensure_2d(static_cast<size_t>(row_bytes), static_cast<size_t>(rows)));
      view.plane[i] = planes[i].as<uint8_t>();
      view.stride[i] = static_cast<int>(planes[i].pitch());
    }
    return {};
  }

  CudaStatus upload(const HostFrame &h) {
    P3D_CUDA_TRY_STATUS(allocate(h.format(), h.width(), h.height()));
    const FrameView hv = h.view();
    for (int i = 0; i < frame_plane_count(h.format()); ++i) {
      int row_bytes = 0, rows = 0;
      frame_plane_size(h.format(), h.width(), h.height(), i, &row_bytes, &rows);
      P3D_CUDA_TRY(cudaMemcpy2D(view.plane[i], view.stride[i], hv.plane[i], hv.stride[i], row_bytes, rows,
                                cudaMemcpyHostToDevice));
    }
    return {};
  }

  // Into *h (allocated here, of the frame's format and size).
  CudaStatus download(HostFrame *h) const {
    if (h->format() != view.format || h->width() != view.width || h->height() != view.height)
      *h = HostFrame(view.format, view.width, view.height);
    const FrameView hv = h->view();
    for (int i = 0; i < frame_plane_count(view.format); ++i) {
      int row_bytes = 0, rows = 0;
      frame_plane_size(view.format, view.width, view.height, i, &row_bytes, &rows);
      P3D_CUDA_TRY(cudaMemcpy2D(hv.plane[i], hv.stride[i], view.plane[i], view.stride[i], row_bytes, rows,
                                cudaMemcpyDeviceToHost));
    }
    return {};
  }
};

// A width x height picture's depth on a grid of 2^shift-pixel cells.
struct DevDepth {
  DeviceBuffer buf;
  DepthGrid<float> view;

  CudaStatus allocate(int width, int height, int shift) {
    const int w = grid_cells(width, shift), h = grid_cells(height, shift);
    P3D_CUDA_TRY_STATUS(buf.ensure_2d(static_cast<size_t>(w) * sizeof(float), static_cast<size_t>(h)));
    view = DepthGrid<float>{ImageView<float>{buf.as<float>(), w, h, buf.pitch()}, width, height, shift};
    return {};
  }
};

}  // namespace p3d::bench
