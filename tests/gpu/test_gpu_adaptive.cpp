// adaptive=true on CUDA memory (cuda/change_gpu.h through the elements):
// the sequences of tests/elements/test_adaptive.cpp (unchanged frames, a
// small box, a big change, cuts, one pixel) give, frame by frame, the
// bytes of adaptive=false on the GPU and of the CPU chain; inside
// letterbox and pillarbox bars too; frames of small changes only, which
// the warp renders a few rows of; a property changed between frames, a
// flush and toggling adaptive give what a fresh element gives. Part of
// test_gpu_elements (its main() skips without a device).
#include <gst/check/gstharness.h>
#include <gst/video/video.h>
#include <gtest/gtest.h>

#include <functional>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "../elements/element_helpers.h"

using namespace p3d;
using namespace p3d::test;

namespace {

// The visible bytes of each plane of an output frame, row by row (the
// strides of buffers from a CUDA download and from the CPU chain differ).
std::vector<uint8_t> visible_bytes(GstBuffer *b, GstHarness *hx) {
  GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
  GstVideoInfo info;
  std::vector<uint8_t> out;
  if (caps && gst_video_info_from_caps(&info, caps)) {
    GstVideoFrame f;
    if (gst_video_frame_map(&f, &info, b, GST_MAP_READ)) {
      for (guint p = 0; p < GST_VIDEO_FRAME_N_PLANES(&f); ++p) {
        const auto *data = static_cast<const uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&f, p));
        const size_t row = static_cast<size_t>(GST_VIDEO_FRAME_COMP_WIDTH(&f, p)) * GST_VIDEO_FRAME_COMP_PSTRIDE(&f, p);
        for (int y = 0; y < GST_VIDEO_FRAME_COMP_HEIGHT(&f, p); ++y) {
          const uint8_t *r = data + static_cast<size_t>(y) * GST_VIDEO_FRAME_PLANE_STRIDE(&f, p);
          out.insert(out.end(), r, r + row);
        }
      }
      gst_video_frame_unmap(&f);
    }
  }
  if (caps) gst_caps_unref(caps);
  return out;
}

// The visible bytes of every frame of `frames` pushed through `launch`.
std::vector<std::vector<uint8_t>> outputs(const std::string &launch, PixelFormat f, const std::vector<cv::Mat> &frames,
                                          const std::function<void(int, GstHarness *)> &between = {}) {
  std::vector<std::vector<uint8_t>> out;
  push_frames(launch, f, frames, [&](GstBuffer *b, GstHarness *hx) { out.push_back(visible_bytes(b, hx)); },
              between);
  return out;
}

// The chain on CUDA memory (every stage processing=gpu) or on the CPU,
// its output in format `out`.
std::string on_device(const std::string &chain, bool adaptive, const std::string &out) {
  return "cudaupload ! video/x-raw(memory:CUDAMemory) ! " +
         with_adaptive(on_every_stage(chain, " processing=gpu"), adaptive) +
         " ! cudadownload ! capsfilter caps=video/x-raw,format=" + out;
}
std::string on_cpu(const std::string &chain, const std::string &out) {
  return on_every_stage(chain, " processing=cpu adaptive=false") + " ! capsfilter caps=video/x-raw,format=" + out;
}

// The frames of a sequence inside black bars: rows above and below (a
// letterbox) or columns left and right (a pillarbox).
std::vector<cv::Mat> in_bars(const std::vector<cv::Mat> &frames, int top, int left) {
  std::vector<cv::Mat> out;
  for (const cv::Mat &f : frames) {
    cv::Mat framed(f.rows + 2 * top, f.cols + 2 * left, CV_8UC3, cv::Scalar(0, 0, 0));
    f.copyTo(framed(cv::Rect(left, top, f.cols, f.rows)));
    out.push_back(framed);
  }
  return out;
}

struct Case {
  std::string chain;
  PixelFormat format;
  const char *out;  // the output's format, pinned on both devices
};

// Frame by frame, the case's chain with adaptive=true on CUDA memory
// gives the bytes of adaptive=false there and of the CPU chain.
void expect_full_computation(const Case &c, const std::vector<cv::Mat> &frames) {
  const auto adaptive = outputs(on_device(c.chain, true, c.out), c.format, frames);
  expect_same_bytes(adaptive, outputs(on_device(c.chain, false, c.out), c.format, frames), c.chain + " on the GPU");
  expect_same_bytes(adaptive, outputs(on_cpu(c.chain, c.out), c.format, frames), c.chain + " against the CPU");
}

TEST(GpuAdaptive, SameBytesAsFullComputationAndTheCpu) {
  const std::vector<Case> cases = {
      {"pseudo3dconvert layout=side-by-side-half", PixelFormat::I420, "I420"},
      {"pseudo3ddepth edge-threshold=8 ! pseudo3dfilter ! pseudo3dwarp max-disparity=12", PixelFormat::RGBA, "RGBA"},
      {"pseudo3dconvert layout=anaglyph", PixelFormat::NV12, "RGBA"},
      {"pseudo3dconvert layout=top-bottom-half fill=background", PixelFormat::RGBA, "RGBA"},
      {"pseudo3dconvert layout=row-interleaved fill=neighbor-average", PixelFormat::BGRx, "BGRx"},
      {"pseudo3ddepth block-size=5 temporal-smoothing=0.3 ! pseudo3dfilter mode=exact scale=2 ! pseudo3dwarp ! "
       "pseudo3dpack layout=top-bottom",
       PixelFormat::RGBA, "RGBA"},
      {"pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp layout=left fill=none", PixelFormat::RGBx, "NV12"},
  };
  for (const Case &c : cases)
    for (const cv::Size size : {cv::Size(160, 100), cv::Size(1280, 720)})
      expect_full_computation(c, changing_sequence(size.width, size.height, 7));
}

// crop-bars on CUDA memory: the views of the picture inside the bars
// (cuda/bars_gpu.h ActiveWarpGpu), behind the warp's gate and rows.
TEST(GpuAdaptive, InsideBarsSameBytesAsFullComputation) {
  const std::string chain = "pseudo3dconvert layout=side-by-side-half";
  const std::vector<cv::Mat> picture = changing_sequence(320, 136, 5);
  for (const auto &[top, left] : {std::pair{52, 0}, std::pair{0, 48}}) {
    const std::vector<cv::Mat> frames = in_bars(picture, top, left);
    const auto adaptive = outputs(on_device(chain, true, "I420"), PixelFormat::I420, frames);
    expect_same_bytes(adaptive, outputs(on_device(chain, false, "I420"), PixelFormat::I420, frames),
                      top ? "letterbox" : "pillarbox");
    expect_same_bytes(adaptive, outputs(on_cpu(chain, "I420"), PixelFormat::I420, frames),
                      std::string(top ? "letterbox" : "pillarbox") + " against the CPU");
  }
}

// Frames whose every change is a small box somewhere, the picture's first
// and last rows among the places: the warp renders only the rows the
// changes reach (cuda/change_gpu.h, the gate's rows) and keeps the others
// in its pair, frame after frame, without backing off.
std::vector<cv::Mat> boxes_sequence(int w, int h, uint32_t seed) {
  std::vector<cv::Mat> frames;
  cv::Mat cur = textured_picture(w, h, seed);
  std::mt19937 rng(seed + 1);
  for (int k = 0; k < 16; ++k) {
    cv::Mat next = cur.clone();
    const int y = k % 4 == 1 ? 0 : k % 4 == 2 ? h - 6 : static_cast<int>(rng() % (h - 6));
    const cv::Rect r(static_cast<int>(rng() % (w - 14)), y, 14, 6);
    if (k > 0) next(r).setTo(cv::Scalar(rng() % 256, rng() % 256, rng() % 256));
    frames.push_back(next);
    cur = next;
  }
  return frames;
}

TEST(GpuAdaptive, PartlyChangedRowsGiveTheFullComputation) {
  const std::vector<Case> cases = {
      {"pseudo3dconvert layout=side-by-side-half", PixelFormat::I420, "I420"},
      {"pseudo3dconvert layout=top-bottom-half fill=none max-disparity=8", PixelFormat::NV12, "NV12"},
      {"pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp layout=right", PixelFormat::RGBA, "RGBA"},
  };
  for (const Case &c : cases)
    for (const cv::Size size : {cv::Size(200, 120), cv::Size(1280, 720)})
      expect_full_computation(c, boxes_sequence(size.width, size.height, 5));
  // Inside letterbox bars: the rows of the picture between them.
  const std::string chain = "pseudo3dconvert layout=side-by-side-half";
  const std::vector<cv::Mat> frames = in_bars(boxes_sequence(320, 136, 9), 52, 0);
  expect_same_bytes(outputs(on_device(chain, true, "I420"), PixelFormat::I420, frames),
                    outputs(on_device(chain, false, "I420"), PixelFormat::I420, frames), "letterbox, boxes");
}

GstElement *element_c(GstHarness *hx) {
  GstElement *c = gst_bin_get_by_name(GST_BIN(hx->element), "c");
  gst_object_unref(c);  // the pipeline holds it
  return c;
}

// Properties changed between frames (the layout among them, which changes
// the output's size), adaptive toggled, a flush: what the GPU stages kept
// is not used where it was made otherwise.
TEST(GpuAdaptive, PropertyChangesTogglesAndFlushes) {
  const std::vector<cv::Mat> frames = changing_sequence(160, 96, 11);
  const std::string chain = "pseudo3dconvert layout=side-by-side-half name=c";
  auto change = [](int k, GstHarness *hx) {
    GstElement *c = element_c(hx);
    if (k == 1) g_object_set(c, "max-disparity", 6.0f, NULL);  // an unchanged frame
    if (k == 5) g_object_set(c, "radius", 2, NULL);
    // Frames 7 and 8 are unchanged: the output of another size, then kept.
    if (k == 7) gst_util_set_object_arg(G_OBJECT(c), "layout", "side-by-side");
    if (k == 8) g_object_set(c, "fill", 0, NULL);  // background
    if (k == 9) g_object_set(c, "convergence", 0.2f, NULL);
    if (k == 11) g_object_set(c, "hypothesis", 1, NULL);
    if (k == 12) g_object_set(c, "adaptive", FALSE, NULL);
    if (k == 13) g_object_set(c, "adaptive", TRUE, NULL);
    if (k == 10) {
      gst_harness_push_event(hx, gst_event_new_flush_start());
      gst_harness_push_event(hx, gst_event_new_flush_stop(TRUE));
      GstSegment seg;
      gst_segment_init(&seg, GST_FORMAT_TIME);
      gst_harness_push_event(hx, gst_event_new_segment(&seg));
    }
  };
  const auto full = outputs(on_device(chain, false, "I420"), PixelFormat::I420, frames, change);
  expect_same_bytes(full, outputs(on_device(chain, true, "I420"), PixelFormat::I420, frames, change),
                    "property changes on the GPU");
  EXPECT_FALSE(full[2] == outputs(on_device(chain, false, "I420"), PixelFormat::I420, frames)[2])
      << "the change at an unchanged frame took effect";
}

}  // namespace
