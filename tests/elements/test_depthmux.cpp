// pseudo3ddepthmux: external depth (grey pictures on a second pad) attached
// to each frame; pseudo3ddepthout: the depth taken out as grey video. Each test says what the element must give; the expected
// depth comes from the CPU reference (common/depth_grey.h), and from the
// conventions' formulas where the reference itself is checked.
#include <gst/check/gstharness.h>
#include <gst/video/video.h>
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "depth_grey.h"
#include "element_helpers.h"

using namespace p3d;
using namespace p3d::test;

namespace {

// The mux with a harness on each sink pad; the video harness pulls from src.
struct Mux {
  GstHarness *video, *depth;
  explicit Mux(const std::string &props = "") {
    GstElement *e = gst_parse_launch(("pseudo3ddepthmux " + props).c_str(), nullptr);
    video = gst_harness_new_with_element(e, "video", "src");
    depth = gst_harness_new_with_element(e, "depth", nullptr);
    gst_object_unref(e);
  }
  ~Mux() {
    gst_harness_teardown(depth);
    gst_harness_teardown(video);
  }
  GstElement *element() const { return video->element; }
};

GstBuffer *at(GstBuffer *buf, double seconds) {
  GST_BUFFER_PTS(buf) = static_cast<GstClockTime>(seconds * GST_SECOND);
  return buf;
}

HostFrame frame_of(int w, int h, uint32_t seed) {
  cv::Mat bgr(h, w, CV_8UC3);
  cv::RNG(seed).fill(bgr, cv::RNG::UNIFORM, 0, 255);
  return HostFrame::from_bgr(bgr, PixelFormat::RGBA, 0);
}

cv::Mat random_grey(int w, int h, int type, uint32_t seed) {
  cv::Mat g(h, w, type);
  cv::RNG(seed).fill(g, cv::RNG::UNIFORM, 0, type == CV_8UC1 ? 256 : 65536);
  return g;
}

// The reference: the element's function on the CPU.
cv::Mat imported(const cv::Mat &grey, int w, int h, const DepthImportParams &p = DepthImportParams()) {
  cv::Mat out(h, w, CV_32FC1);
  ImageView<const uint8_t> src;
  src.data = grey.data;
  src.width = grey.cols;
  src.height = grey.rows;
  src.pitch = grey.step;
  ImageView<float> dst;
  dst.data = out.ptr<float>();
  dst.width = w;
  dst.height = h;
  dst.pitch = out.step;
  import_depth_cpu(p, src, grey.depth() == CV_8U ? 8 : 16, dst);
  return out;
}

// The errors the element posts, waiting up to 2 s for the first.
std::vector<std::string> wait_for_errors(BusMessages &bus) {
  std::vector<std::string> errors;
  for (int i = 0; i < 100 && errors.empty(); ++i) {
    errors = bus.take(GST_MESSAGE_ERROR);
    if (errors.empty()) g_usleep(20000);
  }
  return errors;
}

}  // namespace

// The conventions' formulas, sample by sample.
TEST(DepthImport, Conventions) {
  DepthImportParams p;
  EXPECT_EQ(import_depth_sample(p, 0, 255), 0.f);
  EXPECT_EQ(import_depth_sample(p, 255, 255), 1.f);
  EXPECT_EQ(import_depth_sample(p, 65535, 65535), 1.f);
  p.convention = DepthConvention::NearDark;
  EXPECT_EQ(import_depth_sample(p, 0, 255), 1.f);
  EXPECT_EQ(import_depth_sample(p, 255, 255), 0.f);
  p.convention = DepthConvention::Metric;
  p.near = 500;
  p.far = 4000;
  EXPECT_EQ(import_depth_sample(p, 0, 65535), 0.f) << "0 = not seen: far";
  EXPECT_FLOAT_EQ(import_depth_sample(p, 500, 65535), 1.f);
  EXPECT_FLOAT_EQ(import_depth_sample(p, 4000, 65535), 0.f);
  EXPECT_FLOAT_EQ(import_depth_sample(p, 100, 65535), 1.f) << "nearer than near: clamped";
  EXPECT_FLOAT_EQ(import_depth_sample(p, 60000, 65535), 0.f) << "farther than far: clamped";
  // Linear in 1/distance: 1000 mm is (1/1000 - 1/4000) / (1/500 - 1/4000) = 3/7.
  EXPECT_NEAR(import_depth_sample(p, 1000, 65535), 3.0 / 7.0, 1e-6);
}

// Same size, both sample widths: the frame passes unchanged and carries the
// depth of the reference, bit for bit.
TEST(DepthMux, AttachesGreyDepthOfTheFrameSize) {
  const int w = 37, h = 21;
  for (int type : {CV_8UC1, CV_16UC1}) {
    Mux m;
    const cv::Mat grey = random_grey(w, h, type, 3);
    gst_harness_set_src_caps_str(m.video, raw_caps(PixelFormat::RGBA, w, h).c_str());
    gst_harness_set_src_caps_str(m.depth, grey_caps(grey).c_str());
    const HostFrame f = frame_of(w, h, 1);
    ASSERT_EQ(gst_harness_push(m.depth, at(buffer_from_grey(grey), 0)), GST_FLOW_OK);
    gst_harness_push_event(m.depth, gst_event_new_eos());
    ASSERT_EQ(gst_harness_push(m.video, at(buffer_from_frame(f), 0)), GST_FLOW_OK);
    GstBuffer *out = gst_harness_pull(m.video);
    ASSERT_NE(out, nullptr);
    const cv::Mat d = buffer_depth(out);
    ASSERT_EQ(d.size(), cv::Size(w, h));
    EXPECT_EQ(cv::norm(d, imported(grey, w, h), cv::NORM_INF), 0) << "type " << type;
    GstCaps *caps = gst_pad_get_current_caps(m.video->sinkpad);
    EXPECT_EQ(cv::norm(buffer_to_bgra(out, caps), f.to_bgra(YuvToRgb()), cv::NORM_INF), 0) << "the frame is untouched";
    gst_caps_unref(caps);
    gst_buffer_unref(out);
  }
}

// Another size: resampled to the frame's (the reference's nearest-sample
// resize), including a 1x1 picture (one depth for the whole frame).
TEST(DepthMux, ResamplesDepthOfAnotherSize) {
  const int w = 64, h = 48;
  for (cv::Size ds : {cv::Size(32, 24), cv::Size(100, 7), cv::Size(1, 1)}) {
    Mux m("convention=near-dark");
    const cv::Mat grey = random_grey(ds.width, ds.height, CV_16UC1, 5);
    gst_harness_set_src_caps_str(m.video, raw_caps(PixelFormat::NV12, w, h).c_str());
    gst_harness_set_src_caps_str(m.depth, grey_caps(grey).c_str());
    gst_harness_push(m.depth, at(buffer_from_grey(grey), 0));
    gst_harness_push_event(m.depth, gst_event_new_eos());
    cv::Mat bgr(h, w, CV_8UC3, cv::Scalar(10, 200, 30));
    gst_harness_push(m.video, at(buffer_from_frame(HostFrame::from_bgr(bgr, PixelFormat::NV12)), 0));
    GstBuffer *out = gst_harness_pull(m.video);
    ASSERT_NE(out, nullptr);
    DepthImportParams p;
    p.convention = DepthConvention::NearDark;
    const cv::Mat d = buffer_depth(out);
    ASSERT_EQ(d.size(), cv::Size(w, h));
    EXPECT_EQ(cv::norm(d, imported(grey, w, h, p), cv::NORM_INF), 0) << ds;
    EXPECT_TRUE(cv::checkRange(d, true, nullptr, 0.0, 1.0 + 1e-6)) << ds;
    gst_buffer_unref(out);
  }
}

// Pairing by time: each frame gets the last depth picture not after it; the
// first picture serves frames before it; after the depth stream's end its
// last picture serves the rest.
TEST(DepthMux, PairsFramesWithTheLatestDepthPicture) {
  const int w = 8, h = 8;
  Mux m;
  std::vector<cv::Mat> greys;
  for (int i = 0; i < 3; ++i) greys.emplace_back(h, w, CV_8UC1, cv::Scalar(50 + 80 * i));
  gst_harness_set_src_caps_str(m.video, raw_caps(PixelFormat::RGBA, w, h, ",framerate=2/1").c_str());
  gst_harness_set_src_caps_str(m.depth, grey_caps(greys[0]).c_str());
  // Depth at 0.25 s, 1 s and 2 s; frames every 0.5 s from 0 to 3 s. The
  // aggregator holds one buffer per pad, so each stream is pushed from its
  // own thread, as from the two branches of a pipeline.
  const double depth_times[] = {0.25, 1.0, 2.0};
  const int want[] = {0, 0, 1, 1, 2, 2, 2};
  std::thread depth_branch([&]() {
    for (int k = 0; k < 3; ++k) gst_harness_push(m.depth, at(buffer_from_grey(greys[k]), depth_times[k]));
    gst_harness_push_event(m.depth, gst_event_new_eos());
  });
  for (int i = 0; i < 7; ++i) gst_harness_push(m.video, at(buffer_from_frame(frame_of(w, h, i)), 0.5 * i));
  depth_branch.join();
  std::vector<int> got;
  gst_harness_push_event(m.video, gst_event_new_eos());
  for (int i = 0; i < 7; ++i) {
    GstBuffer *out = gst_harness_pull(m.video);
    ASSERT_NE(out, nullptr) << "frame " << i;
    const cv::Mat d = buffer_depth(out);
    ASSERT_FALSE(d.empty()) << "frame " << i;
    got.push_back(static_cast<int>(std::lround((d.at<float>(0, 0) * 255 - 50) / 80)));
    EXPECT_EQ(GST_BUFFER_PTS(out), static_cast<GstClockTime>(0.5 * i * GST_SECOND));
    gst_buffer_unref(out);
  }
  EXPECT_EQ(got, std::vector<int>(want, want + 7));
}

// One still picture (a single buffer, then the end of the depth stream)
// serves a whole stream of frames.
TEST(DepthMux, StillDepthServesTheWholeStream) {
  const int w = 16, h = 12;
  Mux m;
  const cv::Mat grey = random_grey(w, h, CV_8UC1, 9);
  gst_harness_set_src_caps_str(m.video, raw_caps(PixelFormat::I420, w, h, ",framerate=25/1").c_str());
  gst_harness_set_src_caps_str(m.depth, grey_caps(grey).c_str());
  gst_harness_push(m.depth, at(buffer_from_grey(grey), 0));
  gst_harness_push_event(m.depth, gst_event_new_eos());
  const cv::Mat want = imported(grey, w, h);
  for (int i = 0; i < 50; ++i) {
    cv::Mat bgr(h, w, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i));
    GstBuffer *out =
        gst_harness_push_and_pull(m.video, at(buffer_from_frame(HostFrame::from_bgr(bgr, PixelFormat::I420)), i / 25.0));
    ASSERT_NE(out, nullptr) << "frame " << i;
    EXPECT_EQ(cv::norm(buffer_depth(out), want, cv::NORM_INF), 0) << "frame " << i;
    gst_buffer_unref(out);
  }
}

// A depth stream that ends before giving any picture is an error, not a hang
// or frames without depth.
TEST(DepthMux, NoDepthAtAllIsAnError) {
  Mux m;
  BusMessages bus(m.element());
  gst_harness_set_src_caps_str(m.video, raw_caps(PixelFormat::RGBA, 8, 8).c_str());
  gst_harness_set_src_caps_str(m.depth, grey_caps(cv::Mat(8, 8, CV_8UC1)).c_str());
  gst_harness_push_event(m.depth, gst_event_new_eos());
  gst_harness_push(m.video, at(buffer_from_frame(frame_of(8, 8, 1)), 0));
  gst_harness_push_event(m.video, gst_event_new_eos());
  GstBuffer *out = gst_harness_try_pull(m.video);
  EXPECT_EQ(out, nullptr);
  if (out) gst_buffer_unref(out);
  const std::vector<std::string> errors = wait_for_errors(bus);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("without a depth picture"), std::string::npos) << errors[0];
}

// Nothing linked to the depth pad: GstAggregator waits for data on every
// pad, so the frames wait for good. The element says why, once, as a
// warning (a depth branch may still link late); with the depth pad linked
// it says nothing.
TEST(DepthMux, UnlinkedDepthPadIsReported) {
  for (const bool linked : {false, true}) {
    const std::string depth = linked ? " videotestsrc pattern=gradient ! video/x-raw,format=GRAY8,width=16,height=12 ! m.depth"
                                     : "";
    GstElement *p = gst_parse_launch(("videotestsrc num-buffers=5 ! video/x-raw,width=64,height=48 ! m.video "
                                      "pseudo3ddepthmux name=m ! fakesink" + depth).c_str(),
                                     nullptr);
    ASSERT_NE(p, nullptr);
    GstBus *bus = gst_element_get_bus(p);
    gst_element_set_state(p, GST_STATE_PAUSED);
    // Linked: the pipeline prerolls and nothing is said; unlinked: the
    // warning. No ASSERT until the pipeline is stopped: a waiting pipeline
    // left running would hang the process at gst_deinit().
    GstMessage *msg = gst_bus_timed_pop_filtered(
        bus, 10 * GST_SECOND,
        static_cast<GstMessageType>(GST_MESSAGE_WARNING | GST_MESSAGE_ERROR | GST_MESSAGE_ASYNC_DONE));
    const GstMessageType type = msg ? GST_MESSAGE_TYPE(msg) : GST_MESSAGE_UNKNOWN;
    const std::string text = msg && type != GST_MESSAGE_ASYNC_DONE ? message_text(msg) : "";
    if (msg) gst_message_unref(msg);
    gst_element_set_state(p, GST_STATE_NULL);
    gst_object_unref(bus);
    gst_object_unref(p);
    EXPECT_EQ(type, linked ? GST_MESSAGE_ASYNC_DONE : GST_MESSAGE_WARNING)
        << (linked ? "linked: " : "unlinked: ") << (msg ? text : std::string("nothing in 10 s"));
    if (!linked) {
      EXPECT_NE(text.find("depth pad is not linked"), std::string::npos) << text;
    }
  }
}

// metric with near >= far cannot mean anything: an error naming both.
TEST(DepthMux, MetricNeedsNearBelowFar) {
  Mux m("convention=metric near=5000 far=1000");
  BusMessages bus(m.element());
  const cv::Mat grey(4, 4, CV_16UC1, cv::Scalar(2000));
  gst_harness_set_src_caps_str(m.video, raw_caps(PixelFormat::RGBA, 4, 4).c_str());
  gst_harness_set_src_caps_str(m.depth, grey_caps(grey).c_str());
  gst_harness_push(m.depth, at(buffer_from_grey(grey), 0));
  gst_harness_push_event(m.depth, gst_event_new_eos());
  gst_harness_push(m.video, at(buffer_from_frame(frame_of(4, 4, 1)), 0));
  const std::vector<std::string> errors = wait_for_errors(bus);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("near 5000, far 1000"), std::string::npos) << errors[0];
}

// A new metric pair is set one property after the other, and in one order
// the pair in between is invalid (near=20000 while far is still 10000).
// That must not stop the stream: frames keep the last valid pair, one
// warning says so, and the new pair applies once it is valid. In the other
// order every pair is valid: no warning at all.
TEST(DepthMux, MetricPairChangedWhilePlayingKeepsTheStreamGoing) {
  const cv::Mat grey = random_grey(8, 6, CV_16UC1, 5);
  DepthImportParams old_pair, new_pair;
  old_pair.convention = new_pair.convention = DepthConvention::Metric;
  old_pair.near = 500;
  old_pair.far = 10000;
  new_pair.near = 20000;
  new_pair.far = 50000;
  for (const bool near_first : {true, false}) {
    SCOPED_TRACE(near_first ? "near set first" : "far set first");
    Mux m("convention=metric near=500 far=10000");
    BusMessages bus(m.element());
    gst_harness_set_src_caps_str(m.video, raw_caps(PixelFormat::RGBA, 8, 6).c_str());
    gst_harness_set_src_caps_str(m.depth, grey_caps(grey).c_str());
    ASSERT_EQ(gst_harness_push(m.depth, at(buffer_from_grey(grey), 0)), GST_FLOW_OK);
    gst_harness_push_event(m.depth, gst_event_new_eos());
    int frame = 0;
    auto next_depth = [&]() {
      const double t = 0.04 * frame++;
      EXPECT_EQ(gst_harness_push(m.video, at(buffer_from_frame(frame_of(8, 6, 1)), t)), GST_FLOW_OK);
      GstBuffer *out = gst_harness_pull(m.video);
      if (!out) {
        ADD_FAILURE() << "frame " << frame - 1 << " did not come out";
        return cv::Mat(6, 8, CV_32FC1, cv::Scalar(-1));
      }
      cv::Mat d = buffer_depth(out).clone();
      gst_buffer_unref(out);
      return d;
    };
    EXPECT_EQ(cv::norm(next_depth(), imported(grey, 8, 6, old_pair), cv::NORM_INF), 0);
    g_object_set(m.element(), near_first ? "near" : "far", near_first ? 20000.f : 50000.f, nullptr);
    // Two frames between the sets: near first leaves an invalid pair, and
    // the old pair stays in use; far first gives the valid pair 500/50000.
    DepthImportParams between = old_pair;
    if (!near_first) between.far = 50000;
    for (int i = 0; i < 2; ++i) EXPECT_EQ(cv::norm(next_depth(), imported(grey, 8, 6, between), cv::NORM_INF), 0);
    g_object_set(m.element(), near_first ? "far" : "near", near_first ? 50000.f : 20000.f, nullptr);
    EXPECT_EQ(cv::norm(next_depth(), imported(grey, 8, 6, new_pair), cv::NORM_INF), 0);
    EXPECT_TRUE(bus.take(GST_MESSAGE_ERROR).empty());
    const std::vector<std::string> warnings = bus.take(GST_MESSAGE_WARNING);
    if (near_first) {
      ASSERT_EQ(warnings.size(), 1u) << "one warning for the invalid pair, not one a frame";
      EXPECT_NE(warnings[0].find("near 20000, far 10000"), std::string::npos) << warnings[0];
    } else {
      EXPECT_TRUE(warnings.empty()) << warnings[0];
    }
  }
}

// The stages that follow take the depth as they take pseudo3ddepth's: a
// whole chain from a video test source and a grey depth picture.
TEST(DepthMux, FeedsTheStereoChain) {
  const std::string err = run_to_eos(
      "videotestsrc num-buffers=5 ! video/x-raw,format=RGBA,width=64,height=48 ! m.video "
      "videotestsrc num-buffers=1 pattern=gradient ! video/x-raw,format=GRAY16_LE,width=32,height=24 ! m.depth "
      "pseudo3ddepthmux name=m ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack layout=side-by-side-half ! fakesink");
  EXPECT_EQ(err, "");
}

// Depth out: 16- and 8-bit grey of the frame's size, white = near, the
// reference's values; fed back through pseudo3ddepthmux it is the same
// depth to within half a step.
TEST(DepthOut, GreyOfTheDepthAndBackThroughTheMux) {
  const int w = 45, h = 31;
  const HostFrame f = frame_of(w, h, 4);
  for (const char *format : {"GRAY16_LE", "GRAY8"}) {
    GstHarness *est = gst_harness_new_parse("pseudo3ddepth ! pseudo3dfilter");
    gst_harness_set_src_caps_str(est, raw_caps(PixelFormat::RGBA, w, h).c_str());
    GstBuffer *with_depth = gst_harness_push_and_pull(est, buffer_from_frame(f));
    ASSERT_NE(with_depth, nullptr);
    const cv::Mat depth = buffer_depth(with_depth);
    GstHarness *out =
        gst_harness_new_parse((std::string("pseudo3ddepthout ! capsfilter caps=video/x-raw,format=") + format).c_str());
    gst_harness_set_src_caps_str(out, raw_caps(PixelFormat::RGBA, w, h).c_str());
    GstBuffer *grey_buf = gst_harness_push_and_pull(out, gst_buffer_ref(with_depth));
    ASSERT_NE(grey_buf, nullptr) << format;
    GstCaps *caps = gst_pad_get_current_caps(out->sinkpad);
    GstVideoInfo info;
    ASSERT_TRUE(gst_video_info_from_caps(&info, caps));
    gst_caps_unref(caps);
    EXPECT_EQ(GST_VIDEO_INFO_WIDTH(&info), w);
    EXPECT_EQ(GST_VIDEO_INFO_HEIGHT(&info), h);
    const bool eight = GST_VIDEO_INFO_FORMAT(&info) == GST_VIDEO_FORMAT_GRAY8;
    EXPECT_EQ(eight, std::string(format) == "GRAY8");
    GstVideoFrame vf;
    ASSERT_TRUE(gst_video_frame_map(&vf, &info, grey_buf, GST_MAP_READ));
    const cv::Mat grey(h, w, eight ? CV_8UC1 : CV_16UC1, GST_VIDEO_FRAME_PLANE_DATA(&vf, 0),
                       GST_VIDEO_FRAME_PLANE_STRIDE(&vf, 0));
    const cv::Mat grey_copy = grey.clone();
    gst_video_frame_unmap(&vf);
    const double smax = eight ? 255 : 65535;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double s = eight ? grey_copy.at<uint8_t>(y, x) : grey_copy.at<uint16_t>(y, x);
        const float d = depth.at<float>(y, x);
        ASSERT_EQ(s, export_depth_sample(d, static_cast<uint32_t>(smax))) << x << "," << y;
        ASSERT_LE(std::abs(s - std::clamp(d, 0.f, 1.f) * smax), 0.5 + 1e-3) << x << "," << y << ": the nearest step";
      }
    // Back in through the mux.
    Mux m;
    gst_harness_set_src_caps_str(m.video, raw_caps(PixelFormat::RGBA, w, h).c_str());
    gst_harness_set_src_caps_str(m.depth, grey_caps(grey_copy).c_str());
    gst_harness_push(m.depth, at(buffer_from_grey(grey_copy), 0));
    gst_harness_push_event(m.depth, gst_event_new_eos());
    GstBuffer *back = gst_harness_push_and_pull(m.video, at(buffer_from_frame(f), 0));
    ASSERT_NE(back, nullptr);
    EXPECT_LE(cv::norm(buffer_depth(back), depth, cv::NORM_INF), 0.5 / smax + 1e-6) << format;
    gst_buffer_unref(back);
    gst_buffer_unref(grey_buf);
    gst_buffer_unref(with_depth);
    gst_harness_teardown(out);
    gst_harness_teardown(est);
  }
}

// Upstream may hand over frames in either memory domain whatever grey
// format downstream takes: a caps query from upstream keeps CUDA memory
// (in a build with CUDA) next to system memory, at the same size.
TEST(DepthOut, FramesInEitherMemoryDomain) {
  // The domains the element takes at all (CUDA memory only in a CUDA build).
  auto domains = [](GstCaps *caps, bool *cuda, bool *system) {
    *cuda = *system = false;
    for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
      GstCapsFeatures *f = gst_caps_get_features(caps, i);
      (f && gst_caps_features_contains(f, "memory:CUDAMemory") ? *cuda : *system) = true;
    }
  };
  GstElement *probe = gst_element_factory_make("pseudo3ddepthout", nullptr);
  ASSERT_NE(probe, nullptr);
  GstPad *probe_sink = gst_element_get_static_pad(probe, "sink");
  GstCaps *templ = gst_pad_get_pad_template_caps(probe_sink);
  bool templ_cuda, templ_system;
  domains(templ, &templ_cuda, &templ_system);
  gst_caps_unref(templ);
  gst_object_unref(probe_sink);
  gst_object_unref(probe);

  GstHarness *hx = gst_harness_new_parse("pseudo3ddepthout ! capsfilter caps=video/x-raw,format=GRAY8,width=64");
  GstCaps *caps = gst_pad_peer_query_caps(hx->srcpad, nullptr);
  ASSERT_NE(caps, nullptr);
  gchar *text = gst_caps_to_string(caps);
  bool cuda, system;
  domains(caps, &cuda, &system);
  EXPECT_NE(std::string(text).find("width=(int)64"), std::string::npos) << text;
  EXPECT_TRUE(system) << text;
  EXPECT_EQ(cuda, templ_cuda) << text;
  g_free(text);
  gst_caps_unref(caps);
  gst_harness_teardown(hx);
}

// Without depth: one clear error that says what to put before it.
TEST(DepthOut, FramesWithoutDepthAreAnError) {
  GstHarness *hx = gst_harness_new_parse("pseudo3ddepthout");
  BusMessages bus(hx->element);
  gst_harness_set_src_caps_str(hx, raw_caps(PixelFormat::NV12, 16, 8).c_str());
  cv::Mat bgr(8, 16, CV_8UC3, cv::Scalar(1, 2, 3));
  EXPECT_EQ(gst_harness_push(hx, buffer_from_frame(HostFrame::from_bgr(bgr, PixelFormat::NV12))), GST_FLOW_ERROR);
  const std::vector<std::string> errors = bus.take(GST_MESSAGE_ERROR);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("put pseudo3ddepth or pseudo3ddepthmux"), std::string::npos) << errors[0];
  gst_harness_teardown(hx);
}

// A real video: vtest.avi's depth taken out as GRAY8 and encoded, read back
// with its frame count and size.
TEST(DepthOut, VideoDepthEncodesAsGreyVideo) {
  const std::string out = output_dir() + "/vtest-depth.mkv";
  const std::string err = run_to_eos("videotestsrc num-buffers=20 pattern=ball ! video/x-raw,width=160,height=120 ! "
                                     "pseudo3ddepth ! pseudo3dfilter ! pseudo3ddepthout ! video/x-raw,format=GRAY8 ! "
                                     "videoconvert ! x264enc speed-preset=ultrafast ! matroskamux ! filesink location=" +
                                     out);
  ASSERT_EQ(err, "");
  int frames = 0;
  const std::string back = run_to_eos("filesrc location=" + out + " ! decodebin ! video/x-raw,width=160,height=120 ! "
                                      "fakesink name=s signal-handoffs=false",
                                      60, [&](GstElement *p) {
                                        GstElement *s = gst_bin_get_by_name(GST_BIN(p), "s");
                                        guint64 n = 0;
                                        GstStructure *st = nullptr;
                                        g_object_get(s, "stats", &st, NULL);
                                        if (st) {
                                          gst_structure_get_uint64(st, "rendered", &n);
                                          gst_structure_free(st);
                                        }
                                        frames = static_cast<int>(n);
                                        gst_object_unref(s);
                                      });
  EXPECT_EQ(back, "");
  EXPECT_EQ(frames, 20);
}
