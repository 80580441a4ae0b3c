#pragma once
#include "gstpseudo3dbase.h"
G_BEGIN_DECLS
#define GST_TYPE_PSEUDO3D_FILTER (gst_pseudo3d_filter_get_type())
G_DECLARE_FINAL_TYPE(GstPseudo3DFilter, gst_pseudo3d_filter, GST, PSEUDO3D_FILTER, GstPseudo3DBase)
GST_ELEMENT_REGISTER_DECLARE(pseudo3dfilter);
G_END_DECLS
