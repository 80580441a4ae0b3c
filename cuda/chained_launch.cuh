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
// ramp-up overlap the predecessor's last blocks. Measured on an H100
// (pseudo3d-bench, same-loan A/B, docs/benchmarks.md): 4K chain 0.4714 ->
// 0.4600 ms, 1080p 0.2001 -> 0.1885, 8K 1.6635 -> 1.6523.
//
// Every kernel launched by launch_chained() calls chained_kernel_start()
// first, before it reads or writes anything (tests/gpu/test_gpu_chained.cpp
// fails without the wait). A kernel whose code has no wait (PTX for an
// architecture before sm_90, as the compute_75 PTX that a newer card would
// JIT) is launched plainly: chained_launch_allowed() checks the function's
// PTX version, so a missing wait can never race. Not every kernel gains:
// the warp's BackgroundSmooth sums kernel, whose grid is mostly blocks that
// return at once, lost 11 us at 4K to the two instructions in each of them
// while it had a block a tile; with a block for every 8 tiles it gains and
// is chained too (cuda/warp.cu, launch_smooth).
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
