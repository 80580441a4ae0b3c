#pragma once
#include <gst/base/gstaggregator.h>
G_BEGIN_DECLS
#define GST_TYPE_PSEUDO3D_DEPTH_MUX (gst_pseudo3d_depth_mux_get_type())
G_DECLARE_FINAL_TYPE(GstPseudo3DDepthMux, gst_pseudo3d_depth_mux, GST, PSEUDO3D_DEPTH_MUX, GstAggregator)
GST_ELEMENT_REGISTER_DECLARE(pseudo3ddepthmux);
G_END_DECLS
