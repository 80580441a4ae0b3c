// P010_10LE and I420_10LE on CUDA memory through the elements: depth !
// filter ! warp into 10-bit 4:2:0 on CUDA memory, and pseudo3dconvert
// processing=gpu, against the same chains on the CPU, every plane byte for
// byte; with crop-bars on letterboxed frames and with adaptive work on a
// sequence that repeats frames. RGBA64_LE, which GStreamer 1.22's CUDA
// allocator does not hold, stays off CUDA memory.
#include <gst/check/gstharness.h>
#include <gst/gst.h>
#include <gst/video/video.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "../elements/element_helpers.h"
#include "test_data.h"

using namespace p3d;
using namespace p3d::test;

namespace {

// The format of a GStreamer format name, of the formats tests push.
bool pixel_format_from_name(const char *name, PixelFormat *out) {
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420, PixelFormat::RGBA, PixelFormat::BGRA, PixelFormat::RGBx,
                        PixelFormat::BGRx, PixelFormat::P010, PixelFormat::I420_10, PixelFormat::RGBA64})
    if (std::strcmp(gst_format_name(f), name) == 0) {
      *out = f;
      return true;
    }
  return false;
}

// The output frame of a buffer, copied into a HostFrame of its caps'
// format (row padding left out); an empty frame where the caps do not map.
HostFrame frame_of(GstBuffer *buf, GstCaps *caps) {
  GstVideoInfo info;
  PixelFormat format;
  if (!caps || !gst_video_info_from_caps(&info, caps) || !pixel_format_from_name(GST_VIDEO_INFO_NAME(&info), &format))
    return HostFrame();
  HostFrame out(format, GST_VIDEO_INFO_WIDTH(&info), GST_VIDEO_INFO_HEIGHT(&info));
  GstVideoFrame f;
  if (!gst_video_frame_map(&f, &info, buf, GST_MAP_READ)) return HostFrame();
  const FrameView v = out.view();
  for (int p = 0; p < frame_plane_count(format); ++p) {
    int row = 0, rows = 0;
    frame_plane_size(format, v.width, v.height, p, &row, &rows);
    for (int y = 0; y < rows; ++y)
      std::memcpy(v.plane[p] + static_cast<size_t>(y) * v.stride[p],
                  static_cast<const uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&f, p)) +
                      static_cast<size_t>(y) * GST_VIDEO_FRAME_PLANE_STRIDE(&f, p),
                  static_cast<size_t>(row));
  }
  gst_video_frame_unmap(&f);
  return out;
}

// Every frame through `launch`, the outputs as host frames; *warp_caps:
// the caps of the warp's source pad at the end (which memory it ran on).
std::vector<HostFrame> run(const std::string &launch, const std::vector<HostFrame> &frames,
                           std::string *warp_caps = nullptr) {
  std::vector<HostFrame> out;
  GstHarness *h = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(h, raw_caps(frames[0].format(), frames[0].width(), frames[0].height()).c_str());
  for (const HostFrame &fr : frames) {
    GstBuffer *b = gst_harness_push_and_pull(h, buffer_from_frame(fr));
    if (!b) {
      ADD_FAILURE() << "no output from " << launch;
      break;
    }
    GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
    out.push_back(frame_of(b, caps));
    if (caps) gst_caps_unref(caps);
    gst_buffer_unref(b);
  }
  if (warp_caps) {
    GstIterator *it = gst_bin_iterate_recurse(GST_BIN(h->element));
    GValue v = G_VALUE_INIT;
    while (gst_iterator_next(it, &v) == GST_ITERATOR_OK) {
      GstElement *e = GST_ELEMENT(g_value_get_object(&v));
      if (g_str_has_prefix(GST_OBJECT_NAME(e), "pseudo3dwarp")) {
        GstPad *src = gst_element_get_static_pad(e, "src");
        *warp_caps = current_caps(src);
        gst_object_unref(src);
      }
      g_value_reset(&v);
    }
    g_value_unset(&v);
    gst_iterator_free(it);
  }
  gst_harness_teardown(h);
  return out;
}

// "" when every plane byte of two frames is the same.
std::string difference(const HostFrame &a, const HostFrame &b) {
  if (a.format() != b.format() || a.width() != b.width() || a.height() != b.height())
    return "different formats or sizes";
  const FrameView va = a.view(), vb = b.view();
  for (int p = 0; p < frame_plane_count(a.format()); ++p) {
    int row = 0, rows = 0;
    frame_plane_size(a.format(), a.width(), a.height(), p, &row, &rows);
    for (int y = 0; y < rows; ++y)
      if (std::memcmp(va.plane[p] + static_cast<size_t>(y) * va.stride[p],
                      vb.plane[p] + static_cast<size_t>(y) * vb.stride[p], static_cast<size_t>(row)) != 0)
        return "plane " + std::to_string(p) + " row " + std::to_string(y) + " differs";
  }
  return "";
}

void expect_same(const std::vector<HostFrame> &gpu, const std::vector<HostFrame> &cpu, const std::string &what) {
  ASSERT_EQ(gpu.size(), cpu.size()) << what;
  for (size_t k = 0; k < gpu.size(); ++k) EXPECT_EQ(difference(gpu[k], cpu[k]), "") << what << ", frame " << k;
}

// depth ! filter ! warp with `props` on every stage (and depth_props on
// the depth stage), into `out_format`: on CUDA memory (cudaupload before,
// cudadownload after) or on the CPU.
std::string stages(bool gpu, const std::string &props, const char *layout, const char *out_format,
                   const std::string &depth_props = "") {
  const std::string p = std::string(" processing=") + (gpu ? "gpu" : "cpu") + props;
  const std::string chain = "pseudo3ddepth" + p + depth_props + " ! pseudo3dfilter" + p +
                            " ! pseudo3dwarp max-disparity=4 layout=" + layout + p;
  if (!gpu) return chain + " ! capsfilter caps=video/x-raw,format=" + out_format;
  return "cudaupload ! video/x-raw(memory:CUDAMemory) ! " + chain +
         " ! capsfilter caps=\"video/x-raw(memory:CUDAMemory), format=" + out_format +
         "\" ! cudadownload ! capsfilter caps=video/x-raw,format=" + out_format;
}

// Deep frames of a 16-bit picture (low bits used); `bars`: rows of black
// above and below the picture (a letterboxed film).
std::vector<HostFrame> deep_frames(PixelFormat f, int w, int h, int count, int bars = 0) {
  std::vector<HostFrame> frames;
  for (int k = 0; k < count; ++k) {
    cv::Mat pic = deep_picture(w, h, 40 + static_cast<uint32_t>(k));
    if (bars > 0) {
      pic.rowRange(0, bars).setTo(cv::Scalar::all(0));
      pic.rowRange(h - bars, h).setTo(cv::Scalar::all(0));
    }
    frames.push_back(HostFrame::from_bgr16(pic, f));
  }
  return frames;
}

TEST(GpuDeepChain, TenBitOnCudaMemoryMatchesTheCpuChain) {
  for (PixelFormat in : {PixelFormat::P010, PixelFormat::I420_10})
    for (const char *out : {"P010_10LE", "I420_10LE"})
      for (const char *layout : {"side-by-side-half", "anaglyph", "top-bottom", "side-by-side"}) {
        const std::vector<HostFrame> frames = deep_frames(in, 322, 182, 3);
        std::string caps;
        const auto gpu = run(stages(true, "", layout, out), frames, &caps);
        const auto cpu = run(stages(false, "", layout, out), frames);
        const std::string what = std::string(format_name(in)) + " -> " + out + " " + layout;
        EXPECT_NE(caps.find("memory:CUDAMemory"), std::string::npos) << what << ": the warp ran on " << caps;
        expect_same(gpu, cpu, what);
      }
}

TEST(GpuDeepChain, UltraHdP010) {
  const std::vector<HostFrame> frames = deep_frames(PixelFormat::P010, 3840, 2160, 2);
  expect_same(run(stages(true, "", "side-by-side-half", "P010_10LE"), frames),
              run(stages(false, "", "side-by-side-half", "P010_10LE"), frames), "4K P010 side-by-side-half");
}

TEST(GpuDeepChain, CropBarsOnLetterboxedTenBit) {
  const std::vector<HostFrame> frames = deep_frames(PixelFormat::P010, 640, 360, 12, 44);
  for (const char *layout : {"side-by-side-half", "anaglyph"})
    expect_same(run(stages(true, "", layout, "P010_10LE", " crop-bars=auto"), frames),
                run(stages(false, "", layout, "P010_10LE", " crop-bars=auto"), frames),
                std::string("crop-bars ") + layout);
}

// Frames repeated and changed in part: what adaptive work keeps on the GPU
// is what the CPU chain computes (itself byte-equal to adaptive=false).
TEST(GpuDeepChain, AdaptiveOnARepeatingTenBitSequence) {
  std::vector<HostFrame> frames = deep_frames(PixelFormat::P010, 320, 180, 2);
  const std::vector<HostFrame> base = frames;
  for (int k = 0; k < 6; ++k) frames.push_back(base[k % 2 == 0 ? 0 : 1]);
  HostFrame touched = base[0];  // one luma sample's low bits changed
  store_code(touched.view(), 0, 90, 160, load_code(touched.view(), 0, 90, 160) ^ 1);
  frames.push_back(touched);
  frames.push_back(touched);
  for (float tolerance : {0.f, 2.f}) {
    char props[64];
    std::snprintf(props, sizeof props, " adaptive=true reuse-tolerance=%g", tolerance);
    expect_same(run(stages(true, props, "side-by-side-half", "P010_10LE"), frames),
                run(stages(false, props, "side-by-side-half", "P010_10LE"), frames), std::string("adaptive,") + props);
  }
}

TEST(GpuDeepChain, ConvertBinOnTheGpuMatchesTheCpu) {
  const std::vector<HostFrame> frames = deep_frames(PixelFormat::I420_10, 400, 226, 3);
  for (const char *layout : {"side-by-side-half", "anaglyph"}) {
    const std::string tail = std::string(" layout=") + layout + " ! capsfilter caps=video/x-raw,format=I420_10LE";
    expect_same(run("pseudo3dconvert processing=gpu" + tail, frames),
                run("pseudo3dconvert processing=cpu" + tail, frames), std::string("pseudo3dconvert ") + layout);
  }
}

// No stage offers RGBA64_LE on CUDA memory; the warp's and the depth
// stage's CUDA templates carry the 10-bit 4:2:0 formats.
TEST(GpuDeepChain, CudaTemplatesHoldWhatTheAllocatorTakes) {
  GstCaps *rgba64 = gst_caps_from_string("video/x-raw(memory:CUDAMemory), format=RGBA64_LE");
  GstCaps *ten = gst_caps_from_string("video/x-raw(memory:CUDAMemory), format={ P010_10LE, I420_10LE }");
  for (const char *name : {"pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp", "pseudo3dpack"}) {
    GstElementFactory *factory = gst_element_factory_find(name);
    ASSERT_NE(factory, nullptr) << name;
    bool any_ten = false;
    for (const GList *l = gst_element_factory_get_static_pad_templates(factory); l; l = l->next) {
      GstCaps *caps = gst_static_caps_get(&static_cast<GstStaticPadTemplate *>(l->data)->static_caps);
      EXPECT_FALSE(gst_caps_can_intersect(caps, rgba64)) << name;
      any_ten = any_ten || gst_caps_can_intersect(caps, ten);
      gst_caps_unref(caps);
    }
    EXPECT_TRUE(any_ten) << name;
    gst_object_unref(factory);
  }
  gst_caps_unref(rgba64);
  gst_caps_unref(ten);
}

}  // namespace
