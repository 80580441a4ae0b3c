/**
 * SECTION:element-pseudo3dsignal
 * @title: pseudo3dsignal
 *
 * Prepares an encoded stereo H.264 or H.265 stream for a muxer, so that the
 * file reads back right in GStreamer and in ffmpeg-based players. Put it
 * between the parser and the muxer:
 *
 *  * It writes the stream's eye order into the frame-packing SEI: x264
 *    (x264enc frame-packing=auto) always marks the first view as the left
 *    one, so right-view-first content (pseudo3dpack swap-eyes=true) would
 *    otherwise be shown with its depth reversed.
 *  * It hides the multiview caps from the muxer (multiview-mode=mono), so
 *    the stereo packing travels in the SEI alone (x264 writes it):
 *    GStreamer 1.22's mp4mux
 *    writes the eye order of its svmi box inverted, and matroskamux writes a
 *    wrong StereoMode for right-view-first side-by-side, none for
 *    interleaved layouts, and a display size that GStreamer reads per frame
 *    and ffmpeg per view. h264parse (GStreamer) and ffmpeg both read the
 *    SEI. pseudo3d-mkvstereo adds a correct StereoMode to a finished
 *    Matroska file for players that only read the container.
 *  * For H.265 it does the same, and says so once per caps with a
 *    warning: x265enc (1.22) writes no frame-packing SEI, and the muxers'
 *    own signalling is wrong for ffmpeg (matroskamux's display size, read
 *    per view: SAR 1:2 for top-bottom, 2:1 for side-by-side) or absent
 *    (mp4mux), so the file carries no stereo signalling. pseudo3d-mkvstereo
 *    adds a correct StereoMode to the finished Matroska file; H.264 carries
 *    the SEI.
 *
 * The pixel-aspect-ratio is left alone: send the frame's own (1/1 for
 * square pixels) with the half-aspect flag, as pseudo3dpack does.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 videotestsrc num-buffers=100 ! pseudo3dconvert layout=side-by-side-half swap-eyes=true ! videoconvert ! video/x-raw,format=I420 ! x264enc frame-packing=auto ! h264parse ! pseudo3dsignal ! mp4mux ! filesink location=sbs.mp4
 * ]|
 */
#include "gstpseudo3dsignal.h"

#include <gst/video/video.h>

#include "frame_packing_sei.h"

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_signal_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_signal_debug

struct _GstPseudo3DSignal {
  GstBaseTransform parent;
  /* negotiated (streaming thread) */
  p3d::gst::NalSyntax syntax;
  int length_size;  // 0: Annex B byte-stream
  gboolean stereo;
  gboolean right_first;
  guint64 rewritten;
};

#define gst_pseudo3d_signal_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DSignal, gst_pseudo3d_signal, GST_TYPE_BASE_TRANSFORM);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dsignal, "pseudo3dsignal", GST_RANK_NONE, GST_TYPE_PSEUDO3D_SIGNAL);

#define SIGNAL_CAPS                                                                      \
  "video/x-h264, stream-format=(string){ byte-stream, avc, avc3 }, alignment=(string)au; " \
  "video/x-h265, stream-format=(string){ byte-stream, hvc1, hev1 }, alignment=(string)au"

static GstStaticPadTemplate sink_template =
    GST_STATIC_PAD_TEMPLATE("sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(SIGNAL_CAPS));
static GstStaticPadTemplate src_template =
    GST_STATIC_PAD_TEMPLATE("src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(SIGNAL_CAPS));

// Whether caps structure s says the right view comes first.
static bool right_view_first(const GstStructure *s) {
  guint flags = 0, mask = 0;
  return gst_structure_get_flagset(s, "multiview-flags", &flags, &mask) &&
         (flags & mask & GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_VIEW_FIRST) != 0;
}

// Downstream the stream is mono as far as caps go; upstream it may be anything.
static GstCaps *gst_pseudo3d_signal_transform_caps(GstBaseTransform *, GstPadDirection direction, GstCaps *caps,
                                                   GstCaps *filter) {
  GstCaps *out = gst_caps_copy(caps);
  for (guint i = 0; i < gst_caps_get_size(out); ++i) {
    GstStructure *s = gst_caps_get_structure(out, i);
    gst_structure_remove_fields(s, "multiview-mode", "multiview-flags", "views", NULL);
    if (direction == GST_PAD_SINK) gst_structure_set(s, "multiview-mode", G_TYPE_STRING, "mono", NULL);
  }
  if (filter) {
    GstCaps *tmp = gst_caps_intersect_full(filter, out, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(out);
    out = tmp;
  }
  return out;
}

// NAL length field size of avc/hvc1 streams, from codec_data (avcC byte 4 /
// hvcC byte 21, low two bits + 1); 4 when it cannot be read.
static int length_size_from_codec_data(const GstStructure *s, p3d::gst::NalSyntax syntax) {
  const GValue *v = gst_structure_get_value(s, "codec_data");
  if (!v || !GST_VALUE_HOLDS_BUFFER(v)) return 4;
  GstBuffer *cd = gst_value_get_buffer(v);
  GstMapInfo map;
  int size = 4;
  if (gst_buffer_map(cd, &map, GST_MAP_READ)) {
    const gsize at = syntax == p3d::gst::NalSyntax::H264 ? 4 : 21;
    if (map.size > at) size = (map.data[at] & 0x03) + 1;
    gst_buffer_unmap(cd, &map);
  }
  return size;
}

static gboolean gst_pseudo3d_signal_set_caps(GstBaseTransform *trans, GstCaps *incaps, GstCaps *) {
  GstPseudo3DSignal *self = GST_PSEUDO3D_SIGNAL(trans);
  const GstStructure *s = gst_caps_get_structure(incaps, 0);
  self->syntax = gst_structure_has_name(s, "video/x-h265") ? p3d::gst::NalSyntax::H265 : p3d::gst::NalSyntax::H264;
  const gchar *format = gst_structure_get_string(s, "stream-format");
  self->length_size = g_strcmp0(format, "byte-stream") == 0 || !format ? 0 : length_size_from_codec_data(s, self->syntax);
  const gchar *mode = gst_structure_get_string(s, "multiview-mode");
  const GstVideoMultiviewMode m = mode ? gst_video_multiview_mode_from_caps_string(mode) : GST_VIDEO_MULTIVIEW_MODE_NONE;
  self->stereo = m != GST_VIDEO_MULTIVIEW_MODE_NONE && m != GST_VIDEO_MULTIVIEW_MODE_MONO &&
                 m != GST_VIDEO_MULTIVIEW_MODE_LEFT && m != GST_VIDEO_MULTIVIEW_MODE_RIGHT;
  self->right_first = right_view_first(s);
  GST_INFO_OBJECT(self, "%s stream, %s", self->stereo ? "stereo" : "2D",
                  self->right_first ? "right view first" : "left view first");
  if (self->stereo && self->syntax == p3d::gst::NalSyntax::H265)
    GST_ELEMENT_WARNING(self, STREAM, FORMAT, ("H.265 stereo: the muxer gets no stereo signalling"),
                        ("only a frame-packing SEI in the stream carries the layout, and x265enc writes none; the "
                         "muxers' own signalling is wrong for ffmpeg (Matroska's display size) or absent (MP4): "
                         "use H.264, or pseudo3d-mkvstereo on the finished Matroska file"));
  // A left-first stereo stream usually needs no rewrite (x264 writes left
  // first); the buffers are still checked, so other encoders are corrected too.
  return TRUE;
}

static GstFlowReturn gst_pseudo3d_signal_transform_ip(GstBaseTransform *trans, GstBuffer *buf) {
  GstPseudo3DSignal *self = GST_PSEUDO3D_SIGNAL(trans);
  if (!self->stereo) return GST_FLOW_OK;
  GstMapInfo map;
  if (!gst_buffer_map(buf, &map, GST_MAP_READWRITE)) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Could not map an encoded buffer"), (nullptr));
    return GST_FLOW_ERROR;
  }
  const int n = p3d::gst::set_sei_eye_order_in_buffer(map.data, map.size, self->syntax, self->length_size,
                                                      self->right_first);
  gst_buffer_unmap(buf, &map);
  if (n > 0) {
    self->rewritten += n;
    GST_LOG_OBJECT(self, "set the eye order of %d frame-packing SEI message(s)", n);
  }
  return GST_FLOW_OK;
}

static gboolean gst_pseudo3d_signal_start(GstBaseTransform *trans) {
  GstPseudo3DSignal *self = GST_PSEUDO3D_SIGNAL(trans);
  self->stereo = self->right_first = FALSE;
  self->rewritten = 0;
  return TRUE;
}

static void gst_pseudo3d_signal_class_init(GstPseudo3DSignalClass *klass) {
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass *trans_class = GST_BASE_TRANSFORM_CLASS(klass);
  gst_element_class_set_static_metadata(
      element_class, "pseudo3d stereo signalling for muxers", "Codec/Parser/Video",
      "Writes the eye order into the H.264/H.265 frame-packing SEI and keeps the multiview caps from the muxer, so "
      "MP4 and Matroska files read back right in GStreamer and ffmpeg",
      "pseudo3d developers");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);
  trans_class->transform_caps = GST_DEBUG_FUNCPTR(gst_pseudo3d_signal_transform_caps);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_pseudo3d_signal_set_caps);
  trans_class->transform_ip = GST_DEBUG_FUNCPTR(gst_pseudo3d_signal_transform_ip);
  trans_class->start = GST_DEBUG_FUNCPTR(gst_pseudo3d_signal_start);
  trans_class->passthrough_on_same_caps = FALSE;
  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_signal_debug, "pseudo3dsignal", 0, "pseudo3d stereo signalling");
}

static void gst_pseudo3d_signal_init(GstPseudo3DSignal *self) {
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), TRUE);
}
