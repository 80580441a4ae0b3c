#pragma once
#include <gst/base/gstbasetransform.h>
G_BEGIN_DECLS
#define GST_TYPE_PSEUDO3D_DEPTH_OUT (gst_pseudo3d_depth_out_get_type())
G_DECLARE_FINAL_TYPE(GstPseudo3DDepthOut, gst_pseudo3d_depth_out, GST, PSEUDO3D_DEPTH_OUT, GstBaseTransform)
GST_ELEMENT_REGISTER_DECLARE(pseudo3ddepthout);
G_END_DECLS
