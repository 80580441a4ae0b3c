#pragma once
#include "gstpseudo3dbase.h"
G_BEGIN_DECLS
#define GST_TYPE_PSEUDO3D_DEPTH (gst_pseudo3d_depth_get_type())
G_DECLARE_FINAL_TYPE(GstPseudo3DDepth, gst_pseudo3d_depth, GST, PSEUDO3D_DEPTH, GstPseudo3DBase)
GST_ELEMENT_REGISTER_DECLARE(pseudo3ddepth);
G_END_DECLS
