#include "element_helpers.h"

#include <random>

#include <gtest/gtest.h>

#include "test_data.h"

#include <cstdlib>
#include <cstring>

#include <glib/gstdio.h>
#include <opencv2/imgproc.hpp>

#include "depth_meta.h"

namespace p3d::test {

const char *gst_format_name(PixelFormat f) { return format_name(f); }  // same spelling as GStreamer

std::string raw_caps(PixelFormat f, int width, int height, const char *extra) {
  // HostFrame::from_bgr writes BT.601 limited-range YUV; say so, since
  // GStreamer would assume BT.709 for HD sizes.
  const char *colorimetry = is_packed_rgb(f) ? "" : ",colorimetry=bt601";
  return std::string("video/x-raw,format=") + gst_format_name(f) + ",width=" + std::to_string(width) +
         ",height=" + std::to_string(height) + ",framerate=30/1" + colorimetry + extra;
}

GstBuffer *buffer_from_frame(const HostFrame &frame) {
  GstVideoInfo info;
  gst_video_info_set_format(&info, gst_video_format_from_string(gst_format_name(frame.format())), frame.width(),
                            frame.height());
  GstBuffer *buf = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&info), nullptr);
  GstVideoFrame vf;
  gst_video_frame_map(&vf, &info, buf, GST_MAP_WRITE);
  const FrameView src = frame.view();
  for (int p = 0; p < frame_plane_count(frame.format()); ++p) {
    int row = 0, rows = 0;
    frame_plane_size(frame.format(), frame.width(), frame.height(), p, &row, &rows);
    for (int y = 0; y < rows; ++y)
      memcpy(static_cast<uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&vf, p)) + y * GST_VIDEO_FRAME_PLANE_STRIDE(&vf, p),
             src.plane[p] + y * src.stride[p], row);
  }
  gst_video_frame_unmap(&vf);
  gst_buffer_add_video_meta_full(buf, GST_VIDEO_FRAME_FLAG_NONE, GST_VIDEO_INFO_FORMAT(&info), frame.width(),
                                 frame.height(), GST_VIDEO_INFO_N_PLANES(&info), info.offset, info.stride);
  return buf;
}

static GstVideoInfo grey_info(const cv::Mat &grey) {
  GstVideoInfo info;
  gst_video_info_set_format(&info, grey.depth() == CV_8U ? GST_VIDEO_FORMAT_GRAY8 : GST_VIDEO_FORMAT_GRAY16_LE, grey.cols,
                            grey.rows);
  return info;
}

GstBuffer *buffer_from_grey(const cv::Mat &grey) {
  GstVideoInfo info = grey_info(grey);
  GstBuffer *buf = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&info), nullptr);
  GstVideoFrame vf;
  gst_video_frame_map(&vf, &info, buf, GST_MAP_WRITE);
  for (int y = 0; y < grey.rows; ++y)
    memcpy(static_cast<uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&vf, 0)) + y * GST_VIDEO_FRAME_PLANE_STRIDE(&vf, 0),
           grey.ptr(y), grey.cols * grey.elemSize());
  gst_video_frame_unmap(&vf);
  gst_buffer_add_video_meta_full(buf, GST_VIDEO_FRAME_FLAG_NONE, GST_VIDEO_INFO_FORMAT(&info), grey.cols, grey.rows,
                                 1, info.offset, info.stride);
  return buf;
}

std::string grey_caps(const cv::Mat &grey) {
  GstVideoInfo info = grey_info(grey);
  GstCaps *caps = gst_video_info_to_caps(&info);
  gchar *s = gst_caps_to_string(caps);
  std::string out = s;
  g_free(s);
  gst_caps_unref(caps);
  return out;
}

cv::Mat buffer_to_bgra(GstBuffer *buf, GstCaps *caps) {
  GstVideoInfo info;
  if (!gst_video_info_from_caps(&info, caps)) return cv::Mat();
  GstVideoFrame vf;
  if (!gst_video_frame_map(&vf, &info, buf, GST_MAP_READ)) return cv::Mat();
  FrameView v;
  const char *name = gst_video_format_to_string(GST_VIDEO_INFO_FORMAT(&info));
  bool known = false;
  for (PixelFormat f : {PixelFormat::NV12, PixelFormat::I420, PixelFormat::RGBA, PixelFormat::BGRA, PixelFormat::RGBx,
                        PixelFormat::BGRx})
    if (!strcmp(name, gst_format_name(f))) {
      v.format = f;
      known = true;
    }
  if (!known) {  // the 8-bit formats only (load_rgba with 8-bit parameters)
    gst_video_frame_unmap(&vf);
    return cv::Mat();
  }
  v.width = info.width;
  v.height = info.height;
  for (guint p = 0; p < GST_VIDEO_FRAME_N_PLANES(&vf); ++p) {
    v.plane[p] = static_cast<uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&vf, p));
    v.stride[p] = GST_VIDEO_FRAME_PLANE_STRIDE(&vf, p);
  }
  cv::Mat out(v.height, v.width, CV_8UC4);
  const YuvToRgb m;
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x) {
      const Rgba c = load_rgba(v, x, y, m);
      out.at<cv::Vec4b>(y, x) = cv::Vec4b(c.b, c.g, c.r, c.a);
    }
  gst_video_frame_unmap(&vf);
  return out;
}

// The plugin is a loaded module, not linked into the tests: find the meta
// by its registered API name and read the plane's fields directly.
static const p3d::gst::DepthPlane *meta_plane(GstBuffer *buf) {
  const GType api = g_type_from_name("Pseudo3DDepthMetaAPI");
  if (!api) return nullptr;
  auto *meta = reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_get_meta(buf, api));
  if (!meta || !meta->plane || !*meta->plane) return nullptr;
  return meta->plane->get();
}

DepthPlaneInfo buffer_depth_info(GstBuffer *buf) {
  DepthPlaneInfo i;
  if (const p3d::gst::DepthPlane *d = meta_plane(buf)) {
    i.present = true;
    i.on_device = d->on_device;
    i.width = d->width;
    i.height = d->height;
    i.shift = d->shift;
    i.active = d->active_rect();
  }
  return i;
}

cv::Mat buffer_depth(GstBuffer *buf) {
  const p3d::gst::DepthPlane *plane = meta_plane(buf);
  if (!plane) return cv::Mat();
  const p3d::gst::DepthPlane &d = *plane;
  if (d.on_device) return cv::Mat();
  cv::Mat m(d.height, d.width, CV_32FC1);
  memcpy(m.data, d.host.data(), d.host.size() * sizeof(float));
  return m;
}

std::string run_to_eos(const std::string &launch, int timeout_s, const std::function<void(GstElement *)> &at_eos) {
  GError *err = nullptr;
  GstElement *pipeline = gst_parse_launch(launch.c_str(), &err);
  if (!pipeline) {
    std::string msg = err ? err->message : "parse failed";
    g_clear_error(&err);
    return msg;
  }
  if (err) {  // a recoverable parse warning (e.g. unknown property) is a failure here
    std::string msg = err->message;
    g_clear_error(&err);
    gst_object_unref(pipeline);
    return msg;
  }
  std::string result;
  GstBus *bus = gst_element_get_bus(pipeline);
  // A failed state change posts its reason as an error message: wait for
  // that too (at once if the change failed, else up to the timeout).
  const bool failed = gst_element_set_state(pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE;
  GstMessage *msg = gst_bus_timed_pop_filtered(bus, failed ? 0 : (GstClockTime)timeout_s * GST_SECOND,
                                               (GstMessageType)(GST_MESSAGE_EOS | GST_MESSAGE_ERROR));
  if (!msg) {
    result = failed ? "state change failed" : "timeout";
  } else {
    if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR) {
      result = message_text(msg);
    } else if (failed) {
      result = "state change failed";
    } else if (at_eos) {
      at_eos(pipeline);
    }
    gst_message_unref(msg);
  }
  gst_object_unref(bus);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(pipeline);
  return result;
}

std::string output_dir() {
  const char *env = std::getenv("P3D_OUT_DIR");
  std::string dir = env && *env ? env : "test-output";
  g_mkdir_with_parents(dir.c_str(), 0755);
  return dir;
}

BusMessages::BusMessages(GstElement *element) : element_(GST_ELEMENT(gst_object_ref(element))), bus_(gst_bus_new()) {
  gst_element_set_bus(element_, bus_);
}

BusMessages::~BusMessages() {
  for (GstMessage *m : pending_) gst_message_unref(m);
  gst_element_set_bus(element_, nullptr);
  gst_object_unref(bus_);
  gst_object_unref(element_);
}

std::vector<std::string> BusMessages::take(GstMessageType type) {
  while (GstMessage *m = gst_bus_pop(bus_)) pending_.push_back(m);
  std::vector<std::string> texts;
  std::vector<GstMessage *> kept;
  for (GstMessage *m : pending_) {
    if (GST_MESSAGE_TYPE(m) != type) {
      kept.push_back(m);
      continue;
    }
    texts.push_back(message_text(m));
    gst_message_unref(m);
  }
  pending_ = kept;
  return texts;
}

std::string message_text(GstMessage *msg) {
  GError *e = nullptr;
  gchar *dbg = nullptr;
  if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR)
    gst_message_parse_error(msg, &e, &dbg);
  else if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_WARNING)
    gst_message_parse_warning(msg, &e, &dbg);
  std::string text = std::string(e ? e->message : "") + " (" + (dbg ? dbg : "") + ")";
  g_clear_error(&e);
  g_free(dbg);
  return text;
}

std::string first_bus_error(GstElement *element) {
  GstBus *bus = gst_element_get_bus(element);
  std::string text;
  if (GstMessage *m = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR)) {
    text = message_text(m);
    gst_message_unref(m);
  }
  gst_object_unref(bus);
  return text;
}

std::string current_caps(GstPad *pad) {
  GstCaps *caps = gst_pad_get_current_caps(pad);
  if (!caps) return "";
  gchar *s = gst_caps_to_string(caps);
  std::string out = s;
  g_free(s);
  gst_caps_unref(caps);
  return out;
}

cv::Mat textured_picture(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  cv::Mat bgr(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uint8_t>(40 + (x * 150) / w + rng() % 12),
                                          static_cast<uint8_t>(60 + (y * 130) / h + rng() % 12),
                                          static_cast<uint8_t>(90 + rng() % 12));
  for (int i = 0; i < 5; ++i) {
    const cv::Rect r(static_cast<int>(rng() % w), static_cast<int>(rng() % h), w / 5, h / 4);
    cv::rectangle(bgr, r, cv::Scalar(rng() % 256, rng() % 256, rng() % 256), cv::FILLED);
  }
  return bgr;
}

void push_frames(const std::string &launch, PixelFormat f, const std::vector<cv::Mat> &frames,
                 const std::function<void(GstBuffer *, GstHarness *)> &take,
                 const std::function<void(int, GstHarness *)> &between) {
  GstHarness *h = gst_harness_new_parse(launch.c_str());
  gst_harness_set_src_caps_str(h, raw_caps(f, frames[0].cols, frames[0].rows).c_str());
  for (size_t k = 0; k < frames.size(); ++k) {
    if (between) between(static_cast<int>(k), h);
    GstBuffer *in = buffer_from_frame(HostFrame::from_bgr(frames[k], f));
    GST_BUFFER_PTS(in) = k * GST_SECOND / 25;
    GstBuffer *b = gst_harness_push_and_pull(h, in);
    if (!b) {
      ADD_FAILURE() << launch << ": no output for frame " << k;
      break;
    }
    take(b, h);
    gst_buffer_unref(b);
  }
  gst_harness_teardown(h);
}


std::vector<cv::Mat> changing_sequence(int w, int h, uint32_t seed) {
  std::vector<cv::Mat> frames;
  cv::Mat cur = textured_picture(w, h, seed);
  std::mt19937 rng(seed + 1);
  for (int k = 0; k < 14; ++k) {
    cv::Mat next = cur.clone();
    switch (k % 7) {
      case 0: case 1: break;  // unchanged
      case 2: case 3: {  // a small box moves
        const cv::Rect r(static_cast<int>(rng() % (w - 12)), static_cast<int>(rng() % (h - 10)), 12, 10);
        cv::rectangle(next, r, cv::Scalar(rng() % 256, rng() % 256, rng() % 256), cv::FILLED);
        break;
      }
      case 4: {  // a big change
        cv::rectangle(next, cv::Rect(w / 4, h / 5, w / 2, h / 2), cv::Scalar(rng() % 256, 30, 200), cv::FILLED);
        break;
      }
      case 5: next = textured_picture(w, h, seed + 100 + k); break;  // a cut
      default: next.at<cv::Vec3b>(h / 2, w / 2) = cv::Vec3b(1, 2, 3); break;  // one pixel
    }
    frames.push_back(next);
    cur = next;
  }
  return frames;
}

std::vector<std::vector<uint8_t>> output_bytes(const std::string &launch, PixelFormat f,
                                               const std::vector<cv::Mat> &frames,
                                               const std::function<void(int, GstHarness *)> &between) {
  std::vector<std::vector<uint8_t>> out;
  push_frames(
      launch, f, frames,
      [&](GstBuffer *b, GstHarness *) {
        GstMapInfo map;
        gst_buffer_map(b, &map, GST_MAP_READ);
        out.emplace_back(map.data, map.data + map.size);
        gst_buffer_unmap(b, &map);
      },
      between);
  return out;
}

void expect_same_bytes(const std::vector<std::vector<uint8_t>> &a, const std::vector<std::vector<uint8_t>> &b,
                       const std::string &what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t k = 0; k < a.size(); ++k) EXPECT_TRUE(a[k] == b[k]) << what << ": frame " << k << " differs";
}

std::string on_every_stage(const std::string &chain, const std::string &option) {
  std::string out;
  size_t i = 0;
  while (i <= chain.size()) {
    const size_t bang = chain.find(" ! ", i);
    std::string part = chain.substr(i, bang == std::string::npos ? std::string::npos : bang - i);
    if (part.rfind("pseudo3d", 0) == 0) part += option;
    out += part;
    if (bang == std::string::npos) break;
    out += " ! ";
    i = bang + 3;
  }
  return out;
}

}  // namespace p3d::test
