// Whether the conversion runs on an NVIDIA GPU, and making decodebin use
// the GPU's decoders (NVDEC) when it does.
#pragma once

#include <string>

#include "options.h"

namespace p3d::convert {

// True when the plugin was built with CUDA and a CUDA device with nvcodec's
// cudaupload/cudadownload is there: pseudo3dconvert processing=gpu starts.
bool gpu_usable();

// The processing the run uses: Cpu or Gpu (auto resolved). False with
// *error for processing=gpu without a usable GPU.
bool resolve_processing(Processing asked, Processing *resolved, std::string *error);

// The stages' `processing` value for a resolved processing: "gpu" or "cpu".
const char *processing_nick(Processing processing);

// The pipeline description of `stages` (plugin elements linked by "!", a
// tee's branch included) for system-memory frames on a resolved
// processing. On the GPU they sit between cudaupload and cudadownload with
// CUDA memory in between, as pseudo3dconvert wraps its own chain: the frame
// is uploaded once, every stage runs on the device and the result is
// downloaded once. On the CPU the stages as they are.
std::string on_processing(Processing processing, const std::string &stages);

// Raises the NVDEC decoders (nvh264dec, nvh265dec, ...) above the software
// ones for this process, so that decodebin picks them and they hand over
// CUDA memory. Returns how many were raised.
int prefer_gpu_decoders();

// Whether a decoder factory is one of the NVDEC decoders.
bool is_gpu_decoder(const std::string &factory);

}  // namespace p3d::convert
