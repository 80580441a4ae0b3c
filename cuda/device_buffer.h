// Device memory owned by one object, grown on demand and never shrunk, so a
// steady stream allocates nothing per frame.
#pragma once

#include <cstddef>

#include "cuda_check.h"

namespace p3d {

class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  ~DeviceBuffer();
  DeviceBuffer(const DeviceBuffer &) = delete;
  DeviceBuffer &operator=(const DeviceBuffer &) = delete;
  DeviceBuffer(DeviceBuffer &&o) noexcept;
  DeviceBuffer &operator=(DeviceBuffer &&o) noexcept;

  // Makes the buffer hold at least `bytes` (contents undefined after growth).
  CudaStatus ensure(size_t bytes);
  // Pitched 2-D variant: at least `height` rows of `row_bytes`; pitch() tells the row pitch.
  CudaStatus ensure_2d(size_t row_bytes, size_t height);
  void release();

  void *get() const { return ptr_; }
  template <typename T>
  T *as() const { return static_cast<T *>(ptr_); }
  size_t size() const { return size_; }
  size_t pitch() const { return pitch_; }

 private:
  void *ptr_ = nullptr;
  size_t size_ = 0;
  size_t pitch_ = 0;
};

// True when a CUDA device can be used by the runtime API (for tests' skip).
bool cuda_device_present();

}  // namespace p3d
