#pragma once
#include "gstpseudo3dbase.h"
G_BEGIN_DECLS
#define GST_TYPE_PSEUDO3D_PACK (gst_pseudo3d_pack_get_type())
G_DECLARE_FINAL_TYPE(GstPseudo3DPack, gst_pseudo3d_pack, GST, PSEUDO3D_PACK, GstPseudo3DBase)
GST_ELEMENT_REGISTER_DECLARE(pseudo3dpack);
G_END_DECLS
