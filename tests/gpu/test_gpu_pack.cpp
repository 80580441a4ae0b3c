// pack_gpu against pack_cpu, packed RGB and 4:2:0 output. Tolerance: none. Both run the same pack_pixel
// (common/pack.h): integer means for the half formats and one fixed float
// evaluation order for the anaglyphs, compiled without contraction on both
// sides (-ffp-contract=off / -fmad=false), so every byte must match,
// including the 4th byte of X formats.
#include <cstdio>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "gpu_util.h"
#include "pack.h"
#include "pack_gpu.h"
#include "test_data.h"

namespace p3d {
namespace {

using test::kAllLayouts;
using test::kAllGlasses;
using test::kAllMethods;
using test::kPackedFormats;


// Every layout x swap, and for anaglyphs every glasses x method x swap.
std::vector<PackParams> every_params() {
  std::vector<PackParams> all;
  for (PackLayout l : kAllLayouts)
    for (bool swap : {false, true}) {
      PackParams p;
      p.layout = l;
      p.swap_eyes = swap;
      if (l != PackLayout::Anaglyph) {
        all.push_back(p);
        continue;
      }
      for (AnaglyphGlasses g : kAllGlasses)
        for (AnaglyphMethod m : kAllMethods) {
          p.glasses = g;
          p.method = m;
          all.push_back(p);
        }
    }
  return all;
}

std::string describe(const PackParams &p, PixelFormat f, int view_w, int view_h) {
  std::ostringstream s;
  s << test::format_name(f) << " view " << view_w << "x" << view_h << " layout " << int(p.layout) << " glasses "
    << int(p.glasses) << " method " << int(p.method) << " swap " << p.swap_eyes << " input " << int(p.input)
    << (p.input_right_first ? " right first" : "");
  return s.str();
}

uint32_t fresh_seed() { return std::random_device{}(); }

// Output size for `in` holding the pair as p.input says.
void out_size(const PackParams &p, const HostFrame &in, int *w, int *h) {
  int vw = 0, vh = 0;
  EXPECT_TRUE(input_view_size(p.input, in.width(), in.height(), &vw, &vh));
  pack_size(p.layout, vw, vh, w, h);
}

HostFrame cpu_pack(const PackParams &p, const HostFrame &in) {
  int w = 0, h = 0;
  out_size(p, in, &w, &h);
  HostFrame out(in.format(), w, h, 8);
  pack_cpu(p, in.view(), out.view());
  return out;
}

// Bytes of the pixels (4 per pixel, X byte included) that differ; the first
// difference is described in *where.
long long raw_diff(const HostFrame &a, const HostFrame &b, std::string *where) {
  if (a.width() != b.width() || a.height() != b.height() || a.format() != b.format()) {
    *where = "frame size or format differs";
    return -1;
  }
  long long n = 0;
  const FrameView va = a.view(), vb = b.view();
  for (int y = 0; y < va.height; ++y) {
    const uint8_t *ra = va.plane[0] + static_cast<size_t>(y) * va.stride[0];
    const uint8_t *rb = vb.plane[0] + static_cast<size_t>(y) * vb.stride[0];
    for (int i = 0; i < 4 * va.width; ++i) {
      if (ra[i] == rb[i]) continue;
      if (n++ == 0) {
        std::ostringstream s;
        s << "first at pixel (" << i / 4 << "," << y << ") byte " << i % 4 << ": " << int(ra[i]) << " vs "
          << int(rb[i]);
        *where = s.str();
      }
    }
  }
  return n;
}

class GpuPack : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(cudaSuccess, cudaStreamCreate(&stream_)); }
  void TearDown() override { cudaStreamDestroy(stream_); }

  // GPU result of `in` (already on the device as `din`) into `out`, compared
  // byte for byte with the CPU; no write may land outside the pixels.
  void expect_exact(const PackParams &p, const HostFrame &in, const test::DeviceFrame &din, test::DeviceOutput &out,
                    const std::string &what) {
    test::check_cuda(pack_gpu(p, din.view(), out.view(), stream_));
    ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_)) << what;
    const test::DeviceOutput::Result got = out.download();
    std::string where;
    EXPECT_EQ(raw_diff(got.frame, cpu_pack(p, in), &where), 0) << what << ": " << where;
    EXPECT_EQ(got.writes_outside, 0) << what;
  }

  // Every params on `in` in aligned (vectorised) device outputs.
  void expect_exact_all(const HostFrame &in, const std::vector<PackParams> &params, const std::string &what) {
    const test::DeviceFrame din = test::DeviceFrame::upload(in);
    for (const PackParams &p : params) {
      int w = 0, h = 0;
      out_size(p, in, &w, &h);
      test::DeviceOutput out = test::DeviceOutput::aligned(in.format(), w, h, 0xA5);
      expect_exact(p, in, din, out, what + " " + describe(p, in.format(), in.width() / 2, in.height()));
      if (HasFailure()) return;  // one precise report beats hundreds of copies
    }
  }

  cudaStream_t stream_ = nullptr;
};

TEST_F(GpuPack, EveryParamsEveryFormatRandom) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (PixelFormat f : kPackedFormats) {
    HostFrame in(f, 2 * 67, 31, 12);
    in.fill_random(seed);
    expect_exact_all(in, every_params(), "random");
  }
}

// Every input arrangement, either eye first, into every layout (and the
// linear-light anaglyph, whose tables travel with the launch).
// The anaglyph of a side-by-side pair whose view width is a multiple of 4
// takes the kernel with 16-byte loads: every glasses x method x swap x
// eye order in every packed format, at widths that take it (68, 4) and
// one that does not (70).
TEST_F(GpuPack, AnaglyphPairSixteenByteLoads) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::vector<PackParams> anaglyphs;
  for (PackParams p : every_params())
    if (p.layout == PackLayout::Anaglyph)
      for (bool rf : {false, true}) {
        p.input_right_first = rf;
        anaglyphs.push_back(p);
      }
  for (int w : {68, 4, 70})
    for (PixelFormat f : kPackedFormats) {
      HostFrame in(f, 2 * w, 9, 8);
      in.fill_random(seed + w);
      expect_exact_all(in, anaglyphs, "anaglyph pair");
    }
}

TEST_F(GpuPack, EveryInputArrangement) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::vector<PackParams> params;
  for (StereoInput input : test::kAllInputs)
    for (bool rf : {false, true})
      for (PackLayout l : kAllLayouts) {
        PackParams p;
        p.layout = l;
        p.input = input;
        p.input_right_first = rf;
        p.swap_eyes = rf && l == PackLayout::TopBottom;
        params.push_back(p);
        if (l == PackLayout::Anaglyph) {
          p.method = AnaglyphMethod::DuboisLinear;
          params.push_back(p);
        }
      }
  const int sizes[][2] = {{1, 2}, {5, 4}, {66, 18}, {133, 38}};
  for (const auto &sz : sizes)
    for (PixelFormat f : {PixelFormat::RGBA, PixelFormat::BGRx}) {
      HostFrame in(f, sz[0], sz[1], 4);
      in.fill_random(seed + sz[0]);
      std::vector<PackParams> fitting;
      for (const PackParams &p : params) {
        int vw = 0, vh = 0;
        if (input_view_size(p.input, sz[0], sz[1], &vw, &vh)) fitting.push_back(p);
      }
      expect_exact_all(in, fitting, "input arrangement");
    }
}

TEST_F(GpuPack, OddSizes) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const int sizes[][2] = {{1, 1}, {3, 2}, {33, 17}, {1001, 7}};
  for (const auto &s : sizes)
    for (PixelFormat f : kPackedFormats) {
      HostFrame in(f, 2 * s[0], s[1], 4);
      in.fill_random(seed + s[0]);
      expect_exact_all(in, every_params(), "odd size");
    }
}

// Rows that are not 16-byte aligned take the per-pixel kernel: offset
// starts, strides that are not multiples of 16 (a 4-byte multiple is what
// packed RGB guarantees).
TEST_F(GpuPack, UnalignedOutputRows) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const int sizes[][2] = {{1, 1}, {3, 2}, {33, 17}};
  for (const auto &s : sizes)
    for (PixelFormat f : kPackedFormats) {
      HostFrame in(f, 2 * s[0], s[1]);
      in.fill_random(seed + s[1]);
      const test::DeviceFrame din = test::DeviceFrame::upload(in);
      for (const PackParams &p : every_params()) {
        int w = 0, h = 0;
        pack_size(p.layout, s[0], s[1], &w, &h);
        const size_t tight = 4 * static_cast<size_t>(w);
        const size_t layouts[][2] = {{tight, 4}, {tight + 4, 0}, {tight + 12, 8}};
        for (const auto &l : layouts) {
          test::DeviceOutput out(f, w, h, l[0], l[1], 0x5A);
          expect_exact(p, in, din, out,
                       describe(p, f, s[0], s[1]) + " stride " + std::to_string(l[0]) + " offset " +
                           std::to_string(l[1]));
          if (HasFailure()) return;
        }
      }
    }
}

// Two runs into outputs poisoned with complementary bytes: a pixel the kernel
// skips keeps its poison, so at least one of the runs differs from the CPU.
TEST_F(GpuPack, PoisonedOutputsAreFullyWritten) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (PixelFormat f : {PixelFormat::RGBA, PixelFormat::BGRx}) {
    HostFrame in(f, 2 * 129, 45);
    in.fill_random(seed);
    const test::DeviceFrame din = test::DeviceFrame::upload(in);
    for (const PackParams &p : every_params())
      for (uint8_t poison : {uint8_t(0x00), uint8_t(0xFF)}) {
        int w = 0, h = 0;
        pack_size(p.layout, 129, 45, &w, &h);
        test::DeviceOutput out = test::DeviceOutput::aligned(f, w, h, poison);
        expect_exact(p, in, din, out, describe(p, f, 129, 45) + " poison " + std::to_string(poison));
        if (HasFailure()) return;
      }
  }
}

TEST_F(GpuPack, AloePair) {
  const cv::Mat l = test::load_data_image("aloeL.jpg"), r = test::load_data_image("aloeR.jpg");
  ASSERT_FALSE(l.empty());
  ASSERT_FALSE(r.empty());
  cv::Mat pair;
  cv::hconcat(l, r, pair);
  for (PixelFormat f : kPackedFormats) expect_exact_all(HostFrame::from_bgr(pair, f, 20), every_params(), "aloe");
}

std::vector<PackParams> large_params() {
  std::vector<PackParams> all;
  for (PackLayout l : {PackLayout::SideBySideHalf, PackLayout::TopBottom, PackLayout::TopBottomHalf,
                       PackLayout::Checkerboard, PackLayout::Anaglyph}) {
    PackParams p;
    p.layout = l;
    all.push_back(p);
  }
  PackParams gray;
  gray.method = AnaglyphMethod::Gray;
  gray.glasses = AnaglyphGlasses::AmberBlue;
  gray.swap_eyes = true;
  all.push_back(gray);
  return all;
}

TEST_F(GpuPack, UltraHd) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  HostFrame in(PixelFormat::BGRx, 2 * 3840, 2160);
  in.fill_random(seed);
  expect_exact_all(in, large_params(), "3840x2160");
}

TEST_F(GpuPack, EightK) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  HostFrame in(PixelFormat::RGBA, 2 * 7680, 4320);
  in.fill_random(seed);
  expect_exact_all(in, large_params(), "7680x4320");
}

// ---- 4:2:0 output ----

// Samples of every plane that differ between two frames of one format and
// size; the first is described in *where.
long long plane_diff(const HostFrame &a, const HostFrame &b, std::string *where) {
  if (a.width() != b.width() || a.height() != b.height() || a.format() != b.format()) {
    *where = "frame size or format differs";
    return -1;
  }
  long long n = 0;
  for (int i = 0; i < frame_plane_count(a.format()); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(a.format(), a.width(), a.height(), i, &row_bytes, &rows);
    for (int y = 0; y < rows; ++y)
      for (int x = 0; x < row_bytes; ++x) {
        const uint8_t va = a.view().plane[i][static_cast<size_t>(y) * a.view().stride[i] + x];
        const uint8_t vb = b.view().plane[i][static_cast<size_t>(y) * b.view().stride[i] + x];
        if (va != vb && n++ == 0)
          *where = "plane " + std::to_string(i) + " byte (" + std::to_string(x) + "," + std::to_string(y) +
                   "): " + std::to_string(va) + " vs " + std::to_string(vb);
      }
  }
  return n;
}

// `in` packed into `format` on both sides, the device output poisoned with
// `poison` first (a skipped sample keeps it and differs from the CPU's).
void expect_yuv_exact(const PackParams &p, const HostFrame &in, const test::DeviceFrame &din, PixelFormat format,
                      uint8_t poison, cudaStream_t stream, const std::string &what) {
  int w = 0, h = 0;
  out_size(p, in, &w, &h);
  HostFrame cpu(format, w, h, 6);
  pack_cpu(p, in.view(), cpu.view());
  HostFrame poisoned(format, w, h);
  poisoned.fill(poison);
  const test::DeviceFrame dout = test::DeviceFrame::upload(poisoned);
  test::check_cuda(pack_gpu(p, din.view(), dout.view(), stream));
  ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream)) << what;
  std::string where;
  EXPECT_EQ(plane_diff(dout.download(), cpu, &where), 0) << what << ": " << where;
}

// Every layout and anaglyph, NV12 and I420, three colorimetries, odd and
// even sizes, two poisons: byte for byte the CPU's.
TEST_F(GpuPack, YuvOutputEveryParams) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const RgbToYuv matrices[] = {rgb_to_yuv_params(0.2126, 0.0722, false), rgb_to_yuv_params(0.299, 0.114, true),
                               rgb_to_yuv_params(0.2627, 0.0593, false)};
  const int sizes[][2] = {{1, 1}, {3, 2}, {33, 17}, {67, 31}};
  for (const auto &sz : sizes) {
    HostFrame in(PixelFormat::BGRA, 2 * sz[0], sz[1], 4);
    in.fill_random(seed + sz[0]);
    const test::DeviceFrame din = test::DeviceFrame::upload(in);
    for (PackParams p : every_params())
      for (const RgbToYuv &m : matrices)
        for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420})
          for (uint8_t poison : {uint8_t(0x00), uint8_t(0xFF)}) {
            p.yuv = m;
            expect_yuv_exact(p, in, din, f, poison, stream_, "yuv " + describe(p, f, sz[0], sz[1]));
            if (HasFailure()) return;
          }
  }
}

// Every input arrangement into half side-by-side I420 (the converter's
// default), on the Aloe pair and at 4K.
TEST_F(GpuPack, YuvOutputInputArrangementsAndAloe) {
  const cv::Mat l = test::load_data_image("aloeL.jpg"), r = test::load_data_image("aloeR.jpg");
  ASSERT_FALSE(l.empty());
  ASSERT_FALSE(r.empty());
  cv::Mat pair;
  cv::hconcat(l, r, pair);
  const HostFrame aloe = HostFrame::from_bgr(pair, PixelFormat::RGBA, 20);
  const test::DeviceFrame daloe = test::DeviceFrame::upload(aloe);
  for (StereoInput input : test::kAllInputs) {
    PackParams p;
    p.layout = PackLayout::SideBySideHalf;
    p.input = input;
    int vw = 0, vh = 0;
    if (!input_view_size(input, aloe.width(), aloe.height(), &vw, &vh)) continue;
    expect_yuv_exact(p, aloe, daloe, PixelFormat::I420, 0x5A, stream_, "aloe input " + std::to_string(int(input)));
  }
}

TEST_F(GpuPack, YuvOutputUltraHd) {
  const uint32_t seed = fresh_seed();
  SCOPED_TRACE("seed " + std::to_string(seed));
  HostFrame in(PixelFormat::RGBA, 2 * 3840, 2160);
  in.fill_random(seed);
  const test::DeviceFrame din = test::DeviceFrame::upload(in);
  for (PackLayout l : {PackLayout::SideBySideHalf, PackLayout::TopBottom, PackLayout::Anaglyph}) {
    PackParams p;
    p.layout = l;
    for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420})
      expect_yuv_exact(p, in, din, f, 0xA5, stream_, "3840x2160 yuv layout " + std::to_string(int(l)));
  }
}

TEST_F(GpuPack, RejectsMismatchedFramesWithoutWriting) {
  HostFrame in(PixelFormat::RGBA, 2 * 8, 4);
  in.fill_random(1);
  const test::DeviceFrame din = test::DeviceFrame::upload(in);
  PackParams p;
  p.layout = PackLayout::SideBySideHalf;
  test::DeviceOutput wrong_size = test::DeviceOutput::aligned(PixelFormat::RGBA, 16, 4, 0x33);
  EXPECT_EQ(pack_gpu(p, din.view(), wrong_size.view(), stream_).code, cudaErrorInvalidValue);
  test::DeviceOutput wrong_format = test::DeviceOutput::aligned(PixelFormat::BGRA, 8, 4, 0x33);
  EXPECT_EQ(pack_gpu(p, din.view(), wrong_format.view(), stream_).code, cudaErrorInvalidValue);
  ASSERT_EQ(cudaSuccess, cudaStreamSynchronize(stream_));
  EXPECT_EQ(wrong_size.download().frame.to_bgra().at<cv::Vec4b>(0, 0), cv::Vec4b(0x33, 0x33, 0x33, 0x33));
}

}  // namespace
}  // namespace p3d
