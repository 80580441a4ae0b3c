// System memory that reports failure instead of aborting: GStreamer's
// default allocator uses g_malloc, which ends the process when a large
// frame cannot be allocated. This allocator uses g_try_malloc, so a pool
// built on it returns GST_FLOW_ERROR and the element posts an error naming
// the size. The memory it hands out is ordinary wrapped system memory.
#pragma once

#include <gst/gst.h>

namespace p3d::gst {

// The process-wide instance (a new reference).
GstAllocator *host_allocator_get();

}  // namespace p3d::gst
