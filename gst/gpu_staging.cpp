#include "gpu_staging.h"

#if HAVE_CUDA
namespace p3d::gst {

// Row bytes and rows of every plane come from frame_plane_size(), the one
// description of the formats' geometry.
CudaStatus GpuStaging::allocate(Slot slot, const FrameView &host, FrameView *dev) {
  *dev = host;
  for (int i = 0; i < frame_plane_count(host.format); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(host.format, host.width, host.height, i, &row_bytes, &rows);
    P3D_CUDA_TRY_STATUS(frame_[slot][i].ensure_2d(row_bytes, rows));
    dev->plane[i] = frame_[slot][i].as<uint8_t>();
    dev->stride[i] = static_cast<int>(frame_[slot][i].pitch());
  }
  return {};
}

CudaStatus GpuStaging::upload(Slot slot, const FrameView &host, FrameView *dev, cudaStream_t stream) {
  P3D_CUDA_TRY_STATUS(allocate(slot, host, dev));
  for (int i = 0; i < frame_plane_count(host.format); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(host.format, host.width, host.height, i, &row_bytes, &rows);
    P3D_CUDA_TRY(cudaMemcpy2DAsync(dev->plane[i], dev->stride[i], host.plane[i], host.stride[i], row_bytes, rows,
                                   cudaMemcpyHostToDevice, stream));
  }
  return {};
}

CudaStatus GpuStaging::download(const FrameView &dev, const FrameView &host, cudaStream_t stream) {
  for (int i = 0; i < frame_plane_count(host.format); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(host.format, host.width, host.height, i, &row_bytes, &rows);
    P3D_CUDA_TRY(cudaMemcpy2DAsync(host.plane[i], host.stride[i], dev.plane[i], dev.stride[i], row_bytes, rows,
                                   cudaMemcpyDeviceToHost, stream));
  }
  return {};
}

CudaStatus GpuStaging::allocate_depth(Slot slot, int width, int height, ImageView<float> *dev) {
  P3D_CUDA_TRY_STATUS(depth_[slot].ensure_2d(static_cast<size_t>(width) * sizeof(float), height));
  *dev = ImageView<float>{depth_[slot].as<float>(), width, height, depth_[slot].pitch()};
  return {};
}

CudaStatus GpuStaging::upload_depth(Slot slot, ImageView<const float> host, ImageView<float> *dev,
                                    cudaStream_t stream) {
  P3D_CUDA_TRY_STATUS(allocate_depth(slot, host.width, host.height, dev));
  P3D_CUDA_TRY(cudaMemcpy2DAsync(dev->data, dev->pitch, host.data, host.pitch, host.width * sizeof(float), host.height,
                                 cudaMemcpyHostToDevice, stream));
  return {};
}

CudaStatus GpuStaging::download_depth(ImageView<const float> dev, ImageView<float> host, cudaStream_t stream) {
  P3D_CUDA_TRY(cudaMemcpy2DAsync(host.data, host.pitch, dev.data, dev.pitch, dev.width * sizeof(float), dev.height,
                                 cudaMemcpyDeviceToHost, stream));
  return {};
}

void GpuStaging::release() {
  for (auto &slot : frame_)
    for (DeviceBuffer &b : slot) b.release();
  for (DeviceBuffer &b : depth_) b.release();
}

}  // namespace p3d::gst
#endif
