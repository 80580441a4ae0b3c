#include "chained_launch.cuh"

#include <mutex>
#include <vector>

namespace p3d {

bool chained_launch_allowed(const void *kernel) {
  struct Known {
    const void *kernel;
    int device;
    bool allowed;
  };
  static std::mutex lock;
  static std::vector<Known> known;  // a few dozen kernels at most
  int device = 0;
  if (cudaGetDevice(&device) != cudaSuccess) return false;
  std::lock_guard<std::mutex> hold(lock);
  for (const Known &k : known)
    if (k.kernel == kernel && k.device == device) return k.allowed;
  cudaFuncAttributes a{};
  if (cudaFuncGetAttributes(&a, kernel) != cudaSuccess) {
    // Launch plainly this time and ask again next time; clear the error so
    // that a later cudaPeekAtLastError() does not report it as its own (a
    // real fault shows in the launch itself).
    cudaGetLastError();
    return false;
  }
  const bool allowed = a.ptxVersion >= 90;
  known.push_back(Known{kernel, device, allowed});
  return allowed;
}

namespace {
__global__ void zero_bytes_kernel(unsigned char *p, size_t bytes) {
  chained_kernel_start();
  for (size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x; i < bytes;
       i += static_cast<size_t>(gridDim.x) * blockDim.x)
    p[i] = 0;
}
}  // namespace

cudaError_t zero_chained(void *p, size_t bytes, cudaStream_t stream) {
  if (bytes == 0) return cudaSuccess;
  const unsigned blocks = static_cast<unsigned>((bytes + 255) / 256 < 1024 ? (bytes + 255) / 256 : 1024);
  return launch_chained(zero_bytes_kernel, blocks, 256, 0, stream, static_cast<unsigned char *>(p), bytes);
}
}  // namespace p3d
