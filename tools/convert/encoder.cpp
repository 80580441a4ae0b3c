#include "encoder.h"

#include "gst_run.h"
#include "input_probe.h"
#include "mkv_stereo.h"

#include <cstring>

namespace p3d::convert {

namespace {

// Whether the encoder's sink template lists a raw format.
bool sink_accepts_format(const char *factory, const char *format) {
  GstElementFactory *f = gst_element_factory_find(factory);
  if (!f) return false;
  bool found = false;
  for (const GList *l = gst_element_factory_get_static_pad_templates(f); l && !found; l = l->next) {
    auto *t = static_cast<GstStaticPadTemplate *>(l->data);
    if (t->direction != GST_PAD_SINK) continue;
    GstCaps *caps = gst_static_caps_get(&t->static_caps);
    GstCaps *want = gst_caps_new_simple("video/x-raw", "format", G_TYPE_STRING, format, NULL);
    found = gst_caps_can_intersect(caps, want);
    gst_caps_unref(want);
    gst_caps_unref(caps);
  }
  gst_object_unref(f);
  return found;
}

// Sets an enum or numeric property given as text, if the element has it
// and the text is a valid value (NVENC's properties differ between
// GStreamer releases).
void set_if_valid(GstElement *e, const char *property, const char *value) {
  GParamSpec *p = g_object_class_find_property(G_OBJECT_GET_CLASS(e), property);
  if (!p) return;
  GValue v = G_VALUE_INIT;
  g_value_init(&v, p->value_type);
  if (gst_value_deserialize(&v, value) && !g_param_value_validate(p, &v)) g_object_set_property(G_OBJECT(e), property, &v);
  g_value_unset(&v);
}

// NVENC presets of 1.22's nvh264enc/nvh265enc for the x264 names (options.cpp
// accepts those only).
const char *nvenc_preset(const std::string &p) {
  if (p == "ultrafast" || p == "superfast" || p == "veryfast" || p == "faster") return "hp";
  if (p == "slow" || p == "slower" || p == "veryslow" || p == "placebo") return "hq";
  return "default";
}

}  // namespace

bool has_deep_samples(const GstCaps *decoded) { return caps_sample_bits(decoded) > 8; }

std::string colour_loss(const GstCaps *decoded, const EncoderChoice &c) {
  if (!decoded || gst_caps_is_empty(decoded)) return "";
  const GstStructure *s = gst_caps_get_structure(decoded, 0);
  std::string loss;
  const int bits = caps_sample_bits(decoded);
  if (bits > 8 && c.deep_format.empty())
    loss = "the input has " + std::to_string(bits) + " bits a sample; the output has 8 (" + c.deep_hint + ")";
  else if (bits > 10)
    loss = "the input has " + std::to_string(bits) + " bits a sample; the output has 10";
  const bool static_hdr = gst_structure_has_field(s, "mastering-display-info") ||
                          gst_structure_has_field(s, "content-light-level");
  if (static_hdr && c.factory != "x265enc" && c.factory != "nvh265enc") {
    if (!loss.empty()) loss += "; ";
    loss += "the input's HDR mastering-display and light-level metadata is not written by " + c.factory +
            " (its transfer and colours are): --codec h265 keeps it";
  }
  return loss;
}

int default_crf(Codec codec) { return codec == Codec::H264 ? 20 : 24; }

namespace {

bool have_h265_encoder(Processing processing) {
  return have_element("x265enc") || (processing == Processing::Gpu && have_element("nvh265enc"));
}

}  // namespace

bool settle_codec(Options *o, Processing processing, int input_bits, std::string *error) {
  if (o->codec != Codec::Auto) return true;
  o->codec = have_h265_encoder(processing) && input_bits > 8 ? Codec::H265 : Codec::H264;
  if (o->codec == Codec::H264 && o->crf > 50) {
    *error = "invalid value '" + std::to_string(o->crf) + "' for --crf (0 to 50 for H.264, which --codec auto chose)";
    return false;
  }
  return true;
}

bool is_stereo_layout(const std::string &layout) {
  MkvStereoLayout arrangement;
  return mkv_stereo_layout_from_name(layout, &arrangement) && arrangement != MkvStereoLayout::Mono;
}

bool choose_encoder(const Options &o, Processing processing, const std::string &layout, EncoderChoice *c,
                    std::string *error) {
  const bool h264 = o.codec == Codec::H264;
  const char *sw = h264 ? "x264enc" : "x265enc";
  const char *hw = h264 ? "nvh264enc" : "nvh265enc";
  // NVENC writes no frame-packing SEI. For H.264 stereo in MP4 that SEI is
  // the only signalling GStreamer reads, and of the interleaved layouts and
  // the right eye first the only one at all (the st3d box written after
  // muxing says left-first side by side and top-bottom only; mp4mux's own
  // box is wrong, see pseudo3dsignal), so x264 is kept there; Matroska gets
  // its StereoMode after muxing instead (container_stereo.h).
  const bool mp4_family = o.kind == OutputKind::Mp4 || o.kind == OutputKind::Mov;
  const bool sei_needed = h264 && is_stereo_layout(layout) && mp4_family;
  const bool use_hw = processing == Processing::Gpu && have_element(hw) && !(sei_needed && have_element(sw));
  if (use_hw) {
    c->factory = hw;
  } else if (have_element(sw)) {
    c->factory = sw;
  } else {
    *error = std::string("no ") + (h264 ? "H.264" : "H.265") + " encoder installed (" + sw + " from " +
             (h264 ? "gstreamer1.0-plugins-ugly" : "gstreamer1.0-plugins-bad") + ")";
    return false;
  }
  c->parser = h264 ? "h264parse" : "h265parse";
  c->writes_stereo_sei = c->factory == "x264enc";
  // Anaglyph colours sit in the chroma: 4:4:4 keeps them from bleeding
  // (x264 High 4:4:4, x265 Main 4:4:4). Packed stereo stays 4:2:0 for players.
  c->raw_format = layout == "anaglyph" && sink_accepts_format(c->factory.c_str(), "Y444") ? "Y444" : "I420";
  // 10-bit input keeps 10 bits through the stages into H.265 Main 10:
  // x265enc takes I420_10LE (Y444_10LE, Main 4:4:4 10, for anaglyphs on
  // the CPU path), NVENC P010_10LE. On the GPU path an anaglyph keeps its
  // 4:4:4 colours in 8 bits: CUDA memory holds no 16-bit R'G'B' for the
  // stages to hand on, only 10-bit 4:2:0.
  const bool gpu_anaglyph = processing == Processing::Gpu && c->raw_format == "Y444";
  const std::string deep = gpu_anaglyph                                           ? std::string()
                           : c->factory == "x265enc"                              ? c->raw_format + "_10LE"
                           : c->factory == "nvh265enc" && c->raw_format == "I420" ? std::string("P010_10LE")
                                                                                  : std::string();
  if (!deep.empty() && sink_accepts_format(c->factory.c_str(), deep.c_str()))
    c->deep_format = deep;
  else if (gpu_anaglyph)
    c->deep_hint = std::string("the GPU path keeps an anaglyph's 4:4:4 colours in 8 bits: --processing cpu") +
                   (h264 ? " --codec h265" : "") + " keeps 10";
  else if (h264)
    c->deep_hint = have_h265_encoder(processing)
                       ? "--codec h265 keeps 10"
                       : "an H.265 encoder would keep 10: x265enc, in gstreamer1.0-plugins-bad";
  else
    c->deep_hint = c->factory + " here takes no 10-bit input";
  return true;
}

namespace {

// x265enc (1.22) opens a new encoder on every flush, and fails with "Can
// not initialize x265 encoder" when it has had no caps yet: the flushing
// seek of --start/--duration reaches it before the first frame does. An
// encoder without caps has nothing to flush, so such flushes stop at its
// sink pad (START and STOP alike: no caps can arrive while flushing).
GstPadProbeReturn drop_flush_before_caps(GstPad *pad, GstPadProbeInfo *info, gpointer) {
  const GstEventType t = GST_EVENT_TYPE(GST_PAD_PROBE_INFO_EVENT(info));
  if ((t == GST_EVENT_FLUSH_START || t == GST_EVENT_FLUSH_STOP) && !gst_pad_has_current_caps(pad))
    return GST_PAD_PROBE_DROP;
  return GST_PAD_PROBE_OK;
}

}  // namespace

GstElement *make_encoder(const EncoderChoice &c, const Options &o) {
  GstElement *e = gst_element_factory_make(c.factory.c_str(), "encoder");
  if (!e) return nullptr;
  GstPad *sink = gst_element_get_static_pad(e, "sink");
  if (sink) {
    gst_pad_add_probe(sink, GST_PAD_PROBE_TYPE_EVENT_FLUSH, drop_flush_before_caps, nullptr, nullptr);
    gst_object_unref(sink);
  }
  const int crf = o.crf >= 0 ? o.crf : default_crf(o.codec);
  const std::string preset = o.preset.empty() ? "medium" : o.preset;
  if (c.factory == "x264enc") {
    // pass=qual is x264's CRF (constant rate factor) with quantizer as the factor.
    gst_util_set_object_arg(G_OBJECT(e), "pass", "qual");
    g_object_set(e, "quantizer", static_cast<guint>(crf), "threads", 0u, NULL);
    gst_util_set_object_arg(G_OBJECT(e), "speed-preset", preset.c_str());
    gst_util_set_object_arg(G_OBJECT(e), "frame-packing", "auto");
  } else if (c.factory == "x265enc") {
    const std::string opts = "crf=" + std::to_string(crf);
    g_object_set(e, "option-string", opts.c_str(), NULL);  // x265 uses every core by default
    gst_util_set_object_arg(G_OBJECT(e), "speed-preset", preset.c_str());
  } else {  // NVENC: variable bitrate with a constant-quality target
    set_if_valid(e, "rc-mode", "vbr-hq");
    set_if_valid(e, "const-quality", std::to_string(crf).c_str());
    set_if_valid(e, "preset", nvenc_preset(preset));
  }
  return e;
}

}  // namespace p3d::convert
