// Sums and maxima of an unsigned value over the 32 lanes of a warp, all
// lanes taking part (full mask). sm_80 and newer do it in hardware
// (__reduce_add_sync, __reduce_max_sync); Turing (sm_75), which CUDA 13 still
// compiles for, has no such instruction and gets a butterfly of shuffles.
// Unsigned sums (mod 2^32) and maxima do not depend on the order of the
// operations, so both give the same bits on every GPU; the GPU suite checks
// the shuffle form against the hardware one (warp_reduce_check.cu).
#pragma once

#include <cstdint>

namespace p3d {

constexpr unsigned kWarpFullMask = 0xffffffffu;

__device__ __forceinline__ uint32_t warp_reduce_sum_shuffle(uint32_t v) {
  for (int o = 16; o > 0; o >>= 1) v += __shfl_xor_sync(kWarpFullMask, v, o);
  return v;
}

__device__ __forceinline__ uint32_t warp_reduce_max_shuffle(uint32_t v) {
  for (int o = 16; o > 0; o >>= 1) v = max(v, __shfl_xor_sync(kWarpFullMask, v, o));
  return v;
}

__device__ __forceinline__ uint32_t warp_reduce_sum(uint32_t v) {
#if __CUDA_ARCH__ >= 800
  return __reduce_add_sync(kWarpFullMask, v);
#else
  return warp_reduce_sum_shuffle(v);
#endif
}

__device__ __forceinline__ uint32_t warp_reduce_max(uint32_t v) {
#if __CUDA_ARCH__ >= 800
  return __reduce_max_sync(kWarpFullMask, v);
#else
  return warp_reduce_max_shuffle(v);
#endif
}

}  // namespace p3d
