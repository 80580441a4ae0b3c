/**
 * SECTION:element-pseudo3dconvert
 * @title: pseudo3dconvert
 *
 * The whole 2D-to-3D chain in one element: pseudo3ddepth ! pseudo3dfilter !
 * pseudo3dwarp ! pseudo3dpack, exposing the stages' main properties under
 * the same names. Usable wherever one video filter is expected, such as
 * playbin's video-filter.
 *
 * ## Example launch lines
 * |[
 * gst-launch-1.0 playbin uri=file:///path/movie.mp4 video-filter="pseudo3dconvert layout=anaglyph"
 * gst-launch-1.0 videotestsrc ! pseudo3dconvert layout=side-by-side-half ! videoconvert ! autovideosink
 * ]|
 */
#include "gstpseudo3dconvert.h"

#include "gstpseudo3ddepth.h"
#include "gstpseudo3dfilter.h"
#include "gstpseudo3dpack.h"
#include "gstpseudo3dwarp.h"

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_convert_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_convert_debug

enum Stage { STAGE_DEPTH, STAGE_FILTER, STAGE_WARP, STAGE_PACK, N_STAGES };

// The proxied properties: property id - 1 indexes this table.
static const struct {
  Stage stage;
  const char *name;
} kProxied[] = {
    {STAGE_DEPTH, "method"},          {STAGE_DEPTH, "hypothesis"},      {STAGE_DEPTH, "temporal-smoothing"},
    {STAGE_FILTER, "radius"},         {STAGE_FILTER, "sigma-space"},    {STAGE_FILTER, "sigma-range"},
    {STAGE_WARP, "max-disparity"},    {STAGE_WARP, "convergence"},      {STAGE_WARP, "view"},
    {STAGE_WARP, "fill"},             {STAGE_PACK, "layout"},           {STAGE_PACK, "glasses"},
    {STAGE_PACK, "anaglyph-method"},  {STAGE_PACK, "swap-eyes"},
};
#define PROP_CUDA_DEVICE_ID (G_N_ELEMENTS(kProxied) + 1)

struct _GstPseudo3DConvert {
  GstBin parent;
  GstElement *stage[N_STAGES];
};

#define gst_pseudo3d_convert_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DConvert, gst_pseudo3d_convert, GST_TYPE_BIN);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dconvert, "pseudo3dconvert", GST_RANK_NONE, GST_TYPE_PSEUDO3D_CONVERT);

// A pspec for the bin with the child's name, range, default and blurb.
static GParamSpec *clone_pspec(GParamSpec *p) {
  const char *name = g_param_spec_get_name(p), *nick = g_param_spec_get_nick(p), *blurb = g_param_spec_get_blurb(p);
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | (p->flags & (GST_PARAM_MUTABLE_PLAYING | GST_PARAM_MUTABLE_READY)));
  if (G_IS_PARAM_SPEC_ENUM(p)) {
    auto *e = G_PARAM_SPEC_ENUM(p);
    return g_param_spec_enum(name, nick, blurb, p->value_type, e->default_value, flags);
  }
  if (G_IS_PARAM_SPEC_INT(p)) {
    auto *i = G_PARAM_SPEC_INT(p);
    return g_param_spec_int(name, nick, blurb, i->minimum, i->maximum, i->default_value, flags);
  }
  if (G_IS_PARAM_SPEC_FLOAT(p)) {
    auto *f = G_PARAM_SPEC_FLOAT(p);
    return g_param_spec_float(name, nick, blurb, f->minimum, f->maximum, f->default_value, flags);
  }
  if (G_IS_PARAM_SPEC_BOOLEAN(p))
    return g_param_spec_boolean(name, nick, blurb, G_PARAM_SPEC_BOOLEAN(p)->default_value, flags);
  g_return_val_if_reached(nullptr);
}

static void gst_pseudo3d_convert_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DConvert *self = GST_PSEUDO3D_CONVERT(object);
  if (prop_id == PROP_CUDA_DEVICE_ID) {
    for (GstElement *e : self->stage) g_object_set_property(G_OBJECT(e), "cuda-device-id", value);
  } else if (prop_id >= 1 && prop_id <= G_N_ELEMENTS(kProxied)) {
    g_object_set_property(G_OBJECT(self->stage[kProxied[prop_id - 1].stage]), kProxied[prop_id - 1].name, value);
  } else {
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
  }
}

static void gst_pseudo3d_convert_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DConvert *self = GST_PSEUDO3D_CONVERT(object);
  if (prop_id == PROP_CUDA_DEVICE_ID) {
    g_object_get_property(G_OBJECT(self->stage[STAGE_DEPTH]), "cuda-device-id", value);
  } else if (prop_id >= 1 && prop_id <= G_N_ELEMENTS(kProxied)) {
    g_object_get_property(G_OBJECT(self->stage[kProxied[prop_id - 1].stage]), kProxied[prop_id - 1].name, value);
  } else {
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
  }
}

static void gst_pseudo3d_convert_class_init(GstPseudo3DConvertClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  gobject_class->set_property = gst_pseudo3d_convert_set_property;
  gobject_class->get_property = gst_pseudo3d_convert_get_property;

  const GType stage_types[N_STAGES] = {GST_TYPE_PSEUDO3D_DEPTH, GST_TYPE_PSEUDO3D_FILTER, GST_TYPE_PSEUDO3D_WARP,
                                       GST_TYPE_PSEUDO3D_PACK};
  for (guint i = 0; i < G_N_ELEMENTS(kProxied); ++i) {
    auto *stage_class = static_cast<GObjectClass *>(g_type_class_ref(stage_types[kProxied[i].stage]));
    GParamSpec *p = g_object_class_find_property(stage_class, kProxied[i].name);
    g_object_class_install_property(gobject_class, i + 1, clone_pspec(p));
    g_type_class_unref(stage_class);
  }
  auto *depth_class = static_cast<GObjectClass *>(g_type_class_ref(GST_TYPE_PSEUDO3D_DEPTH));
  g_object_class_install_property(gobject_class, PROP_CUDA_DEVICE_ID,
                                  clone_pspec(g_object_class_find_property(depth_class, "cuda-device-id")));
  g_type_class_unref(depth_class);

  gst_element_class_set_static_metadata(element_class, "pseudo3d 2D-to-3D conversion", "Filter/Effect/Video",
                                        "Turns 2D video into stereo 3D: depth estimation, depth filtering, view "
                                        "synthesis and stereo packing in one element",
                                        "pseudo3d developers");
  GstElementClass *depth_eclass = GST_ELEMENT_CLASS(g_type_class_ref(GST_TYPE_PSEUDO3D_DEPTH));
  GstElementClass *pack_eclass = GST_ELEMENT_CLASS(g_type_class_ref(GST_TYPE_PSEUDO3D_PACK));
  gst_element_class_add_pad_template(
      element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS,
                                          gst_pad_template_get_caps(gst_element_class_get_pad_template(depth_eclass, "sink"))));
  gst_element_class_add_pad_template(
      element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS,
                                          gst_pad_template_get_caps(gst_element_class_get_pad_template(pack_eclass, "src"))));
  g_type_class_unref(depth_eclass);
  g_type_class_unref(pack_eclass);
  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_convert_debug, "pseudo3dconvert", 0, "pseudo3d conversion bin");
}

static void gst_pseudo3d_convert_init(GstPseudo3DConvert *self) {
  const char *factories[N_STAGES] = {"pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp", "pseudo3dpack"};
  for (int i = 0; i < N_STAGES; ++i) {
    self->stage[i] = gst_element_factory_make(factories[i], factories[i] + 8);  // "depth", "filter", ...
    gst_bin_add(GST_BIN(self), self->stage[i]);
  }
  gst_element_link_many(self->stage[0], self->stage[1], self->stage[2], self->stage[3], NULL);
  GstPad *sink = gst_element_get_static_pad(self->stage[STAGE_DEPTH], "sink");
  GstPad *src = gst_element_get_static_pad(self->stage[STAGE_PACK], "src");
  GstElementClass *klass = GST_ELEMENT_GET_CLASS(self);
  gst_element_add_pad(GST_ELEMENT(self), gst_ghost_pad_new_from_template(
                                             "sink", sink, gst_element_class_get_pad_template(klass, "sink")));
  gst_element_add_pad(GST_ELEMENT(self), gst_ghost_pad_new_from_template(
                                             "src", src, gst_element_class_get_pad_template(klass, "src")));
  gst_object_unref(sink);
  gst_object_unref(src);
}
