#include "gpu.h"

#include <gst/gst.h>

namespace p3d::convert {

namespace {
// nvcodec's NVDEC decoders in GStreamer 1.22. They register with a rank
// below the software decoders (SECONDARY), so decodebin would not pick them.
const char *const kGpuDecoders[] = {"nvh264dec", "nvh265dec",       "nvvp9dec",        "nvav1dec",
                                    "nvvp8dec",  "nvmpeg2videodec", "nvmpeg4videodec"};
}  // namespace

bool gpu_usable() {
  // The bin refuses READY with processing=gpu when it cannot run there: the
  // same test the conversion itself would fail, so nothing can disagree.
  GstElement *probe = gst_element_factory_make("pseudo3dconvert", nullptr);
  if (!probe) return false;
  gst_object_ref_sink(probe);
  gst_util_set_object_arg(G_OBJECT(probe), "processing", "gpu");
  const bool ok = gst_element_set_state(probe, GST_STATE_READY) == GST_STATE_CHANGE_SUCCESS;
  gst_element_set_state(probe, GST_STATE_NULL);
  gst_object_unref(probe);
  return ok;
}

bool resolve_processing(Processing asked, Processing *resolved, std::string *error) {
  if (asked == Processing::Cpu) {
    *resolved = Processing::Cpu;
    return true;
  }
  const bool gpu = gpu_usable();
  if (asked == Processing::Gpu && !gpu) {
    *error = "--processing gpu: no usable NVIDIA GPU (needs the plugin built with CUDA, the NVIDIA driver and "
             "nvcodec's cudaupload/cudadownload)";
    return false;
  }
  *resolved = gpu ? Processing::Gpu : Processing::Cpu;
  return true;
}

const char *processing_nick(Processing processing) { return processing == Processing::Gpu ? "gpu" : "cpu"; }

std::string on_processing(Processing processing, const std::string &stages) {
  if (processing != Processing::Gpu) return stages;
  // cudaupload also offers system memory: insist on device memory after it.
  return "cudaupload ! video/x-raw(memory:CUDAMemory) ! " + stages + " ! cudadownload";
}

int prefer_gpu_decoders() {
  int raised = 0;
  for (const char *name : kGpuDecoders) {
    GstPluginFeature *f = gst_registry_lookup_feature(gst_registry_get(), name);
    if (!f) continue;
    gst_plugin_feature_set_rank(f, GST_RANK_PRIMARY + 10);
    gst_object_unref(f);
    ++raised;
  }
  return raised;
}

bool is_gpu_decoder(const std::string &factory) {
  for (const char *name : kGpuDecoders)
    if (factory == name) return true;
  return false;
}

}  // namespace p3d::convert
