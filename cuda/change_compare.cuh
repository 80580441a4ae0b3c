// FrameHistoryGpu::compare's kernel (cuda/change_gpu.h), a template on
// the sample: bytes (cuda/change_gpu.cu) or the deep formats' 16-bit
// samples (cuda/kernels_deep.cu).
#pragma once

#include "../common/change_map.h"
#include "cuda_check.h"

namespace p3d {
namespace change_detail {

// The kept copy's planes.
struct KeptPlanes {
  uint8_t *plane[3];
  size_t pitch[3];
};

// The compare of a deep frame (cuda/kernels_deep.cu):
// launch_compare_of<uint16_t>.
CudaStatus launch_compare_deep(const FrameView &frame, const KeptPlanes &kept, int planes, float tolerance,
                               uint8_t *flags, int tiles_x, int tiles_y, cudaStream_t stream);

namespace {

constexpr int kCompareThreads = 256;

// Tiles a block of the compare kernel takes side by side (one row of
// tiles high): their rows are loaded as one run of 16-byte words a plane.
constexpr int kCompareTilesX = 4;

// The bytes a whole tile spans in a row of plane p (a partial last tile
// spans fewer): a word of the run belongs to tile offset / tile_bytes.
__device__ int tile_bytes(PixelFormat f, int p) {
  const PlaneBox b = plane_box(f, p, PixelRect{0, 0, kChangeTile, kChangeTile});
  return b.b1 - b.b0;
}

// Calls f(tile, current, kept) for each unit of plane p's rows [box.r0,
// box.r1) x bytes [box.b0, box.b1) that this thread handles: 16-byte
// words where the run and both planes allow, else samples (Sample: a
// byte, or a 16-bit sample of the deep formats). tile: the unit's tile
// within the block's run.
template <class Sample, typename F>
__device__ void for_run(const FrameView &frame, const KeptPlanes &kept, int p, const PlaneBox &box, F &&f) {
  const int run = box.b1 - box.b0, rows = box.r1 - box.r0, per_tile = tile_bytes(frame.format, p);
  const size_t cur_pitch = static_cast<size_t>(frame.stride[p]);
  const uintptr_t align = reinterpret_cast<uintptr_t>(frame.plane[p]) | reinterpret_cast<uintptr_t>(kept.plane[p]) |
                          cur_pitch | kept.pitch[p] | static_cast<uintptr_t>(box.b0) | static_cast<uintptr_t>(run);
  if (align % 16 == 0) {
    const int per_row = run / 16;
    for (int i = threadIdx.x; i < per_row * rows; i += blockDim.x) {
      const int y = box.r0 + i / per_row, w = i % per_row;
      f(16 * w / per_tile, reinterpret_cast<uint4 *>(frame.plane[p] + y * cur_pitch + box.b0) + w,
        reinterpret_cast<uint4 *>(kept.plane[p] + y * kept.pitch[p] + box.b0) + w);
    }
    return;
  }
  constexpr int kBytes = sizeof(Sample);
  const int samples = run / kBytes;
  for (int i = threadIdx.x; i < samples * rows; i += blockDim.x) {
    const int y = box.r0 + i / samples, b = kBytes * (i % samples);
    f(b / per_tile, reinterpret_cast<Sample *>(frame.plane[p] + y * cur_pitch + box.b0 + b),
      reinterpret_cast<Sample *>(kept.plane[p] + y * kept.pitch[p] + box.b0 + b));
  }
}

// Sums of |a - b| over the samples of two units: bytes, or 16-bit samples.
template <class Sample>
__device__ unsigned sad(const uint4 &a, const uint4 &b) {
  if constexpr (sizeof(Sample) == 1) {
    return __vsadu4(a.x, b.x) + __vsadu4(a.y, b.y) + __vsadu4(a.z, b.z) + __vsadu4(a.w, b.w);
  } else {
    unsigned s = 0;
    for (const unsigned d :
         {__vabsdiffu2(a.x, b.x), __vabsdiffu2(a.y, b.y), __vabsdiffu2(a.z, b.z), __vabsdiffu2(a.w, b.w)})
      s += (d & 0xffffu) + (d >> 16);
    return s;
  }
}
template <class Sample>
__device__ unsigned sad(Sample a, Sample b) {
  return a > b ? a - b : b - a;
}
__device__ inline bool same(const uint4 &a, const uint4 &b) {
  return a.x == b.x && a.y == b.y && a.z == b.z && a.w == b.w;
}
template <class Sample>
__device__ bool same(Sample a, Sample b) {
  return a == b;
}

// A block a run of kCompareTilesX tiles: FrameHistory::compare's test of
// each tile, then the changed tiles' bytes recorded. tolerance: in the
// samples' units (FrameHistory::compare's, times units_per_level()).
// A plain launch (<<< >>>).
template <class Sample>
__global__ void compare_tiles_kernel(FrameView frame, KeptPlanes kept, int planes, float tolerance, uint8_t *flags,
                                     int tiles_x) {
  __shared__ unsigned long long diff[kCompareTilesX];
  __shared__ int differs[kCompareTilesX];
  const int tx0 = blockIdx.x * kCompareTilesX, ty = blockIdx.y;
  const int tiles = min(kCompareTilesX, tiles_x - tx0);
  if (threadIdx.x < kCompareTilesX) {
    diff[threadIdx.x] = 0;
    differs[threadIdx.x] = 0;
  }
  __syncthreads();
  const PixelRect first = tile_pixels(tx0, ty, frame.width, frame.height);
  const PixelRect r{first.x0, first.y0, tile_pixels(tx0 + tiles - 1, ty, frame.width, frame.height).x1, first.y1};
  for (int p = 0; p < planes; ++p)
    for_run<Sample>(frame, kept, p, plane_box(frame.format, p, r), [&](int t, const auto *cur, const auto *old) {
      if (tolerance > 0.f) {
        const unsigned d = sad<Sample>(*cur, *old);
        if (d) atomicAdd(&diff[t], static_cast<unsigned long long>(d));
      } else if (!same(*cur, *old)) {
        differs[t] = 1;
      }
    });
  __syncthreads();
  __shared__ int changed[kCompareTilesX];
  if (threadIdx.x < tiles) {
    const int t = threadIdx.x;
    bool c = differs[t] != 0;
    if (tolerance > 0.f) {
      const PixelRect tr = tile_pixels(tx0 + t, ty, frame.width, frame.height);
      unsigned long long samples = 0;
      for (int p = 0; p < planes; ++p) {
        const PlaneBox b = plane_box(frame.format, p, tr);
        samples += static_cast<unsigned long long>((b.b1 - b.b0) / static_cast<int>(sizeof(Sample))) * (b.r1 - b.r0);
      }
      c = tile_over_tolerance(diff[t], samples, tolerance);
    }
    changed[t] = c;
    flags[static_cast<size_t>(ty) * tiles_x + tx0 + t] = c ? 1 : 0;
  }
  __syncthreads();
  bool any = false;
  for (int t = 0; t < tiles; ++t) any = any || changed[t];
  if (!any) return;
  for (int p = 0; p < planes; ++p)
    for_run<Sample>(frame, kept, p, plane_box(frame.format, p, r), [&](int t, const auto *cur, auto *old) {
      if (changed[t]) *old = *cur;
    });
}

// The kernel over a frame's tiles_x x tiles_y tiles.
template <class Sample>
CudaStatus launch_compare_of(const FrameView &frame, const KeptPlanes &kept, int planes, float tolerance,
                             uint8_t *flags, int tiles_x, int tiles_y, cudaStream_t stream) {
  const unsigned runs = static_cast<unsigned>((tiles_x + kCompareTilesX - 1) / kCompareTilesX);
  compare_tiles_kernel<Sample><<<dim3(runs, static_cast<unsigned>(tiles_y)), kCompareThreads, 0, stream>>>(
      frame, kept, planes, tolerance, flags, tiles_x);
  P3D_CUDA_TRY_LAUNCH(compare_tiles_kernel);
  return {};
}

}  // namespace
}  // namespace change_detail
}  // namespace p3d
