#include "device_buffer.h"

#include <utility>

namespace p3d {

DeviceBuffer::~DeviceBuffer() { release(); }

DeviceBuffer::DeviceBuffer(DeviceBuffer &&o) noexcept
    : ptr_(std::exchange(o.ptr_, nullptr)), size_(std::exchange(o.size_, 0)), pitch_(std::exchange(o.pitch_, 0)) {}

DeviceBuffer &DeviceBuffer::operator=(DeviceBuffer &&o) noexcept {
  if (this != &o) {
    release();
    ptr_ = std::exchange(o.ptr_, nullptr);
    size_ = std::exchange(o.size_, 0);
    pitch_ = std::exchange(o.pitch_, 0);
  }
  return *this;
}

void DeviceBuffer::release() {
  if (ptr_) cudaFree(ptr_);  // errors on free are not actionable; the context may already be gone
  ptr_ = nullptr;
  size_ = pitch_ = 0;
}

CudaStatus DeviceBuffer::ensure(size_t bytes) {
  if (bytes <= size_ && ptr_) return {};
  release();
  if (bytes == 0) bytes = 1;
  P3D_CUDA_TRY_ALLOC(cudaMalloc(&ptr_, bytes), bytes);
  size_ = bytes;
  pitch_ = bytes;
  return {};
}

CudaStatus DeviceBuffer::ensure_2d(size_t row_bytes, size_t height) {
  if (row_bytes == 0) row_bytes = 1;
  if (height == 0) height = 1;
  if (ptr_ && pitch_ >= row_bytes && pitch_ * height <= size_) return {};
  release();
  size_t pitch = 0;
  P3D_CUDA_TRY_ALLOC(cudaMallocPitch(&ptr_, &pitch, row_bytes, height), row_bytes * height);
  pitch_ = pitch;
  size_ = pitch * height;
  return {};
}

bool cuda_device_present() {
  int n = 0;
  if (cudaGetDeviceCount(&n) != cudaSuccess) return false;
  return n > 0;
}

}  // namespace p3d
