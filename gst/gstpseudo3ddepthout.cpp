/**
 * SECTION:element-pseudo3ddepthout
 * @title: pseudo3ddepthout
 *
 * Takes the depth map out of a pseudo3d stream as grey video (GRAY16_LE or
 * GRAY8, white = near, the frame's size and timing), for inspection or for
 * other tools: put it after pseudo3ddepth, pseudo3dfilter or
 * pseudo3ddepthmux, on a branch of a tee when the stereo chain goes on. A
 * frame without depth is an error that says where the depth comes from.
 * Depth in CUDA memory is read back to system memory. Depth d in [0, 1]
 * becomes round(d * 65535) (or * 255), so pseudo3ddepthmux reads it back
 * as the same depth to within half a step.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 filesrc location=vtest.avi ! decodebin ! videoconvert ! pseudo3ddepth ! pseudo3dfilter ! \
 *   pseudo3ddepthout ! video/x-raw,format=GRAY8 ! videoconvert ! x264enc ! mp4mux ! filesink location=depth.mp4
 * ]|
 */
#include "gstpseudo3ddepthout.h"

#include <gst/video/video.h>

#include <string>
#include <vector>

#include "config.h"
#include "depth_grey.h"
#include "depth_meta.h"
#include "video_util.h"

#if HAVE_CUDA
#include <cuda_runtime_api.h>

#include "gpu_context.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_depth_out_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_depth_out_debug

#define GREY_FORMATS "{ GRAY16_LE, GRAY8 }"

struct _GstPseudo3DDepthOut {
  GstBaseTransform parent;
  GstVideoInfo out_info;       // negotiated (streaming thread)
  std::vector<float> *staging;  // a device depth read back
};

#define gst_pseudo3d_depth_out_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DDepthOut, gst_pseudo3d_depth_out, GST_TYPE_BASE_TRANSFORM);
GST_ELEMENT_REGISTER_DEFINE(pseudo3ddepthout, "pseudo3ddepthout", GST_RANK_NONE, GST_TYPE_PSEUDO3D_DEPTH_OUT);

static GstCaps *grey_template_caps() {
  return gst_caps_from_string("video/x-raw, format=(string)" GREY_FORMATS
                              ", width=(int)[1, 8192], height=(int)[1, 8192], framerate=(fraction)[0/1, MAX]");
}

// Frames of one size become grey pictures of that size: the size, timing
// and pixel aspect stay; format, colour and stereo fields go; the grey side
// is system memory only.
static GstCaps *gst_pseudo3d_depth_out_transform_caps(GstBaseTransform *, GstPadDirection direction, GstCaps *caps,
                                                      GstCaps *filter) {
  GstCaps *out = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    GstStructure *s = gst_structure_copy(gst_caps_get_structure(caps, i));
    gst_structure_remove_fields(s, "format", "colorimetry", "chroma-site", "multiview-mode", "multiview-flags", "views",
                                NULL);
    // New caps have system-memory features: right for the grey side; the
    // frame side gets the structure in both domains (the template keeps
    // the CUDA one only where the build has CUDA).
    GstCaps *one = gst_caps_new_full(s, NULL);
    if (direction == GST_PAD_SRC) {
      GstCaps *cuda = gst_caps_copy(one);
      gst_caps_set_features_simple(cuda, gst_caps_features_new("memory:CUDAMemory", NULL));
      one = gst_caps_merge(cuda, one);
    }
    GstCaps *templ = direction == GST_PAD_SINK ? grey_template_caps()
                                                : p3d::gst::caps_all_domains(P3D_ALL_FORMATS, p3d::kMaxFrameSide);
    GstCaps *inter = gst_caps_intersect_full(templ, one, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(one);
    gst_caps_unref(templ);
    out = gst_caps_merge(out, inter);
  }
  if (filter) {
    GstCaps *tmp = gst_caps_intersect_full(filter, out, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(out);
    out = tmp;
  }
  return out;
}

static gboolean gst_pseudo3d_depth_out_get_unit_size(GstBaseTransform *, GstCaps *caps, gsize *size) {
  GstVideoInfo info;
  if (!gst_video_info_from_caps(&info, caps)) return FALSE;
  *size = GST_VIDEO_INFO_SIZE(&info);
  return TRUE;
}

static gboolean gst_pseudo3d_depth_out_set_caps(GstBaseTransform *trans, GstCaps *, GstCaps *outcaps) {
  GstPseudo3DDepthOut *self = GST_PSEUDO3D_DEPTH_OUT(trans);
  return gst_video_info_from_caps(&self->out_info, outcaps);
}

// The depth as a host view: the plane's own, or read back from the device
// into the element's staging vector. FALSE after posting an error.
static gboolean host_depth(GstPseudo3DDepthOut *self, p3d::gst::DepthPlane *plane, p3d::ImageView<const float> *out) {
  if (!plane->on_device) {
    *out = p3d::as_const(plane->view());
    return TRUE;
  }
#if HAVE_CUDA
  // A compact plane (depth_plane.h) comes back as its cells, behind the
  // full-size map in the same vector, and is copied out to the pixels.
  const size_t row = static_cast<size_t>(plane->width) * sizeof(float);
  const size_t pixels = static_cast<size_t>(plane->width) * plane->height;
  const p3d::ImageView<float> d = plane->view();  // its cells
  const size_t cells_row = static_cast<size_t>(d.width) * sizeof(float);
  self->staging->resize(pixels + (plane->shift > 0 ? static_cast<size_t>(d.width) * d.height : 0));
  float *landing = plane->shift > 0 ? self->staging->data() + pixels : self->staging->data();
  p3d::gst::CudaContextScope scope(plane->context);
  if (!scope.ok()) {
    GST_ELEMENT_ERROR(self, RESOURCE, READ, ("Could not read the depth map back from the GPU"),
                      ("could not make the depth's CUDA context current"));
    return FALSE;
  }
  const cudaError_t err =
      cudaMemcpy2D(landing, cells_row, d.data, d.pitch, cells_row, d.height, cudaMemcpyDeviceToHost);
  if (err != cudaSuccess) {
    GST_ELEMENT_ERROR(self, RESOURCE, READ, ("Could not read the depth map back from the GPU"),
                      ("cudaMemcpy2D: %s", cudaGetErrorName(err)));
    return FALSE;
  }
  const p3d::ImageView<float> full{self->staging->data(), plane->width, plane->height, row};
  if (plane->shift > 0)
    p3d::expand_grid(p3d::DepthGrid<const float>{p3d::ImageView<const float>{landing, d.width, d.height, cells_row},
                                                  plane->width, plane->height, plane->shift},
                     full);
  *out = p3d::as_const(full);
  return TRUE;
#else
  GST_ELEMENT_ERROR(self, STREAM, FAILED, ("The depth map is in GPU memory, but this build has no CUDA"), (nullptr));
  return FALSE;
#endif
}

static GstFlowReturn gst_pseudo3d_depth_out_transform(GstBaseTransform *trans, GstBuffer *inbuf, GstBuffer *outbuf) {
  GstPseudo3DDepthOut *self = GST_PSEUDO3D_DEPTH_OUT(trans);
  p3d::gst::DepthPlane *plane = pseudo3d_buffer_get_depth(inbuf);
  const int w = GST_VIDEO_INFO_WIDTH(&self->out_info), h = GST_VIDEO_INFO_HEIGHT(&self->out_info);
  if (!plane) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("pseudo3ddepthout needs a depth map"),
                      ("put pseudo3ddepth or pseudo3ddepthmux before it (an element that changes the frame, such "
                       "as a scaler or videoconvert, drops the depth)"));
    return GST_FLOW_ERROR;
  }
  if (plane->width != w || plane->height != h) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("The depth map does not fit the frame"),
                      ("depth %dx%d, frame %dx%d", plane->width, plane->height, w, h));
    return GST_FLOW_ERROR;
  }
  p3d::ImageView<const float> depth;
  if (!host_depth(self, plane, &depth)) return GST_FLOW_ERROR;
  GstVideoFrame out;
  if (!gst_video_frame_map(&out, &self->out_info, outbuf, GST_MAP_WRITE)) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Could not write the grey frame"), (nullptr));
    return GST_FLOW_ERROR;
  }
  p3d::ImageView<uint8_t> grey{static_cast<uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(&out, 0)), w, h,
                               static_cast<size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(&out, 0))};
  p3d::export_depth_cpu(depth, GST_VIDEO_FRAME_FORMAT(&out) == GST_VIDEO_FORMAT_GRAY8 ? 8 : 16, grey);
  gst_video_frame_unmap(&out);
  return GST_FLOW_OK;
}

static gboolean gst_pseudo3d_depth_out_stop(GstBaseTransform *trans) {
  GstPseudo3DDepthOut *self = GST_PSEUDO3D_DEPTH_OUT(trans);
  std::vector<float>().swap(*self->staging);
  return TRUE;
}

static void gst_pseudo3d_depth_out_finalize(GObject *object) {
  delete GST_PSEUDO3D_DEPTH_OUT(object)->staging;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pseudo3d_depth_out_class_init(GstPseudo3DDepthOutClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass *trans_class = GST_BASE_TRANSFORM_CLASS(klass);
  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_depth_out_debug, "pseudo3ddepthout", 0, "pseudo3d depth as grey video");
  gobject_class->finalize = gst_pseudo3d_depth_out_finalize;
  gst_element_class_set_static_metadata(element_class, "pseudo3d depth out", "Filter/Converter/Video",
                                        "Outputs the depth map that rides with each frame as grey video (white = "
                                        "near), for inspection or other tools",
                                        "pseudo3d developers");
  GstCaps *frames = p3d::gst::caps_all_domains(P3D_ALL_FORMATS, p3d::kMaxFrameSide), *grey = grey_template_caps();
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS, frames));
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, grey));
  gst_caps_unref(frames);
  gst_caps_unref(grey);
  trans_class->transform_caps = GST_DEBUG_FUNCPTR(gst_pseudo3d_depth_out_transform_caps);
  trans_class->get_unit_size = GST_DEBUG_FUNCPTR(gst_pseudo3d_depth_out_get_unit_size);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_pseudo3d_depth_out_set_caps);
  trans_class->transform = GST_DEBUG_FUNCPTR(gst_pseudo3d_depth_out_transform);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_pseudo3d_depth_out_stop);
  trans_class->passthrough_on_same_caps = FALSE;
}

static void gst_pseudo3d_depth_out_init(GstPseudo3DDepthOut *self) { self->staging = new std::vector<float>(); }
