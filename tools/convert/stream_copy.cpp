#include "stream_copy.h"

#include <algorithm>
#include <cstring>

#include "gst_run.h"

namespace p3d::convert {

namespace {

// Encoded audio the containers take as they are, with the parser that puts
// it into the framing the muxers want (e.g. ADTS AAC from MPEG-TS into
// raw AAC with codec_data for MP4). mp4 = mp4mux/qtmux's audio template.
struct AudioCodec {
  const char *media;
  int mpeg_min, mpeg_max;  // audio/mpeg only: mpegversion 1 = MP1/2/3, 2/4 = AAC
  const char *parser;
  bool mp4, mkv;
};
const AudioCodec kAudio[] = {
    {"audio/mpeg", 2, 4, "aacparse", true, true},    {"audio/mpeg", 1, 1, "mpegaudioparse", true, true},
    {"audio/x-ac3", 0, 0, "ac3parse", true, true},    {"audio/x-eac3", 0, 0, "ac3parse", false, true},
    {"audio/x-opus", 0, 0, "opusparse", true, true},  {"audio/x-vorbis", 0, 0, "vorbisparse", false, true},
    {"audio/x-flac", 0, 0, "flacparse", false, true}, {"audio/x-dts", 0, 0, "dcaparse", false, true},
};

// Audio encoders for streams that cannot be copied, best first: AAC plays
// everywhere; Opus and Vorbis only where no AAC encoder is installed.
const char *const kAudioEncodersMp4[] = {"avenc_aac", "voaacenc", "fdkaacenc", "opusenc"};
const char *const kAudioEncodersMkv[] = {"avenc_aac", "voaacenc", "fdkaacenc", "opusenc", "vorbisenc"};

const AudioCodec *audio_codec(const GstStructure *s) {
  for (const AudioCodec &c : kAudio) {
    if (!gst_structure_has_name(s, c.media)) continue;
    if (c.mpeg_max > 0) {
      int v = 0;
      if (!gst_structure_get_int(s, "mpegversion", &v) || v < c.mpeg_min || v > c.mpeg_max) continue;
    }
    return &c;
  }
  return nullptr;
}

bool container_takes(const AudioCodec &c, OutputKind kind) { return kind == OutputKind::Mkv ? c.mkv : c.mp4; }

const char *audio_encoder(OutputKind kind) {
  if (kind == OutputKind::Mkv) {
    for (const char *e : kAudioEncodersMkv)
      if (have_element(e)) return e;
  } else {
    for (const char *e : kAudioEncodersMp4)
      if (have_element(e)) return e;
  }
  return nullptr;
}

std::string extension_name(OutputKind kind) {
  return kind == OutputKind::Mkv ? "Matroska" : kind == OutputKind::Mov ? "QuickTime" : "MP4";
}

// Matroska's SRT track comes out of matroskademux as Pango markup (text
// escaped as &amp; &lt; &gt;); the muxers take plain UTF-8. Undo the
// escaping; for MP4 (tx3g has no markup) drop the tags as well.
std::string markup_to_text(const std::string &in, bool strip_tags) {
  std::string out;
  for (size_t i = 0; i < in.size(); ++i) {
    if (strip_tags && in[i] == '<') {
      const size_t close = in.find('>', i);
      if (close != std::string::npos) {
        i = close;
        continue;
      }
    }
    if (in[i] == '&') {
      static const struct {
        const char *entity;
        char c;
      } kEntities[] = {{"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
      bool replaced = false;
      for (const auto &e : kEntities)
        if (in.compare(i, std::strlen(e.entity), e.entity) == 0) {
          out += e.c;
          i += std::strlen(e.entity) - 1;
          replaced = true;
          break;
        }
      if (replaced) continue;
    }
    out += in[i];
  }
  return out;
}

GstPadProbeReturn unmarkup_probe(GstPad *, GstPadProbeInfo *info, gpointer strip_tags) {
  GstBuffer *buf = GST_PAD_PROBE_INFO_BUFFER(info);
  GstMapInfo map;
  if (!gst_buffer_map(buf, &map, GST_MAP_READ)) return GST_PAD_PROBE_OK;
  const std::string text =
      markup_to_text(std::string(reinterpret_cast<const char *>(map.data), map.size), strip_tags != nullptr);
  gst_buffer_unmap(buf, &map);
  GstBuffer *out = gst_buffer_new_memdup(text.data(), text.size());
  gst_buffer_copy_into(out, buf, GST_BUFFER_COPY_METADATA, 0, -1);
  gst_buffer_unref(buf);
  GST_PAD_PROBE_INFO_DATA(info) = out;
  return GST_PAD_PROBE_OK;
}

// Adds the elements to `bin`, links them in order from `pad` to a new
// request pad of `mux`, and starts them.
bool link_chain(GstElement *bin, GstPad *pad, GstElement **chain, int n, GstElement *mux, const char *mux_pad) {
  for (int i = 0; i < n; ++i)
    if (!chain[i]) {  // a missing plugin: nothing was added yet
      for (int j = 0; j < n; ++j)
        if (chain[j]) gst_object_unref(gst_object_ref_sink(chain[j]));
      return false;
    }
  for (int i = 0; i < n; ++i) gst_bin_add(GST_BIN(bin), chain[i]);
  for (int i = 0; i + 1 < n; ++i)
    if (!gst_element_link(chain[i], chain[i + 1])) return false;
  GstPad *sink = gst_element_get_static_pad(chain[0], "sink");
  const bool head = gst_pad_link(pad, sink) == GST_PAD_LINK_OK;
  gst_object_unref(sink);
  GstPad *mux_sink = gst_element_request_pad_simple(mux, mux_pad);
  GstPad *tail = gst_element_get_static_pad(chain[n - 1], "src");
  const bool linked = mux_sink && gst_pad_link(tail, mux_sink) == GST_PAD_LINK_OK;
  gst_object_unref(tail);
  if (mux_sink) gst_object_unref(mux_sink);
  for (int i = n - 1; i >= 0; --i) gst_element_sync_state_with_parent(chain[i]);
  return head && linked;
}

}  // namespace

GstElement *make_unbounded_queue() {
  GstElement *q = gst_element_factory_make("queue", nullptr);
  if (q) g_object_set(q, "max-size-buffers", 0u, "max-size-bytes", 0u, "max-size-time", G_GUINT64_CONSTANT(0), NULL);
  return q;
}

bool keep_encoded(const GstCaps *caps, OutputKind kind) {
  if (gst_caps_is_empty(caps) || gst_caps_is_any(caps)) return false;
  const GstStructure *s = gst_caps_get_structure(caps, 0);
  if (const AudioCodec *c = audio_codec(s)) return container_takes(*c, kind) && have_element(c->parser);
  if (gst_structure_has_name(s, "application/x-ass") || gst_structure_has_name(s, "application/x-ssa"))
    return kind == OutputKind::Mkv;  // MP4: let decodebin turn it into text
  return false;
}

StreamRoute route_stream(const GstCaps *caps, OutputKind kind) {
  StreamRoute r;
  const GstStructure *s = gst_caps_get_structure(caps, 0);
  const std::string name = gst_structure_get_name(s);
  const std::string container = extension_name(kind);
  if (name == "audio/x-raw") {
    r.mux_pad = "audio_%u";
    r.action = audio_encoder(kind) ? StreamAction::Encode : StreamAction::Drop;
    r.why = "no AAC, Opus or Vorbis encoder installed (gstreamer1.0-libav has avenc_aac)";
  } else if (const AudioCodec *c = audio_codec(s); c && container_takes(*c, kind) && have_element(c->parser)) {
    r.action = StreamAction::Copy;
    r.parser = c->parser;
    r.mux_pad = "audio_%u";
  } else if (name.rfind("audio/", 0) == 0) {
    r.why = "no decoder for " + name;
  } else if (name == "text/x-raw") {
    const char *format = gst_structure_get_string(s, "format");
    r.mux_pad = "subtitle_%u";
    if (format && std::strcmp(format, "utf8") == 0) {
      r.action = StreamAction::Copy;
    } else if (have_element("capssetter")) {
      r.action = StreamAction::Text;
    } else {
      r.why = "subtitle markup needs capssetter (gstreamer1.0-plugins-good)";
    }
  } else if (kind == OutputKind::Mkv && (name == "application/x-ass" || name == "application/x-ssa" ||
                                         name == "subpicture/x-dvd")) {
    r.action = StreamAction::Copy;
    r.mux_pad = "subtitle_%u";
  } else {
    r.why = container + " has no place for " + name;
  }
  return r;
}

GstPad *link_stream_branch(GstElement *bin, GstPad *pad, const GstCaps *caps, const StreamRoute &route,
                           OutputKind kind, GstElement *mux, std::string *error) {
  GstElement *chain[5] = {};
  int n = 0;
  chain[n++] = make_unbounded_queue();
  if (route.action == StreamAction::Copy) {
    if (route.parser) chain[n++] = gst_element_factory_make(route.parser, nullptr);
  } else if (route.action == StreamAction::Encode) {
    const char *encoder = audio_encoder(kind);
    chain[n++] = gst_element_factory_make("audioconvert", nullptr);
    chain[n++] = gst_element_factory_make("audioresample", nullptr);
    GstElement *enc = gst_element_factory_make(encoder, nullptr);
    if (enc && std::strcmp(encoder, "vorbisenc") != 0) {  // vorbisenc: quality mode
      int channels = 2;
      gst_structure_get_int(gst_caps_get_structure(caps, 0), "channels", &channels);
      g_object_set(enc, "bitrate", std::min(64000 * std::max(channels, 1), 512000), NULL);
    }
    chain[n++] = enc;
  } else if (route.action == StreamAction::Text) {
    GstElement *setter = gst_element_factory_make("capssetter", nullptr);
    if (setter) {
      GstCaps *utf8 = gst_caps_from_string("text/x-raw,format=utf8");
      g_object_set(setter, "caps", utf8, NULL);
      gst_caps_unref(utf8);
      GstPad *src = gst_element_get_static_pad(setter, "src");
      gst_pad_add_probe(src, GST_PAD_PROBE_TYPE_BUFFER, unmarkup_probe,
                        kind == OutputKind::Mkv ? nullptr : GINT_TO_POINTER(1), nullptr);
      gst_object_unref(src);
    }
    chain[n++] = setter;
  }
  GstElement *head = chain[0];
  if (head) gst_object_ref(head);
  if (!link_chain(bin, pad, chain, n, mux, route.mux_pad)) {
    gchar *desc = gst_caps_to_string(caps);
    *error = std::string("could not put the stream ") + desc + " into the output";
    g_free(desc);
    if (head) gst_object_unref(head);
    return nullptr;
  }
  GstPad *sink = gst_element_get_static_pad(head, "sink");
  gst_object_unref(head);
  return sink;
}

bool link_to_fakesink(GstElement *bin, GstPad *pad) {
  GstElement *sink = gst_element_factory_make("fakesink", nullptr);
  g_object_set(sink, "sync", FALSE, "async", FALSE, NULL);
  gst_bin_add(GST_BIN(bin), sink);
  GstPad *sinkpad = gst_element_get_static_pad(sink, "sink");
  const bool ok = gst_pad_link(pad, sinkpad) == GST_PAD_LINK_OK;
  gst_object_unref(sinkpad);
  gst_element_sync_state_with_parent(sink);
  return ok;
}

}  // namespace p3d::convert
