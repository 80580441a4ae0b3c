// The GPU stages on 16-bit pictures (P010, I420_10, RGBA64) against the
// CPU references, byte for byte, as for 8-bit ones (the same P3D_HD helpers,
// built for Rgba16 in cuda/kernels_deep.cu):
//  * the high-byte copy that the depth estimate and the filter read;
//  * the depth estimate of deep frames, RGBD depth from a deep grey
//    picture, and the filter with a deep guide;
//  * the warp into RGBA64, every fill and view, at every key place;
//  * the pack of an RGBA64 pair into RGBA64, P010 and I420_10;
//  * render_packed from each deep source into each deep output.
// Pictures are random 16-bit samples and the low-bit-rich deep_picture().
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "bilateral.h"
#include "bilateral_gpu.h"
#include "depth_estimate.h"
#include "depth_estimate_gpu.h"
#include "gpu_util.h"
#include "high_bytes_gpu.h"
#include "pack.h"
#include "pack_gpu.h"
#include "test_data.h"
#include "warp.h"
#include "warp_gpu.h"
#include "warp_internal.h"

namespace p3d {
namespace {

using test::DeviceDepth;
using test::DeviceFrame;

uint32_t fresh_seed() { return std::random_device{}(); }

// Every byte of every plane's pixels (row padding left out): "" when the
// frames are equal, else how many bytes differ and where the first is.
std::string plane_difference(const HostFrame &want, const HostFrame &got) {
  if (want.format() != got.format() || want.width() != got.width() || want.height() != got.height())
    return "frames of different formats or sizes";
  const FrameView a = want.view(), b = got.view();
  long long differing = 0;
  std::ostringstream first;
  for (int p = 0; p < frame_plane_count(a.format); ++p) {
    int row = 0, rows = 0;
    frame_plane_size(a.format, a.width, a.height, p, &row, &rows);
    for (int y = 0; y < rows; ++y)
      for (int i = 0; i < row; ++i) {
        const int va = a.plane[p][static_cast<size_t>(y) * a.stride[p] + i];
        const int vb = b.plane[p][static_cast<size_t>(y) * b.stride[p] + i];
        if (va != vb && differing++ == 0)
          first << "first in plane " << p << " row " << y << " byte " << i << ": cpu " << va << " gpu " << vb;
      }
  }
  return differing == 0 ? "" : std::to_string(differing) + " bytes differ, " + first.str();
}

// A deep frame: random 16-bit samples, or deep_picture() converted.
HostFrame deep_frame(PixelFormat f, int w, int h, uint32_t seed, bool random) {
  if (!random) return HostFrame::from_bgr16(test::deep_picture(w, h, seed), f, 6);
  HostFrame frame(f, w, h, 6);
  frame.fill_random(seed);
  return frame;
}

// Depth with slopes and steps: holes for the fills, occlusions for the keys.
cv::Mat step_depth(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.f, 1.f);
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<float>(y, x) = 0.2f + 0.3f * static_cast<float>(x) / static_cast<float>(w);
  for (int k = 0; k < 4; ++k) {
    const int x0 = static_cast<int>(rng() % (w / 2 + 1)), y0 = static_cast<int>(rng() % (h / 2 + 1));
    d(cv::Rect(x0, y0, std::max(1, w / 4), std::max(1, h / 4))) = cv::Scalar(u01(rng));
  }
  return d;
}

const YuvToRgb kTenBit = yuv_to_rgb_params(0.299, 0.114, false, 10);

class GpuDeep : public ::testing::Test {
 public:
  void SetUp() override {
    test::check_cuda(CudaStatus{cudaStreamCreate(&stream_), "cudaStreamCreate", __FILE__, __LINE__});
  }
  void TearDown() override {
    if (stream_) cudaStreamDestroy(stream_);
  }

  // renderer_.render against warp_render_cpu into RGBA64: bytes and holes.
  // depth_shift: the GPU reads the depth on cells of 2^depth_shift pixels
  // (`depth` constant over them: cell_constant), where rows share a
  // z-buffer in groups.
  void expect_warp_same(const WarpParams &p, const HostFrame &src, const cv::Mat &depth, int depth_shift = 0) {
    const int w = src.width(), h = src.height();
    std::ostringstream what;
    what << test::format_name(src.format()) << " " << w << "x" << h << " max_disparity " << p.max_disparity << " view "
         << int(p.view) << " fill " << int(p.fill) << " cells of " << (1 << depth_shift);
    SCOPED_TRACE(what.str());
    HostFrame cpu(PixelFormat::RGBA64, 2 * w, h, 8);
    const long long cpu_holes = warp_render_cpu(p, src.view(), kTenBit, depth_view_of(depth), cpu.view());
    ASSERT_GE(cpu_holes, 0);
    const DeviceFrame dsrc = DeviceFrame::upload(src);
    const DeviceDepth ddepth = DeviceDepth::upload_grid(depth, depth_shift);
    const DeviceFrame dout(PixelFormat::RGBA64, 2 * w, h);  // poisoned
    long long gpu_holes = -7;
    test::check_cuda(
        renderer_.render(p, dsrc.view(), kTenBit, as_const(ddepth.grid()), dout.view(), stream_, &gpu_holes));
    ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
    EXPECT_EQ(gpu_holes, cpu_holes);
    EXPECT_EQ(plane_difference(cpu, dout.download()), "");
  }

  // render_packed against warp_render_cpu into an RGBA64 pair, then pack_cpu.
  void expect_packed_same(const WarpParams &w, const PackParams &pp, const HostFrame &src, const cv::Mat &depth,
                          PixelFormat out_format, int depth_shift = 0) {
    const int sw = src.width(), sh = src.height();
    std::ostringstream what;
    what << test::format_name(src.format()) << " -> " << test::format_name(out_format) << " " << sw << "x" << sh
         << " layout " << int(pp.layout) << " method " << int(pp.method) << " fill " << int(w.fill);
    SCOPED_TRACE(what.str());
    int pw = 0, ph = 0;
    pack_size(pp.layout, sw, sh, &pw, &ph);
    HostFrame pair(PixelFormat::RGBA64, 2 * sw, sh, 8), cpu(out_format, pw, ph, 8);
    ASSERT_GE(warp_render_cpu(w, src.view(), kTenBit, depth_view_of(depth), pair.view()), 0);
    pack_cpu(pp, pair.view(), cpu.view());
    const DeviceFrame dsrc = DeviceFrame::upload(src);
    const DeviceDepth ddepth = DeviceDepth::upload_grid(depth, depth_shift);
    const DeviceFrame dout(out_format, pw, ph);  // poisoned
    test::check_cuda(
        renderer_.render_packed(w, pp, dsrc.view(), kTenBit, as_const(ddepth.grid()), dout.view(), stream_));
    ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
    EXPECT_EQ(plane_difference(cpu, dout.download()), "");
  }

  // The depth the stream's work wrote, bit for bit the CPU's.
  void expect_same_depth(const DeviceDepth &gpu, const cv::Mat &cpu) {
    ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
    const test::FloatDiff d = test::compare_f32(gpu.download(), cpu);
    EXPECT_EQ(d.nonfinite, 0);
    EXPECT_EQ(d.max_abs, 0.0);
  }

 protected:
  cudaStream_t stream_ = nullptr;
  WarpRendererGpu renderer_;
};

TEST_F(GpuDeep, HighByteCopyIsTheCpuCopy) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  for (PixelFormat f : test::kDeepFormats)
    for (const cv::Size size : {cv::Size(33, 21), cv::Size(64, 48)})
      for (bool random : {true, false}) {
        SCOPED_TRACE(std::string(test::format_name(f)) + " " + std::to_string(size.width) + "x" +
                     std::to_string(size.height) + (random ? " random" : " picture"));
        const HostFrame src = deep_frame(f, size.width, size.height, seed, random);
        HostFrame cpu(high_byte_format(f), size.width, size.height, 4);
        high_byte_copy_cpu(src.view(), cpu.view());
        const DeviceFrame dsrc = DeviceFrame::upload(src);
        const DeviceFrame dout(high_byte_format(f), size.width, size.height);
        test::check_cuda(high_byte_copy_gpu(dsrc.view(), dout.view(), stream_, frame_plane_count(f)));
        ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
        EXPECT_EQ(plane_difference(cpu, dout.download()), "");
      }
}

TEST_F(GpuDeep, DepthOfDeepFramesIsTheCpuDepth) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  for (PixelFormat f : test::kDeepFormats)
    for (bool random : {true, false}) {
      SCOPED_TRACE(std::string(test::format_name(f)) + (random ? " random" : " picture"));
      const HostFrame src = deep_frame(f, 160, 96, seed, random);
      const DepthParams params;
      cv::Mat cpu(src.height(), src.width(), CV_32FC1);
      DepthEstimatorCpu cpu_estimator;
      cpu_estimator.estimate(params, src.view(), depth_view_of(cpu));
      DepthEstimatorGpu gpu_estimator;
      const DeviceFrame dsrc = DeviceFrame::upload(src);
      DeviceDepth gpu(src.width(), src.height());
      test::check_cuda(gpu_estimator.estimate(params, dsrc.view(), gpu.grid(), stream_));
      expect_same_depth(gpu, cpu);
    }
}

// RGBD input's depth from a deep grey picture (depth_from_grey, 10-bit
// parameters for the 10-bit Y'CbCr formats).
TEST_F(GpuDeep, DepthFromDeepGreyIsTheCpuDepth) {
  for (PixelFormat f : test::kDeepFormats) {
    SCOPED_TRACE(test::format_name(f));
    const HostFrame grey = deep_frame(f, 75, 41, 9, false);
    cv::Mat cpu(grey.height(), grey.width(), CV_32FC1);
    for (int y = 0; y < grey.height(); ++y)
      for (int x = 0; x < grey.width(); ++x) cpu.at<float>(y, x) = depth_from_grey(grey.view(), x, y, kTenBit);
    const DeviceFrame dgrey = DeviceFrame::upload(grey);
    DeviceDepth gpu(grey.width(), grey.height());
    test::check_cuda(depth_from_grey_gpu(dgrey.view(), kTenBit, gpu.view(), stream_));
    expect_same_depth(gpu, cpu);
  }
}

TEST_F(GpuDeep, FilterWithADeepGuideIsTheCpuFilter) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  const BilateralParams params = test::bilateral_params(4, 3.f, 20.f);
  BilateralFilterGpu filter;
  for (PixelFormat f : test::kDeepFormats) {
    SCOPED_TRACE(test::format_name(f));
    const HostFrame guide = deep_frame(f, 97, 61, seed, false);
    const cv::Mat depth = step_depth(97, 61, seed);
    cv::Mat cpu(depth.size(), CV_32FC1);
    bilateral_filter_cpu(params, guide.view(), depth_view_of(depth), depth_view_of(cpu));
    const DeviceFrame dguide = DeviceFrame::upload(guide);
    const DeviceDepth in = DeviceDepth::upload(depth);
    DeviceDepth out(depth.cols, depth.rows);
    test::check_cuda(filter.run(params, dguide.view(), as_const(in.grid()), out.grid(), stream_));
    expect_same_depth(out, cpu);
  }
}

TEST_F(GpuDeep, WarpEveryFillAndView) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  for (PixelFormat f : test::kDeepFormats)
    for (bool random : {true, false}) {
      const HostFrame src = deep_frame(f, 97, 61, seed, random);
      const cv::Mat depth = step_depth(97, 61, seed + 1);
      for (const auto &fill : kHoleFillNames)
        for (const auto &view : kStereoViewNames)
          expect_warp_same(test::warp_params(9.f, 0.3f, view.value, fill.value), src, depth);
    }
}

// Rows at each key place the 16-bit kernels take: 32-bit keys in shared
// memory (1080p), 64-bit keys in shared memory (a parallax past 127
// pixels), 64-bit keys in global memory (a row too wide for shared memory
// at 8 bytes a converted pixel).
TEST_F(GpuDeep, WarpAtEveryKeyPlace) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  struct Case {
    int w, h;
    float max_disparity;
  };
  for (const Case c : {Case{1920, 24, 40.f}, Case{1200, 16, 300.f}, Case{20000, 3, 60.f}})
    for (HoleFill fill : {HoleFill::BackgroundSmooth, HoleFill::Background, HoleFill::NeighborAverage}) {
      const HostFrame src = deep_frame(PixelFormat::P010, c.w, c.h, seed, true);
      expect_warp_same(test::warp_params(c.max_disparity, 0.f, StereoView::Both, fill), src,
                       step_depth(c.w, c.h, seed + 2));
    }
}

// The row kernels the device's residency picks for 16-bit rows take the
// rows of a depth cell together (what WarpOnDepthGrids then compares). On
// Hopper (cuda/warp_plan.h): RowsTogether blocks at 1080p, WideGroup
// blocks at 4K.
TEST_F(GpuDeep, RowsOfACellGoTogether) {
  int dev = 0, optin = 0, major = 0;
  ASSERT_EQ(cudaSuccess, cudaGetDevice(&dev));
  ASSERT_EQ(cudaSuccess, cudaDeviceGetAttribute(&optin, cudaDevAttrMaxSharedMemoryPerBlockOptin, dev));
  ASSERT_EQ(cudaSuccess, cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, dev));
  std::vector<const void *> attributes_set;
  for (const int w : {1920, 3840}) {
    warp_detail::RowKernelChoice c;
    test::check_cuda(
        warp_detail::query_row_kernels<Rgba16>(HoleFill::BackgroundSmooth, w, optin, &attributes_set, &c));
    EXPECT_TRUE(c.groups) << w;
    EXPECT_EQ(c.pixel_bytes, sizeof(Rgba16));
    if (major == 9) {
      EXPECT_EQ(c.rows_together, w == 1920) << w;
      EXPECT_EQ(c.wide_groups, w == 3840) << w;
    }
  }
}

// Depth on cells of 2, 4 and 8 pixels, both eyes warped: the rows of a
// group share one z-buffer (RowsTogether and WideGroup blocks:
// RowsOfACellGoTogether), at a 1080p and a 4K width.
TEST_F(GpuDeep, WarpOnDepthGrids) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  for (const int w : {1920, 3840})
    for (const int shift : {1, 2, 3}) {
      const HostFrame src = deep_frame(PixelFormat::I420_10, w, 40, seed, true);
      const cv::Mat depth = test::cell_constant(step_depth(w, 40, seed + 5), shift);
      for (HoleFill fill :
           {HoleFill::BackgroundSmooth, HoleFill::Background, HoleFill::NeighborAverage, HoleFill::None})
        expect_warp_same(test::warp_params(30.f, 0.3f, StereoView::Both, fill), src, depth, shift);
    }
}

// Every layout and method into each deep format, on views 45 and 46
// pixels wide: an even width into RGBA64 takes the two-pixel anaglyph
// kernel (pack_anaglyph_pair16_vec), an odd one the generic kernel; the
// even width with the eyes swapped.
TEST_F(GpuDeep, PackEveryLayoutIntoEveryDeepFormat) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  for (const int vw : {45, 46}) {
    HostFrame pair(PixelFormat::RGBA64, 2 * vw, 27, 8);
    pair.fill_random(seed + vw);
    const DeviceFrame dpair = DeviceFrame::upload(pair);
    for (PixelFormat out_format : test::kDeepFormats)
      for (PackLayout layout : test::kAllLayouts)
        for (AnaglyphMethod method : test::kAllMethods) {
          if (layout != PackLayout::Anaglyph && method != AnaglyphMethod::Dubois) continue;
          PackParams p = test::pack_params(layout, AnaglyphGlasses::RedCyan, method);
          p.yuv = rgb_to_yuv_params(0.2126, 0.0722, false, 10);
          p.swap_eyes = vw % 2 == 0;
          SCOPED_TRACE(std::string(test::format_name(out_format)) + " width " + std::to_string(vw) + " layout " +
                       std::to_string(int(layout)) + " method " + std::to_string(int(method)));
          int w = 0, h = 0;
          pack_size(layout, vw, 27, &w, &h);
          HostFrame cpu(out_format, w, h, 8);
          pack_cpu(p, pair.view(), cpu.view());
          const DeviceFrame dout(out_format, w, h);
          test::check_cuda(pack_gpu(p, dpair.view(), dout.view(), stream_));
          ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
          EXPECT_EQ(plane_difference(cpu, dout.download()), "");
        }
  }
}

// RGBA64 pixels move as 64-bit words where they are 8-byte aligned and as
// bytes elsewhere (load_packed16, store_rgba16 in device code): the pack
// of a pair at a 2-byte offset, into an output at a 6-byte offset, gives
// the CPU's bytes and writes nothing outside its pixels, as the aligned
// frames do.
TEST_F(GpuDeep, PackOfMisalignedRgba64Frames) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  constexpr int kW = 46, kH = 27;  // even: aligned frames take the two-pixel anaglyph kernel
  HostFrame pair(PixelFormat::RGBA64, 2 * kW, kH, 8);
  pair.fill_random(seed);
  const size_t pair_row = 8 * 2 * kW;
  for (const size_t in_offset : {0, 2}) {
    test::DeviceOutput in(PixelFormat::RGBA64, 2 * kW, kH, pair_row + 16, in_offset, 0);
    ASSERT_EQ(cudaSuccess, cudaMemcpy2D(in.view().plane[0], in.view().stride[0], pair.view().plane[0],
                                        pair.view().stride[0], pair_row, kH, cudaMemcpyHostToDevice));
    for (const size_t out_offset : {0, 6})
      for (PackLayout layout : {PackLayout::SideBySide, PackLayout::SideBySideHalf, PackLayout::Anaglyph}) {
        SCOPED_TRACE(::testing::Message() << "offsets " << in_offset << "/" << out_offset << " layout "
                                          << static_cast<int>(layout));
        const PackParams p = test::pack_params(layout);
        int w = 0, h = 0;
        pack_size(layout, kW, kH, &w, &h);
        HostFrame cpu(PixelFormat::RGBA64, w, h, 8);
        pack_cpu(p, pair.view(), cpu.view());
        // Rows 16-byte aligned at offset 0, so that the anaglyph takes the
        // two-pixel kernel there.
        test::DeviceOutput out(PixelFormat::RGBA64, w, h, 8 * static_cast<size_t>(w) + 16, out_offset, 0xa5);
        test::check_cuda(pack_gpu(p, in.view(), out.view(), stream_));
        const test::DeviceOutput::Result r = out.download();
        EXPECT_EQ(r.writes_outside, 0);
        EXPECT_EQ(plane_difference(cpu, r.frame), "");
      }
  }
}

TEST_F(GpuDeep, RenderPackedFromEachDeepSourceIntoEachDeepOutput) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  for (PixelFormat src_format : test::kDeepFormats) {
    const HostFrame src = deep_frame(src_format, 98, 62, seed, false);
    const cv::Mat depth = step_depth(98, 62, seed + 3);
    for (PixelFormat out_format : test::kDeepFormats)
      for (PackLayout layout :
           {PackLayout::SideBySide, PackLayout::SideBySideHalf, PackLayout::TopBottomHalf, PackLayout::Anaglyph}) {
        PackParams pp = test::pack_params(layout);
        pp.yuv = rgb_to_yuv_params(0.2126, 0.0722, false, 10);
        expect_packed_same(test::warp_params(8.f, 0.3f, StereoView::Both, HoleFill::BackgroundSmooth), pp, src, depth,
                           out_format);
      }
  }
}

TEST_F(GpuDeep, UltraHdP010SideBySideHalf) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  const HostFrame src = deep_frame(PixelFormat::P010, 3840, 2160, seed, false);
  PackParams pp = test::pack_params(PackLayout::SideBySideHalf);
  pp.yuv = rgb_to_yuv_params(0.2126, 0.0722, false, 10);
  // Depth on the 4K grid's cells of 4 pixels, as the elements hand it on.
  expect_packed_same(test::warp_params(60.f, 0.3f, StereoView::Both, HoleFill::BackgroundSmooth), pp, src,
                     test::cell_constant(step_depth(3840, 2160, seed + 4), 2), PixelFormat::P010, 2);
}

}  // namespace
}  // namespace p3d
