// Chained launches: Hopper's programmatic dependent launch (PDL) for the
// kernels of a frame, which follow each other on one stream.
//
// A plain launch starts a kernel only once the one before it has finished:
// the GPU drains, then ramps up again, a few microseconds a boundary, and a
// frame's chain has about ten (six in the depth stage alone). A kernel
// launched by launch_chained() may be scheduled as soon as every block of
// the kernel before it has begun (chained_kernel_start() lets it), and its
// own chained_kernel_start() then waits until that kernel has completed and
// its writes are visible. So every kernel still sees all of its
// predecessors' results, as after a plain launch; only the launch and the
// ramp-up overlap the predecessor's last blocks (measured:
// docs/benchmarks.md, Design measurements, "Chained launches").
//
// Every kernel launched by launch_chained() calls chained_kernel_start()
// first, before it reads or writes anything (tests/gpu/test_gpu_chained.cpp
// fails without the wait). A kernel whose code has no wait (PTX for an
// architecture before sm_90, as the compute_75 PTX that a newer card would
// JIT) is launched plainly: chained_launch_allowed() checks the function's
// PTX version, so a missing wait can never race. Chain a kernel only where
// it gains: in a grid of mostly blocks that return at once, the two
// instructions in each of them cost more than the overlap saves (the
// warp's BackgroundSmooth sums kernel gains because it has a block for
// every 8 tiles, not one a tile: cuda/warp_smooth.cu, launch_smooth).
#pragma once

#include <utility>

#include <cuda_runtime.h>

namespace p3d {

// The first statement of every kernel launched by launch_chained():
// lets the next kernel in the stream be scheduled, then waits for the
// previous one. No-op before sm_90 and when not launched chained.
__device__ __forceinline__ void chained_kernel_start() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  asm volatile("griddepcontrol.launch_dependents;" ::: "memory");
  asm volatile("griddepcontrol.wait;" ::: "memory");
#endif
}

// Whether `kernel`'s code on the current device has chained_kernel_start()'s
// wait (its PTX is sm_90 or later); cached per kernel and device.
bool chained_launch_allowed(const void *kernel);

// cudaMemsetAsync(p, 0, bytes, stream) as a chained kernel.
cudaError_t zero_chained(void *p, size_t bytes, cudaStream_t stream);

// kernel<<<grid, block, smem, stream>>>(args...), chained to the kernel
// before it where chained_launch_allowed(). Returns the launch's error
// (cudaLaunchKernelEx reports a bad configuration itself).
template <typename... Params, typename... Args>
cudaError_t launch_chained(void (*kernel)(Params...), dim3 grid, dim3 block, size_t smem, cudaStream_t stream,
                           Args &&...args) {
  cudaLaunchAttribute chained{};
  chained.id = cudaLaunchAttributeProgrammaticStreamSerialization;
  chained.val.programmaticStreamSerializationAllowed = 1;
  cudaLaunchConfig_t config{};
  config.gridDim = grid;
  config.blockDim = block;
  config.dynamicSmemBytes = smem;
  config.stream = stream;
  if (chained_launch_allowed(reinterpret_cast<const void *>(kernel))) {
    config.attrs = &chained;
    config.numAttrs = 1;
  }
  return cudaLaunchKernelEx(&config, kernel, std::forward<Args>(args)...);
}

}  // namespace p3d
