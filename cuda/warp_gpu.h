// GPU DIBR warp and hole filling: the function of common/warp.h, bit-exact
// with warp_render_cpu (same P3D_HD helpers, -fmad=false; the z-buffer max
// is order independent, so atomicMax gives the CPU's sequential result).
//
// Per frame, all on `stream`: one block per output row y renders both eyes
// of it: the source row is converted once (load_rgba) into shared memory,
// then per warped eye it clears its z-buffer (shared memory; global memory
// only for rows too wide for it, from about 28000 pixels on Hopper with
// 32-bit keys, 19000 with 64-bit ones; rows wider than about 50000 pixels
// are refused with cudaErrorInvalidValue), scatters
// the depth row (atomicMax on 32-bit keys where every hit lies within 127
// pixels of its target, 64-bit ones otherwise), resolves colours and holes
// (kHoleColour for fill=None), adds the row's holes to a device counter and,
// for Background, fills the row's holes: a ballot per 32-pixel chunk gives
// its hole bits, and each hole finds its nearest non-holes by searching
// those bits (holes are narrow: rarely past the next chunk), no host sync.
// An eye with shift 0 is copied. Where both eyes are warped and a second
// z-buffer costs no resident row (rows up to about 4600 pixels on Hopper),
// the block renders them together: each source pixel's depths are read
// once and placed in both z-buffers, and each target resolves both eyes.
// Row groups: where both eyes are warped with 32-bit keys and the depth is
// on cells of 2 x 2 pixels or more (the filter's 4 x 4 grid at 4K and
// 8K), the rows of a cell row hold the same z-buffers (the keys hold where
// a hit comes from, not its colour), so one block renders up to 4 such
// rows from one scatter, each with its own source row; where shared memory
// holds a source row for each of them (4K), it converts them all first and
// resolves them in one pass. The output is the same as row by row. The
// groups that whole waves of resident blocks take go first; the rows after
// them, too few groups to fill another wave, take a block a row (in
// RowsTogether blocks, at 4K, a block an eye), so that the last wave does
// not run on a few SMs while the rest idle (measured: docs/benchmarks.md,
// Design measurements, "Warp: row groups").
//  * BackgroundSmooth: the row kernel also finds every hole's anchor (the
//    clean pixels from the chunks' hole bits, nearest clean / non-hole
//    pixels by bit search as for Background) and writes the states of the
//    chunks with holes and whether each 32-pixel chunk of the row has a
//    hole, and lists the tiles with holes; then a block (256 threads, 512
//    where shared memory bounds the tiles an SM holds anyway) per listed
//    tile of 32 columns x up to 32 rows and eye copies the states and
//    anchors of
//    its rows and R more above and below into shared memory, slides the
//    +-R window down the column runs of holes (column sums V for its
//    columns and Rx more either side) and sums V over +-Rx along each
//    hole's row run. No host sync. Scratch: kSmoothBytesPerPixel per pixel
//    and eye.
//  * NeighborAverage: afterwards, Jacobi steps ping-ponging two hole masks,
//    in batches of kWarpFillBatch steps; after each batch the host reads the
//    per-step fill counts (a stream sync) to stop when no hole is left or a
//    step filled nothing (what is left is then painted kFillBlack).
// Buffers grow on demand and are reused: no per-frame allocation once the
// largest frame has been seen. One renderer serves one stream at a time.
#pragma once

#include <vector>

#include "../common/pack.h"
#include "../common/warp.h"
#include "cuda_check.h"
#include "device_buffer.h"

namespace p3d {

// NeighborAverage steps launched between two host checks of the counters.
constexpr int kWarpFillBatch = 8;
// BackgroundSmooth scratch per pixel and eye: anchor (Rgba), state; and a
// byte per 32-pixel chunk of a row and eye (has it a hole).
constexpr size_t kSmoothBytesPerPixel = sizeof(Rgba) + 1;

// The row kernels render() chose for rows of `width` pixels and `fill`
// with both eyes warped and 32-bit keys (cuda/warp.cu,
// choose_row_kernels): both eyes at once, and row groups where the depth
// is on cells of 2 x 2 pixels or more, in blocks of a row's size or in
// wide blocks of wide_group_threads, row by row or all rows together.
struct RowKernelChoice {
  int width = -1;
  HoleFill fill = HoleFill::None;
  bool both_eyes = false;
  bool groups = false;
  bool wide_groups = false;
  bool rows_together = false;
  int wide_group_threads = 0;  // a WideGroup or RowsTogether block's size
  int group_slots = 0;         // the group blocks the device holds resident (waves)
};

// The BackgroundSmooth sums kernel's block size last chosen, for a kernel
// and its shared memory (cuda/warp.cu, smooth_tile_threads).
struct SmoothSumsLaunch {
  const void *kernel = nullptr;  // the kernel with no register bound, for the frame's plan
  size_t smem = 0;
  const void *launch = nullptr;  // the kernel launched: it, or its register-bound twin
  int threads = 0;
};

struct FusedAnaglyph;  // cuda/warp.cu

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
  CudaStatus render(const WarpParams &params, const FrameView &src, const YuvToRgb &m, DepthGrid<const float> depth,
                    const FrameView &out, cudaStream_t stream, long long *holes_out = nullptr);
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
  CudaStatus render_packed(const WarpParams &params, const PackParams &pack, const FrameView &src, const YuvToRgb &m,
                           DepthGrid<const float> depth, const FrameView &out, cudaStream_t stream,
                           bool *fused_out = nullptr);

 private:
  CudaStatus render_pair(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                         DepthGrid<const float> depth, const FrameView &out, const FusedAnaglyph *fused,
                         cudaStream_t stream, long long *holes_out, bool *fused_used);
  CudaStatus neighbour_average(const FrameView &out, int width, int height, cudaStream_t stream);

  // keys_: H x W 64-bit keys (a row per block, both eyes in turn), only for
  // rows too wide for shared memory.
  // counters_: total holes, per-step fill counts, BackgroundSmooth's tile
  // count and marks (zeroed every frame). scratch_: the two NeighborAverage
  // hole masks (2 eyes x H x W bytes each). smooth_: the BackgroundSmooth
  // planes (anchors, states, chunk flags; 2 eyes) and its tile list.
  // pair_: render_packed's stereo pair (2W x H, 4 bytes a pixel).
  DeviceBuffer keys_, counters_, scratch_, smooth_, pair_;
  int smem_optin_ = -1;  // the device's opt-in shared memory per block, read once
  int resident_patch_blocks_ = -1;  // the fused anaglyph's patch kernel: one wave of its blocks, read once
  // The kernels whose shared-memory attributes this renderer has set (once
  // per kernel, to the device's most, not every frame).
  std::vector<const void *> attributes_set_;
  // The row kernels for the last width and fill, asked once per width and
  // fill.
  RowKernelChoice rows_;
  SmoothSumsLaunch sums_launch_;
};

}  // namespace p3d
