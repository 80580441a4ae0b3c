// GPU DIBR warp (cuda/warp_gpu.h): a frame's passes, planned and launched.
//
// Per frame, all on `stream`, no host sync but NeighborAverage's and
// holes_out's:
//  * the row kernel (cuda/warp_rows.cu): a block per output row, or per
//    group of rows that read one depth cell row, renders both eyes: the
//    source row converted once (load_rgba) into shared memory, a z-buffer
//    an eye (shared memory; global memory only for rows too wide for it,
//    from about 28000 pixels on Hopper with 32-bit keys, 19000 with 64-bit
//    ones; rows wider than about 50000 pixels are refused with
//    cudaErrorInvalidValue) filled by atomicMax (32-bit keys where every
//    hit lies within 127 pixels of its target, 64-bit ones otherwise), the
//    colours and holes resolved (kHoleColour for fill=None), the holes
//    counted on the device, and Background's holes filled in the row; an
//    eye with shift 0 is copied;
//  * BackgroundSmooth: the sums kernel (cuda/warp_smooth.cu) fills the
//    holes from the anchors the row kernel found, tile by listed tile;
//  * NeighborAverage: Jacobi steps in batches, the host reading the fill
//    counts after each (cuda/warp_neighbour.cu);
//  * render_packed with the anaglyph fused: the patch kernel
//    (cuda/warp_packed.cu) mixes the pixels next to holes.
// Which row kernel, key place, row groups, tiles and block sizes a frame
// takes is cuda/warp_plan.h's choice, from what this file and the
// launchers read of the device.
#include <vector>

#include "chained_launch.cuh"
#include "warp_gpu.h"
#include "warp_internal.h"

namespace p3d {
namespace warp_detail {

// Lets `kernel` take as much dynamic shared memory as the device allows a
// block beside the kernel's static shared memory (past 48 KiB only by
// opting in), and asks for the largest carveout, so that as many blocks
// share an SM as their shared memory allows. Always the most, not a
// frame's size: the limit belongs to the kernel, shared by every renderer
// in the process, so a renderer that set a smaller one for its smaller
// rows would make another's launch fail; and the default 48 KiB count the
// static bytes too (a row of 5956 pixels with 32-bit keys takes 49144
// dynamic bytes, past it with the row kernel's 16 static ones). `done`
// lists the kernels this renderer has set up, so no frame after the first
// makes a call (a renderer serves one device).
CudaStatus allow_shared_memory(const void *kernel, int smem_optin, std::vector<const void *> *done) {
  for (const void *k : *done)
    if (k == kernel) return {};
  cudaFuncAttributes a{};
  P3D_CUDA_TRY(cudaFuncGetAttributes(&a, kernel));
  P3D_CUDA_TRY(cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize,
                                    smem_optin - static_cast<int>(a.sharedSizeBytes)));
  P3D_CUDA_TRY(cudaFuncSetAttribute(kernel, cudaFuncAttributePreferredSharedMemoryCarveout,
                                    static_cast<int>(cudaSharedmemCarveoutMaxShared)));
  done->push_back(kernel);
  return {};
}

CudaStatus invalid_frames() {
  return CudaStatus{cudaErrorInvalidValue, "warp_frames_fit(src, depth, out)", __FILE__, __LINE__};
}

}  // namespace warp_detail

using namespace warp_detail;

CudaStatus WarpRendererGpu::render(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                                   ImageView<const float> depth, const FrameView &out, cudaStream_t stream,
                                   long long *holes_out) {
  return render(params, src, m, full_grid(depth), out, stream, holes_out);
}

CudaStatus WarpRendererGpu::render(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                                   DepthGrid<const float> depth, const FrameView &out, cudaStream_t stream,
                                   long long *holes_out, StageGate gate) {
  return render_pair(params, src, m, depth, out, nullptr, stream, holes_out, nullptr, gate);
}

CudaStatus WarpRendererGpu::render_pair(const WarpParams &params, const FrameView &src, const YuvToRgb &m,
                                        DepthGrid<const float> depth, const FrameView &out,
                                        const FusedAnaglyph *fused_request, cudaStream_t stream, long long *holes_out,
                                        bool *fused_used, StageGate gate) {
  if (!warp_frames_fit(src, depth, out)) return invalid_frames();
  const WarpParams p = warp_sanitize(params);
  const int W = src.width, H = src.height;
  const float D = disparity_scale(p, W);
  const EyeShifts eyes{{warp_eye_shift(p, D, 0), warp_eye_shift(p, D, 1)}};
  // 16-bit pictures take the Rgba16 kernels (cuda/kernels_deep.cu).
  const bool deep = is_deep(src.format);
  const size_t pixel_bytes = deep ? sizeof(Rgba16) : sizeof(Rgba);
  const bool average = p.fill == HoleFill::NeighborAverage;
  const bool smooth = p.fill == HoleFill::BackgroundSmooth;
  if (average && gate.state)
    return CudaStatus{cudaErrorInvalidValue, "fill=NeighborAverage (host-checked steps) with a stage gate", __FILE__,
                      __LINE__};

  if (smem_optin_ < 0) {
    int dev = 0;
    P3D_CUDA_TRY(cudaGetDevice(&dev));
    P3D_CUDA_TRY(cudaDeviceGetAttribute(&smem_optin_, cudaDevAttrMaxSharedMemoryPerBlockOptin, dev));
  }
  const RowFrame frame{W, H, warp_narrow_keys_fit(eyes.shift[0], eyes.shift[1], D, p.convergence),
                       eyes.shift[0] != 0.f && eyes.shift[1] != 0.f, depth.shift, smem_optin_, pixel_bytes};
  if (!row_fits(W, 0, smem_optin_, pixel_bytes))  // rows wider than ~50000 pixels on Hopper (half that of 16-bit ones)
    return CudaStatus{cudaErrorInvalidValue, "row_smem_bytes(W) <= cudaDevAttrMaxSharedMemoryPerBlockOptin", __FILE__,
                      __LINE__};
  if (row_kernels_apply(frame) && (rows_.width != W || rows_.fill != p.fill || rows_.pixel_bytes != pixel_bytes))
    P3D_CUDA_TRY_STATUS(deep ? query_row_kernels<Rgba16>(p.fill, W, smem_optin_, &attributes_set_, &rows_)
                             : query_row_kernels<Rgba>(p.fill, W, smem_optin_, &attributes_set_, &rows_));
  const RowPlan rows = plan_rows(frame, rows_);
  if (rows.keys == KeyPlace::WideGlobal)
    P3D_CUDA_TRY_STATUS(keys_.ensure(static_cast<size_t>(W) * H * sizeof(WideKeys::Word)));
  if (average) P3D_CUDA_TRY_STATUS(scratch_.ensure(2 * 2 * static_cast<size_t>(W) * H));  // two masks, both eyes
  const size_t plane = 2 * static_cast<size_t>(W) * H;                                      // both eyes
  const size_t chunk_flags = 2 * static_cast<size_t>(H) * row_chunks(W);  // both eyes
  const SmoothPlan plan = smooth ? plan_smooth(eyes, D, W, H, smem_optin_, pixel_bytes) : SmoothPlan{};
  // The tile list's words, after the anchors, states and chunk flags.
  const size_t list_offset = align16(plane * smooth_bytes_per_pixel(pixel_bytes) + chunk_flags);
  if (smooth) {
    const size_t had = smooth_.size();
    P3D_CUDA_TRY_STATUS(smooth_.ensure(list_offset + sizeof(unsigned) * plan.tiles()));
    // Cleared once a (re)allocation: the sums kernel's copy loads every
    // anchor of a chunk with holes beside its state and drops those whose
    // state names none, so no byte it loads may be uninitialised memory
    // (compute-sanitizer initcheck), though no such value is ever used.
    if (smooth_.size() != had) {
      P3D_CUDA_TRY(zero_chained(smooth_.get(), smooth_.size(), stream));
      gate = gate.every_row();  // the states and anchors of the rows left out are gone
    }
  }
  const size_t counter_bytes = kTileMarksOffset + sizeof(unsigned) * plan.tiles();
  P3D_CUDA_TRY_STATUS(counters_.ensure(counter_bytes));
  uint8_t *counters = counters_.as<uint8_t>();
  auto *total = reinterpret_cast<unsigned long long *>(counters + kTotalOffset);
  P3D_CUDA_TRY(zero_chained(counters, counter_bytes, stream));

  uint8_t *mask = average ? scratch_.as<uint8_t>() : nullptr;
  // BackgroundSmooth scratch, both eyes each: anchors, states, chunk flags,
  // then the tile list; the tile marks and counts are in counters_.
  SmoothScratch sc{};
  if (smooth) {
    sc.anchor = smooth_.get();
    sc.state = smooth_.as<uint8_t>() + plane * pixel_bytes;
    sc.chunk_holes = sc.state + plane;
    sc.tile_list = reinterpret_cast<unsigned *>(smooth_.as<uint8_t>() + list_offset);
    sc.tile_mark = reinterpret_cast<unsigned *>(counters + kTileMarksOffset);
    sc.tile_count = reinterpret_cast<unsigned *>(counters + kTileCountOffset);
    sc.tile_rows = plan.tile_rows;
    sc.tiles_x = plan.tiles_x;
    sc.tiles_y = plan.tiles_y;
  }
  const bool words = rows_aligned(out, 0, static_cast<int>(pixel_bytes));
  // The pack fused where the rows are resolved together (both eyes of a
  // target at hand) and the sums kernel fills the holes; 8-bit views only
  // (the 16-bit row kernels have no fused anaglyph).
  const bool fuse = fused_request && !deep && rows.rows_together && smooth && words;
  const RowLaunch launch{src, m, depth, out, eyes, D, p.convergence, p.fill,
                         rows.keys, keys_.as<WideKeys::Word>(), mask, sc, total, words, rows.smem, stream, smem_optin_,
                         &attributes_set_, rows.group_rows, rows.tail_y0, rows.wide_groups, rows.rows_together,
                         rows.wide_group_threads, fuse ? *fused_request : FusedAnaglyph{}, gate};
  P3D_CUDA_TRY_STATUS(deep ? launch_row_kernel<Rgba16>(launch) : launch_row_kernel<Rgba>(launch));
  if (average) P3D_CUDA_TRY_STATUS(neighbour_average(out, W, H, stream));
  if (smooth)
    P3D_CUDA_TRY_STATUS(deep ? launch_smooth<Rgba16>(plan, sc, out, W, H, stream, smem_optin_, &attributes_set_,
                                                     &sums_launch_)
                             : launch_smooth<Rgba>(plan, sc, out, W, H, stream, smem_optin_, &attributes_set_,
                                                   &sums_launch_));
  if (fuse)
    P3D_CUDA_TRY_STATUS(
        launch_fused_patch(out, *fused_request, sc, plan, rows.tail_y0, stream, &resident_patch_blocks_, gate));
  if (fused_used) *fused_used = fuse;

  if (holes_out) {
    unsigned long long h = 0;
    P3D_CUDA_TRY(cudaMemcpyAsync(&h, total, sizeof(h), cudaMemcpyDeviceToHost, stream));
    P3D_CUDA_TRY(cudaStreamSynchronize(stream));
    *holes_out = static_cast<long long>(h);
  }
  return {};
}

}  // namespace p3d
