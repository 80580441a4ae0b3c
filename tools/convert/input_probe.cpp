#include "input_probe.h"

#include <gst/video/video.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>

namespace p3d::convert {

namespace {

// Bits a sample of parsed video caps, 0 when they do not say.
int caps_sample_bits(const GstCaps *caps) {
  if (!caps || gst_caps_is_empty(caps)) return 0;
  const GstStructure *s = gst_caps_get_structure(caps, 0);
  guint luma = 0;
  if (gst_structure_get_uint(s, "bit-depth-luma", &luma)) return static_cast<int>(luma);
  const gchar *format = gst_structure_get_string(s, "format");
  const GstVideoFormatInfo *finfo = format ? gst_video_format_get_info(gst_video_format_from_string(format)) : nullptr;
  return finfo ? static_cast<int>(GST_VIDEO_FORMAT_INFO_DEPTH(finfo, 0)) : 0;
}

struct Probe {
  GstElement *pipeline = nullptr;
  std::atomic<int> bits{0};
};

// The first fixed video caps on a parsebin pad (streaming thread): their
// bits, then a message that ends the wait. The pads stay unlinked:
// nothing is decoded.
void take_caps(Probe *probe, GstCaps *caps) {
  if (!caps || gst_caps_is_empty(caps) || !gst_caps_is_fixed(caps)) return;
  if (!g_str_has_prefix(gst_structure_get_name(gst_caps_get_structure(caps, 0)), "video/")) return;
  int expected = 0;
  if (!probe->bits.compare_exchange_strong(expected, std::max(1, caps_sample_bits(caps)))) return;
  gst_element_post_message(probe->pipeline,
                           gst_message_new_application(GST_OBJECT(probe->pipeline),
                                                       gst_structure_new_empty("p3d-probe-video")));
}

GstPadProbeReturn on_event(GstPad *, GstPadProbeInfo *info, gpointer data) {
  GstEvent *event = GST_PAD_PROBE_INFO_EVENT(info);
  if (GST_EVENT_TYPE(event) == GST_EVENT_CAPS) {
    GstCaps *caps = nullptr;
    gst_event_parse_caps(event, &caps);
    take_caps(static_cast<Probe *>(data), caps);
  }
  return GST_PAD_PROBE_OK;
}

// A pad may come with its caps set, or get them after: both are watched.
void on_pad_added(GstElement *, GstPad *pad, gpointer data) {
  gst_pad_add_probe(pad, GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM, on_event, data, nullptr);
  GstCaps *caps = gst_pad_get_current_caps(pad);
  take_caps(static_cast<Probe *>(data), caps);
  if (caps) gst_caps_unref(caps);
}

}  // namespace

int video_sample_bits(const std::string &path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return 0;
  GstElement *src = gst_element_factory_make("filesrc", nullptr);
  GstElement *parse = gst_element_factory_make("parsebin", nullptr);
  if (!src || !parse) {
    if (src) gst_object_unref(gst_object_ref_sink(src));
    if (parse) gst_object_unref(gst_object_ref_sink(parse));
    return 0;
  }
  Probe probe;
  probe.pipeline = gst_pipeline_new("pseudo3d-probe");
  g_object_set(src, "location", path.c_str(), NULL);
  gst_bin_add_many(GST_BIN(probe.pipeline), src, parse, NULL);
  gst_element_link(src, parse);
  g_signal_connect(parse, "pad-added", G_CALLBACK(on_pad_added), &probe);
  GstBus *bus = gst_element_get_bus(probe.pipeline);
  if (gst_element_set_state(probe.pipeline, GST_STATE_PAUSED) != GST_STATE_CHANGE_FAILURE) {
    // The first video pad, an error (a stream with no parser, a damaged
    // file: the conversion reports those itself) or the end; 10 s at most.
    const auto types = static_cast<GstMessageType>(GST_MESSAGE_APPLICATION | GST_MESSAGE_ERROR | GST_MESSAGE_EOS);
    GstMessage *msg = gst_bus_timed_pop_filtered(bus, 10 * GST_SECOND, types);
    if (msg) gst_message_unref(msg);
  }
  gst_element_set_state(probe.pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(probe.pipeline);
  const int bits = probe.bits.load();
  return bits > 1 ? bits : 0;  // 1: video caps that state no depth
}

}  // namespace p3d::convert
