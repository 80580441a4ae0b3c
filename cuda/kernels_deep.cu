// The kernels of 16-bit pictures (P010, I420_10, RGBA64): the warp's (row,
// smooth sums, NeighborAverage), the pack's, the bars', the change
// compare's and the grey depth's kernels built for them, and the
// high-byte copy the depth estimate and the filter read. This translation unit defines
// P3D_DEVICE_DEEP before any include, so that its device code reads the
// deep formats (common/frame.h, is_deep); the 8-bit kernels live in the
// other files, which compile those branches away.
#define P3D_DEVICE_DEEP 1

// The shared P3D_HD helpers have other device bodies here than in the
// 8-bit units: only whole-program compilation (no -rdc, one device image a
// unit) keeps each unit's kernels with its own.
#ifdef __CUDACC_RDC__
#error "cuda/kernels_deep.cu needs whole-program compilation (-rdc=false)"
#endif

#include <algorithm>

#include "bars_kernels.cuh"
#include "change_compare.cuh"
#include "depth_grey.cuh"
#include "high_bytes_gpu.h"
#include "pack_kernels.cuh"
#include "warp_neighbour.cuh"
#include "warp_rows.cuh"
#include "warp_smooth.cuh"

namespace p3d {
namespace {

// A thread narrows 8 samples of a row of plane blockIdx.z (one 16-byte
// load and one 8-byte store where both rows are aligned), high_byte()
// each. The plane's pointers and sizes are picked by value, not indexed
// by blockIdx.z: an array of a kernel parameter indexed at run time would
// be copied to local memory by every thread.
constexpr int kHighBytesPerThread = 8;

// One plane of the copy: its rows in and out, their strides and sizes.
struct HighBytePlane {
  const uint8_t *in;
  uint8_t *out;
  int in_stride, out_stride, samples, rows;
};
struct HighBytePlanes {
  HighBytePlane p0, p1, p2;
};

__global__ void high_byte_copy_kernel(PixelFormat format, HighBytePlanes planes) {
  chained_kernel_start();
  const HighBytePlane pl = blockIdx.z == 0 ? planes.p0 : blockIdx.z == 1 ? planes.p1 : planes.p2;
  const int i0 = (blockIdx.x * blockDim.x + threadIdx.x) * kHighBytesPerThread;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (y >= pl.rows || i0 >= pl.samples) return;
  const uint8_t *in = pl.in + static_cast<size_t>(y) * pl.in_stride + 2 * static_cast<size_t>(i0);
  uint8_t *to = pl.out + static_cast<size_t>(y) * pl.out_stride + i0;
  const bool whole = i0 + kHighBytesPerThread <= pl.samples;
  if (whole && reinterpret_cast<uintptr_t>(in) % 16 == 0 && reinterpret_cast<uintptr_t>(to) % 8 == 0) {
    const uint4 v = *reinterpret_cast<const uint4 *>(in);
    unsigned lo = 0, hi = 0;
#pragma unroll
    for (int k = 0; k < 2; ++k) {
      const unsigned a = k == 0 ? v.x : v.z, b = k == 0 ? v.y : v.w;
      const unsigned word = high_byte(format, static_cast<int>(a & 0xffffu)) |
                            high_byte(format, static_cast<int>(a >> 16)) << 8 |
                            high_byte(format, static_cast<int>(b & 0xffffu)) << 16 |
                            static_cast<unsigned>(high_byte(format, static_cast<int>(b >> 16))) << 24;
      (k == 0 ? lo : hi) = word;
    }
    *reinterpret_cast<uint2 *>(to) = make_uint2(lo, hi);
    return;
  }
  const int n = whole ? kHighBytesPerThread : pl.samples - i0;
  for (int k = 0; k < n; ++k) to[k] = high_byte(format, load_u16(in, k));
}

}  // namespace

CudaStatus high_byte_copy_gpu(const FrameView &src, const FrameView &out, cudaStream_t stream, int planes) {
  if (!is_deep(src.format) || out.format != high_byte_format(src.format) || out.width != src.width ||
      out.height != src.height || planes < 1 || planes > frame_plane_count(src.format))
    return CudaStatus{cudaErrorInvalidValue, "high_byte_copy_gpu: a deep frame into its high_byte_format", __FILE__,
                      __LINE__};
  HighBytePlane each[3] = {};
  int widest = 0, tallest = 0;
  for (int p = 0; p < planes; ++p) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(src.format, src.width, src.height, p, &row_bytes, &rows);
    each[p] = HighBytePlane{src.plane[p], out.plane[p], src.stride[p], out.stride[p], row_bytes / 2, rows};
    widest = std::max(widest, each[p].samples);
    tallest = std::max(tallest, each[p].rows);
  }
  const dim3 block(32, 8);
  const int threads_x = (widest + kHighBytesPerThread - 1) / kHighBytesPerThread;
  const dim3 grid((threads_x + 31) / 32, (tallest + 7) / 8, planes);
  P3D_CUDA_TRY(launch_chained(high_byte_copy_kernel, grid, block, 0, stream, src.format,
                              HighBytePlanes{each[0], each[1], each[2]}));
  return {};
}

CudaStatus HighByteFrame::of(const FrameView &src, cudaStream_t stream, FrameView *view8, bool luma_only) {
  *view8 = src;
  if (!is_deep(src.format)) return {};
  FrameView out{};
  out.format = high_byte_format(src.format);
  out.width = src.width;
  out.height = src.height;
  const int planes = frame_plane_count(out.format);
  size_t offset[3] = {0, 0, 0}, total = 0;
  for (int p = 0; p < planes; ++p) {
    int row = 0, rows = 0;
    frame_plane_size(out.format, src.width, src.height, p, &row, &rows);
    out.stride[p] = (row + 15) & ~15;
    offset[p] = total;
    total += static_cast<size_t>(out.stride[p]) * rows;
  }
  P3D_CUDA_TRY_STATUS(copy_.ensure(total));
  for (int p = 0; p < planes; ++p) out.plane[p] = copy_.as<uint8_t>() + offset[p];
  P3D_CUDA_TRY_STATUS(high_byte_copy_gpu(src, out, stream, luma_only ? 1 : planes));
  *view8 = out;
  return {};
}

namespace bars_detail {

CudaStatus launch_bar_counts_deep(const FrameView &frame, int luma_threshold, uint32_t *rows, uint32_t *cols,
                                  cudaStream_t stream) {
  return launch_bar_counts_of(frame, luma_threshold, rows, cols, stream);
}
CudaStatus launch_views_outside_deep(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                                     cudaStream_t stream, StageGate gate) {
  return launch_views_outside_of<Rgba16>(src, m, active, pair, stream, gate);
}

}  // namespace bars_detail

namespace depth_grey_detail {

CudaStatus launch_depth_from_grey_deep(const FrameView &grey, const YuvToRgb &m, ImageView<float> depth,
                                       cudaStream_t stream) {
  return launch_depth_from_grey_of(grey, m, depth, stream);
}

}  // namespace depth_grey_detail

namespace change_detail {

CudaStatus launch_compare_deep(const FrameView &frame, const KeptPlanes &kept, int planes, float tolerance,
                               uint8_t *flags, int tiles_x, int tiles_y, cudaStream_t stream) {
  return launch_compare_of<uint16_t>(frame, kept, planes, tolerance, flags, tiles_x, tiles_y, stream);
}

}  // namespace change_detail

namespace pack_detail {
namespace {

// The 16-bit default case, an anaglyph of a side-by-side RGBA64 pair into
// RGBA64, two pixels a thread: each eye's two input pixels come in one
// 16-byte load and the two outputs go in one 16-byte store (the launcher
// checks 16-byte aligned rows and an even view width, so no thread has a
// ragged end), anaglyph() per pixel as pack_pixel_for gives it. The
// generic kernel reads and writes each pixel through the format-generic
// load_pixel / store_pixel, which next to the mix's own sums made this
// pack bound by its instructions (measured: docs/benchmarks.md, "10-bit
// frames (P010)").
constexpr int kDeepVec = 2;
__global__ void pack_anaglyph_pair16_vec(const PackKernelParams kp) {
  chained_kernel_start();
  if (kp.gate.closed()) return;
  const int x0 = (blockIdx.x * blockDim.x + threadIdx.x) * kDeepVec;
  const int y = (gridDim.y - 1 - blockIdx.y) * blockDim.y + threadIdx.y;  // bottom up, as every pack kernel
  if (x0 >= kp.out.width || y >= kp.out.height) return;
  const int w = kp.in.width / 2;
  const uint8_t *row = kp.in.plane[0] + static_cast<size_t>(y) * kp.in.stride[0];
  ulonglong2 eye[2];
  for (int e = 0; e < 2; ++e)
    eye[e] = *reinterpret_cast<const ulonglong2 *>(row + 8 * static_cast<size_t>(x0 + view_slot(kp.p, e) * w));
  const uint64_t a = rgba_word(anaglyph(kp.am, word_rgba(static_cast<uint64_t>(eye[0].x)),
                                        word_rgba(static_cast<uint64_t>(eye[1].x))));
  const uint64_t b = rgba_word(anaglyph(kp.am, word_rgba(static_cast<uint64_t>(eye[0].y)),
                                        word_rgba(static_cast<uint64_t>(eye[1].y))));
  *reinterpret_cast<ulonglong2 *>(kp.out.plane[0] + static_cast<size_t>(y) * kp.out.stride[0] +
                                  8 * static_cast<size_t>(x0)) = make_ulonglong2(a, b);
}

// pack_anaglyph_pair16_vec's conditions (besides the side-by-side input).
bool anaglyph_pair16_vec(const PackParams &p, const FrameView &in, const FrameView &out) {
  return p.layout == PackLayout::Anaglyph && out.format == PixelFormat::RGBA64 && (in.width / 2) % kDeepVec == 0 &&
         rows_aligned(in, 0, 16) && rows_aligned(out, 0, 16);
}

}  // namespace

CudaStatus launch_pack_deep(const PackKernelParams &kp, cudaStream_t stream) {
  if (kp.p.input == StereoInput::SideBySide && anaglyph_pair16_vec(kp.p, kp.in, kp.out)) {
    const dim3 block(kBlockX, kBlockY);
    const dim3 grid((kp.out.width / kDeepVec + kBlockX - 1) / kBlockX, (kp.out.height + kBlockY - 1) / kBlockY);
    P3D_CUDA_TRY(launch_chained(pack_anaglyph_pair16_vec, grid, block, 0, stream, kp));
    return {};
  }
  return with_input(kp.p.input, [&](auto input) { return launch_plain<decltype(input)::value, Rgba16>(kp, stream); });
}

}  // namespace pack_detail

namespace warp_detail {

template <>
CudaStatus query_row_kernels<Rgba16>(HoleFill fill, int W, int smem_optin, std::vector<const void *> *attributes_set,
                                     RowKernelChoice *choice) {
  return query_row_kernels_of<Rgba16>(fill, W, smem_optin, attributes_set, choice);
}

// 16-bit pictures take every block kind but the fused anaglyph's.
template <>
CudaStatus launch_row_kernel<Rgba16>(const RowLaunch &l) {
  switch (l.keys) {
    case KeyPlace::NarrowSharedPerEye:
      if (l.group_rows == 1) return launch_rows<NarrowKeys, true, true, RowBlock::Row, false, Rgba16>(l);
      if (l.rows_together) return launch_rows<NarrowKeys, true, true, RowBlock::RowsTogether, false, Rgba16>(l);
      return l.wide_groups ? launch_rows<NarrowKeys, true, true, RowBlock::WideGroup, false, Rgba16>(l)
                           : launch_rows<NarrowKeys, true, true, RowBlock::Group, false, Rgba16>(l);
    case KeyPlace::NarrowShared:
      return launch_rows<NarrowKeys, true, false, RowBlock::Row, false, Rgba16>(l);
    case KeyPlace::WideShared:
      return launch_rows<WideKeys, true, false, RowBlock::Row, false, Rgba16>(l);
    case KeyPlace::WideGlobal:
      return launch_rows<WideKeys, false, false, RowBlock::Row, false, Rgba16>(l);
  }
  return CudaStatus{cudaErrorInvalidValue, "KeyPlace of a 16-bit picture", __FILE__, __LINE__};
}

template <>
CudaStatus launch_smooth<Rgba16>(const SmoothPlan &plan, const SmoothScratch &sc, const FrameView &out, int W, int H,
                                 cudaStream_t stream, int smem_optin, std::vector<const void *> *attributes_set,
                                 SmoothSumsLaunch *threads_cache) {
  return launch_smooth_of<Rgba16>(plan, sc, out, W, H, stream, smem_optin, attributes_set, threads_cache);
}

template <>
CudaStatus launch_neighbour_step<Rgba16>(const FrameView &out, int W, int H, const uint8_t *mask_in,
                                         uint8_t *mask_out, unsigned *filled, cudaStream_t stream) {
  return launch_neighbour_step_of<Rgba16>(out, W, H, mask_in, mask_out, filled, stream);
}
template <>
CudaStatus launch_paint_holes<Rgba16>(const FrameView &out, int W, int H, const uint8_t *mask, cudaStream_t stream) {
  return launch_paint_holes_of<Rgba16>(out, W, H, mask, stream);
}

}  // namespace warp_detail
}  // namespace p3d
