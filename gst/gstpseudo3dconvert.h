#pragma once
#include <gst/gst.h>
G_BEGIN_DECLS
#define GST_TYPE_PSEUDO3D_CONVERT (gst_pseudo3d_convert_get_type())
G_DECLARE_FINAL_TYPE(GstPseudo3DConvert, gst_pseudo3d_convert, GST, PSEUDO3D_CONVERT, GstBin)
GST_ELEMENT_REGISTER_DECLARE(pseudo3dconvert);
G_END_DECLS
