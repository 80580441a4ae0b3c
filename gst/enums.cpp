#include "enums.h"

#include <cstddef>

#include "bilateral.h"
#include "depth_estimate.h"
#include "depth_grey.h"
#include "pack.h"
#include "warp.h"

// The GEnumValue array of a names table (common/enum_name.h), built once and
// kept for the type's lifetime (GLib keeps the pointer). `first`, if given,
// is a value before the table's, whose values then count from 1.
template <typename E, std::size_t N>
static GType register_enum(const gchar *type_name, const p3d::EnumName<E> (&table)[N],
                           const GEnumValue *first = nullptr) {
  const gint offset = first ? 1 : 0;
  auto *values = g_new0(GEnumValue, N + offset + 1);
  if (first) values[0] = *first;
  for (std::size_t i = 0; i < N; ++i)
    values[i + offset] = {static_cast<gint>(table[i].value) + offset, table[i].description, table[i].nick};
  return g_enum_register_static(type_name, values);
}

#define P3D_ENUM_FROM_TABLE(func, TypeName, ...)     \
  GType func(void) {                                  \
    static GType type = 0;                            \
    if (g_once_init_enter(&type)) {                   \
      GType t = register_enum(TypeName, __VA_ARGS__); \
      g_once_init_leave(&type, t);                    \
    }                                                 \
    return type;                                      \
  }

// The elements' own enums, which no tool reads, keep their table here.
#define P3D_DEFINE_ENUM(func, TypeName, ...)                              \
  GType func(void) {                                                      \
    static GType type = 0;                                                \
    if (g_once_init_enter(&type)) {                                       \
      static const GEnumValue values[] = {__VA_ARGS__, {0, NULL, NULL}};  \
      GType t = g_enum_register_static(TypeName, values);                 \
      g_once_init_leave(&type, t);                                        \
    }                                                                     \
    return type;                                                          \
  }

P3D_ENUM_FROM_TABLE(gst_pseudo3d_hypothesis_get_type, "GstPseudo3DHypothesis", p3d::kHypothesisNames)
P3D_ENUM_FROM_TABLE(gst_pseudo3d_filter_mode_get_type, "GstPseudo3DFilterMode", p3d::kFilterModeNames)
P3D_ENUM_FROM_TABLE(gst_pseudo3d_depth_convention_get_type, "GstPseudo3DDepthConvention",
                    p3d::kDepthConventionNames)
P3D_ENUM_FROM_TABLE(gst_pseudo3d_view_get_type, "GstPseudo3DView", p3d::kStereoViewNames)
P3D_ENUM_FROM_TABLE(gst_pseudo3d_fill_get_type, "GstPseudo3DFill", p3d::kHoleFillNames)
P3D_ENUM_FROM_TABLE(gst_pseudo3d_layout_get_type, "GstPseudo3DLayout", p3d::kPackLayoutNames)
P3D_ENUM_FROM_TABLE(gst_pseudo3d_glasses_get_type, "GstPseudo3DGlasses", p3d::kGlassesNames)
P3D_ENUM_FROM_TABLE(gst_pseudo3d_anaglyph_method_get_type, "GstPseudo3DAnaglyphMethod", p3d::kAnaglyphMethodNames)

static const GEnumValue kFromCaps = {GST_PSEUDO3D_INPUT_LAYOUT_FROM_CAPS,
                                     "From the caps' multiview-mode and multiview-flags", "from-caps"};
P3D_ENUM_FROM_TABLE(gst_pseudo3d_input_layout_get_type, "GstPseudo3DInputLayout", p3d::kStereoInputNames,
                    &kFromCaps)

P3D_DEFINE_ENUM(gst_pseudo3d_depth_method_get_type, "GstPseudo3DDepthMethod",
                {GST_PSEUDO3D_DEPTH_METHOD_EDGES, "Estimate from edges and a depth-gradient hypothesis", "edges"},
                {GST_PSEUDO3D_DEPTH_METHOD_RGBD,
                 "Input holds colour (left half) and depth as grey (right half, white = near)", "rgbd"})

P3D_DEFINE_ENUM(gst_pseudo3d_processing_get_type, "GstPseudo3DProcessing",
                {GST_PSEUDO3D_PROCESSING_AUTO, "GPU when a CUDA device and nvcodec are available, else CPU", "auto"},
                {GST_PSEUDO3D_PROCESSING_CPU, "CPU (CUDA-memory input still runs on the GPU)", "cpu"},
                {GST_PSEUDO3D_PROCESSING_GPU, "GPU; an error if none is available", "gpu"})

P3D_DEFINE_ENUM(gst_pseudo3d_crop_bars_get_type, "GstPseudo3DCropBars",
                {GST_PSEUDO3D_CROP_BARS_OFF, "The whole frame", "off"},
                {GST_PSEUDO3D_CROP_BARS_AUTO, "Find letterbox and pillarbox bars and leave them out", "auto"})
