// Shared helpers of the element tests: buffers from HostFrames and back,
// caps strings, reading the depth meta, running a launch line to EOS.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <gst/check/gstharness.h>
#include <gst/gst.h>
#include <gst/video/video.h>

#include <opencv2/core.hpp>

#include "frame.h"
#include "host_frame.h"

namespace p3d::test {

const char *gst_format_name(PixelFormat f);
std::string raw_caps(PixelFormat f, int width, int height, const char *extra = "");
// A GstBuffer (system memory) holding the frame, laid out as GstVideoInfo
// says (with its strides), plus a GstVideoMeta.
GstBuffer *buffer_from_frame(const HostFrame &frame);
// A GRAY8 (CV_8UC1) or GRAY16_LE (CV_16UC1) buffer of the picture, with
// GstVideoInfo's strides and a GstVideoMeta; its caps: grey_caps().
GstBuffer *buffer_from_grey(const cv::Mat &grey);
std::string grey_caps(const cv::Mat &grey);
// The buffer's pixels as BGRA through load_rgba (info from caps).
cv::Mat buffer_to_bgra(GstBuffer *buf, GstCaps *caps);
// The depth meta as a CV_32FC1 copy; empty if none (or on the device).
cv::Mat buffer_depth(GstBuffer *buf);
// Where the depth meta's plane is and how it is held (gst/depth_plane.h);
// present false without one.
struct DepthPlaneInfo {
  bool present = false, on_device = false;
  int width = 0, height = 0, shift = 0;
  PixelRect active;  // the plane's active_rect()
};
DepthPlaneInfo buffer_depth_info(GstBuffer *buf);
// Runs a launch line to EOS (timeout in seconds); returns the error message
// or "" on success. at_eos, if given, sees the pipeline at EOS before it is
// stopped (negotiated caps and sink statistics are still there).
std::string run_to_eos(const std::string &launch, int timeout_s = 60,
                       const std::function<void(GstElement *pipeline)> &at_eos = {});
// Pushes every frame of `frames` (BGR, converted to f; PTS at 25 frames/s)
// through a harness of `launch` and hands each output buffer to `take`
// (which does not keep it); between(k, harness) runs before frame k. A
// frame without output fails the test and ends the run.
void push_frames(const std::string &launch, PixelFormat f, const std::vector<cv::Mat> &frames,
                 const std::function<void(GstBuffer *, GstHarness *)> &take,
                 const std::function<void(int, GstHarness *)> &between = {});

// A picture (BGR) with edges for the depth and texture for the warp:
// ramps with noise and five rectangles of random colours.
cv::Mat textured_picture(int w, int h, uint32_t seed);

// A sequence of the kinds a stream has (14 frames of textured_picture):
// the same frame again, a small object moving, a big change, a cut to
// another picture and back, one pixel.
std::vector<cv::Mat> changing_sequence(int w, int h, uint32_t seed);

// The output bytes of every frame of `frames` pushed through `launch`
// (push_frames). between(k, harness) runs before frame k is pushed.
std::vector<std::vector<uint8_t>> output_bytes(const std::string &launch, PixelFormat f,
                                               const std::vector<cv::Mat> &frames,
                                               const std::function<void(int, GstHarness *)> &between = {});

// Fails the test where the outputs of two runs differ in any byte.
void expect_same_bytes(const std::vector<std::vector<uint8_t>> &a, const std::vector<std::vector<uint8_t>> &b,
                       const std::string &what);

// The launch line with `option` (" name=value") added to every pseudo3d
// element of it; with_adaptive: adaptive=<on>.
std::string on_every_stage(const std::string &chain, const std::string &option);
inline std::string with_adaptive(const std::string &chain, bool on) {
  return on_every_stage(chain, std::string(" adaptive=") + (on ? "true" : "false"));
}

// Folder for files tests write (pictures of outputs).
std::string output_dir();

// Collects the error and warning messages an element (a harness's element,
// which has no pipeline) posts: it gets a bus of its own.
class BusMessages {
 public:
  explicit BusMessages(GstElement *element);
  ~BusMessages();
  BusMessages(const BusMessages &) = delete;
  BusMessages &operator=(const BusMessages &) = delete;
  // Texts ("message (debug)") of the messages of `type` posted so far.
  std::vector<std::string> take(GstMessageType type);

 private:
  GstElement *element_;
  GstBus *bus_;
  std::vector<GstMessage *> pending_;  // popped, not yet asked for
};

// "message (debug)" of an error or warning message.
std::string message_text(GstMessage *msg);

// message_text() of the first error on the element's bus, taken off it;
// empty when there is none.
std::string first_bus_error(GstElement *element);

// The caps on the pad (empty string if none).
std::string current_caps(GstPad *pad);

}  // namespace p3d::test
