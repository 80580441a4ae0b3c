// The pseudo3d plugin: registers the elements and the depth meta. Nothing else.
#include <gst/gst.h>

#include "config.h"
#include "depth_meta.h"
#include "gstpseudo3dconvert.h"
#include "gstpseudo3ddepth.h"
#include "gstpseudo3ddepthmux.h"
#include "gstpseudo3ddepthout.h"
#include "gstpseudo3dfilter.h"
#include "gstpseudo3dpack.h"
#include "gstpseudo3dsignal.h"
#include "gstpseudo3dwarp.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudaloader.h>
#include <gst/cuda/gstcudamemory.h>
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_plugin_debug);

static gboolean plugin_init(GstPlugin *plugin) {
  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_plugin_debug, "pseudo3d", 0, "pseudo3d plugin");
#if HAVE_CUDA
  // Without the driver library the elements still register and run on the CPU.
  if (gst_cuda_load_library())
    gst_cuda_memory_init_once();
  else
    GST_CAT_INFO(gst_pseudo3d_plugin_debug, "CUDA driver library not found: CPU processing only");
#endif
  pseudo3d_depth_meta_get_info();
  gboolean ok = TRUE;
  ok &= GST_ELEMENT_REGISTER(pseudo3ddepth, plugin);
  ok &= GST_ELEMENT_REGISTER(pseudo3dfilter, plugin);
  ok &= GST_ELEMENT_REGISTER(pseudo3dwarp, plugin);
  ok &= GST_ELEMENT_REGISTER(pseudo3dpack, plugin);
  ok &= GST_ELEMENT_REGISTER(pseudo3dconvert, plugin);
  ok &= GST_ELEMENT_REGISTER(pseudo3dsignal, plugin);
  ok &= GST_ELEMENT_REGISTER(pseudo3ddepthmux, plugin);
  ok &= GST_ELEMENT_REGISTER(pseudo3ddepthout, plugin);
  return ok;
}

GST_PLUGIN_DEFINE(GST_VERSION_MAJOR, GST_VERSION_MINOR, pseudo3d,
                  "2D to stereo 3D conversion by depth-image-based rendering (CPU and CUDA)", plugin_init, VERSION,
                  GST_LICENSE, GST_PACKAGE_NAME, GST_PACKAGE_ORIGIN)
