#include "stage_depth.h"

#include <string>

#include "depth_meta.h"

GST_DEBUG_CATEGORY_EXTERN(gst_pseudo3d_base_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_base_debug

namespace p3d::gst {

bool depth_fits(GstPseudo3DBase *self, const DepthPlane *plane, GstPseudo3DPath path, int width, int height) {
  if (!plane || plane->width != width || plane->height != height) return false;
  const bool device = path == GST_PSEUDO3D_PATH_GPU;
  if (plane->on_device != device) return false;
#if HAVE_CUDA
  if (device && plane->context != self->gpu->context()) return false;
#else
  (void)self;
#endif
  return true;
}

DepthPlane *frame_depth(GstPseudo3DBase *self, GstBuffer *buf, GstPseudo3DPath path, int width, int height) {
  DepthPlane *depth = pseudo3d_buffer_get_depth(buf);
  const char *name = GST_ELEMENT_NAME(gst_element_get_factory(GST_ELEMENT(self)));
  if (!depth) {
    GST_ELEMENT_ERROR(self, STREAM, FORMAT, ("%s needs a depth map, and this frame carries none", name),
                      ("put pseudo3ddepth before %s; elements that change the frame between them (scaling, flipping, "
                       "cropping, videoconvert, cudaupload/cudadownload) drop the depth, so put those before "
                       "pseudo3ddepth",
                       name));
    return nullptr;
  }
  if (!depth_fits(self, depth, path, width, height)) {
    GST_ELEMENT_ERROR(self, STREAM, FORMAT, ("The frame's depth map does not fit the frame"),
                      ("depth %dx%d in %s memory, frame %dx%d in %s memory; put pseudo3ddepth right before %s",
                       depth->width, depth->height, depth->on_device ? "device" : "host", width, height,
                       path == GST_PSEUDO3D_PATH_GPU ? "device" : "host", name));
    return nullptr;
  }
  return depth;
}

DepthPlanePtr new_depth(GstPseudo3DBase *self, DepthPlanePool &pool, GstPseudo3DPath path, int width, int height,
                        int shift) {
  std::string error;
#if HAVE_CUDA
  if (path != GST_PSEUDO3D_PATH_GPU) shift = 0;  // host planes are full-size
  DepthPlanePtr plane =
      pool.acquire(width, height, shift, path == GST_PSEUDO3D_PATH_GPU ? self->gpu->context() : nullptr, &error);
#else
  (void)path;
  shift = 0;
  DepthPlanePtr plane = pool.acquire(width, height, 0, nullptr, &error);
#endif
  if (!plane)
    GST_ELEMENT_ERROR(self, RESOURCE, NO_SPACE_LEFT,
                      ("Could not allocate a %dx%d depth map (%" G_GSIZE_FORMAT " bytes)", width, height,
                       static_cast<gsize>(p3d::grid_cells(width, shift)) * p3d::grid_cells(height, shift) *
                           sizeof(float)),
                      ("%s", error.c_str()));
  return plane;
}

bool set_active(GstPseudo3DBase *self, DepthPlane *plane, PixelRect rect) {
  std::string error;
#if HAVE_CUDA
  const bool ok = plane->set_active(rect, plane->on_device ? self->gpu->stream() : nullptr, &error);
#else
  const bool ok = plane->set_active(rect, nullptr, &error);
#endif
  if (!ok)
    GST_ELEMENT_ERROR(self, RESOURCE, FAILED, ("Could not clear the depth map outside the active picture"),
                      ("%s", error.c_str()));
  return ok;
}

}  // namespace p3d::gst
