// One way to check CUDA runtime calls: every call and launch goes through
// P3D_CUDA_TRY, which returns a CudaStatus naming the failed call, the error
// name and the place, for the gst layer to put into GST_ELEMENT_ERROR.
#pragma once

#include <string>

#include <cuda_runtime_api.h>

namespace p3d {

struct CudaStatus {
  cudaError_t code = cudaSuccess;
  const char *call = nullptr;  // source text of the failed call
  const char *file = nullptr;
  int line = 0;

  bool ok() const { return code == cudaSuccess; }
  // "cudaMalloc(&p, n) failed: cudaErrorMemoryAllocation (out of memory) at cuda/x.cu:12"
  std::string message() const;
};

}  // namespace p3d

#define P3D_CUDA_TRY(call)                                              \
  do {                                                                  \
    const cudaError_t p3d_err_ = (call);                                \
    if (p3d_err_ != cudaSuccess)                                        \
      return ::p3d::CudaStatus{p3d_err_, #call, __FILE__, __LINE__};    \
  } while (0)

// After a <<<>>> launch: configuration errors show up here.
#define P3D_CUDA_TRY_LAUNCH(kernel_name) P3D_CUDA_TRY(cudaPeekAtLastError() /* launch of kernel_name */)

// Propagate a CudaStatus from a callee.
#define P3D_CUDA_TRY_STATUS(expr)                 \
  do {                                            \
    const ::p3d::CudaStatus p3d_st_ = (expr);     \
    if (!p3d_st_.ok()) return p3d_st_;            \
  } while (0)
