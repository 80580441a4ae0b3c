// One way to check CUDA runtime calls: every call and launch goes through
// P3D_CUDA_TRY, which returns a CudaStatus naming the failed call, the error
// name and the place, for the gst layer to put into GST_ELEMENT_ERROR.
//
// Fault injection (tests only): cuda_fault_inject_after(n) makes the n-th
// checked call from then on report cudaErrorLaunchFailure (the call itself
// still runs and succeeds), so the GPU suite can prove that a failure in the
// middle of a stream ends in a clean element error. Costs one relaxed atomic
// load per checked call while disarmed.
#pragma once

#include <atomic>
#include <cstddef>
#include <string>

#include <cuda_runtime_api.h>

namespace p3d {

struct CudaStatus {
  cudaError_t code = cudaSuccess;
  const char *call = nullptr;  // source text of the failed call
  const char *file = nullptr;
  int line = 0;
  size_t bytes = 0;  // for a failed allocation: the size asked for

  bool ok() const { return code == cudaSuccess; }
  // "cudaMalloc(&p, n) failed: cudaErrorMemoryAllocation (out of memory) at cuda/x.cu:12"
  std::string message() const;
};

// Arms (n >= 1) or disarms (n <= 0) the fault hook described above.
void cuda_fault_inject_after(int n);

namespace detail {
extern std::atomic<int> g_fault_countdown;
cudaError_t fault_tick(cudaError_t err);
inline cudaError_t checked(cudaError_t err) {
  if (g_fault_countdown.load(std::memory_order_relaxed) > 0) return fault_tick(err);
  return err;
}
}  // namespace detail

}  // namespace p3d

#define P3D_CUDA_TRY(call)                                              \
  do {                                                                  \
    const cudaError_t p3d_err_ = ::p3d::detail::checked(call);          \
    if (p3d_err_ != cudaSuccess)                                        \
      return ::p3d::CudaStatus{p3d_err_, #call, __FILE__, __LINE__};    \
  } while (0)

// An allocation: like P3D_CUDA_TRY, and the status records the size.
#define P3D_CUDA_TRY_ALLOC(call, nbytes)                                          \
  do {                                                                            \
    const cudaError_t p3d_err_ = ::p3d::detail::checked(call);                    \
    if (p3d_err_ != cudaSuccess)                                                  \
      return ::p3d::CudaStatus{p3d_err_, #call, __FILE__, __LINE__, (nbytes)};    \
  } while (0)

// After a <<<>>> launch: configuration errors show up here.
#define P3D_CUDA_TRY_LAUNCH(kernel_name) P3D_CUDA_TRY(cudaPeekAtLastError() /* launch of kernel_name */)

// Propagate a CudaStatus from a callee.
#define P3D_CUDA_TRY_STATUS(expr)                 \
  do {                                            \
    const ::p3d::CudaStatus p3d_st_ = (expr);     \
    if (!p3d_st_.ok()) return p3d_st_;            \
  } while (0)
