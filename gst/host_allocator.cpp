#include "host_allocator.h"

namespace {

struct HostAllocator {
  GstAllocator parent;
};
struct HostAllocatorClass {
  GstAllocatorClass parent_class;
};

GType host_allocator_get_type();
G_DEFINE_TYPE(HostAllocator, host_allocator, GST_TYPE_ALLOCATOR)

GstMemory *host_alloc(GstAllocator *, gsize size, GstAllocationParams *params) {
  const gsize align = params->align | gst_memory_alignment;
  const gsize maxsize = size + params->prefix + params->padding;
  if (maxsize < size || maxsize + align < maxsize) return nullptr;  // overflow
  auto *data = static_cast<guint8 *>(g_try_malloc(maxsize + align));
  if (!data) return nullptr;
  // Start the usable area on the requested alignment, as the default allocator does.
  gsize offset = 0;
  const guintptr addr = reinterpret_cast<guintptr>(data);
  if (addr & align) offset = (align + 1) - (addr & align);
  if (params->flags & GST_MEMORY_FLAG_ZERO_PREFIXED && params->prefix) memset(data + offset, 0, params->prefix);
  if (params->flags & GST_MEMORY_FLAG_ZERO_PADDED && params->padding)
    memset(data + offset + params->prefix + size, 0, params->padding);
  return gst_memory_new_wrapped(static_cast<GstMemoryFlags>(params->flags), data, maxsize + align, offset + params->prefix,
                                size, data, g_free);
}

void host_free(GstAllocator *, GstMemory *mem) {
  // Never reached: wrapped memory belongs to the system allocator, which frees it.
  gst_memory_unref(mem);
}

void host_allocator_class_init(HostAllocatorClass *klass) {
  GstAllocatorClass *alloc_class = GST_ALLOCATOR_CLASS(klass);
  alloc_class->alloc = host_alloc;
  alloc_class->free = host_free;
}

void host_allocator_init(HostAllocator *self) {
  GST_ALLOCATOR(self)->mem_type = "Pseudo3DHostMemory";
}

}  // namespace

namespace p3d::gst {

GstAllocator *host_allocator_get() {
  static GstAllocator *instance = nullptr;
  if (g_once_init_enter(&instance)) {
    auto *a = static_cast<GstAllocator *>(g_object_new(host_allocator_get_type(), nullptr));
    gst_object_ref_sink(a);
    GST_OBJECT_FLAG_SET(a, GST_OBJECT_FLAG_MAY_BE_LEAKED);
    g_once_init_leave(&instance, a);
  }
  return static_cast<GstAllocator *>(gst_object_ref(instance));
}

}  // namespace p3d::gst
