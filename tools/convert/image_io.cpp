#include "image_io.h"

#include <gst/app/gstappsink.h>
#include <gst/app/gstappsrc.h>
#include <gst/video/video.h>

#include <atomic>
#include <cstring>

#include "gst_run.h"

namespace p3d::convert {

namespace {

// videoflip's video-direction for EXIF orientations 1..8.
const char *flip_for_orientation(int o) {
  static const char *const kDirections[] = {"identity", "identity", "horiz", "180", "vert",
                                            "ul-lr",    "90r",      "ur-ll", "90l"};
  return o >= 1 && o <= 8 ? kDirections[o] : "identity";
}

// decodebin's autoplug-continue: a picture larger than the 3D stages take
// is refused from the size its typefind or parser reads in the header,
// before a decoder is plugged (a 20000x20000 PNG would take seconds and
// gigabytes to decode, then fail to negotiate); the pad is exposed
// encoded, and the run ends on this error, the first one posted.
gboolean refuse_too_large(GstElement *decodebin, GstPad *, GstCaps *caps, gpointer refused) {
  std::string message;
  if (!too_large(caps, &message)) return TRUE;
  if (!static_cast<std::atomic<bool> *>(refused)->exchange(true)) post_error(decodebin, message);
  return FALSE;
}

// decodebin's pad-added: the decoded size, where no header gave one
// before (a decoder whose output decodebin exposes before its caps are
// fixed). The error comes before the first frame reaches the stages.
void refuse_too_large_pad(GstElement *decodebin, GstPad *pad, gpointer refused) {
  GstCaps *caps = gst_pad_get_current_caps(pad);
  std::string message;
  if (caps && too_large(caps, &message) && !static_cast<std::atomic<bool> *>(refused)->exchange(true))
    post_error(decodebin, message);
  if (caps) gst_caps_unref(caps);
}

}  // namespace

GstElement *launch(const std::string &description, std::string *error) {
  GError *err = nullptr;
  GstElement *p = gst_parse_launch(description.c_str(), &err);
  if (err) {
    *error = std::string("GStreamer: ") + err->message;
    g_clear_error(&err);
    if (p) gst_object_unref(p);
    return nullptr;
  }
  return p;
}

GstElement *by_name(GstElement *pipeline, const char *name) {
  GstElement *e = gst_bin_get_by_name(GST_BIN(pipeline), name);
  if (e) gst_object_unref(e);  // the pipeline keeps it alive
  return e;
}

Image Image::crop_columns(int x0, int w) const {
  Image out;
  out.width = w;
  out.height = height;
  const int bpp = kBytesPerPixel;
  out.data.resize(static_cast<size_t>(w) * height * bpp);
  for (int y = 0; y < height; ++y)
    std::memcpy(&out.data[static_cast<size_t>(y) * w * bpp], &data[(static_cast<size_t>(y) * width + x0) * bpp],
                static_cast<size_t>(w) * bpp);
  return out;
}

GstBuffer *image_to_buffer(const Image &image, GstCaps **caps) {
  GstVideoInfo info;
  gst_video_info_set_format(&info, GST_VIDEO_FORMAT_RGBA, image.width, image.height);
  GST_VIDEO_INFO_FPS_N(&info) = 0;  // a still picture
  GST_VIDEO_INFO_FPS_D(&info) = 1;
  *caps = gst_video_info_to_caps(&info);
  GstBuffer *buf = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&info), nullptr);
  GstVideoFrame frame;
  gst_video_frame_map(&frame, &info, buf, GST_MAP_WRITE);
  const size_t row = static_cast<size_t>(image.width) * Image::kBytesPerPixel;
  for (int y = 0; y < image.height; ++y)
    std::memcpy(static_cast<uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&frame, 0)) + y * GST_VIDEO_FRAME_PLANE_STRIDE(&frame, 0),
                &image.data[y * row], row);
  gst_video_frame_unmap(&frame);
  GST_BUFFER_PTS(buf) = 0;
  return buf;
}

bool image_from_sample(GstSample *sample, Image *out) {
  GstVideoInfo info;
  if (!gst_video_info_from_caps(&info, gst_sample_get_caps(sample))) return false;
  if (GST_VIDEO_INFO_FORMAT(&info) != GST_VIDEO_FORMAT_RGBA) return false;
  GstVideoFrame frame;
  if (!gst_video_frame_map(&frame, &info, gst_sample_get_buffer(sample), GST_MAP_READ)) return false;
  out->width = GST_VIDEO_INFO_WIDTH(&info);
  out->height = GST_VIDEO_INFO_HEIGHT(&info);
  const size_t row = static_cast<size_t>(out->width) * Image::kBytesPerPixel;
  out->data.resize(row * out->height);
  for (int y = 0; y < out->height; ++y)
    std::memcpy(&out->data[y * row],
                static_cast<const uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&frame, 0)) + y * GST_VIDEO_FRAME_PLANE_STRIDE(&frame, 0),
                row);
  gst_video_frame_unmap(&frame);
  return true;
}

std::vector<uint8_t> bytes_of_sample(GstSample *sample) {
  GstBuffer *b = gst_sample_get_buffer(sample);
  std::vector<uint8_t> bytes(gst_buffer_get_size(b));
  gst_buffer_extract(b, 0, bytes.data(), bytes.size());
  return bytes;
}

bool run_for_samples(GstElement *pipeline, GstElement *appsrc, GstBuffer *buffer, GstElement *const *sinks,
                     GstSample **samples, int n, std::string *error, std::string *error_source) {
  for (int i = 0; i < n; ++i) samples[i] = nullptr;
  GstBus *bus = gst_element_get_bus(pipeline);
  bool failed = false;
  if (gst_element_set_state(pipeline, GST_STATE_PLAYING) != GST_STATE_CHANGE_FAILURE) {
    if (appsrc) {
      gst_app_src_push_buffer(GST_APP_SRC(appsrc), buffer);
      buffer = nullptr;
      gst_app_src_end_of_stream(GST_APP_SRC(appsrc));
    }
    // Poll the sinks and the bus: an appsink waits on nothing if an
    // element fails.
    for (int got = 0; got < n && !failed;) {
      for (int i = 0; i < n && !failed; ++i) {
        if (samples[i]) continue;
        samples[i] = gst_app_sink_try_pull_sample(GST_APP_SINK(sinks[i]), 100 * GST_MSECOND);
        if (samples[i]) {
          ++got;
        } else if (GstMessage *msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR)) {
          *error = error_text(msg);
          if (error_source) *error_source = message_source_path(msg);
          gst_message_unref(msg);
          failed = true;
        } else if (gst_app_sink_is_eos(GST_APP_SINK(sinks[i]))) {
          *error = "no picture came out";
          failed = true;
        }
      }
    }
  } else {
    GstMessage *msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR);
    *error = msg ? error_text(msg) : "the pipeline did not start";
    if (msg && error_source) *error_source = message_source_path(msg);
    if (msg) gst_message_unref(msg);
    failed = true;
  }
  for (int i = 0; i < n && failed; ++i) {
    if (samples[i]) gst_sample_unref(samples[i]);
    samples[i] = nullptr;
  }
  if (buffer) gst_buffer_unref(buffer);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  return !failed;
}

GstSample *run_for_one_sample(GstElement *pipeline, GstElement *appsrc, GstBuffer *buffer, GstElement *appsink,
                              std::string *error) {
  GstSample *sample = nullptr;
  run_for_samples(pipeline, appsrc, buffer, &appsink, &sample, 1, error);
  return sample;
}

bool read_image(const std::string &path, int exif_orientation, Image *out, std::string *error) {
  GstElement *p = launch(std::string("filesrc name=src ! decodebin name=dec ! videoconvert ! videoflip "
                                     "video-direction=") +
                             flip_for_orientation(exif_orientation) +
                             " ! videoconvert ! video/x-raw,format=RGBA ! appsink name=sink sync=false",
                         error);
  if (!p) return false;
  g_object_set(by_name(p, "src"), "location", path.c_str(), NULL);
  std::atomic<bool> refused{false};
  g_signal_connect(by_name(p, "dec"), "autoplug-continue", G_CALLBACK(refuse_too_large), &refused);
  g_signal_connect(by_name(p, "dec"), "pad-added", G_CALLBACK(refuse_too_large_pad), &refused);
  GstSample *s = run_for_one_sample(p, nullptr, nullptr, by_name(p, "sink"), error);
  const bool ok = s && image_from_sample(s, out);
  if (s && !ok) *error = "could not read the decoded picture";
  if (!ok && !refused) *error = "not a picture GStreamer can read (" + *error + ")";
  if (s) gst_sample_unref(s);
  gst_object_unref(p);
  return ok;
}

bool encode_image(const Image &image, const std::string &codec, bool full_chroma, std::vector<uint8_t> *bytes,
                  std::string *error) {
  std::string tail;
  // JPEG (JFIF) means full-range Y'CbCr, and every reader decodes it so;
  // videoconvert's default for YUV is TV range (16-235), which would wash
  // every picture out. colorimetry 1:4:0:0 is full range, BT.601 matrix:
  // what jpegdec itself reports.
  if (codec == "jpeg")
    tail = std::string("videoconvert ! video/x-raw,format=") + (full_chroma ? "Y444" : "I420") +
           ",colorimetry=1:4:0:0 ! jpegenc quality=95";
  else
    tail = "videoconvert ! video/x-raw,format=RGB ! pngenc";
  GstElement *p = launch("appsrc name=src format=time ! " + tail + " ! appsink name=sink sync=false", error);
  if (!p) return false;
  GstCaps *caps = nullptr;
  GstBuffer *buf = image_to_buffer(image, &caps);
  GstElement *src = by_name(p, "src");
  g_object_set(src, "caps", caps, NULL);
  gst_caps_unref(caps);
  GstSample *s = run_for_one_sample(p, src, buf, by_name(p, "sink"), error);
  if (s) {
    *bytes = bytes_of_sample(s);
    gst_sample_unref(s);
  }
  gst_object_unref(p);
  return s != nullptr;
}

}  // namespace p3d::convert
