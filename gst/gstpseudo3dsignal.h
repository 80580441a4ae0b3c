#pragma once
#include <gst/base/gstbasetransform.h>
G_BEGIN_DECLS
#define GST_TYPE_PSEUDO3D_SIGNAL (gst_pseudo3d_signal_get_type())
G_DECLARE_FINAL_TYPE(GstPseudo3DSignal, gst_pseudo3d_signal, GST, PSEUDO3D_SIGNAL, GstBaseTransform)
GST_ELEMENT_REGISTER_DECLARE(pseudo3dsignal);
G_END_DECLS
