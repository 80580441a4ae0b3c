// A stage's access to the depth meta (depth_meta.h): the depth map a frame
// carries, checked to fit it, and new planes for the depth a stage attaches.
// A map fits when it has the frame's size and lives in the frame's memory
// (and, on the device, in the element's CUDA context); a stage never reads
// a map that does not fit.
#pragma once

#include <gst/gst.h>

#include "depth_plane.h"
#include "gstpseudo3dbase.h"

namespace p3d::gst {

// Whether a plane fits a width x height frame on `path` (no error posted).
bool depth_fits(GstPseudo3DBase *self, const DepthPlane *plane, GstPseudo3DPath path, int width, int height);
// The frame's depth map, checked to fit the frame. Otherwise posts one
// element error that says why and where the depth comes from (pseudo3ddepth
// right before the stage), and returns null.
DepthPlane *frame_depth(GstPseudo3DBase *self, GstBuffer *buf, GstPseudo3DPath path, int width, int height);
// A depth plane for a frame of `path` from `pool`; posts an element error
// with the size on failure and returns null. shift: on GST_PSEUDO3D_PATH_GPU
// the plane holds a value a 2^shift x 2^shift cell (depth_plane.h); host
// planes are full-size whatever it says.
DepthPlanePtr new_depth(GstPseudo3DBase *self, DepthPlanePool &pool, GstPseudo3DPath path, int width, int height,
                        int shift = 0);

// DepthPlane::set_active on the stage's stream; posts an element error and
// returns false when the device refuses it.
bool set_active(GstPseudo3DBase *self, DepthPlane *plane, PixelRect rect);
}  // namespace p3d::gst
