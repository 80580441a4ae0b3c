// GPU DIBR warp and hole filling: the function of common/warp.h, bit-exact
// with warp_render_cpu (same P3D_HD helpers, -fmad=false; the z-buffer max
// is order independent, so atomicMax gives the CPU's sequential result).
//
// How a frame is rendered: cuda/warp.cu, and the files it names. Rows
// wider than the device's shared memory allows (about 50000 pixels on
// Hopper) are refused with cudaErrorInvalidValue. No host sync, but
// fill=NeighborAverage's (one a batch of its steps) and holes_out's.
// Buffers grow on demand and are reused: no per-frame allocation once the
// largest frame has been seen. One renderer serves one stream at a time.
#pragma once

#include <vector>

#include "../common/pack.h"
#include "../common/warp.h"
#include "change_gpu.h"
#include "cuda_check.h"
#include "device_buffer.h"
#include "warp_plan.h"  // the renderer's cached choices

namespace p3d {

struct FusedAnaglyph;  // cuda/warp_internal.h

class WarpRendererGpu {
 public:
  // src, depth, out: device memory (out is packed RGB, 2W x H). If
  // holes_out is not null, the hole count is copied back (a stream sync).
  // fill=NeighborAverage synchronises to test for remaining holes.
  // Frames that do not fit (warp_frames_fit) give cudaErrorInvalidValue and
  // nothing is launched.
  CudaStatus render(const WarpParams &params, const FrameView &src, const YuvToRgb &m, ImageView<const float> depth,
                    const FrameView &out, cudaStream_t stream, long long *holes_out = nullptr);
  // The same with the depth on a grid (p3d_defs.h DepthGrid): the filter's
  // coarse cells, read in place; the result is the full-size map's.
  // A closed gate (cuda/change_gpu.h: an adaptive stage keeping the frame)
  // makes every kernel return at once; fill=NeighborAverage, whose steps
  // the host checks, takes none (cudaErrorInvalidValue). A gate's rows
  // (the adaptive warp's: those its changes reach) are the only rows
  // rendered: out must hold the rows of the last frame rendered into it
  // with the same parameters (the renderer keeps its fill's states and
  // anchors of every row), as the pairs render_packed and ActiveWarpGpu
  // keep do.
  CudaStatus render(const WarpParams &params, const FrameView &src, const YuvToRgb &m, DepthGrid<const float> depth,
                    const FrameView &out, cudaStream_t stream, long long *holes_out = nullptr, StageGate gate = {});
  // Renders the pair and packs it in one: the function of warp_render_cpu()
  // then pack_cpu() of its 2W x H pair (pack.input is taken as the pair's
  // side-by-side, left first). out: pack_size()'s size, packed RGB or
  // NV12/I420 (pack_args_valid() for that pair). A side-by-side output is
  // rendered into out directly. An anaglyph on gamma values (every method
  // but dubois-linear) into packed RGB with 4-byte aligned rows, with
  // BackgroundSmooth where the rows are resolved together (both eyes
  // warped, depth on cells of 4 x 4 pixels, RowsTogether blocks: 4K on
  // Hopper), is fused: the row kernel writes the anaglyph pixels where
  // neither eye has a hole, and only the pixels next to holes go through
  // the pair, so the full pair is neither written nor read back
  // (measured: docs/benchmarks.md, Design measurements, "Fused pack").
  // Anything else renders into a scratch pair, then pack_gpu(). *fused_out
  // (if not null) says which ran. No host sync (but fill=NeighborAverage's).
  // The gate's rows apply to the scratch pair, which the renderer keeps
  // from frame to frame (every row when it is new); a side-by-side output
  // and an anaglyph that may fuse (the conditions above but the rows
  // resolved together) render every row of a frame the gate runs.
  CudaStatus render_packed(const WarpParams &params, const PackParams &pack, const FrameView &src, const YuvToRgb &m,
                           DepthGrid<const float> depth, const FrameView &out, cudaStream_t stream,
                           bool *fused_out = nullptr, StageGate gate = {});

 private:
  CudaStatus render_pair(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                         DepthGrid<const float> depth, const FrameView &out, const FusedAnaglyph *fused,
                         cudaStream_t stream, long long *holes_out, bool *fused_used, StageGate gate);
  CudaStatus neighbour_average(const FrameView &out, int width, int height, cudaStream_t stream);

  // keys_: H x W 64-bit keys (a row per block, both eyes in turn), only for
  // rows too wide for shared memory.
  // counters_: total holes, per-step fill counts, BackgroundSmooth's tile
  // count and marks (zeroed every frame). scratch_: the two NeighborAverage
  // hole masks (2 eyes x H x W bytes each). smooth_: the BackgroundSmooth
  // planes (anchors, states, chunk flags; 2 eyes) and its tile list.
  // pair_: render_packed's stereo pair (2W x H, 4 or 8 bytes a pixel).
  DeviceBuffer keys_, counters_, scratch_, smooth_, pair_;
  int smem_optin_ = -1;  // the device's opt-in shared memory per block, read once
  int resident_patch_blocks_ = -1;  // the fused anaglyph's patch kernel: one wave of its blocks, read once
  // The kernels whose shared-memory attributes this renderer has set (once
  // per kernel, to the device's most, not every frame).
  std::vector<const void *> attributes_set_;
  // The row kernels for the last width and fill, asked once per width and
  // fill.
  warp_detail::RowKernelChoice rows_;
  warp_detail::SmoothSumsLaunch sums_launch_;
};

}  // namespace p3d
