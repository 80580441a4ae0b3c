// GEnum types for the elements' enumerated properties (values mirror the
// common/ parameter enums one to one).
#pragma once

#include <glib-object.h>

G_BEGIN_DECLS

#define GST_TYPE_PSEUDO3D_HYPOTHESIS (gst_pseudo3d_hypothesis_get_type())
GType gst_pseudo3d_hypothesis_get_type(void);
#define GST_TYPE_PSEUDO3D_DEPTH_METHOD (gst_pseudo3d_depth_method_get_type())
GType gst_pseudo3d_depth_method_get_type(void);
#define GST_TYPE_PSEUDO3D_VIEW (gst_pseudo3d_view_get_type())
GType gst_pseudo3d_view_get_type(void);
#define GST_TYPE_PSEUDO3D_FILL (gst_pseudo3d_fill_get_type())
GType gst_pseudo3d_fill_get_type(void);
#define GST_TYPE_PSEUDO3D_LAYOUT (gst_pseudo3d_layout_get_type())
GType gst_pseudo3d_layout_get_type(void);
#define GST_TYPE_PSEUDO3D_GLASSES (gst_pseudo3d_glasses_get_type())
GType gst_pseudo3d_glasses_get_type(void);
#define GST_TYPE_PSEUDO3D_ANAGLYPH_METHOD (gst_pseudo3d_anaglyph_method_get_type())
GType gst_pseudo3d_anaglyph_method_get_type(void);

#define GST_TYPE_PSEUDO3D_PROCESSING (gst_pseudo3d_processing_get_type())
GType gst_pseudo3d_processing_get_type(void);

// pseudo3dconvert's processing property.
typedef enum {
  GST_PSEUDO3D_PROCESSING_AUTO = 0,
  GST_PSEUDO3D_PROCESSING_CPU = 1,
  GST_PSEUDO3D_PROCESSING_GPU = 2
} GstPseudo3DProcessing;

// pseudo3ddepth's crop-bars property.
#define GST_TYPE_PSEUDO3D_CROP_BARS (gst_pseudo3d_crop_bars_get_type())
GType gst_pseudo3d_crop_bars_get_type(void);
typedef enum { GST_PSEUDO3D_CROP_BARS_OFF = 0, GST_PSEUDO3D_CROP_BARS_AUTO = 1 } GstPseudo3DCropBars;

// pseudo3ddepth's method property.
typedef enum { GST_PSEUDO3D_DEPTH_METHOD_EDGES = 0, GST_PSEUDO3D_DEPTH_METHOD_RGBD = 1 } GstPseudo3DDepthMethod;

#define GST_TYPE_PSEUDO3D_FILTER_MODE (gst_pseudo3d_filter_mode_get_type())
GType gst_pseudo3d_filter_mode_get_type(void);
#define GST_TYPE_PSEUDO3D_DEPTH_CONVENTION (gst_pseudo3d_depth_convention_get_type())
GType gst_pseudo3d_depth_convention_get_type(void);

#define GST_TYPE_PSEUDO3D_INPUT_LAYOUT (gst_pseudo3d_input_layout_get_type())
GType gst_pseudo3d_input_layout_get_type(void);
// pseudo3dpack's input-layout property: from the caps, or p3d::StereoInput + 1
// (an int, so every value of the GEnum is a valid value of the type).
typedef gint GstPseudo3DInputLayout;
#define GST_PSEUDO3D_INPUT_LAYOUT_FROM_CAPS 0

G_END_DECLS
