/**
 * SECTION:element-pseudo3dpack
 * @title: pseudo3dpack
 *
 * Packs a full-resolution side-by-side stereo pair (pseudo3dwarp's output,
 * or any 2W x H side-by-side frame) into a display or delivery format:
 * anaglyph (red-cyan, green-magenta, amber-blue; Dubois, colour, half colour
 * or grey), side-by-side or top-bottom at full or half ("anamorphic")
 * resolution, row- or column-interleaved, checkerboard, or one view. Output
 * caps carry multiview-mode/multiview-flags so encoders and muxers can
 * signal the packing (half-aspect for the half formats, mono for anaglyph).
 * layout=side-by-side without swap-eyes passes buffers through.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 videotestsrc ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack layout=anaglyph glasses=red-cyan anaglyph-method=dubois ! videoconvert ! autovideosink
 * ]|
 */
#include "gstpseudo3dpack.h"

#include "enums.h"
#include "pack.h"
#include "video_util.h"

#if HAVE_CUDA
#include "pack_gpu.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_pack_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_pack_debug

enum { PROP_0, PROP_LAYOUT, PROP_GLASSES, PROP_ANAGLYPH_METHOD, PROP_SWAP_EYES };

struct _GstPseudo3DPack {
  GstPseudo3DBase parent;
  p3d::PackParams params;
};

#define gst_pseudo3d_pack_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DPack, gst_pseudo3d_pack, GST_TYPE_PSEUDO3D_BASE);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dpack, "pseudo3dpack", GST_RANK_NONE, GST_TYPE_PSEUDO3D_PACK);

static p3d::PackParams read_params(GstPseudo3DPack *self) {
  GST_OBJECT_LOCK(self);
  const p3d::PackParams p = self->params;
  GST_OBJECT_UNLOCK(self);
  return p;
}

// Output size over the 2W x H input, per axis (pack_size() in ratio form).
static void get_size_ratio(GstPseudo3DBase *base, gint *wn, gint *wd, gint *hn, gint *hd) {
  const p3d::PackLayout layout = read_params(GST_PSEUDO3D_PACK(base)).layout;
  *wn = *wd = *hn = *hd = 1;
  switch (layout) {
    case p3d::PackLayout::SideBySide: break;
    case p3d::PackLayout::TopBottom:
      *wd = 2;
      *hn = 2;
      break;
    default: *wd = 2; break;
  }
}

static void set_src_multiview(GstPseudo3DBase *base, GstStructure *s) {
  const p3d::PackLayout layout = read_params(GST_PSEUDO3D_PACK(base)).layout;
  const char *mode = "mono";
  guint flags = 0;
  gint par_n = 1, par_d = 1;  // factor on the input's pixel-aspect-ratio
  switch (layout) {
    case p3d::PackLayout::Anaglyph: mode = "mono"; break;
    case p3d::PackLayout::SideBySide: mode = "side-by-side"; break;
    case p3d::PackLayout::SideBySideHalf:
      mode = "side-by-side";
      flags = GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT;
      par_n = 2;  // as gst_video_info_to_caps folds half-aspect into the PAR
      break;
    case p3d::PackLayout::TopBottom: mode = "top-bottom"; break;
    case p3d::PackLayout::TopBottomHalf:
      mode = "top-bottom";
      flags = GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT;
      par_d = 2;
      break;
    case p3d::PackLayout::RowInterleaved: mode = "row-interleaved"; break;
    case p3d::PackLayout::ColumnInterleaved: mode = "column-interleaved"; break;
    case p3d::PackLayout::Checkerboard: mode = "checkerboard"; break;
    case p3d::PackLayout::Left: mode = "left"; break;
    case p3d::PackLayout::Right: mode = "right"; break;
  }
  gst_structure_set(s, "multiview-mode", G_TYPE_STRING, mode, "multiview-flags", GST_TYPE_VIDEO_MULTIVIEW_FLAGSET,
                    flags, GST_FLAG_SET_MASK_EXACT, NULL);
  if (par_n != par_d) {
    gint n = 1, d = 1;
    if (gst_structure_get_fraction(s, "pixel-aspect-ratio", &n, &d) || !gst_structure_has_field(s, "pixel-aspect-ratio"))
      gst_structure_set(s, "pixel-aspect-ratio", GST_TYPE_FRACTION, n * par_n, d * par_d, NULL);
  }
}

static void update_passthrough(GstPseudo3DPack *self) {
  const p3d::PackParams p = read_params(self);
  // The input already is a full side-by-side pair.
  gst_base_transform_set_passthrough(GST_BASE_TRANSFORM(self),
                                     p.layout == p3d::PackLayout::SideBySide && !p.swap_eyes);
}

static gboolean set_info(GstPseudo3DBase *base, GstCaps *, GstVideoInfo *in, GstCaps *, GstVideoInfo *out) {
  int w = 0, h = 0;
  const p3d::PackParams p = read_params(GST_PSEUDO3D_PACK(base));
  p3d::pack_size(p.layout, GST_VIDEO_INFO_WIDTH(in) / 2, GST_VIDEO_INFO_HEIGHT(in), &w, &h);
  if (GST_VIDEO_INFO_WIDTH(in) % 2 != 0 || w != GST_VIDEO_INFO_WIDTH(out) || h != GST_VIDEO_INFO_HEIGHT(out)) {
    GST_ELEMENT_ERROR(base, CORE, NEGOTIATION, ("Input is not a side-by-side pair of the expected size"),
                      ("input %dx%d, output %dx%d, expected output %dx%d", GST_VIDEO_INFO_WIDTH(in),
                       GST_VIDEO_INFO_HEIGHT(in), GST_VIDEO_INFO_WIDTH(out), GST_VIDEO_INFO_HEIGHT(out), w, h));
    return FALSE;
  }
  update_passthrough(GST_PSEUDO3D_PACK(base));
  return TRUE;
}

static GstFlowReturn process(GstPseudo3DBase *base, GstPseudo3DPath path, GstBuffer *, GstVideoFrame *in,
                             GstVideoFrame *out) {
  const p3d::PackParams params = read_params(GST_PSEUDO3D_PACK(base));
  const p3d::FrameView src = p3d::gst::frame_view(in), dst = p3d::gst::frame_view(out);
#if HAVE_CUDA
  if (path != GST_PSEUDO3D_PATH_CPU) {
    using p3d::gst::GpuStaging;
    const p3d::CudaStatus st = [&]() -> p3d::CudaStatus {
      p3d::FrameView fin, fout;
      P3D_CUDA_TRY_STATUS(p3d::gst::device_frame(base, path, GpuStaging::kInput, src, true, &fin));
      P3D_CUDA_TRY_STATUS(p3d::gst::device_frame(base, path, GpuStaging::kOutput, dst, false, &fout));
      P3D_CUDA_TRY_STATUS(p3d::pack_gpu(params, fin, fout, base->stream));
      return p3d::gst::frame_to_host(base, path, fout, dst);
    }();
    if (!st.ok()) return gst_pseudo3d_base_cuda_error(base, st, "packing the stereo pair");
    return gst_pseudo3d_base_sync(base);
  }
#else
  (void)path;
#endif
  p3d::pack_cpu(params, src, dst);
  return GST_FLOW_OK;
}

static void gst_pseudo3d_pack_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_LAYOUT: self->params.layout = static_cast<p3d::PackLayout>(g_value_get_enum(value)); break;
    case PROP_GLASSES: self->params.glasses = static_cast<p3d::AnaglyphGlasses>(g_value_get_enum(value)); break;
    case PROP_ANAGLYPH_METHOD: self->params.method = static_cast<p3d::AnaglyphMethod>(g_value_get_enum(value)); break;
    case PROP_SWAP_EYES: self->params.swap_eyes = g_value_get_boolean(value); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
  update_passthrough(self);
  // The layout decides the output size and multiview caps.
  if (prop_id == PROP_LAYOUT) gst_base_transform_reconfigure_src(GST_BASE_TRANSFORM(self));
}

static void gst_pseudo3d_pack_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(object);
  GST_OBJECT_LOCK(self);
  switch (prop_id) {
    case PROP_LAYOUT: g_value_set_enum(value, static_cast<gint>(self->params.layout)); break;
    case PROP_GLASSES: g_value_set_enum(value, static_cast<gint>(self->params.glasses)); break;
    case PROP_ANAGLYPH_METHOD: g_value_set_enum(value, static_cast<gint>(self->params.method)); break;
    case PROP_SWAP_EYES: g_value_set_boolean(value, self->params.swap_eyes); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
  GST_OBJECT_UNLOCK(self);
}

static void gst_pseudo3d_pack_class_init(GstPseudo3DPackClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstPseudo3DBaseClass *base_class = GST_PSEUDO3D_BASE_CLASS(klass);
  const p3d::PackParams d;
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING);

  gobject_class->set_property = gst_pseudo3d_pack_set_property;
  gobject_class->get_property = gst_pseudo3d_pack_get_property;

  g_object_class_install_property(
      gobject_class, PROP_LAYOUT,
      g_param_spec_enum("layout", "Layout",
                        "Stereo format of the output (changing it renegotiates the output caps)",
                        GST_TYPE_PSEUDO3D_LAYOUT, static_cast<gint>(d.layout), flags));
  g_object_class_install_property(
      gobject_class, PROP_GLASSES,
      g_param_spec_enum("glasses", "Anaglyph glasses", "Colour filters of the glasses (layout=anaglyph)",
                        GST_TYPE_PSEUDO3D_GLASSES, static_cast<gint>(d.glasses), flags));
  g_object_class_install_property(
      gobject_class, PROP_ANAGLYPH_METHOD,
      g_param_spec_enum("anaglyph-method", "Anaglyph method",
                        "How colours are mixed for the glasses (layout=anaglyph): Dubois least squares ghosts "
                        "least; colour keeps most colour; grey is the most comfortable",
                        GST_TYPE_PSEUDO3D_ANAGLYPH_METHOD, static_cast<gint>(d.method), flags));
  g_object_class_install_property(
      gobject_class, PROP_SWAP_EYES,
      g_param_spec_boolean("swap-eyes", "Swap eyes",
                           "Exchange the left and right views (cross-eyed viewing, reversed glasses)", d.swap_eyes,
                           flags));

  gst_element_class_set_static_metadata(element_class, "pseudo3d stereo packing", "Filter/Converter/Video",
                                        "Packs a side-by-side stereo pair into anaglyph, side-by-side, top-bottom, "
                                        "interleaved or single-view output",
                                        "pseudo3d developers");
  GstCaps *caps = p3d::gst::caps_all_domains(P3D_PACKED_FORMATS);
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS, caps));
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, caps));
  gst_caps_unref(caps);

  base_class->get_size_ratio = get_size_ratio;
  base_class->set_src_multiview = set_src_multiview;
  base_class->set_info = set_info;
  base_class->process = process;

  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_pack_debug, "pseudo3dpack", 0, "pseudo3d stereo packing");
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_LAYOUT, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_GLASSES, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_ANAGLYPH_METHOD, (GstPluginAPIFlags)0);
}

static void gst_pseudo3d_pack_init(GstPseudo3DPack *self) {
  self->params = p3d::PackParams();
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), FALSE);
  update_passthrough(self);
}
