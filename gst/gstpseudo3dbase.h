// GstPseudo3DBase: the abstract base of every pseudo3d stage, the
// GstBaseTransform glue the stages share, written once:
//  * the processing and cuda-device-id properties (refused while PAUSED or
//    PLAYING, with a warning on the bus) and the path a negotiated stream
//    runs on (the GPU on CUDA memory, the CPU on system memory);
//  * caps: sizes and multiview fields through the stage's
//    transform_geometry, formats, CUDA memory preferred when a GPU is
//    usable; refusals posted once per caps; live renegotiation of the
//    caps-deciding properties (staged_geometry.h);
//  * allocation: CUDA pools, host buffers that fail with an element error
//    instead of aborting the process;
//  * stream events: the temporal-history reset on FLUSH_STOP, STREAM_START,
//    SEGMENT and DISCONT buffers; QoS (late frames are dropped);
//  * frames: mapping, one element error per failure, C++ exceptions caught.
// What a stage calls beside it: caps_geometry.h (size arithmetic for
// transform_geometry), stage_gpu.h (the GPU side: context, pools, run_gpu)
// and stage_depth.h (the depth meta). A stage implements set_info plus
// process (or process_ip for in-place).
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/video/video.h>

#include "config.h"
#include "enums.h"
#include "frame.h"
#include "gpu_context.h"
#include "processing_latency.h"
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
  gboolean adaptive;      /* stage_adaptive.h */
  gfloat reuse_tolerance;

  /* private */
  p3d::gst::GpuContext *gpu;
  /* What a frame takes, added to LATENCY queries (processing_latency.h). */
  p3d::gst::ProcessingLatency *latency;
  gboolean history_reset_pending; /* object lock */
  gboolean cpu_notice_logged;
  gboolean hidden_in_parent; /* gst_pseudo3d_base_set_hidden_in_parent */
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

/* A stage that a bin creates as a hidden part of itself: messages that tell
 * the user where to insert an element name the bin, which the user placed,
 * instead of the stage. Call it before the element leaves NULL. */
void gst_pseudo3d_base_set_hidden_in_parent(GstPseudo3DBase *self, gboolean hidden);

/* TRUE once after a seek, a flush, a new stream or a discontinuity: a stage
 * with temporal state forgets its history before the frame it processes. */
gboolean gst_pseudo3d_base_take_history_reset(GstPseudo3DBase *self);

G_DEFINE_AUTOPTR_CLEANUP_FUNC(GstPseudo3DBase, gst_object_unref)

G_END_DECLS
