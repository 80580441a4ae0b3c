#include "media_source.h"

#include <fcntl.h>
#include <gst/pbutils/pbutils.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "gst_run.h"

namespace p3d::convert {

namespace {

struct Gate {
  bool open = false;
  bool encoded = false;
  GstSegment segment;
};

GstPadProbeReturn gate_probe(GstPad *, GstPadProbeInfo *info, gpointer data) {
  auto *g = static_cast<Gate *>(data);
  if (info->type & GST_PAD_PROBE_TYPE_EVENT_BOTH) {
    GstEvent *ev = GST_PAD_PROBE_INFO_EVENT(info);
    if (GST_EVENT_TYPE(ev) == GST_EVENT_FLUSH_STOP) g->open = true;
    if (GST_EVENT_TYPE(ev) == GST_EVENT_SEGMENT) gst_event_copy_segment(ev, &g->segment);
    return GST_PAD_PROBE_OK;
  }
  if (!g->open) return GST_PAD_PROBE_DROP;
  if (g->encoded && (info->type & GST_PAD_PROBE_TYPE_BUFFER) && g->segment.format == GST_FORMAT_TIME) {
    // Packets cannot be cut: one that starts before the piece would start
    // the stream early (out of sync) in the output, so it goes.
    const GstClockTime pts = GST_BUFFER_PTS(GST_PAD_PROBE_INFO_BUFFER(info));
    if (GST_CLOCK_TIME_IS_VALID(pts) &&
        (pts < g->segment.start || (GST_CLOCK_TIME_IS_VALID(g->segment.stop) && pts >= g->segment.stop)))
      return GST_PAD_PROBE_DROP;
  }
  return GST_PAD_PROBE_OK;
}

// Video and picture decoders: a photo converted into a video file is
// decoded by an image decoder (jpegdec, pngdec: "Codec/Decoder/Image").
bool is_video_decoder(GstElement *e) {
  GstElementFactory *f = gst_element_get_factory(e);
  const GstElementFactoryListType decoder = GST_ELEMENT_FACTORY_TYPE_DECODER;
  return f && (gst_element_factory_list_is_type(f, decoder | GST_ELEMENT_FACTORY_TYPE_MEDIA_VIDEO) ||
               gst_element_factory_list_is_type(f, decoder | GST_ELEMENT_FACTORY_TYPE_MEDIA_IMAGE));
}

}  // namespace

bool MediaSource::build(GstElement *pipeline, const std::string &input, Hooks hooks, std::string *error) {
  hooks_ = std::move(hooks);
  // A FIFO or a device is opened once, here, and read through fdsrc:
  // filesrc opens and closes its file to probe for random access before it
  // opens it for good, and a writer that writes in that gap gets EPIPE
  // (and the pipeline then waits for data that never comes).
  struct stat st;
  const bool regular = stat(input.c_str(), &st) != 0 || S_ISREG(st.st_mode);
  if (!regular && (fd_ = open(input.c_str(), O_RDONLY | O_CLOEXEC)) < 0) {
    *error = input + ": " + g_strerror(errno);
    return false;
  }
  GstElement *src = gst_element_factory_make(regular ? "filesrc" : "fdsrc", "source");
  GstElement *dec = gst_element_factory_make("decodebin", "decoder");
  if (!src || !dec) {
    if (src) gst_object_unref(gst_object_ref_sink(src));
    if (dec) gst_object_unref(gst_object_ref_sink(dec));
    *error = "GStreamer's filesrc, fdsrc or decodebin is missing (gstreamer1.0-plugins-base)";
    return false;
  }
  if (regular)
    g_object_set(src, "location", input.c_str(), NULL);
  else
    g_object_set(src, "fd", fd_, NULL);
  gst_bin_add_many(GST_BIN(pipeline), src, dec, NULL);
  gst_element_link(src, dec);
  g_signal_connect(dec, "autoplug-continue", G_CALLBACK(on_autoplug_continue), this);
  g_signal_connect(dec, "autoplug-query", G_CALLBACK(on_autoplug_query), this);
  g_signal_connect(dec, "pad-added", G_CALLBACK(on_pad_added), this);
  g_signal_connect(dec, "no-more-pads", G_CALLBACK(on_no_more_pads), this);
  g_signal_connect(dec, "element-added", G_CALLBACK(on_element_added), this);
  return true;
}

MediaSource::~MediaSource() {
  if (fd_ >= 0) close(fd_);
}

void MediaSource::set_piece(GstClockTime start, GstClockTime duration) {
  start_ = start;
  duration_ = duration;
}

void MediaSource::gate_pad(GstPad *pad, bool encoded) {
  if (!has_piece()) return;
  auto *g = new Gate;
  g->encoded = encoded;
  gst_segment_init(&g->segment, GST_FORMAT_UNDEFINED);
  gst_pad_add_probe(pad,
                    static_cast<GstPadProbeType>(GST_PAD_PROBE_TYPE_BUFFER | GST_PAD_PROBE_TYPE_BUFFER_LIST |
                                                 GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM | GST_PAD_PROBE_TYPE_EVENT_FLUSH),
                    gate_probe, g, [](gpointer p) { delete static_cast<Gate *>(p); });
}

bool MediaSource::seek_to_piece(GstPad *pad) {
  const GstClockTime start = piece_start();
  const bool bounded = GST_CLOCK_TIME_IS_VALID(duration_);
  GstEvent *seek = gst_event_new_seek(1.0, GST_FORMAT_TIME,
                                      static_cast<GstSeekFlags>(GST_SEEK_FLAG_FLUSH | GST_SEEK_FLAG_ACCURATE),
                                      GST_SEEK_TYPE_SET, static_cast<gint64>(start),
                                      bounded ? GST_SEEK_TYPE_SET : GST_SEEK_TYPE_NONE,
                                      bounded ? static_cast<gint64>(start + duration_) : -1);
  return gst_pad_push_event(pad, seek);
}

GstClockTime MediaSource::total_time(GstPad *pad) const {
  gint64 dur = -1;
  const bool known = gst_pad_peer_query_duration(pad, GST_FORMAT_TIME, &dur) && dur > 0;
  GstClockTime end = known ? static_cast<GstClockTime>(dur) : GST_CLOCK_TIME_NONE;
  if (GST_CLOCK_TIME_IS_VALID(duration_)) {
    const GstClockTime stop = piece_start() + duration_;
    end = known ? std::min(end, stop) : stop;
  }
  if (!GST_CLOCK_TIME_IS_VALID(end) || end <= piece_start()) return GST_CLOCK_TIME_NONE;
  return end - piece_start();
}

std::string MediaSource::video_decoder() const {
  std::lock_guard<std::mutex> l(lock_);
  return video_decoder_;
}

bool MediaSource::still_picture() const {
  std::lock_guard<std::mutex> l(lock_);
  return input_type_.rfind("image/", 0) == 0;
}

std::string MediaSource::missing_plugin(GstMessage *msg) {
  if (!gst_is_missing_plugin_message(msg)) return "";
  gchar *d = gst_missing_plugin_message_get_description(msg);
  std::string s = d ? d : "";
  g_free(d);
  return s;
}

GstCaps *MediaSource::encoded_caps(GstPad *decoded_pad) {
  GstPad *pad = GST_IS_GHOST_PAD(decoded_pad) ? gst_ghost_pad_get_target(GST_GHOST_PAD(decoded_pad)) : nullptr;
  GstCaps *found = nullptr;
  // decoder ! (decodebin's pad): the decoder's sink caps; a few steps more
  // for what may sit between (a converter, a queue with one sink pad).
  for (int step = 0; pad && !found && step < 8; ++step) {
    GstElement *element = gst_pad_get_parent_element(pad);
    gst_object_unref(pad);
    pad = nullptr;
    if (!element) break;
    // A demuxer's sink caps name the container, not the stream: stop there.
    const char *klass = gst_element_get_metadata(element, GST_ELEMENT_METADATA_KLASS);
    GstPad *sink = klass && strstr(klass, "Demux") ? nullptr : gst_element_get_static_pad(element, "sink");
    gst_object_unref(element);
    if (!sink) break;
    GstCaps *caps = gst_pad_get_current_caps(sink);
    if (caps && !g_str_has_suffix(gst_structure_get_name(gst_caps_get_structure(caps, 0)), "/x-raw"))
      found = caps;
    else if (caps)
      gst_caps_unref(caps);
    pad = gst_pad_get_peer(sink);
    gst_object_unref(sink);
  }
  if (pad) gst_object_unref(pad);
  return found;
}

gboolean MediaSource::on_autoplug_continue(GstElement *bin, GstPad *pad, GstCaps *caps, gpointer self) {
  auto *s = static_cast<MediaSource *>(self);
  // Too large for the 3D stages: no decoder is plugged for it (the pad is
  // exposed encoded and left unlinked), and the run ends on this error.
  std::string message;
  if (too_large(caps, &message)) {
    if (!s->refused_.exchange(true)) post_error(bin, message);
    return FALSE;
  }
  // The first pad decodebin looks at is its typefind's (behind the ghost
  // pad decodebin passes): the file's type.
  GstPad *target = GST_IS_GHOST_PAD(pad) ? gst_ghost_pad_get_target(GST_GHOST_PAD(pad)) : nullptr;
  GstElement *parent = target ? gst_pad_get_parent_element(target) : nullptr;
  GstElementFactory *f = parent ? gst_element_get_factory(parent) : nullptr;
  if (f && g_strcmp0(GST_OBJECT_NAME(f), "typefind") == 0) {
    std::lock_guard<std::mutex> l(s->lock_);
    s->input_type_ = gst_structure_get_name(gst_caps_get_structure(caps, 0));
  }
  if (parent) gst_object_unref(parent);
  if (target) gst_object_unref(target);
  return !(s->hooks_.keep_encoded && s->hooks_.keep_encoded(caps));
}

// decodebin's pads are linked only once every stream is found, but decoders
// choose their output (system or CUDA memory, format) from their first
// frame: answer their caps queries with what the video chain takes, as
// playbin does for its sinks.
gboolean MediaSource::on_autoplug_query(GstElement *, GstPad *, GstElement *element, GstQuery *query, gpointer self) {
  auto *s = static_cast<MediaSource *>(self);
  if (GST_QUERY_TYPE(query) != GST_QUERY_CAPS || !s->hooks_.video_caps || !is_video_decoder(element)) return FALSE;
  GstCaps *filter = nullptr;
  gst_query_parse_caps(query, &filter);
  GstCaps *caps = s->hooks_.video_caps();
  if (filter) {
    GstCaps *both = gst_caps_intersect_full(filter, caps, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(caps);
    caps = both;
  }
  gst_query_set_caps_result(query, caps);
  gst_caps_unref(caps);
  return TRUE;
}

void MediaSource::on_pad_added(GstElement *bin, GstPad *pad, gpointer self) {
  auto *s = static_cast<MediaSource *>(self);
  if (s->refused_) return;  // the run ends on the refusal
  // decodebin exposes a stream that ended before its first decoded frame
  // (a file cut off there) without caps: what the pad could take stands in
  // for them, unfixed (see Hooks::pad_added).
  GstCaps *caps = gst_pad_get_current_caps(pad);
  if (!caps) caps = gst_pad_query_caps(pad, nullptr);
  // A decoder whose output decodebin exposes before its caps are fixed
  // (y4mdec) gives the size only here.
  std::string message;
  if (too_large(caps, &message)) {
    if (!s->refused_.exchange(true)) post_error(bin, message);
  } else if (s->hooks_.pad_added) {
    s->hooks_.pad_added(pad, caps);
  }
  gst_caps_unref(caps);
}

void MediaSource::on_no_more_pads(GstElement *, gpointer self) {
  auto *s = static_cast<MediaSource *>(self);
  if (s->hooks_.no_more_pads) s->hooks_.no_more_pads();
}

void MediaSource::on_element_added(GstBin *, GstElement *element, gpointer self) {
  auto *s = static_cast<MediaSource *>(self);
  if (!is_video_decoder(element)) return;
  // decodebin tries the next decoder when one fails: the last one is in use.
  std::lock_guard<std::mutex> l(s->lock_);
  s->video_decoder_ = GST_OBJECT_NAME(gst_element_get_factory(element));
}

}  // namespace p3d::convert
