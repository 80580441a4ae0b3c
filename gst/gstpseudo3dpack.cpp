/**
 * SECTION:element-pseudo3dpack
 * @title: pseudo3dpack
 *
 * A stereo converter: reads a stereo frame (pseudo3dwarp's full side-by-side
 * pair, or any side-by-side, top-bottom, row/column-interleaved or
 * checkerboard frame, full or half resolution, either eye first, as its
 * caps' multiview-mode and multiview-flags declare) and writes it as an
 * anaglyph (red-cyan, green-magenta, amber-blue; Dubois, colour, half colour
 * or grey), side-by-side or top-bottom at full or half ("anamorphic")
 * resolution, row- or column-interleaved, checkerboard, or one view. The
 * output caps follow GStreamer's multiview conventions, so encoders and
 * muxers signal the packing: multiview-mode per layout, half-aspect on every
 * layout whose views are squeezed, the pixel-aspect-ratio of the input kept,
 * right-view-first exactly when swap-eyes puts the right view first.
 *
 * The output is in the input's packed RGB format, or NV12/I420 when
 * downstream asks for it (an encoder's caps): the pair is packed and
 * converted in one pass (BT.709/BT.601 and the range from the output caps'
 * colorimetry, chroma the mean of each 2x2 block), on the GPU when the
 * frames are there, so no videoconvert and a third of the bytes to
 * download.
 *
 * Plain 2D input is refused: declare how the frame holds the pair with
 * input-layout (and input-right-first). An output in the input's own
 * arrangement and eye order passes buffers through.
 *
 * Every property can be changed while playing; a change that alters the
 * output caps is renegotiated before the next frame, and each frame is
 * packed with the values its caps belong to.
 *
 * ## Example launch lines
 * |[
 * gst-launch-1.0 videotestsrc ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack layout=anaglyph glasses=red-cyan anaglyph-method=dubois ! videoconvert ! autovideosink
 * gst-launch-1.0 filesrc location=sbs-film.mkv ! decodebin ! videoconvert ! pseudo3dpack layout=top-bottom-half ! videoconvert ! autovideosink
 * gst-launch-1.0 filesrc location=film.mp4 ! decodebin ! videoconvert ! pseudo3dconvert layout=side-by-side-half ! video/x-raw,format=I420 ! x264enc frame-packing=side-by-side ! mp4mux ! filesink location=film-3d.mp4
 * ]| The second line turns a film whose caps say side-by-side into half
 * top-bottom for a passive 3D TV; the third packs straight into the
 * encoder's I420.
 */
#include "gstpseudo3dpack.h"

#include "caps_geometry.h"
#include "enums.h"
#include "pack.h"
#include "stage_gpu.h"
#include "staged_geometry.h"
#include "stereo_caps.h"
#include "video_util.h"

#if HAVE_CUDA
#include "pack_gpu.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_pack_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_pack_debug

enum {
  PROP_0,
  PROP_LAYOUT,
  PROP_GLASSES,
  PROP_ANAGLYPH_METHOD,
  PROP_SWAP_EYES,
  PROP_INPUT_LAYOUT,
  PROP_INPUT_RIGHT_FIRST,
};

// The properties that decide the output caps (see staged_geometry.h).
struct PackGeometry {
  p3d::PackLayout layout = p3d::PackLayout::Anaglyph;
  bool swap_eyes = false;
  GstPseudo3DInputLayout input = GST_PSEUDO3D_INPUT_LAYOUT_FROM_CAPS;
  bool input_right_first = false;
  bool operator==(const PackGeometry &o) const {
    return layout == o.layout && swap_eyes == o.swap_eyes && input == o.input &&
           input_right_first == o.input_right_first;
  }
};

struct _GstPseudo3DPack {
  GstPseudo3DBase parent;
  /* object lock */
  p3d::PackParams params;  // glasses and method are read per frame; the rest through geometry
  p3d::gst::StagedGeometry<PackGeometry> *geometry;
  p3d::PackParams active;  // the geometry of the negotiated caps, resolved against the input caps
};

#define gst_pseudo3d_pack_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DPack, gst_pseudo3d_pack, GST_TYPE_PSEUDO3D_BASE);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dpack, "pseudo3dpack", GST_RANK_NONE, GST_TYPE_PSEUDO3D_PACK);

// A declared input layout, or none (from-caps).
static bool declared_input(const PackGeometry &g, p3d::StereoInput *arrangement) {
  if (g.input == GST_PSEUDO3D_INPUT_LAYOUT_FROM_CAPS) return false;
  *arrangement = static_cast<p3d::StereoInput>(g.input - 1);
  return true;
}

// The parameters a frame of this input is packed with: the geometry plus the
// input arrangement (declared, or read from the input's multiview signal).
// False, with *why, when the input holds no stereo pair pseudo3dpack reads.
static bool resolve(const PackGeometry &g, GstVideoMultiviewMode mode, GstVideoMultiviewFlags flags,
                    p3d::PackParams *p, const char **why) {
  p->layout = g.layout;
  p->swap_eyes = g.swap_eyes;
  if (declared_input(g, &p->input)) {
    p->input_right_first = g.input_right_first;
    return true;
  }
  return p3d::gst::arrangement_from_multiview(mode, flags, &p->input, &p->input_right_first, why);
}

// Output size over input size per axis, as a ratio, for views of `input`.
static void size_ratio(p3d::StereoInput input, p3d::PackLayout layout, gint *wn, gint *wd, gint *hn, gint *hd) {
  p3d::pack_size(layout, 1, 1, wn, hn);  // the layout's frame of views of 1 x 1
  *wd = input == p3d::StereoInput::SideBySide ? 2 : 1;
  *hd = input == p3d::StereoInput::TopBottom ? 2 : 1;
}

// How a size goes through the element: towards the source, or back to the
// input size that gives it exactly, or back to every input size whose
// rounded image it is (gst_pseudo3d_sizes_back()).
enum class SizeWay { ToSrc, BackExact, BackRounded };

// One input arrangement's variant of a caps structure.
static GstStructure *transformed(const GstStructure *in, SizeWay way, p3d::StereoInput input,
                                 const PackGeometry &g) {
  gint wn, wd, hn, hd;
  size_ratio(input, g.layout, &wn, &wd, &hn, &hd);
  if (way == SizeWay::ToSrc) return gst_pseudo3d_sizes_forward(in, wn, wd, hn, hd);
  return gst_pseudo3d_sizes_back(in, wn, wd, hn, hd, way == SizeWay::BackRounded);
}

static GstCaps *transform_geometry(GstPseudo3DBase *base, GstPadDirection from, const GstStructure *in) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(base);
  GST_OBJECT_LOCK(self);
  const PackGeometry g = self->geometry->negotiating();
  GST_OBJECT_UNLOCK(self);
  p3d::StereoInput input;
  const bool declared = declared_input(g, &input);

  if (from == GST_PAD_SINK) {
    bool right_first = false;
    const char *why = nullptr;
    // Input that holds no pair still gets output caps: set_info then refuses
    // it with a message that says how to declare the layout.
    if (!declared && !p3d::gst::arrangement_from_structure(in, &input, &right_first, &why))
      input = p3d::StereoInput::SideBySide;
    GstStructure *s = transformed(in, SizeWay::ToSrc, input, g);
    p3d::gst::set_multiview_fields(s, p3d::gst::layout_signal(g.layout, g.swap_eyes), GST_FLAG_SET_MASK_EXACT);
    return p3d::gst::packed_output_caps(s);  // the input's own format, then 4:2:0
  }
  // Towards the sink, 4:2:0 output comes from any packed RGB input.
  const bool from_yuv = p3d::gst::names_yuv420(in);

  // Towards the sink: the input sizes that give this output. A declared
  // layout says nothing about the input's caps. From-caps lists first a
  // structure that leaves multiview-mode open, so that upstream elements
  // that do not set it (2D video) keep it unset rather than fixating the
  // first stereo mode offered here, which would relabel 2D frames as a
  // pair: set_info then refuses them with a message. The arrangements
  // pseudo3dpack reads follow (either eye first).
  // The exact sizes first, then the rounded ones (gst_pseudo3d_sizes_back()).
  GstCaps *caps = gst_caps_new_empty();
  for (const SizeWay way : {SizeWay::BackExact, SizeWay::BackRounded}) {
    GstStructure *open = transformed(in, way, declared ? input : p3d::StereoInput::SideBySide, g);
    gst_structure_remove_fields(open, "multiview-mode", "multiview-flags", "views", NULL);
    if (from_yuv) gst_pseudo3d_set_formats(open, P3D_PACKED_FORMATS);
    caps = gst_caps_merge_structure(caps, open);
    if (declared) continue;
    for (const auto &name : p3d::kStereoInputNames) {
      const p3d::StereoInput arrangement = name.value;
      GstStructure *s = transformed(in, way, arrangement, g);
      if (from_yuv) gst_pseudo3d_set_formats(s, P3D_PACKED_FORMATS);
      p3d::gst::set_multiview_fields(s, p3d::gst::arrangement_signal(arrangement, false),
                                     GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT);
      caps = gst_caps_merge_structure(caps, s);
    }
  }
  return caps;
}

// The output frame the parameters give for this input, or false with *why.
static bool output_for(const p3d::PackParams &p, const GstVideoInfo *in, int *w, int *h, const char **why) {
  int vw = 0, vh = 0;
  if (!p3d::input_view_size(p.input, GST_VIDEO_INFO_WIDTH(in), GST_VIDEO_INFO_HEIGHT(in), &vw, &vh)) {
    *why = p.input == p3d::StereoInput::TopBottom ? "a full top-bottom pair needs an even height"
                                                  : "a full side-by-side pair needs an even width";
    return false;
  }
  p3d::pack_size(p.layout, vw, vh, w, h);
  return true;
}

// Output equal to the input: same arrangement, eye order and format.
static bool passes_through(const p3d::PackParams &p, const GstVideoInfo *in, const GstVideoInfo *out) {
  return p3d::pack_is_identity(p) && GST_VIDEO_INFO_FORMAT(in) == GST_VIDEO_INFO_FORMAT(out);
}

static gboolean set_info(GstPseudo3DBase *base, GstCaps *, GstVideoInfo *in, GstCaps *, GstVideoInfo *out) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(base);
  GST_OBJECT_LOCK(self);
  const PackGeometry g = self->geometry->commit();
  GST_OBJECT_UNLOCK(self);
  p3d::PackParams p;
  const char *why = nullptr;
  if (!resolve(g, GST_VIDEO_INFO_MULTIVIEW_MODE(in), GST_VIDEO_INFO_MULTIVIEW_FLAGS(in), &p, &why)) {
    gchar *text = g_strdup_printf("pseudo3dpack needs a stereo pair, and its input is %s", why);
    gst_pseudo3d_base_refuse_caps(
        base, text, "%s",
        "declare how the frames hold the pair with input-layout=side-by-side (or side-by-side-half, top-bottom, "
        "top-bottom-half, row-interleaved, column-interleaved, checkerboard) and input-right-first=true if the right "
        "view comes first; to make 3D from 2D video, put pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp before "
        "pseudo3dpack, or use pseudo3dconvert");
    g_free(text);
    return FALSE;
  }
  int w = 0, h = 0;
  if (!output_for(p, in, &w, &h, &why) || w != GST_VIDEO_INFO_WIDTH(out) || h != GST_VIDEO_INFO_HEIGHT(out)) {
    return gst_pseudo3d_base_refuse_caps(base, "The input frame does not hold a stereo pair of the declared kind",
                                         "input %dx%d, output %dx%d: %s", GST_VIDEO_INFO_WIDTH(in),
                                         GST_VIDEO_INFO_HEIGHT(in), GST_VIDEO_INFO_WIDTH(out),
                                         GST_VIDEO_INFO_HEIGHT(out), why ? why : "the output size does not fit the layout");
  }
  if (!GST_VIDEO_INFO_IS_RGB(out)) p.yuv = p3d::gst::rgb_to_yuv(out);
  GST_OBJECT_LOCK(self);
  p.glasses = self->params.glasses;
  p.method = self->params.method;
  self->active = p;
  GST_OBJECT_UNLOCK(self);
  gst_base_transform_set_passthrough(GST_BASE_TRANSFORM(self), passes_through(p, in, out));
  return TRUE;
}

// A request whose output caps equal the negotiated ones (swap-eyes of an
// anaglyph, or a declared input layout that the caps already said) takes
// effect at once; any other asks for renegotiation.
static gboolean frame_boundary(GstPseudo3DBase *base) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(base);
  GST_OBJECT_LOCK(self);
  const bool pending = self->geometry->pending();
  const PackGeometry want = self->geometry->requested();
  GST_OBJECT_UNLOCK(self);
  if (!pending) return FALSE;
  const GstVideoInfo *in = &base->in_info, *out = &base->out_info;
  p3d::PackParams p;
  const char *why = nullptr;
  int w = 0, h = 0;
  if (!resolve(want, GST_VIDEO_INFO_MULTIVIEW_MODE(in), GST_VIDEO_INFO_MULTIVIEW_FLAGS(in), &p, &why) ||
      !output_for(p, in, &w, &h, &why))
    return TRUE;  // renegotiation will say why
  const p3d::gst::MultiviewSignal sig = p3d::gst::layout_signal(p.layout, p.swap_eyes);
  if (w != GST_VIDEO_INFO_WIDTH(out) || h != GST_VIDEO_INFO_HEIGHT(out) ||
      sig.mode != GST_VIDEO_INFO_MULTIVIEW_MODE(out) || sig.flags != GST_VIDEO_INFO_MULTIVIEW_FLAGS(out))
    return TRUE;
  GST_OBJECT_LOCK(self);
  self->geometry->activate(want);
  p.glasses = self->params.glasses;
  p.method = self->params.method;
  p.yuv = self->active.yuv;
  const bool was_identity = passes_through(self->active, in, out);
  self->active = p;
  GST_OBJECT_UNLOCK(self);
  if (was_identity != passes_through(p, in, out)) {
    gst_base_transform_set_passthrough(GST_BASE_TRANSFORM(self), passes_through(p, in, out));
    gst_base_transform_reconfigure_src(GST_BASE_TRANSFORM(self));  // redo the allocation
  }
  return FALSE;
}

static GstFlowReturn process(GstPseudo3DBase *base, GstPseudo3DPath path, GstBuffer *, GstVideoFrame *in,
                             GstVideoFrame *out) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(base);
  GST_OBJECT_LOCK(self);
  p3d::PackParams params = self->active;
  params.glasses = self->params.glasses;
  params.method = self->params.method;
  GST_OBJECT_UNLOCK(self);
  const p3d::FrameView src = p3d::gst::frame_view(in), dst = p3d::gst::frame_view(out);
#if HAVE_CUDA
  if (path == GST_PSEUDO3D_PATH_GPU)
    return p3d::gst::run_gpu(base, "packing the stereo pair", [&] {
      return p3d::pack_gpu(params, src, dst, base->gpu->stream());
    });
#else
  (void)path;
#endif
  p3d::pack_cpu(params, src, dst);
  return GST_FLOW_OK;
}

static void gst_pseudo3d_pack_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(object);
  GST_OBJECT_LOCK(self);
  PackGeometry g = self->geometry->requested();
  bool geometry = true;
  switch (prop_id) {
    case PROP_LAYOUT: g.layout = static_cast<p3d::PackLayout>(g_value_get_enum(value)); break;
    case PROP_SWAP_EYES: g.swap_eyes = g_value_get_boolean(value); break;
    case PROP_INPUT_LAYOUT: g.input = g_value_get_enum(value); break;
    case PROP_INPUT_RIGHT_FIRST: g.input_right_first = g_value_get_boolean(value); break;
    case PROP_GLASSES:
      self->params.glasses = static_cast<p3d::AnaglyphGlasses>(g_value_get_enum(value));
      geometry = false;
      break;
    case PROP_ANAGLYPH_METHOD:
      self->params.method = static_cast<p3d::AnaglyphMethod>(g_value_get_enum(value));
      geometry = false;
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      geometry = false;
      break;
  }
  const bool reconfigure = geometry && self->geometry->request(g);
  GST_OBJECT_UNLOCK(self);
  if (reconfigure) gst_base_transform_reconfigure_src(GST_BASE_TRANSFORM(self));
}

static void gst_pseudo3d_pack_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(object);
  GST_OBJECT_LOCK(self);
  const PackGeometry g = self->geometry->requested();
  switch (prop_id) {
    case PROP_LAYOUT: g_value_set_enum(value, static_cast<gint>(g.layout)); break;
    case PROP_SWAP_EYES: g_value_set_boolean(value, g.swap_eyes); break;
    case PROP_INPUT_LAYOUT: g_value_set_enum(value, g.input); break;
    case PROP_INPUT_RIGHT_FIRST: g_value_set_boolean(value, g.input_right_first); break;
    case PROP_GLASSES: g_value_set_enum(value, static_cast<gint>(self->params.glasses)); break;
    case PROP_ANAGLYPH_METHOD: g_value_set_enum(value, static_cast<gint>(self->params.method)); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_pack_finalize(GObject *object) {
  delete GST_PSEUDO3D_PACK(object)->geometry;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pseudo3d_pack_class_init(GstPseudo3DPackClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstPseudo3DBaseClass *base_class = GST_PSEUDO3D_BASE_CLASS(klass);
  const p3d::PackParams d;
  const PackGeometry dg;
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING);

  gobject_class->set_property = gst_pseudo3d_pack_set_property;
  gobject_class->get_property = gst_pseudo3d_pack_get_property;
  gobject_class->finalize = gst_pseudo3d_pack_finalize;

  g_object_class_install_property(
      gobject_class, PROP_LAYOUT,
      g_param_spec_enum("layout", "Layout",
                        "Stereo format of the output (a change while playing renegotiates the output caps before "
                        "the next frame)",
                        GST_TYPE_PSEUDO3D_LAYOUT, static_cast<gint>(dg.layout), flags));
  g_object_class_install_property(
      gobject_class, PROP_GLASSES,
      g_param_spec_enum("glasses", "Anaglyph glasses", "Colour filters of the glasses (layout=anaglyph)",
                        GST_TYPE_PSEUDO3D_GLASSES, static_cast<gint>(d.glasses), flags));
  g_object_class_install_property(
      gobject_class, PROP_ANAGLYPH_METHOD,
      g_param_spec_enum("anaglyph-method", "Anaglyph method",
                        "How colours are mixed for the glasses (layout=anaglyph): Dubois least squares ghosts "
                        "least; colour keeps most colour; grey is the most comfortable. Encode anaglyphs as RGB or "
                        "4:4:4: 4:2:0 chroma smears the red channel",
                        GST_TYPE_PSEUDO3D_ANAGLYPH_METHOD, static_cast<gint>(d.method), flags));
  g_object_class_install_property(
      gobject_class, PROP_SWAP_EYES,
      g_param_spec_boolean("swap-eyes", "Swap eyes",
                           "Exchange the left and right views (cross-eyed viewing, reversed glasses); the output "
                           "caps then say right-view-first",
                           dg.swap_eyes, flags));
  g_object_class_install_property(
      gobject_class, PROP_INPUT_LAYOUT,
      g_param_spec_enum("input-layout", "Input layout",
                        "How the input frames hold the stereo pair: from the caps' multiview-mode and "
                        "multiview-flags (pseudo3dwarp, 3D decoders and demuxers set them), or declared here for "
                        "input whose caps say nothing (plain 2D caps). While playing, a layout the frames cannot "
                        "hold (top-bottom of an odd height) is refused with a warning and the stream goes on",
                        GST_TYPE_PSEUDO3D_INPUT_LAYOUT, dg.input, flags));
  g_object_class_install_property(
      gobject_class, PROP_INPUT_RIGHT_FIRST,
      g_param_spec_boolean("input-right-first", "Input right view first",
                           "With a declared input-layout: the right view comes first (left half, top half, even "
                           "rows or columns); with from-caps the caps' right-view-first flag decides",
                           dg.input_right_first, flags));

  gst_element_class_set_static_metadata(element_class, "pseudo3d stereo packing", "Filter/Converter/Video",
                                        "Converts a stereo pair into anaglyph, side-by-side, top-bottom, "
                                        "interleaved or single-view output",
                                        "pseudo3d developers");
  // Packed RGB in; out the same format, or NV12/I420 for encoders.
  GstCaps *sink = p3d::gst::caps_all_domains(P3D_PACKED_FORMATS, 2 * p3d::kMaxFrameSide);
  GstCaps *src = p3d::gst::caps_all_domains(P3D_ALL_FORMATS, 2 * p3d::kMaxFrameSide);
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS, sink));
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, src));
  gst_caps_unref(sink);
  gst_caps_unref(src);

  base_class->transform_geometry = transform_geometry;
  base_class->set_info = set_info;
  base_class->frame_boundary = frame_boundary;
  base_class->process = process;

  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_pack_debug, "pseudo3dpack", 0, "pseudo3d stereo packing");
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_LAYOUT, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_GLASSES, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_ANAGLYPH_METHOD, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_INPUT_LAYOUT, (GstPluginAPIFlags)0);
}

static void gst_pseudo3d_pack_init(GstPseudo3DPack *self) {
  self->params = p3d::PackParams();
  self->geometry = new p3d::gst::StagedGeometry<PackGeometry>();
  GST_PSEUDO3D_BASE(self)->staged = self->geometry;
  self->active = p3d::PackParams();
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), FALSE);
}
