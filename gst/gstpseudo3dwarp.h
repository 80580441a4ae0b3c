#pragma once
#include "gstpseudo3dbase.h"
G_BEGIN_DECLS
#define GST_TYPE_PSEUDO3D_WARP (gst_pseudo3d_warp_get_type())
G_DECLARE_FINAL_TYPE(GstPseudo3DWarp, gst_pseudo3d_warp, GST, PSEUDO3D_WARP, GstPseudo3DBase)
GST_ELEMENT_REGISTER_DECLARE(pseudo3dwarp);
G_END_DECLS
