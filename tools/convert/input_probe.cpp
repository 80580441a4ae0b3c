#include "input_probe.h"

#include <gst/video/video.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <mutex>

namespace p3d::convert {

std::string tagged_rotation(const GstTagList *tags) {
  gchar *value = nullptr;
  if (!tags || !gst_tag_list_get_string(tags, GST_TAG_IMAGE_ORIENTATION, &value)) return {};
  std::string r = value ? value : "";
  g_free(value);
  return r == "rotate-0" ? std::string() : r;
}

int caps_sample_bits(const GstCaps *caps) {
  if (!caps || gst_caps_is_empty(caps)) return 0;
  const GstStructure *s = gst_caps_get_structure(caps, 0);
  guint luma = 0;
  if (gst_structure_get_uint(s, "bit-depth-luma", &luma)) return static_cast<int>(luma);
  const gchar *format = gst_structure_get_string(s, "format");
  const GstVideoFormatInfo *finfo = format ? gst_video_format_get_info(gst_video_format_from_string(format)) : nullptr;
  return finfo ? static_cast<int>(GST_VIDEO_FORMAT_INFO_DEPTH(finfo, 0)) : 0;
}

namespace {

// What the streaming threads find, read by the main thread once the wait
// is over and the pipeline stopped.
struct Probe {
  GstElement *pipeline = nullptr;
  std::mutex lock;
  GstPad *video = nullptr;  // the first pad with video caps (not owned)
  InputFacts facts;
  bool done = false;
};

void finish(Probe *probe) {
  probe->done = true;
  gst_element_post_message(probe->pipeline, gst_message_new_application(GST_OBJECT(probe->pipeline),
                                                                        gst_structure_new_empty("p3d-probe-done")));
}

// The events and first buffer of a parsebin pad (streaming thread): the
// first pad whose caps are video is the one read; its caps give the bits,
// its tags the orientation, and its first frame ends the wait (the sticky
// caps and tags come before it). Nothing is decoded: the parsed frames go
// to fakesinks.
GstPadProbeReturn on_data(GstPad *pad, GstPadProbeInfo *info, gpointer data) {
  auto *probe = static_cast<Probe *>(data);
  std::lock_guard<std::mutex> l(probe->lock);
  if (probe->done || (probe->video && probe->video != pad)) return GST_PAD_PROBE_OK;
  if (!(GST_PAD_PROBE_INFO_TYPE(info) & GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM)) {
    if (probe->video) finish(probe);  // a buffer: everything before it was seen
    return GST_PAD_PROBE_OK;
  }
  GstEvent *event = GST_PAD_PROBE_INFO_EVENT(info);
  if (GST_EVENT_TYPE(event) == GST_EVENT_CAPS) {
    GstCaps *caps = nullptr;
    gst_event_parse_caps(event, &caps);
    if (caps && !gst_caps_is_empty(caps) &&
        g_str_has_prefix(gst_structure_get_name(gst_caps_get_structure(caps, 0)), "video/")) {
      probe->video = pad;
      probe->facts.bits = caps_sample_bits(caps);
    }
  } else if (GST_EVENT_TYPE(event) == GST_EVENT_TAG && probe->video == pad) {
    GstTagList *tags = nullptr;
    gst_event_parse_tag(event, &tags);
    if (!tagged_rotation(tags).empty()) probe->facts.rotated = true;
  }
  return GST_PAD_PROBE_OK;
}

// Each parsebin pad gets the probe and a fakesink: a stream left unlinked
// would stop the demuxer (not-linked) before the others are read.
void on_pad_added(GstElement *, GstPad *pad, gpointer data) {
  auto *probe = static_cast<Probe *>(data);
  gst_pad_add_probe(pad,
                    static_cast<GstPadProbeType>(GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM | GST_PAD_PROBE_TYPE_BUFFER |
                                                 GST_PAD_PROBE_TYPE_BUFFER_LIST),
                    on_data, data, nullptr);
  GstElement *sink = gst_element_factory_make("fakesink", nullptr);
  if (!sink) return;
  g_object_set(sink, "sync", FALSE, "async", FALSE, NULL);
  gst_bin_add(GST_BIN(probe->pipeline), sink);
  gst_element_sync_state_with_parent(sink);
  GstPad *sinkpad = gst_element_get_static_pad(sink, "sink");
  gst_pad_link(pad, sinkpad);
  gst_object_unref(sinkpad);
}

// Every stream is exposed: with no video among them there is nothing to
// wait for (a long audio file would otherwise be parsed to its end).
void on_no_more_pads(GstElement *parse, gpointer data) {
  auto *probe = static_cast<Probe *>(data);
  bool video = false;
  GstIterator *it = gst_element_iterate_src_pads(parse);
  GValue item = G_VALUE_INIT;
  while (!video && gst_iterator_next(it, &item) == GST_ITERATOR_OK) {
    GstCaps *caps = gst_pad_get_current_caps(GST_PAD(g_value_get_object(&item)));
    video = caps && !gst_caps_is_empty(caps) &&
            g_str_has_prefix(gst_structure_get_name(gst_caps_get_structure(caps, 0)), "video/");
    if (caps) gst_caps_unref(caps);
    g_value_reset(&item);
  }
  g_value_unset(&item);
  gst_iterator_free(it);
  std::lock_guard<std::mutex> l(probe->lock);
  if (!video && !probe->done) finish(probe);
}

}  // namespace

InputFacts probe_input(const std::string &path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return {};
  GstElement *src = gst_element_factory_make("filesrc", nullptr);
  GstElement *parse = gst_element_factory_make("parsebin", nullptr);
  if (!src || !parse) {
    if (src) gst_object_unref(gst_object_ref_sink(src));
    if (parse) gst_object_unref(gst_object_ref_sink(parse));
    return {};
  }
  Probe probe;
  probe.pipeline = gst_pipeline_new("pseudo3d-probe");
  g_object_set(src, "location", path.c_str(), NULL);
  gst_bin_add_many(GST_BIN(probe.pipeline), src, parse, NULL);
  gst_element_link(src, parse);
  g_signal_connect(parse, "pad-added", G_CALLBACK(on_pad_added), &probe);
  g_signal_connect(parse, "no-more-pads", G_CALLBACK(on_no_more_pads), &probe);
  GstBus *bus = gst_element_get_bus(probe.pipeline);
  if (gst_element_set_state(probe.pipeline, GST_STATE_PLAYING) != GST_STATE_CHANGE_FAILURE) {
    // The first video frame, an error (a damaged file: the conversion
    // reports it itself) or the end.
    const auto types = static_cast<GstMessageType>(GST_MESSAGE_APPLICATION | GST_MESSAGE_ERROR | GST_MESSAGE_EOS);
    GstMessage *msg = gst_bus_timed_pop_filtered(bus, 10 * GST_SECOND, types);
    if (msg) gst_message_unref(msg);
  }
  // Stopped: no streaming thread runs the pad probes any more.
  gst_element_set_state(probe.pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(probe.pipeline);
  return probe.facts;
}

}  // namespace p3d::convert
