// The documented fallback for system-memory caps on a machine with a GPU:
// device copies of host frames and depth maps, so a stage can run its
// kernels and copy the result back. Buffers grow on demand and are reused,
// so a steady stream allocates nothing per frame. (With memory:CUDAMemory
// caps none of this is used: frames stay on the device.)
#pragma once

#include "config.h"

#if HAVE_CUDA
#include "cuda_check.h"
#include "device_buffer.h"
#include "frame.h"

namespace p3d::gst {

class GpuStaging {
 public:
  enum Slot { kInput = 0, kOutput = 1 };

  // Device frame shaped like `host` (same format and size) in `slot`.
  CudaStatus allocate(Slot slot, const FrameView &host, FrameView *dev);
  CudaStatus upload(Slot slot, const FrameView &host, FrameView *dev, cudaStream_t stream);
  CudaStatus download(const FrameView &dev, const FrameView &host, cudaStream_t stream);

  CudaStatus allocate_depth(Slot slot, int width, int height, ImageView<float> *dev);
  CudaStatus upload_depth(Slot slot, ImageView<const float> host, ImageView<float> *dev, cudaStream_t stream);
  CudaStatus download_depth(ImageView<const float> dev, ImageView<float> host, cudaStream_t stream);

  // Frees every buffer (the owning context must be current).
  void release();

 private:
  DeviceBuffer frame_[2][3];
  DeviceBuffer depth_[2];
};

}  // namespace p3d::gst
#endif
