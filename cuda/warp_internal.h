// What the warp's translation units share and nothing outside cuda/warp*.cu
// includes: the kernels' parameter structs, the counters' layout, and the
// launchers each file gives the renderer (cuda/warp.cu):
//   warp_rows.cu     the row kernel: query_row_kernels, launch_row_kernel
//   warp_smooth.cu   BackgroundSmooth's sums: launch_smooth
//   warp_packed.cu   render_packed and the fused anaglyph's patch kernel:
//                    launch_fused_patch
//   warp_neighbour.cu  NeighborAverage's steps (WarpRendererGpu::neighbour_average)
// The launchers that take a pixel type are built for Rgba in those files
// and for Rgba16 (16-bit pictures) in kernels_deep.cu, from the kernel
// templates of warp_rows.cuh, warp_smooth.cuh and warp_neighbour.cuh.
// The host-side choices they launch with are cuda/warp_plan.h's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "../common/frame.h"
#include "../common/warp.h"
#include "change_gpu.h"
#include "cuda_check.h"
#include "warp_plan.h"

namespace p3d {

// The anaglyph output of a fused render (WarpRendererGpu::render_packed,
// cuda/warp_packed.cu): `out` W x H, packed RGB in the pair's format with
// 4-byte aligned rows; the gamma mix's fixed-point matrices
// (anaglyph_mix_word, common/pack.h), kernel parameters so that the mix
// reads them as constant operands; `swap`: the right eye is shown as the
// left (PackParams::swap_eyes). out.plane[0] null: not fused.
struct FusedAnaglyph {
  FrameView out;
  int32_t left[9], right[9];  // AnaglyphMatrices::left_q, right_q
  bool swap;
};

namespace warp_detail {

// NeighborAverage steps launched between two host checks of the counters.
constexpr int kWarpFillBatch = 8;

// Layout of counters_, zeroed every frame: total hole count, the per-step
// fill counts of one NeighborAverage batch, BackgroundSmooth's tile count,
// then its tile marks (one word a tile).
constexpr size_t kTotalOffset = 0;
constexpr size_t kFilledOffset = sizeof(unsigned long long);
constexpr size_t kTileCountOffset = kFilledOffset + sizeof(unsigned) * kWarpFillBatch;
constexpr size_t kTileMarksOffset = kTileCountOffset + sizeof(unsigned);

// BackgroundSmooth's scratch (both eyes, W x H each) and its tiles. The
// sums kernel works on tiles of 32 columns (one chunk) x `tile_rows` rows
// of one eye; the row kernel lists the tiles that hold a hole (after each
// eye's resolve loop), so that the sums kernel visits those and no others
// (most tiles of a frame have none: launching a block for each would cost
// about as much as the sums themselves). Tile t = (eye * tiles_y + y /
// tile_rows) * tiles_x + chunk.
struct SmoothScratch {
  uint8_t *state;        // kState* flags of every pixel of the chunks with holes
  void *anchor;          // every hole's anchor: the pictures' pixel type (Rgba, Rgba16)
  uint8_t *chunk_holes;  // whether each 32-pixel chunk of a row has a hole (2 eyes x H x chunks)
  unsigned *tile_mark;   // per tile: listed yet (zeroed every frame)
  unsigned *tile_list;   // the listed tiles, in no particular order
  unsigned *tile_count;  // how many are listed (zeroed every frame)
  int tile_rows, tiles_x, tiles_y;
};

// A frame's row kernel launch (launch_row_kernel).
struct RowLaunch {
  FrameView src;
  YuvToRgb m;
  DepthGrid<const float> depth;
  FrameView out;
  EyeShifts eyes;
  float D, convergence;
  HoleFill fill;
  KeyPlace keys;
  unsigned long long *global_keys;
  uint8_t *mask;
  SmoothScratch smooth;
  unsigned long long *total;
  bool words;
  size_t smem;
  cudaStream_t stream;
  int smem_optin;
  std::vector<const void *> *attributes_set;
  int group_rows;  // rows a block (NarrowSharedPerEye only; 1: a row's block)
  int tail_y0;     // row groups: from this row on, a block a row or eye (group_tail_y0)
  bool wide_groups;  // groups in WideGroup blocks, of wide_group_threads
  bool rows_together;  // groups in RowsTogether blocks, of wide_group_threads
  int wide_group_threads;
  FusedAnaglyph fused;  // out.plane[0] null: not fused
  StageGate gate;       // closed: the adaptive stage keeps this frame (cuda/change_gpu.h)
};

// cuda/warp.cu.
// Lets `kernel` take as much dynamic shared memory as the device allows a
// block and the largest carveout, once per kernel and renderer (`done`).
CudaStatus allow_shared_memory(const void *kernel, int smem_optin, std::vector<const void *> *done);
// The error of frames that do not fit (warp_frames_fit).
CudaStatus invalid_frames();

// cuda/warp_rows.cu.
// choose_row_kernels for rows of W pixels of type Px and `fill`, from what
// the device holds of each candidate kernel. *choice is replaced only
// once every query succeeded.
template <class Px>
CudaStatus query_row_kernels(HoleFill fill, int W, int smem_optin, std::vector<const void *> *attributes_set,
                             RowKernelChoice *choice);
template <>
CudaStatus query_row_kernels<Rgba>(HoleFill fill, int W, int smem_optin, std::vector<const void *> *attributes_set,
                                   RowKernelChoice *choice);
template <>
CudaStatus query_row_kernels<Rgba16>(HoleFill fill, int W, int smem_optin, std::vector<const void *> *attributes_set,
                                     RowKernelChoice *choice);
// The row kernel for the run's key place, row groups and fill, on pixels
// of type Px (Rgba16: no fused anaglyph; warp_plan.h).
template <class Px>
CudaStatus launch_row_kernel(const RowLaunch &l);
template <>
CudaStatus launch_row_kernel<Rgba>(const RowLaunch &l);
template <>
CudaStatus launch_row_kernel<Rgba16>(const RowLaunch &l);

// cuda/warp_smooth.cu.
// BackgroundSmooth sums, after the row kernel wrote the states and anchors
// and listed the tiles with holes. No host sync.
template <class Px>
CudaStatus launch_smooth(const SmoothPlan &plan, const SmoothScratch &sc, const FrameView &out, int W, int H,
                         cudaStream_t stream, int smem_optin, std::vector<const void *> *attributes_set,
                         SmoothSumsLaunch *threads_cache);
template <>
CudaStatus launch_smooth<Rgba>(const SmoothPlan &plan, const SmoothScratch &sc, const FrameView &out, int W, int H,
                               cudaStream_t stream, int smem_optin, std::vector<const void *> *attributes_set,
                               SmoothSumsLaunch *threads_cache);
template <>
CudaStatus launch_smooth<Rgba16>(const SmoothPlan &plan, const SmoothScratch &sc, const FrameView &out, int W, int H,
                                 cudaStream_t stream, int smem_optin, std::vector<const void *> *attributes_set,
                                 SmoothSumsLaunch *threads_cache);

// cuda/warp_neighbour.cu.
// One NeighborAverage Jacobi step over both eyes of `out` (mask_in: the
// holes before it, mask_out: after; *filled: the pixels it filled), and the
// paint of the holes left in `mask` (kFillBlack).
template <class Px>
CudaStatus launch_neighbour_step(const FrameView &out, int W, int H, const uint8_t *mask_in, uint8_t *mask_out,
                                 unsigned *filled, cudaStream_t stream);
template <class Px>
CudaStatus launch_paint_holes(const FrameView &out, int W, int H, const uint8_t *mask, cudaStream_t stream);
template <>
CudaStatus launch_neighbour_step<Rgba>(const FrameView &out, int W, int H, const uint8_t *mask_in, uint8_t *mask_out,
                                       unsigned *filled, cudaStream_t stream);
template <>
CudaStatus launch_neighbour_step<Rgba16>(const FrameView &out, int W, int H, const uint8_t *mask_in,
                                         uint8_t *mask_out, unsigned *filled, cudaStream_t stream);
template <>
CudaStatus launch_paint_holes<Rgba>(const FrameView &out, int W, int H, const uint8_t *mask, cudaStream_t stream);
template <>
CudaStatus launch_paint_holes<Rgba16>(const FrameView &out, int W, int H, const uint8_t *mask, cudaStream_t stream);

// cuda/warp_packed.cu.
// The fused anaglyph's patch kernel after the sums kernel: the pixels the
// row kernel left in `pair` mixed into f.out. *resident_blocks: one wave
// of its blocks, read from the device once (-1: not yet).
CudaStatus launch_fused_patch(const FrameView &pair, const FusedAnaglyph &f, const SmoothScratch &sc,
                              const SmoothPlan &plan, int tail_y0, cudaStream_t stream, int *resident_blocks,
                              StageGate gate);

}  // namespace warp_detail
}  // namespace p3d
