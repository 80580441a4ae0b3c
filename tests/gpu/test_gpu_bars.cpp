// The device side of crop-bars (cuda/bars_gpu.h) against common/bars.h.
// What the tests prove, byte for byte:
//  * BarCountsGpu gives bar_counts_cpu's row and column counts (every
//    format, limited and full range, odd sizes, rows with padding, bars
//    and noise), also for frames queued one after another, each count()
//    taken before the next; on its own stream, joined to the caller's,
//    and a count left untaken ended by the next;
//  * views_outside_gpu writes views_outside_cpu's pixels and no other;
//  * ActiveWarpGpu::render gives warp_pack_changed_cpu()'s output with
//    the same ActiveArea (every row): a letterbox, a pillarbox and both,
//    every fill, depth on cells of 1, 2 and 4 pixels, the pair itself as
//    the output, packs into packed RGB and 4:2:0; a rect off the depth's
//    cells is refused.
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "adaptive.h"
#include "bars.h"
#include "bars_gpu.h"
#include "gpu_util.h"
#include "test_data.h"

namespace p3d {
namespace {

// The first plane row whose visible bytes differ ("" when none).
std::string plane_difference(const HostFrame &want, const HostFrame &got) {
  const FrameView a = want.view(), b = got.view();
  if (a.format != b.format || a.width != b.width || a.height != b.height) return "geometry differs";
  for (int p = 0; p < frame_plane_count(a.format); ++p) {
    const bool chroma = p > 0;
    const int rows = chroma ? (a.height + 1) / 2 : a.height;
    int bytes = is_packed_rgb(a.format) ? 4 * a.width : a.width;
    if (chroma) bytes = a.format == PixelFormat::NV12 ? 2 * ((a.width + 1) / 2) : (a.width + 1) / 2;
    for (int y = 0; y < rows; ++y)
      if (std::memcmp(a.plane[p] + static_cast<size_t>(y) * a.stride[p], b.plane[p] + static_cast<size_t>(y) * b.stride[p],
                      bytes) != 0)
        return "plane " + std::to_string(p) + " row " + std::to_string(y);
  }
  return "";
}

// A frame with black bars around `picture` (random colours there) and a
// few bright noise pixels in the bars.
HostFrame barred_frame(PixelFormat f, int w, int h, PixelRect picture, uint32_t seed) {
  std::mt19937 rng(seed);
  HostFrame frame(f, w, h, 3);
  frame.fill_random(rng());
  cv::Mat bgr = frame.to_bgra();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool inside = x >= picture.x0 && x < picture.x1 && y >= picture.y0 && y < picture.y1;
      if (!inside && rng() % 50 != 0) bgr.at<cv::Vec4b>(y, x) = cv::Vec4b(rng() % 20, rng() % 20, rng() % 20, 255);
    }
  cv::Mat bgr3;
  cv::cvtColor(bgr, bgr3, cv::COLOR_BGRA2BGR);
  return HostFrame::from_bgr(bgr3, f, 5);
}

// A ramp with near boxes on it: disocclusions for every fill.
cv::Mat steps_on_a_ramp(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  cv::Mat d(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<float>(y, x) = 0.3f * static_cast<float>(y) / static_cast<float>(h);
  for (int k = 0; k < 5; ++k) {
    const int x0 = static_cast<int>(rng() % (w - 20)), y0 = static_cast<int>(rng() % (h - 20));
    d(cv::Rect(x0, y0, 20, 20)).setTo(cv::Scalar(0.5 + (rng() % 50) / 100.0));
  }
  return d;
}

class GpuBars : public ::testing::Test {
 public:
  void SetUp() override { test::check_cuda(CudaStatus{cudaStreamCreate(&stream_), "cudaStreamCreate", __FILE__, __LINE__}); }
  void TearDown() override {
    counts_.reset();
    if (stream_) cudaStreamDestroy(stream_);
  }

 protected:
  cudaStream_t stream_ = nullptr;
  BarCountsGpu counts_;
};

TEST_F(GpuBars, CountsAreTheCpuCounts) {
  std::mt19937 rng(std::random_device{}());
  const uint32_t seed = rng();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  int index = 0;
  for (const PixelFormat f : test::kAllFormats)
    for (const bool full_range : {false, true}) {
      const int w = 97 + 31 * (index % 3), h = 65 + 17 * (index % 2);
      const PixelRect picture{index % 2 ? 16 : 0, 8, w - (index % 2 ? 16 : 0), h - 8};
      const HostFrame host = barred_frame(f, w, h, picture, seed + index++);
      const int threshold = bar_luma_threshold(yuv_to_rgb_params(0.2126, 0.0722, full_range));
      BarCounts want, got;
      bar_counts_cpu(host.view(), threshold, &want);
      const test::DeviceFrame dev = test::DeviceFrame::upload(host);
      test::check_cuda(counts_.count(dev.view(), threshold, stream_));
      CudaStatus st;
      ASSERT_TRUE(counts_.take(&got, &st));
      test::check_cuda(st);
      EXPECT_EQ(got.rows, want.rows) << test::format_name(f) << " full range " << full_range;
      EXPECT_EQ(got.cols, want.cols) << test::format_name(f) << " full range " << full_range;
      EXPECT_FALSE(counts_.take(&got, &st)) << "taken once";
    }
}

// The counts run on BarCountsGpu's own stream: joined to the caller's
// stream they are the frame's counts; a count left untaken is ended by
// the next count(), whose counts take() then hands over (not the first's);
// settle() waits without taking, and leaves nothing to join.
TEST_F(GpuBars, CountsBesideTheCallersStream) {
  const int w = 160, h = 96, threshold = bar_luma_threshold(YuvToRgb());
  const HostFrame a = barred_frame(PixelFormat::NV12, w, h, PixelRect{0, 16, w, h - 16}, 41);
  const HostFrame b = barred_frame(PixelFormat::NV12, w, h, PixelRect{24, 0, w - 24, h}, 42);
  BarCounts want_a, want_b, got;
  bar_counts_cpu(a.view(), threshold, &want_a);
  bar_counts_cpu(b.view(), threshold, &want_b);
  ASSERT_NE(want_a.rows, want_b.rows);
  const test::DeviceFrame da = test::DeviceFrame::upload(a), db = test::DeviceFrame::upload(b);
  CudaStatus st;
  // Joined: the caller's stream waits for the count.
  test::check_cuda(counts_.count(da.view(), threshold, stream_));
  test::check_cuda(counts_.join(stream_));
  ASSERT_EQ(cudaStreamSynchronize(stream_), cudaSuccess);
  ASSERT_TRUE(counts_.take(&got, &st));
  test::check_cuda(st);
  EXPECT_EQ(got.rows, want_a.rows);
  // Untaken: the next count ends it, and its own counts are taken.
  test::check_cuda(counts_.count(da.view(), threshold, stream_));
  test::check_cuda(counts_.count(db.view(), threshold, stream_));
  counts_.settle();
  ASSERT_TRUE(counts_.take(&got, &st));
  test::check_cuda(st);
  EXPECT_EQ(got.rows, want_b.rows);
  EXPECT_EQ(got.cols, want_b.cols);
  test::check_cuda(counts_.join(stream_));  // after settle(): nothing to join
  EXPECT_FALSE(counts_.take(&got, &st)) << "taken once";
}

TEST_F(GpuBars, ViewsOutsideAreTheCpuViews) {
  for (const PixelFormat f : {PixelFormat::NV12, PixelFormat::I420, PixelFormat::BGRx})
    for (const PixelRect rect : {PixelRect{0, 8, 96, 56}, PixelRect{16, 0, 80, 64}, PixelRect{8, 8, 87, 55}}) {
      HostFrame src(f, 96, 64, 3);
      src.fill_random(77);
      const PixelFormat pair_format = f == PixelFormat::BGRx ? PixelFormat::BGRx : PixelFormat::RGBA;
      HostFrame cpu(pair_format, 192, 64, 0);
      cpu.fill(0x5A);
      views_outside_cpu(src.view(), YuvToRgb(), rect, cpu.view(), nullptr);
      HostFrame poisoned(pair_format, 192, 64, 0);
      poisoned.fill(0x5A);
      const test::DeviceFrame dsrc = test::DeviceFrame::upload(src), dpair = test::DeviceFrame::upload(poisoned);
      test::check_cuda(views_outside_gpu(dsrc.view(), YuvToRgb(), rect, dpair.view(), stream_));
      ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
      EXPECT_EQ(plane_difference(cpu, dpair.download()), "") << test::format_name(f);
    }
}

TEST_F(GpuBars, ActiveWarpIsTheCpuWarp) {
  std::mt19937 rng(std::random_device{}());
  const uint32_t seed = rng();
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  const int W = 160, H = 96;
  WarpRendererGpu renderer;
  ActiveWarpGpu active;
  int index = 0;
  for (const PixelRect rect : {PixelRect{0, 16, W, 80}, PixelRect{24, 0, 136, H}, PixelRect{8, 8, 152, 88}})
    for (const HoleFill fill : test::kAllFills)
      for (const PackLayout layout : {PackLayout::SideBySide, PackLayout::Anaglyph, PackLayout::TopBottomHalf})
        for (const int shift : {0, 1, 2}) {
          ++index;
          const PixelFormat src_format = test::kAllFormats[index % 6];
          const PixelFormat out_format =
              layout == PackLayout::SideBySide ? PixelFormat::BGRA : (index % 2 ? PixelFormat::NV12 : PixelFormat::RGBA);
          SCOPED_TRACE(::testing::Message() << "rect " << rect.x0 << "," << rect.y0 << " " << rect.x1 << "," << rect.y1
                                            << " fill " << enum_nick(kHoleFillNames, fill) << " layout "
                                            << enum_nick(kPackLayoutNames, layout) << " cells " << (1 << shift) << " "
                                            << test::format_name(src_format) << " -> "
                                            << test::format_name(out_format));
          HostFrame src(src_format, W, H, 2);
          src.fill_random(seed + index);
          const cv::Mat depth = test::cell_constant(steps_on_a_ramp(W, H, seed + index), shift);
          const WarpParams params = test::warp_params(5.f, 0.45f, StereoView::Both, fill);
          const PackParams pack = test::pack_params(layout);
          int ow, oh;
          pack_size(layout, W, H, &ow, &oh);
          const PixelFormat pair_format = is_packed_rgb(out_format) ? out_format : PixelFormat::RGBA;
          HostFrame pair(pair_format, 2 * W, H, 0), apair(pair_format, 2 * rect.width(), rect.height(), 0);
          HostFrame cpu(out_format, ow, oh, 0);
          WarpCpuScratch scratch;
          const ActiveArea area{rect, apair.view()};
          const bool pair_is_out = pack_is_identity(pack) && is_packed_rgb(out_format);
          ASSERT_GE(warp_pack_changed_cpu(params, pack, src.view(), YuvToRgb(), depth_view_of(depth),
                                          pair_is_out ? cpu.view() : pair.view(), cpu.view(), scratch, nullptr, &area),
                    0);
          const test::DeviceFrame dsrc = test::DeviceFrame::upload(src), dout(out_format, ow, oh);
          const test::DeviceDepth ddepth = test::DeviceDepth::upload_grid(depth, shift);
          test::check_cuda(active.render(renderer, params, pack, dsrc.view(), YuvToRgb(), as_const(ddepth.grid()), rect,
                                         dout.view(), stream_));
          ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
          EXPECT_EQ(plane_difference(cpu, dout.download()), "");
        }
  // A rect whose corner is not on the depth's cells.
  const test::DeviceFrame src(PixelFormat::NV12, W, H), out(PixelFormat::RGBA, 2 * W, H);
  const test::DeviceDepth depth(W, H, 3);
  EXPECT_EQ(active
                .render(renderer, test::warp_params(5.f, 0.5f, StereoView::Both, HoleFill::Background),
                        test::pack_params(PackLayout::SideBySide), src.view(), YuvToRgb(), as_const(depth.grid()),
                        PixelRect{0, 4, W, 92}, out.view(), stream_)
                .code,
            cudaErrorInvalidValue);
}

}  // namespace
}  // namespace p3d
