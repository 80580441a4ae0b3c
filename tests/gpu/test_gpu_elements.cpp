// The GStreamer chain on the GPU (memory:CUDAMemory between every stage)
// against the same chain on the CPU, on random and real frames, every input
// format, odd sizes and 4K; device memory flat over 1000 frames. Skipped
// (exit 77) without a CUDA device or without nvcodec's cudaupload.
#include <gst/check/gstharness.h>
#include <gmodule.h>
#include <gst/gst.h>
#include <gst/app/gstappsink.h>
#include <gst/cuda/gstcudacontext.h>
#include <gst/cuda/gstcudautils.h>
#include <gtest/gtest.h>

#include <cuda_runtime_api.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <regex>
#include <thread>
#include <cstdlib>

#include "../elements/element_helpers.h"
#include "test_data.h"

using namespace p3d;
using namespace p3d::test;

namespace {

const char *kStages =
    "pseudo3ddepth processing=%1$s ! pseudo3dfilter processing=%1$s ! pseudo3dwarp max-disparity=4 processing=%1$s ! "
    "pseudo3dpack layout=%2$s processing=%1$s";

// The stages on CUDA memory (kDevice), with processing=auto on system memory
// (kAuto, which runs on the CPU although a GPU is usable), or on the CPU.
enum Where { kDevice, kAuto, kCpu };

std::string chain(Where where, const char *layout, const char *out_format) {
  char stages[512];
  snprintf(stages, sizeof stages, kStages, where == kCpu ? "cpu" : where == kAuto ? "auto" : "gpu", layout);
  std::string s = where == kDevice ? std::string("cudaupload ! video/x-raw(memory:CUDAMemory) ! ") + stages +
                                         " ! cudadownload"
                                   : std::string(stages);
  return s + " ! capsfilter caps=video/x-raw,format=" + out_format;
}

HostFrame picture(PixelFormat f, int w, int h, uint32_t seed) {
  cv::Mat bgr(h, w, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(bgr, bgr, cv::Size(0, 0), 2.0);
  for (int i = 0; i < 6; ++i) {
    const cv::Point a(rng.uniform(0, w), rng.uniform(0, h)), b(rng.uniform(0, w), rng.uniform(0, h));
    cv::rectangle(bgr, a, b, cv::Scalar(rng.uniform(0, 255), rng.uniform(0, 255), rng.uniform(0, 255)), cv::FILLED);
  }
  return HostFrame::from_bgr(bgr, f);
}

// Runs frames through a launch line; returns the outputs as BGRA and the
// warp's negotiated src caps (to prove which memory it ran on).
std::vector<cv::Mat> run_chain(const std::string &launch, PixelFormat f, int w, int h,
                               const std::vector<HostFrame> &frames, std::string *warp_caps = nullptr) {
  std::vector<cv::Mat> out;
  GstHarness *hx = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(hx, raw_caps(f, w, h).c_str());
  for (const HostFrame &fr : frames) {
    GstBuffer *b = gst_harness_push_and_pull(hx, buffer_from_frame(fr));
    if (!b) {
      ADD_FAILURE() << "no output from " << launch;
      break;
    }
    GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
    out.push_back(buffer_to_bgra(b, caps));
    gst_caps_unref(caps);
    gst_buffer_unref(b);
  }
  if (warp_caps) {
    GstElement *warp = gst_bin_get_by_name(GST_BIN(hx->element), "pseudo3dwarp0");
    if (!warp) {  // names are per process: find by factory
      GstIterator *it = gst_bin_iterate_recurse(GST_BIN(hx->element));
      GValue v = G_VALUE_INIT;
      while (gst_iterator_next(it, &v) == GST_ITERATOR_OK) {
        GstElement *e = GST_ELEMENT(g_value_get_object(&v));
        if (g_str_has_prefix(GST_OBJECT_NAME(e), "pseudo3dwarp")) warp = GST_ELEMENT(gst_object_ref(e));
        g_value_reset(&v);
      }
      g_value_unset(&v);
      gst_iterator_free(it);
    }
    if (warp) {
      GstPad *src = gst_element_get_static_pad(warp, "src");
      GstCaps *c = gst_pad_get_current_caps(src);
      gchar *str = c ? gst_caps_to_string(c) : g_strdup("");
      *warp_caps = str;
      g_free(str);
      if (c) gst_caps_unref(c);
      gst_object_unref(src);
      gst_object_unref(warp);
    }
  }
  gst_harness_teardown(hx);
  return out;
}

void expect_same(const std::vector<cv::Mat> &gpu, const std::vector<cv::Mat> &cpu, const std::string &what) {
  ASSERT_EQ(gpu.size(), cpu.size()) << what;
  for (size_t i = 0; i < gpu.size(); ++i) {
    // Every kernel computes its CPU reference's function with the same float
    // operations (-fmad=false), so the chains must agree exactly.
    const DiffStats d = compare_u8(gpu[i], cpu[i], 0);
    EXPECT_EQ(d.max_abs, 0) << what << " frame " << i << ": " << d.over_tolerance << " samples differ";
  }
}

struct Case {
  PixelFormat format;
  int w, h;
};

class GpuChain : public ::testing::TestWithParam<Case> {};

TEST_P(GpuChain, MatchesCpuChain) {
  const Case c = GetParam();
  std::vector<HostFrame> frames;
  for (uint32_t s = 0; s < 3; ++s) frames.push_back(picture(c.format, c.w, c.h, 100 + s));
  for (const char *layout : {"anaglyph", "side-by-side-half"}) {
    std::string caps, auto_caps;
    const auto gpu = run_chain(chain(kDevice, layout, "BGRA"), c.format, c.w, c.h, frames, &caps);
    const auto on_system = run_chain(chain(kAuto, layout, "BGRA"), c.format, c.w, c.h, frames, &auto_caps);
    const auto cpu = run_chain(chain(kCpu, layout, "BGRA"), c.format, c.w, c.h, frames);
    EXPECT_NE(caps.find("memory:CUDAMemory"), std::string::npos) << "warp did not run on CUDA memory: " << caps;
    EXPECT_EQ(auto_caps.find("memory:CUDAMemory"), std::string::npos) << "system memory became CUDA memory: "
                                                                      << auto_caps;
    expect_same(gpu, cpu, std::string(format_name(c.format)) + " " + layout + " on CUDA memory");
    expect_same(on_system, cpu, std::string(format_name(c.format)) + " " + layout + " processing=auto on system memory");
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, GpuChain,
                         ::testing::Values(Case{PixelFormat::NV12, 640, 360}, Case{PixelFormat::I420, 642, 362},
                                           Case{PixelFormat::RGBA, 333, 177}, Case{PixelFormat::BGRA, 64, 2},
                                           Case{PixelFormat::RGBx, 2, 2}, Case{PixelFormat::BGRx, 1001, 7},
                                           Case{PixelFormat::NV12, 3840, 2160}),
                         [](const auto &info) {
                           return std::string(format_name(info.param.format)) + "_" + std::to_string(info.param.w) +
                                  "x" + std::to_string(info.param.h);
                         });

// On CUDA memory the stages hand depth on as grids (gst/depth_plane.h):
// the estimator's blocks where they are a power of two, the filter's cells
// where its step is. Block sizes and filter steps with and without grids,
// finer and coarser than each other, against the CPU chain.
TEST(GpuChainGrids, MatchTheCpuChain) {
  std::vector<HostFrame> frames;
  for (uint32_t s = 0; s < 3; ++s) frames.push_back(picture(PixelFormat::I420, 642, 362, 500 + s));
  const int blocks[] = {2, 8, 6}, scales[] = {1, 2, 4, 3};
  for (const int b : blocks)
    for (const int scale : scales) {
      std::string launch[2];
      for (int gpu = 0; gpu < 2; ++gpu) {
        const std::string p = gpu ? " processing=gpu" : " processing=cpu";
        launch[gpu] = std::string(gpu ? "cudaupload ! video/x-raw(memory:CUDAMemory) ! " : "") +
                      "pseudo3ddepth block-size=" + std::to_string(b) + p + " ! pseudo3dfilter scale=" +
                      std::to_string(scale) + p + " ! pseudo3dwarp max-disparity=4" + p +
                      " ! pseudo3dpack layout=anaglyph" + p + (gpu ? " ! cudadownload" : "") +
                      " ! capsfilter caps=video/x-raw,format=RGBA";
      }
      const auto gpu = run_chain(launch[1], PixelFormat::I420, 642, 362, frames);
      const auto cpu = run_chain(launch[0], PixelFormat::I420, 642, 362, frames);
      expect_same(gpu, cpu, "block " + std::to_string(b) + " scale " + std::to_string(scale));
    }
}

// The planes the stages attach on CUDA memory: the estimator's block grid
// and the filter's cell grid where their steps are powers of two, else
// full-size, as docs/architecture.md says (the chains above compare the
// output; this says which handoff they ran).
TEST(GpuChainGrids, StagesAttachGridPlanes) {
  const HostFrame frame = picture(PixelFormat::NV12, 640, 360, 9);
  struct Case {
    const char *stages;
    int shift;
  } cases[] = {{"pseudo3ddepth", 1},                          // automatic block 2
               {"pseudo3ddepth block-size=8", 3},
               {"pseudo3ddepth block-size=6", 0},             // no power of two: full-size
               {"pseudo3ddepth ! pseudo3dfilter", 0},          // step 1 up to 2159 rows
               {"pseudo3ddepth ! pseudo3dfilter scale=4", 2},
               {"pseudo3ddepth ! pseudo3dfilter scale=3", 0},
               {"pseudo3ddepth block-size=4 ! pseudo3dfilter radius=0", 2}};  // passed through
  for (const Case &c : cases) {
    GstHarness *hx =
        gst_harness_new_parse((std::string("cudaupload ! video/x-raw(memory:CUDAMemory) ! ") + c.stages).c_str());
    gst_harness_set_src_caps_str(hx, raw_caps(PixelFormat::NV12, 640, 360).c_str());
    GstBuffer *b = gst_harness_push_and_pull(hx, buffer_from_frame(frame));
    ASSERT_NE(b, nullptr) << c.stages;
    const DepthPlaneInfo d = buffer_depth_info(b);
    EXPECT_TRUE(d.present && d.on_device) << c.stages;
    EXPECT_EQ(d.width, 640) << c.stages;
    EXPECT_EQ(d.height, 360) << c.stages;
    EXPECT_EQ(d.shift, c.shift) << c.stages;
    gst_buffer_unref(b);
    gst_harness_teardown(hx);
  }
}

// Real data: Aloe through the whole chain, GPU against CPU.
TEST(GpuChainReal, AloeMatchesCpu) {
  const cv::Mat aloe = load_data_image("aloeL.jpg");
  ASSERT_FALSE(aloe.empty());
  const std::vector<HostFrame> frames = {HostFrame::from_bgr(aloe, PixelFormat::NV12)};
  const auto gpu = run_chain(chain(kDevice, "anaglyph", "RGBA"), PixelFormat::NV12, aloe.cols, aloe.rows, frames);
  const auto cpu = run_chain(chain(kCpu, "anaglyph", "RGBA"), PixelFormat::NV12, aloe.cols, aloe.rows, frames);
  expect_same(gpu, cpu, "aloe");
}

// Real video: the first 12 frames of vtest.avi as a stream, so the depth
// stage's temporal smoothing, static reuse and cut detection run on the GPU
// with history, against the CPU chain frame by frame.
TEST(GpuChainReal, VtestVideoMatchesCpu) {
  std::vector<HostFrame> frames;
  for (int k = 0; k < 12; ++k) {
    char name[64];
    snprintf(name, sizeof name, "vtest.avi.frame-%03d", k);
    const cv::Mat bgr = load_data_image(name);
    ASSERT_FALSE(bgr.empty());
    frames.push_back(HostFrame::from_bgr(bgr, PixelFormat::I420));
  }
  const int w = frames[0].width(), h = frames[0].height();
  const auto gpu = run_chain(chain(kDevice, "anaglyph", "RGBA"), PixelFormat::I420, w, h, frames);
  const auto cpu = run_chain(chain(kCpu, "anaglyph", "RGBA"), PixelFormat::I420, w, h, frames);
  expect_same(gpu, cpu, "vtest");
}

// crop-bars on CUDA memory: letterboxed and pillarboxed frames (the bar
// counts come back from the device), at 720p and 4K, against the CPU chain
// frame by frame.
TEST(GpuChainBars, MatchesCpuChain) {
  struct Bars {
    int w, h, rows, cols;
  };
  for (const Bars b : {Bars{1280, 720, 88, 0}, Bars{960, 720, 0, 120}, Bars{3840, 2160, 280, 0}}) {
    std::vector<HostFrame> frames;
    for (uint32_t s = 0; s < 4; ++s) {
      const HostFrame inner = picture(PixelFormat::NV12, b.w - 2 * b.cols, b.h - 2 * b.rows, 500 + s);
      cv::Mat bgr;
      cv::cvtColor(inner.to_bgra(), bgr, cv::COLOR_BGRA2BGR);
      cv::copyMakeBorder(bgr, bgr, b.rows, b.rows, b.cols, b.cols, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
      frames.push_back(HostFrame::from_bgr(bgr, PixelFormat::NV12));
    }
    for (const char *layout : {"anaglyph", "side-by-side-half"}) {
      const std::string what = std::to_string(b.w) + "x" + std::to_string(b.h) + " bars " + std::to_string(b.rows) +
                               "/" + std::to_string(b.cols) + " " + layout;
      const auto gpu = run_chain(chain(kDevice, layout, "BGRA"), PixelFormat::NV12, b.w, b.h, frames);
      const auto cpu = run_chain(chain(kCpu, layout, "BGRA"), PixelFormat::NV12, b.w, b.h, frames);
      expect_same(gpu, cpu, what);
    }
  }
}

// A cut from a letterbox to a full-frame picture on CUDA memory: the
// counts of a frame are read back at the next frame (common/bars.h, step
// 4), so pseudo3ddepth's rect moves at the frame after the cut, and the
// chain's output is the CPU chain's frame by frame, adaptive or not.
TEST(GpuChainBars, ACutMovesTheRectAsOnTheCpu) {
  constexpr int kBars = 88, kCut = 4;
  std::vector<HostFrame> frames;
  for (int k = 0; k < 8; ++k) {
    const int rows = k < kCut ? kBars : 0;
    const HostFrame inner = picture(PixelFormat::NV12, 1280, 720 - 2 * rows, 520 + (k < kCut ? 0 : 1));
    cv::Mat bgr;
    cv::cvtColor(inner.to_bgra(), bgr, cv::COLOR_BGRA2BGR);
    cv::rectangle(bgr, cv::Rect(40 + 16 * k, 100, 60, 40), cv::Scalar(30, 200, 60), cv::FILLED);
    cv::copyMakeBorder(bgr, bgr, rows, rows, 0, 0, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
    frames.push_back(HostFrame::from_bgr(bgr, PixelFormat::NV12));
  }
  // The rect each frame's depth carries on the device.
  GstHarness *h = gst_harness_new_parse("cudaupload ! video/x-raw(memory:CUDAMemory) ! pseudo3ddepth processing=gpu");
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::NV12, 1280, 720).c_str());
  for (int k = 0; k < static_cast<int>(frames.size()); ++k) {
    GstBuffer *b = gst_harness_push_and_pull(h, buffer_from_frame(frames[k]));
    ASSERT_NE(b, nullptr);
    const DepthPlaneInfo info = buffer_depth_info(b);
    EXPECT_TRUE(info.on_device) << "frame " << k;
    const PixelRect want = k <= kCut ? PixelRect{0, kBars, 1280, 720 - kBars} : PixelRect{0, 0, 1280, 720};
    EXPECT_EQ(info.active, want) << "frame " << k;
    gst_buffer_unref(b);
  }
  gst_harness_teardown(h);
  for (const std::string adaptive : {" adaptive=false", " adaptive=true"}) {
    auto stages = [&adaptive](Where where) {  // every stage with `adaptive`
      return std::regex_replace(chain(where, "side-by-side-half", "BGRA"), std::regex("processing=(\\w+)"),
                                "processing=$1" + adaptive);
    };
    const auto gpu = run_chain(stages(kDevice), PixelFormat::NV12, 1280, 720, frames);
    const auto cpu = run_chain(stages(kCpu), PixelFormat::NV12, 1280, 720, frames);
    expect_same(gpu, cpu, "a cut to a full frame," + adaptive);
  }
}

// The bin on system memory: processing=gpu (cudaupload ! stages ! cudadownload
// inside) gives the CPU bin's output exactly.
TEST(GpuConvertBin, SystemMemoryOnGpuMatchesCpu) {
  std::vector<HostFrame> frames;
  for (uint32_t s = 0; s < 3; ++s) frames.push_back(picture(PixelFormat::I420, 720, 480, 300 + s));
  const char *tail = " layout=top-bottom-half ! capsfilter caps=video/x-raw,format=RGBA";
  const auto gpu = run_chain(std::string("pseudo3dconvert processing=gpu") + tail, PixelFormat::I420, 720, 480, frames);
  const auto cpu = run_chain(std::string("pseudo3dconvert processing=cpu") + tail, PixelFormat::I420, 720, 480, frames);
  expect_same(gpu, cpu, "pseudo3dconvert");
}

// pseudo3dwarp with a layout on CUDA memory packs its own pair
// (WarpRendererGpu::render_packed: an anaglyph fused into the warp where
// the rows of a cell are resolved together, as on the filter's cells of 2
// and 4 rows here on Hopper; the other layouts and NV12 through the pair
// and the pack kernel): the frames of pseudo3dwarp ! pseudo3dpack on the
// CPU, byte for byte. Then layout and swap-eyes changed between the frames
// of one stream on the GPU, each frame against the CPU chain with the
// values set before it; and the bin on CUDA memory, which packs this way.
TEST(GpuWarpLayout, PacksAsTheCpuChain) {
  std::vector<HostFrame> frames;
  for (uint32_t s = 0; s < 3; ++s) frames.push_back(picture(PixelFormat::I420, 642, 362, 700 + s));
  auto launch = [](bool gpu, int scale, const std::string &props, const char *format) {
    const std::string p = gpu ? " processing=gpu" : " processing=cpu";
    const std::string warp = "pseudo3dwarp max-disparity=4" + p + (gpu ? props : " ! pseudo3dpack" + p + props);
    return std::string(gpu ? "cudaupload ! video/x-raw(memory:CUDAMemory) ! " : "") + "pseudo3ddepth" + p +
           " ! pseudo3dfilter scale=" + std::to_string(scale) + p + " ! " + warp + (gpu ? " ! cudadownload" : "") +
           " ! capsfilter caps=video/x-raw,format=" + format;
  };
  for (const int scale : {2, 4})
    for (const char *props : {" layout=anaglyph", " layout=anaglyph swap-eyes=true anaglyph-method=gray",
                              " layout=side-by-side-half", " layout=top-bottom swap-eyes=true"})
      for (const char *format : {"RGBA", "NV12"}) {
        const std::string what = std::string("scale ") + std::to_string(scale) + props + " " + format;
        const auto gpu = run_chain(launch(true, scale, props, format), PixelFormat::I420, 642, 362, frames);
        const auto cpu = run_chain(launch(false, scale, props, format), PixelFormat::I420, 642, 362, frames);
        expect_same(gpu, cpu, what);
      }

  // Changed while playing, on the GPU.
  GstHarness *hx = gst_harness_new_parse(
      "cudaupload ! video/x-raw(memory:CUDAMemory) ! pseudo3ddepth processing=gpu ! pseudo3dfilter scale=4 "
      "processing=gpu ! pseudo3dwarp name=w max-disparity=4 processing=gpu ! cudadownload ! "
      "capsfilter caps=video/x-raw,format=RGBA");
  gst_harness_set_src_caps_str(hx, raw_caps(PixelFormat::I420, 642, 362).c_str());
  GstElement *warp = gst_bin_get_by_name(GST_BIN(hx->element), "w");
  ASSERT_NE(warp, nullptr);
  const char *steps[][2] = {{"anaglyph", "false"}, {"anaglyph", "true"}, {"side-by-side", "false"},
                            {"top-bottom-half", "true"}, {"anaglyph", "false"}};
  for (size_t k = 0; k < G_N_ELEMENTS(steps); ++k) {
    gst_util_set_object_arg(G_OBJECT(warp), "layout", steps[k][0]);
    gst_util_set_object_arg(G_OBJECT(warp), "swap-eyes", steps[k][1]);
    GstBuffer *b = gst_harness_push_and_pull(hx, buffer_from_frame(frames[k % frames.size()]));
    ASSERT_NE(b, nullptr) << steps[k][0];
    GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
    const std::vector<cv::Mat> got = {buffer_to_bgra(b, caps)};
    gst_caps_unref(caps);
    gst_buffer_unref(b);
    // The CPU chain on the frames so far (the depth stage's history), with
    // this step's layout for its last frame.
    std::vector<HostFrame> seq;
    for (size_t i = 0; i <= k; ++i) seq.push_back(frames[i % frames.size()]);
    const std::string props = std::string(" layout=") + steps[k][0] + " swap-eyes=" + steps[k][1];
    const auto cpu = run_chain(launch(false, 4, props, "RGBA"), PixelFormat::I420, 642, 362, seq);
    ASSERT_EQ(cpu.size(), seq.size());
    expect_same(got, {cpu.back()}, props + " changed while playing");
  }
  gst_object_unref(warp);
  gst_harness_teardown(hx);

  // The bin on CUDA memory packs in the warp.
  const std::string bin = "pseudo3dconvert max-disparity=4 layout=anaglyph swap-eyes=true";
  const auto gpu = run_chain("cudaupload ! video/x-raw(memory:CUDAMemory) ! " + bin +
                                 " ! cudadownload ! capsfilter caps=video/x-raw,format=RGBA",
                             PixelFormat::I420, 642, 362, frames);
  const auto cpu = run_chain(bin + " processing=cpu ! capsfilter caps=video/x-raw,format=RGBA", PixelFormat::I420, 642,
                             362, frames);
  expect_same(gpu, cpu, "pseudo3dconvert on CUDA memory");
}

// Colour signalling on CUDA memory, as on system memory (test_colour): the
// bin between cudaupload and cudadownload, written as 4:2:0 and as R'G'B',
// states the input's PQ transfer, BT.2020 primaries and HDR fields, and
// its bytes are the CPU bin's; an anaglyph of PQ video is refused.
TEST(GpuColourCaps, HdrSignalPassesOnCudaMemory) {
  const std::string caps =
      "video/x-raw,format=I420,width=64,height=48,framerate=25/1,colorimetry=bt2100-pq,"
      "mastering-display-info=(string)34000:16000:13250:34500:7500:3000:15635:16450:10000000:1,"
      "content-light-level=(string)1000:400";
  const HostFrame frame = picture(PixelFormat::I420, 64, 48, 41);
  for (const char *out : {"I420", "RGBA"}) {
    GstBuffer *results[2] = {nullptr, nullptr};
    for (int gpu = 0; gpu < 2; ++gpu) {
      const std::string launch = std::string(gpu ? "cudaupload ! video/x-raw(memory:CUDAMemory) ! " : "") +
                                 "pseudo3dconvert layout=side-by-side-half processing=" + (gpu ? "gpu" : "cpu") +
                                 (gpu ? " ! cudadownload" : "") + " ! capsfilter caps=video/x-raw,format=" + out;
      GstHarness *h = gst_harness_new_parse(launch.c_str());
      gst_harness_set_src_caps_str(h, caps.c_str());
      results[gpu] = gst_harness_push_and_pull(h, buffer_from_frame(frame));
      ASSERT_NE(results[gpu], nullptr) << launch;
      GstCaps *got = gst_pad_get_current_caps(h->sinkpad);
      GstVideoInfo info;
      ASSERT_TRUE(got && gst_video_info_from_caps(&info, got)) << launch;
      EXPECT_EQ(info.colorimetry.transfer, GST_VIDEO_TRANSFER_SMPTE2084) << launch;
      EXPECT_EQ(info.colorimetry.primaries, GST_VIDEO_COLOR_PRIMARIES_BT2020) << launch;
      if (GST_VIDEO_INFO_IS_YUV(&info)) {
        EXPECT_EQ(info.colorimetry.matrix, GST_VIDEO_COLOR_MATRIX_BT2020) << launch;
      }
      const GstStructure *st = gst_caps_get_structure(got, 0);
      EXPECT_STREQ(gst_structure_get_string(st, "content-light-level"), "1000:400") << launch;
      EXPECT_NE(gst_structure_get_string(st, "mastering-display-info"), nullptr) << launch;
      gst_caps_unref(got);
      gst_harness_teardown(h);
    }
    GstMapInfo a, b;
    ASSERT_TRUE(gst_buffer_map(results[0], &a, GST_MAP_READ) && gst_buffer_map(results[1], &b, GST_MAP_READ));
    EXPECT_EQ(a.size, b.size);
    EXPECT_EQ(memcmp(a.data, b.data, std::min(a.size, b.size)), 0) << out << ": the GPU bin's bytes are the CPU's";
    gst_buffer_unmap(results[0], &a);
    gst_buffer_unmap(results[1], &b);
    for (GstBuffer *r : results) gst_buffer_unref(r);
  }
  const std::string err =
      run_to_eos("videotestsrc num-buffers=2 ! video/x-raw,format=I420,width=64,height=48,colorimetry=bt2100-pq ! "
                 "cudaupload ! video/x-raw(memory:CUDAMemory) ! pseudo3dconvert layout=anaglyph ! cudadownload ! "
                 "fakesink");
  EXPECT_NE(err.find("An anaglyph needs SDR video"), std::string::npos) << err;
}

// Interlaced video: pseudo3dconvert deinterlaces system memory before it
// uploads (a frame for each field, on the GPU), and refuses interlaced
// CUDA memory, which deinterlace does not take, saying where to
// deinterlace instead.
TEST(GpuConvertBin, InterlacedVideoOnEitherMemory) {
  const std::string src = "videotestsrc num-buffers=3 ! video/x-raw,format=I420,width=64,height=48,framerate=30/1,"
                          "interlace-mode=interleaved ! ";
  std::string rate;
  EXPECT_EQ(run_to_eos(src + "pseudo3dconvert processing=gpu ! fakesink name=sink", 60,
                       [&](GstElement *pipeline) {
                         GstElement *sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
                         GstPad *pad = gst_element_get_static_pad(sink, "sink");
                         GstCaps *caps = gst_pad_get_current_caps(pad);
                         GstVideoInfo info;
                         if (caps && gst_video_info_from_caps(&info, caps))
                           rate = std::to_string(GST_VIDEO_INFO_FPS_N(&info)) + "/" +
                                  std::to_string(GST_VIDEO_INFO_FPS_D(&info));
                         if (caps) gst_caps_unref(caps);
                         gst_object_unref(pad);
                         gst_object_unref(sink);
                       }),
            "");
  EXPECT_EQ(rate, "60/1") << "a frame for each field";
  const std::string err = run_to_eos(src + "cudaupload ! video/x-raw(memory:CUDAMemory) ! pseudo3dconvert name=c3d ! "
                                           "cudadownload ! fakesink");
  EXPECT_NE(err.find("Interlaced video is not supported"), std::string::npos) << err;
  EXPECT_NE(err.find("deinterlace does not take CUDA memory"), std::string::npos) << err;
}

// Device memory stays flat over 1000 frames (pools, no per-frame allocation).
TEST(GpuChainMemory, FlatOver1000Frames) {
  const int w = 640, h = 360;
  GstHarness *hx = gst_harness_new_parse(chain(kDevice, "anaglyph", "RGBA").c_str());
  gst_harness_set_src_caps_str(hx, raw_caps(PixelFormat::NV12, w, h).c_str());
  std::vector<HostFrame> frames;
  for (uint32_t s = 0; s < 4; ++s) frames.push_back(picture(PixelFormat::NV12, w, h, s));
  auto push = [&](int n) {
    for (int i = 0; i < n; ++i) {
      GstBuffer *b = gst_harness_push_and_pull(hx, buffer_from_frame(frames[i % frames.size()]));
      ASSERT_NE(b, nullptr);
      gst_buffer_unref(b);
    }
  };
  push(50);  // warm-up: pools and workspaces reach their steady size
  size_t free0 = 0, free1 = 0, total = 0;
  ASSERT_EQ(cudaMemGetInfo(&free0, &total), cudaSuccess);
  push(1000);
  ASSERT_EQ(cudaMemGetInfo(&free1, &total), cudaSuccess);
  const long long grown = (long long)free0 - (long long)free1;
  RecordProperty("device_memory_growth_bytes", std::to_string(grown));
  EXPECT_LE(grown, 2ll << 20) << "device memory grew by " << grown << " bytes over 1000 frames";
  gst_harness_teardown(hx);
}

// The plugin's fault-injection hook (gst/fault_hook.cpp): the n-th checked
// CUDA call inside the plugin reports a failure.
using InjectFn = void (*)(int);
InjectFn fault_hook() {
  GstPlugin *plugin = gst_registry_find_plugin(gst_registry_get(), "pseudo3d");
  if (!plugin) return nullptr;
  gst_plugin_load(plugin);
  GModule *module = g_module_open(gst_plugin_get_filename(plugin), G_MODULE_BIND_LOCAL);
  gst_object_unref(plugin);
  gpointer fn = nullptr;
  if (module) g_module_symbol(module, "pseudo3d_test_inject_cuda_fault", &fn);
  return reinterpret_cast<InjectFn>(fn);
}

// Waits for an error or EOS; returns the error text ("" for EOS), or
// "timeout" when neither came.
std::string wait_end(GstElement *pipeline, std::string *source) {
  GstBus *bus = gst_element_get_bus(pipeline);
  GstMessage *m =
      gst_bus_timed_pop_filtered(bus, 60 * GST_SECOND, (GstMessageType)(GST_MESSAGE_ERROR | GST_MESSAGE_EOS));
  gst_object_unref(bus);
  if (!m) return "timeout";
  std::string text;
  if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) {
    text = message_text(m);
    if (source) *source = GST_OBJECT_NAME(GST_MESSAGE_SRC(m));
  }
  gst_message_unref(m);
  return text;
}

// A CUDA call failing in the middle of a stream (after frames have flowed):
// one clean element error that names the CUDA failure, no crash and no
// hang; the same pipeline then goes to NULL and runs to EOS again.
TEST(GpuFaults, MidStreamFailureIsACleanErrorAndThePipelineIsReusable) {
  const InjectFn inject = fault_hook();
  ASSERT_NE(inject, nullptr) << "pseudo3d_test_inject_cuda_fault not found in the plugin";
  GstElement *p = gst_parse_launch(
      "videotestsrc num-buffers=120 ! video/x-raw,format=NV12,width=320,height=240 ! cudaupload ! "
      "video/x-raw(memory:CUDAMemory) ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack ! cudadownload ! "
      "fakesink name=sink sync=false",
      nullptr);
  ASSERT_NE(p, nullptr);
  GstElement *sink = gst_bin_get_by_name(GST_BIN(p), "sink");
  for (int after : {1, 5, 23}) {
    SCOPED_TRACE("failing call " + std::to_string(after));
    inject(0);
    ASSERT_NE(gst_element_set_state(p, GST_STATE_PLAYING), GST_STATE_CHANGE_FAILURE);
    // Let frames flow first: the failure must hit a running stream.
    for (int waited = 0; waited < 200; ++waited) {
      GstStructure *stats = nullptr;
      guint64 rendered = 0;
      g_object_get(sink, "stats", &stats, NULL);
      gst_structure_get_uint64(stats, "rendered", &rendered);
      gst_structure_free(stats);
      if (rendered >= 5) break;
      g_usleep(10000);
    }
    inject(after);
    std::string source;
    const std::string err = wait_end(p, &source);
    EXPECT_NE(err, "timeout") << "the pipeline hung";
    EXPECT_NE(err.find("CUDA failure"), std::string::npos) << err;
    EXPECT_NE(err.find("cudaErrorLaunchFailure"), std::string::npos) << err;
    EXPECT_TRUE(g_str_has_prefix(source.c_str(), "pseudo3d")) << source;
    inject(0);
    ASSERT_EQ(gst_element_set_state(p, GST_STATE_NULL), GST_STATE_CHANGE_SUCCESS);
    // Reused: the same pipeline plays through.
    ASSERT_NE(gst_element_set_state(p, GST_STATE_PLAYING), GST_STATE_CHANGE_FAILURE);
    EXPECT_EQ(wait_end(p, nullptr), "");
    ASSERT_EQ(gst_element_set_state(p, GST_STATE_NULL), GST_STATE_CHANGE_SUCCESS);
  }
  gst_object_unref(sink);
  gst_object_unref(p);
}

// Plays `launch` to EOS (or an error) and returns the error text ("" for
// EOS); `setup` may touch the elements before PLAYING.
template <typename Setup>
std::string play(const std::string &launch, Setup &&setup) {
  GstElement *p = gst_parse_launch(launch.c_str(), nullptr);
  if (!p) return "parse failed";
  setup(p);
  gst_element_set_state(p, GST_STATE_PLAYING);
  const std::string err = wait_end(p, nullptr);
  gst_element_set_state(p, GST_STATE_NULL);
  gst_object_unref(p);
  return err;
}

// A change of memory domain never reaches the warp with a depth in the
// wrong memory: after cudaupload the depth is gone and the warp says it
// needs pseudo3ddepth. cudadownload in 1.22 goes passthrough when downstream
// takes GstVideoMeta (the CUDA buffer handed on as system memory, metas and
// all), so there the warp finds a device depth on a host frame and says so;
// either way the error is one, clear, and names the fix. A pseudo3ddepth
// placed after them estimates afresh and the chain runs.
TEST(GpuDepthMeta, CudaUploadAndDownloadDropTheDepth) {
  const char *src = "videotestsrc num-buffers=3 ! video/x-raw,format=NV12,width=64,height=48 ! ";
  std::string err = play(std::string(src) + "pseudo3ddepth ! cudaupload ! video/x-raw(memory:CUDAMemory) ! "
                         "pseudo3dwarp ! fakesink", [](GstElement *) {});
  EXPECT_NE(err.find("needs a depth map"), std::string::npos) << err;
  // (Without the system-memory caps cudadownload would pass CUDA memory
  // through to the warp, which takes it: no change of domain, depth kept.)
  err = play(std::string(src) + "cudaupload ! video/x-raw(memory:CUDAMemory) ! pseudo3ddepth ! cudadownload ! "
             "video/x-raw ! pseudo3dwarp ! fakesink", [](GstElement *) {});
  EXPECT_TRUE(err.find("needs a depth map") != std::string::npos ||
              err.find("depth map does not fit the frame") != std::string::npos)
      << err;
  EXPECT_NE(err.find("put pseudo3ddepth"), std::string::npos) << err;
  err = play(std::string(src) + "cudaupload ! video/x-raw(memory:CUDAMemory) ! pseudo3ddepth ! cudadownload ! "
             "video/x-raw ! pseudo3ddepth ! pseudo3dwarp ! fakesink", [](GstElement *) {});
  EXPECT_EQ(err, "");
}

// Every frame an appsink named "out" receives, as BGRA.
std::vector<cv::Mat> pull_all(GstElement *pipeline) {
  std::vector<cv::Mat> frames;
  GstElement *sink = gst_bin_get_by_name(GST_BIN(pipeline), "out");
  while (GstSample *s = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 30 * GST_SECOND)) {
    frames.push_back(buffer_to_bgra(gst_sample_get_buffer(s), gst_sample_get_caps(s)));
    gst_sample_unref(s);
  }
  gst_object_unref(sink);
  return frames;
}

// Plays `launch` (with an appsink named "out") and returns its frames; an
// error the pipeline posts fails the test with its text.
std::vector<cv::Mat> play_and_pull(const std::string &launch) {
  GstElement *p = gst_parse_launch(launch.c_str(), nullptr);
  if (!p) {
    ADD_FAILURE() << "cannot parse " << launch;
    return {};
  }
  gst_element_set_state(p, GST_STATE_PLAYING);
  std::vector<cv::Mat> frames = pull_all(p);
  const std::string error = first_bus_error(p);
  if (!error.empty()) ADD_FAILURE() << launch << ": " << error;
  gst_element_set_state(p, GST_STATE_NULL);
  gst_object_unref(p);
  return frames;
}

// The grids change under a playing pipeline: a second thread sets the
// estimator's block size and the filter's step to values with and without
// grids (and back) while frames flow on CUDA memory, so consecutive frames
// hand on planes of other shifts through the same pools. The stream ends
// with no error.
TEST(GpuChainGrids, BlockAndStepChangedWhilePlaying) {
  GstElement *p = gst_parse_launch(
      "videotestsrc num-buffers=240 pattern=ball ! video/x-raw,format=NV12,width=640,height=360 ! cudaupload ! "
      "video/x-raw(memory:CUDAMemory) ! pseudo3ddepth name=d ! pseudo3dfilter name=f ! pseudo3dwarp ! "
      "pseudo3dpack ! fakesink sync=false",
      nullptr);
  ASSERT_NE(p, nullptr);
  GstElement *d = gst_bin_get_by_name(GST_BIN(p), "d"), *f = gst_bin_get_by_name(GST_BIN(p), "f");
  std::atomic<bool> stop{false};
  gst_element_set_state(p, GST_STATE_PLAYING);
  std::thread changer([&] {
    const int blocks[] = {0, 8, 6, 4, 2}, steps[] = {0, 4, 3, 2, 8, 1};
    for (int i = 0; !stop; ++i) {
      g_object_set(d, "block-size", blocks[i % 5], NULL);
      g_object_set(f, "scale", steps[i % 6], NULL);
      std::this_thread::sleep_for(std::chrono::milliseconds(3));
    }
  });
  const std::string err = wait_end(p, nullptr);
  stop = true;
  changer.join();
  EXPECT_EQ(err, "");
  gst_element_set_state(p, GST_STATE_NULL);
  gst_object_unref(d);
  gst_object_unref(f);
  gst_object_unref(p);
}

// A flushing seek while CUDA frames play: the estimator's history restarts
// at the seek, so the depth after it (handed on as the estimator's block
// grid and the filter's cell grid, read back by pseudo3ddepthout) is the
// CPU chain's frame for frame: 40 frames, a seek to 3 s, two more.
TEST(GpuChainGrids, FlushingSeekMatchesTheCpuChain) {
  std::vector<cv::Mat> out[2];
  GstClockTime after_seek[2] = {GST_CLOCK_TIME_NONE, GST_CLOCK_TIME_NONE};
  for (int gpu = 0; gpu < 2; ++gpu) {
    const std::string p = gpu ? " processing=gpu" : " processing=cpu";
    const std::string launch =
        std::string("videotestsrc pattern=ball ! video/x-raw,format=NV12,width=640,height=360,framerate=30/1 ! ") +
        (gpu ? "cudaupload ! video/x-raw(memory:CUDAMemory) ! " : "") + "pseudo3ddepth" + p +
        " ! pseudo3dfilter scale=2" + p +
        " ! pseudo3ddepthout ! video/x-raw,format=GRAY16_LE ! videoconvert ! video/x-raw,format=RGBA ! "
        "appsink name=out sync=false max-buffers=4";
    GstElement *pipe = gst_parse_launch(launch.c_str(), nullptr);
    ASSERT_NE(pipe, nullptr) << launch;
    GstElement *sink = gst_bin_get_by_name(GST_BIN(pipe), "out");
    gst_element_set_state(pipe, GST_STATE_PLAYING);
    auto pull = [&](GstClockTime *pts) {
      GstSample *s = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 30 * GST_SECOND);
      if (!s) return false;
      out[gpu].push_back(buffer_to_bgra(gst_sample_get_buffer(s), gst_sample_get_caps(s)));
      if (pts) *pts = GST_BUFFER_PTS(gst_sample_get_buffer(s));
      gst_sample_unref(s);
      return true;
    };
    for (int i = 0; i < 40; ++i) ASSERT_TRUE(pull(nullptr)) << launch;
    ASSERT_TRUE(gst_element_seek_simple(pipe, GST_FORMAT_TIME,
                                        (GstSeekFlags)(GST_SEEK_FLAG_FLUSH | GST_SEEK_FLAG_ACCURATE), 3 * GST_SECOND));
    ASSERT_TRUE(pull(&after_seek[gpu])) << launch;
    ASSERT_TRUE(pull(nullptr)) << launch;
    const std::string error = first_bus_error(pipe);
    if (!error.empty()) ADD_FAILURE() << launch << ": " << error;
    gst_element_set_state(pipe, GST_STATE_NULL);
    gst_object_unref(sink);
    gst_object_unref(pipe);
  }
  EXPECT_EQ(after_seek[0], 3 * GST_SECOND);
  EXPECT_EQ(after_seek[1], 3 * GST_SECOND);
  expect_same(out[1], out[0], "depth across a flushing seek");
}

// pseudo3ddepthmux on CUDA memory: the depth goes to the frame's context
// and the GPU stages after it give the CPU chain's output exactly, for a
// depth picture of the frame's size and of another size, 8 and 16 bits.
TEST(GpuDepthMux, CudaFramesMatchTheCpuChain) {
  for (const char *depth : {"format=GRAY8,width=320,height=240", "format=GRAY16_LE,width=160,height=90"}) {
    std::vector<cv::Mat> out[2];
    for (int gpu = 0; gpu < 2; ++gpu) {
      const std::string launch =
          std::string("videotestsrc num-buffers=4 pattern=ball ! video/x-raw,format=NV12,width=320,height=240 ! ") +
          (gpu ? "cudaupload ! video/x-raw(memory:CUDAMemory) ! " : "") + "m.video " +
          "videotestsrc num-buffers=1 pattern=smpte ! videoconvert ! video/x-raw," + depth + " ! m.depth " +
          "pseudo3ddepthmux name=m ! pseudo3dfilter processing=" + (gpu ? "gpu" : "cpu") +
          " ! pseudo3dwarp processing=" + (gpu ? "gpu" : "cpu") + " ! pseudo3dpack layout=side-by-side processing=" +
          (gpu ? "gpu" : "cpu") + (gpu ? " ! video/x-raw(memory:CUDAMemory) ! cudadownload" : "") +
          " ! video/x-raw,format=RGBA ! appsink name=out sync=false";
      out[gpu] = play_and_pull(launch);
    }
    ASSERT_EQ(out[0].size(), 4u) << depth;
    expect_same(out[1], out[0], std::string("depthmux ") + depth);
  }
}

// pseudo3ddepthout reads a device depth back: the grey video of the GPU
// chain is the CPU chain's, 16 and 8 bits.
// On CUDA memory the depth reaches pseudo3ddepthout full-size (filter at
// step 1), on the filter's cell grid (scale 4) or on the estimator's block
// grid (no filter): each reads back as the CPU chain's full-size map.
TEST(GpuDepthOut, DeviceDepthReadsBackAsTheCpuChain) {
  for (const char *filter : {" ! pseudo3dfilter", " ! pseudo3dfilter scale=4", ""})
    for (const char *format : {"GRAY16_LE", "GRAY8"}) {
      std::vector<cv::Mat> out[2];
      for (int gpu = 0; gpu < 2; ++gpu) {
        const std::string p = gpu ? "gpu" : "cpu";
        const std::string launch =
            std::string("videotestsrc num-buffers=3 pattern=ball ! video/x-raw,format=NV12,width=320,height=240 ! ") +
            (gpu ? "cudaupload ! video/x-raw(memory:CUDAMemory) ! " : "") + "pseudo3ddepth processing=" + p + filter +
            (*filter ? " processing=" + p : std::string()) + " ! pseudo3ddepthout ! video/x-raw,format=" + format +
            " ! videoconvert ! video/x-raw,format=RGBA ! appsink name=out sync=false";
        out[gpu] = play_and_pull(launch);
      }
      ASSERT_EQ(out[0].size(), 3u) << format << filter;
      expect_same(out[1], out[0], std::string("depthout ") + format + filter);
    }
}

// cudaupload on one CUDA context, the stages given another (both device 0,
// set before they start, so nothing shares them): with cuda-device-id -1
// the stages adopt the context of the incoming buffers and give the CPU
// chain's output, instead of failing.
TEST(GpuContext, StagesAdoptTheUpstreamContext) {
  const char *src = "videotestsrc num-buffers=3 pattern=ball ! video/x-raw,format=NV12,width=320,height=240 ! ";
  const char *stages = "pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack";
  GstCudaContext *a = gst_cuda_context_new(0), *b = gst_cuda_context_new(0);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  GstContext *ca = gst_context_new_cuda_context(a), *cb = gst_context_new_cuda_context(b);
  GstElement *gpu = gst_parse_launch((std::string(src) + "cudaupload name=up ! video/x-raw(memory:CUDAMemory) ! " +
                                      stages + " ! cudadownload ! video/x-raw,format=RGBA ! appsink name=out sync=false")
                                         .c_str(),
                                     nullptr);
  ASSERT_NE(gpu, nullptr);
  GstIterator *it = gst_bin_iterate_elements(GST_BIN(gpu));
  GValue v = G_VALUE_INIT;
  while (gst_iterator_next(it, &v) == GST_ITERATOR_OK) {
    GstElement *e = GST_ELEMENT(g_value_get_object(&v));
    const gchar *name = GST_OBJECT_NAME(gst_element_get_factory(e));
    if (g_str_equal(name, "cudaupload")) gst_element_set_context(e, ca);
    if (g_str_has_prefix(name, "pseudo3d")) gst_element_set_context(e, cb);
    g_value_reset(&v);
  }
  g_value_unset(&v);
  gst_iterator_free(it);
  gst_element_set_state(gpu, GST_STATE_PLAYING);
  const std::vector<cv::Mat> got = pull_all(gpu);
  EXPECT_EQ(wait_end(gpu, nullptr), "");
  gst_element_set_state(gpu, GST_STATE_NULL);
  gst_object_unref(gpu);

  GstElement *cpu = gst_parse_launch((std::string(src) + "pseudo3ddepth processing=cpu ! pseudo3dfilter processing=cpu ! "
                                      "pseudo3dwarp processing=cpu ! pseudo3dpack processing=cpu ! "
                                      "video/x-raw,format=RGBA ! appsink name=out sync=false")
                                         .c_str(),
                                     nullptr);
  gst_element_set_state(cpu, GST_STATE_PLAYING);
  const std::vector<cv::Mat> want = pull_all(cpu);
  gst_element_set_state(cpu, GST_STATE_NULL);
  gst_object_unref(cpu);
  ASSERT_EQ(got.size(), 3u);
  expect_same(got, want, "adopted context");
  gst_context_unref(ca);
  gst_context_unref(cb);
  gst_object_unref(a);
  gst_object_unref(b);
}

// processing=gpu asks upstream for CUDA memory: after a plain cudaupload
// (which prefers passing system memory through) the stage negotiates
// memory:CUDAMemory. System memory, which runs on the CPU, is refused with
// one error that says what to insert.
TEST(GpuNegotiation, ProcessingGpuNegotiatesCudaMemoryAndRefusesSystemMemory) {
  GstElement *p = gst_parse_launch("videotestsrc num-buffers=3 ! video/x-raw,format=NV12,width=64,height=48 ! "
                                   "cudaupload ! pseudo3ddepth name=d processing=gpu ! cudadownload ! fakesink",
                                   nullptr);
  gst_element_set_state(p, GST_STATE_PLAYING);
  EXPECT_EQ(wait_end(p, nullptr), "");
  GstElement *d = gst_bin_get_by_name(GST_BIN(p), "d");
  GstPad *sink = gst_element_get_static_pad(d, "sink");
  // Caps stay set until NULL: read them at EOS.
  EXPECT_NE(current_caps(sink).find("memory:CUDAMemory"), std::string::npos) << current_caps(sink);
  gst_object_unref(sink);
  gst_object_unref(d);
  gst_element_set_state(p, GST_STATE_NULL);
  gst_object_unref(p);

  GstHarness *h = gst_harness_new_parse("pseudo3ddepth processing=gpu ! pseudo3dfilter processing=gpu");
  BusMessages bus(h->element);
  gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::NV12, 64, 48).c_str());
  for (int i = 0; i < 3; ++i)
    EXPECT_NE(gst_harness_push(h, buffer_from_frame(picture(PixelFormat::NV12, 64, 48, i))), GST_FLOW_OK);
  const std::vector<std::string> errors = bus.take(GST_MESSAGE_ERROR);
  ASSERT_EQ(errors.size(), 1u) << "one error, from the first stage, not one a buffer";
  EXPECT_NE(errors[0].find("processing=gpu needs video in CUDA memory"), std::string::npos) << errors[0];
  EXPECT_NE(errors[0].find("cudaupload"), std::string::npos) << errors[0];
  gst_harness_teardown(h);
}

// stop() frees the stages' device memory (frames, depth planes, pools):
// the same pipeline, in NULL after a 4K run, holds what it holds after a run
// of no frames at all (the CUDA context, which the pipeline keeps cached).
TEST(GpuChainMemory, FreedAtStop) {
  GstElement *p = gst_parse_launch(
      "videotestsrc name=src ! video/x-raw,format=NV12,width=3840,height=2160 ! cudaupload ! "
      "video/x-raw(memory:CUDAMemory) ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! "
      "pseudo3dpack layout=side-by-side-half ! cudadownload ! fakesink",
      nullptr);
  ASSERT_NE(p, nullptr);
  GstElement *src = gst_bin_get_by_name(GST_BIN(p), "src");
  size_t total = 0, free_idle = 0, free_running = SIZE_MAX, free_stopped = 0;
  auto run = [&](int frames, size_t *free_after) {
    g_object_set(src, "num-buffers", frames, NULL);
    gst_element_set_state(p, GST_STATE_PLAYING);
    gst_element_get_state(p, nullptr, nullptr, 30 * GST_SECOND);
    size_t f = 0;
    ASSERT_EQ(cudaMemGetInfo(&f, &total), cudaSuccess);
    free_running = std::min(free_running, f);
    EXPECT_EQ(wait_end(p, nullptr), "");
    gst_element_set_state(p, GST_STATE_NULL);
    ASSERT_EQ(cudaMemGetInfo(free_after, &total), cudaSuccess);
  };
  run(0, &free_idle);  // the context only
  run(20, &free_stopped);
  RecordProperty("device_memory_held_running_bytes", std::to_string((long long)free_idle - (long long)free_running));
  EXPECT_GT((long long)free_idle - (long long)free_running, 100ll << 20) << "a 4K chain holds its buffers while running";
  const long long kept = (long long)free_idle - (long long)free_stopped;
  RecordProperty("device_memory_kept_after_stop_bytes", std::to_string(kept));
  EXPECT_LE(kept, 8ll << 20) << "device memory still held after stop(): " << kept << " bytes";
  gst_object_unref(src);
  gst_object_unref(p);
}

}  // namespace

int main(int argc, char **argv) {
  gst_init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int n = 0;
  GstElementFactory *up = gst_element_factory_find("cudaupload");
  if (cudaGetDeviceCount(&n) != cudaSuccess || n == 0 || !up) {
    fprintf(stderr, "no CUDA device or no cudaupload: GPU element tests skipped\n");
    return 77;
  }
  gst_object_unref(up);
  return RUN_ALL_TESTS();
}
