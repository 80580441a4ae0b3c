// GstPseudo3DBase: the abstract base of every pseudo3d stage. It owns what
// the stages share, written once:
//  * the processing and cuda-device-id properties (refused while PAUSED or
//    PLAYING, with a warning on the bus);
//  * the GPU: a GpuContext (gpu_context.h), the path a negotiated stream
//    runs on (the GPU on CUDA memory, the CPU on system memory),
//    adoption of an upstream buffer's CUDA context when cuda-device-id is
//    -1, and the "launch, check, wait" block of every GPU frame;
//  * caps: sizes and multiview fields through the stage's transform_geometry,
//    formats, CUDA memory preferred when a GPU is usable;
//  * allocation: CUDA pools on the element's context, host buffers that fail
//    with an element error instead of aborting the process;
//  * stream events: the temporal-history reset on FLUSH_STOP, STREAM_START,
//    SEGMENT and DISCONT buffers; QoS (late frames are dropped);
//  * frames: mapping, the depth-meta check, one element error per failure.
// A stage implements set_info plus process (or process_ip for in-place).
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/video/video.h>

#include "config.h"
#include "depth_plane.h"
#include "enums.h"
#include "frame.h"
#include "gpu_context.h"
#include "staged_geometry.h"

G_BEGIN_DECLS

#define GST_TYPE_PSEUDO3D_BASE (gst_pseudo3d_base_get_type())
#define GST_PSEUDO3D_BASE(obj) (G_TYPE_CHECK_INSTANCE_CAST((obj), GST_TYPE_PSEUDO3D_BASE, GstPseudo3DBase))
#define GST_PSEUDO3D_BASE_CLASS(klass) (G_TYPE_CHECK_CLASS_CAST((klass), GST_TYPE_PSEUDO3D_BASE, GstPseudo3DBaseClass))
#define GST_PSEUDO3D_BASE_GET_CLASS(obj) \
  (G_TYPE_INSTANCE_GET_CLASS((obj), GST_TYPE_PSEUDO3D_BASE, GstPseudo3DBaseClass))

/* Where a negotiated stream is processed. System memory always runs on the
 * CPU: copying every frame to the GPU and back at each stage costs more than
 * the kernels save (docs/benchmarks.md, "Real pipelines"), so a GPU is used
 * on memory:CUDAMemory only (cudaupload before, cudadownload after, as
 * pseudo3dconvert arranges). */
typedef enum {
  GST_PSEUDO3D_PATH_CPU = 0, /* CPU references on mapped memory */
  GST_PSEUDO3D_PATH_GPU = 1, /* memory:CUDAMemory: kernels on the frames in place */
} GstPseudo3DPath;

typedef struct _GstPseudo3DBase GstPseudo3DBase;
typedef struct _GstPseudo3DBaseClass GstPseudo3DBaseClass;

struct _GstPseudo3DBase {
  GstBaseTransform parent;

  /* negotiated (streaming thread) */
  GstVideoInfo in_info;
  GstVideoInfo out_info;
  gboolean cuda_caps; /* memory:CUDAMemory on the pads */

  /* properties (object lock) */
  gint device_id;
  GstPseudo3DProcessing processing;

  /* private */
  p3d::gst::GpuContext *gpu;
  gboolean history_reset_pending; /* object lock */
  gboolean cpu_notice_logged;
  GstCaps *negotiating_caps; /* input caps of the set_info call in progress */
  GstCaps *refused_caps;     /* input caps whose refusal was posted */
  /* The stage's caps-deciding properties (staged_geometry.h), owned by the
   * stage; null when no property changes the caps. Object lock. */
  p3d::gst::StagedGeometryBase *staged;
  /* The thread in which a renegotiation of the running stream is under way
   * (atomic; null when none): its refusals are collected, not posted, and
   * GstBaseTransform's bare warning from it is dropped. */
  GThread *live_thread;
  gchar *live_refusal, *live_refusal_debug;
  gint flush_starts; /* atomic: FLUSH_START events seen */
};

struct _GstPseudo3DBaseClass {
  GstBaseTransformClass parent_class;

  /* Formats of the other pad when the stage converts (null: same format). */
  const gchar *src_formats;
  const gchar *sink_formats;
  /* The structures of the other pad for a caps structure `s` of the pad
   * `from`: s with its geometry fields (width, height, multiview-*, views)
   * rewritten, or several variants of it. Returns new caps without
   * features; null hook: the stage keeps the geometry. Called from
   * transform_caps: read the StagedGeometry's negotiating() value. */
  GstCaps *(*transform_geometry)(GstPseudo3DBase *self, GstPadDirection from, const GstStructure *s);

  /* The negotiated caps (stored in in_info/out_info once accepted): commit
   * the staged geometry, check the caps against it (refusing them with
   * gst_pseudo3d_base_refuse_caps) and set in-place/passthrough. */
  gboolean (*set_info)(GstPseudo3DBase *self, GstCaps *incaps, GstVideoInfo *in_info, GstCaps *outcaps,
                       GstVideoInfo *out_info);
  /* Before each frame, in the streaming thread: TRUE when a staged geometry
   * request differs from the active value (the base then renegotiates). */
  gboolean (*frame_boundary)(GstPseudo3DBase *self);
  /* Not in place: frames are mapped (device pointers on GST_PSEUDO3D_PATH_GPU). */
  GstFlowReturn (*process)(GstPseudo3DBase *self, GstPseudo3DPath path, GstBuffer *inbuf, GstVideoFrame *in,
                           GstVideoFrame *out);
  /* In place: frame mapped for reading; the stage attaches metas to buf. */
  GstFlowReturn (*process_ip)(GstPseudo3DBase *self, GstPseudo3DPath path, GstBuffer *buf, GstVideoFrame *frame);
  /* Frees the stage's buffers and pools: in stop(), and when the element
   * switches CUDA context (then with that context current). */
  void (*release)(GstPseudo3DBase *self);
};

GType gst_pseudo3d_base_get_type(void);

/* Where frames of the negotiated caps are processed. */
GstPseudo3DPath gst_pseudo3d_base_path(GstPseudo3DBase *self);

/* From set_info: refuses the caps with a CORE/NEGOTIATION error saying why.
 * GstBaseTransform retries a failed negotiation for every buffer; the error
 * is posted once per input caps. During the renegotiation of a live
 * property change the refusal is kept instead: the base then refuses the
 * change with a warning and the stream goes on. Returns
 * FALSE (for set_info to return). */
gboolean gst_pseudo3d_base_refuse_caps(GstPseudo3DBase *self, const char *text, const char *debug_format, ...)
    G_GNUC_PRINTF(3, 4);

/* TRUE once after a seek, a flush, a new stream or a discontinuity: a stage
 * with temporal state forgets its history before the frame it processes. */
gboolean gst_pseudo3d_base_take_history_reset(GstPseudo3DBase *self);

/* The frame's depth map, checked to fit the frame (size, memory domain,
 * CUDA context). Otherwise posts one element error that names pseudo3ddepth
 * and says why, and returns null. */
p3d::gst::DepthPlane *gst_pseudo3d_base_frame_depth(GstPseudo3DBase *self, GstBuffer *buf, GstPseudo3DPath path,
                                                    int width, int height);
/* Whether a plane fits a width x height frame on `path` (no error posted). */
gboolean gst_pseudo3d_base_depth_fits(GstPseudo3DBase *self, const p3d::gst::DepthPlane *plane, GstPseudo3DPath path,
                                      int width, int height);
/* A depth plane for a frame of `path` from `pool`; posts an element error
 * with the size on failure and returns null. shift: on GST_PSEUDO3D_PATH_GPU
 * the plane holds a value a 2^shift x 2^shift cell (depth_plane.h); host
 * planes are full-size whatever it says. */
p3d::gst::DepthPlanePtr gst_pseudo3d_base_new_depth(GstPseudo3DBase *self, p3d::gst::DepthPlanePool &pool,
                                                    GstPseudo3DPath path, int width, int height, int shift = 0);

/* Caps helpers for transform_geometry: value * num / den for an int, an int
 * range or a list of them (clamped to 1..G_MAXINT); caps holding one copy
 * of a structure. */
void gst_pseudo3d_scale_field(GstStructure *s, const char *field, gint num, gint den);
/* The way back through gst_pseudo3d_scale_field(s, field, num, den): every
 * value v with v * num / den (rounded down) among the field's values, so
 * that a size whose forward image is rounded (an odd width halved) still
 * passes the caps query, and set_info() can refuse it with its reason
 * instead of a bare not-negotiated. */
void gst_pseudo3d_unscale_field(GstStructure *s, const char *field, gint num, gint den);
/* A copy of structure `in` (input sizes) with the output sizes of an
 * element whose output width and height are input * wn / wd and
 * input * hn / hd (gst_pseudo3d_scale_field). */
GstStructure *gst_pseudo3d_sizes_forward(const GstStructure *in, gint wn, gint wd, gint hn, gint hd);
/* A copy of sink-side-bound structure `in` (output sizes) with the input
 * sizes that give them, for an element whose output width and height are
 * input * wn / wd and input * hn / hd: the exact inverse, or (`rounded`)
 * every size whose rounded image they are. A transform towards the sink
 * offers the exact structures first, so that a free upstream fixates a size
 * that works, and the rounded ones after them. */
GstStructure *gst_pseudo3d_sizes_back(const GstStructure *in, gint wn, gint wd, gint hn, gint hd, gboolean rounded);
GstCaps *gst_pseudo3d_caps_of(GstStructure *s); /* takes s */
/* Sets the format field to `formats` ("{ A, B }" or one name) and drops the
 * colorimetry and chroma-site, which belong to the old format family. */
void gst_pseudo3d_set_formats(GstStructure *s, const gchar *formats);

G_DEFINE_AUTOPTR_CLEANUP_FUNC(GstPseudo3DBase, gst_object_unref)

G_END_DECLS

#if HAVE_CUDA
/* Posts a GST_ELEMENT_ERROR naming the failed CUDA call; returns GST_FLOW_ERROR. */
GstFlowReturn gst_pseudo3d_base_cuda_error(GstPseudo3DBase *self, const p3d::CudaStatus &st, const char *what);

namespace p3d::gst {
/* The GPU part of one frame, the same for every stage: `launch` queues the
 * work on the element's stream (returning the first failure), then the
 * stream is waited for, so the buffer leaves with its work done. A failure
 * posts one element error naming `what` and the failed call. */
template <typename Launch>
GstFlowReturn run_gpu(GstPseudo3DBase *self, const char *what, Launch &&launch) {
  CudaStatus st = launch();
  if (st.ok()) st = self->gpu->sync();
  return st.ok() ? GST_FLOW_OK : gst_pseudo3d_base_cuda_error(self, st, what);
}
}  // namespace p3d::gst
#endif
