// GstPseudo3DBase: the abstract base of every pseudo3d stage. It owns what
// the stages share, written once: the cuda-device-id property, the CUDA
// context (shared through GstContext) and stream, the negotiated memory
// domain, caps mapping for stages that change size or format, CUDA buffer
// pools, frame mapping, and turning CUDA failures into element errors.
// A stage implements set_info plus process (or process_ip for in-place).
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/video/video.h>

#include "config.h"
#include "enums.h"
#include "frame.h"
#include "gpu_staging.h"

#if HAVE_CUDA
#include <cuda_runtime_api.h>
#include <gst/cuda/gstcudacontext.h>

#include "cuda_check.h"
#endif

G_BEGIN_DECLS

#define GST_TYPE_PSEUDO3D_BASE (gst_pseudo3d_base_get_type())
#define GST_PSEUDO3D_BASE(obj) (G_TYPE_CHECK_INSTANCE_CAST((obj), GST_TYPE_PSEUDO3D_BASE, GstPseudo3DBase))
#define GST_PSEUDO3D_BASE_CLASS(klass) (G_TYPE_CHECK_CLASS_CAST((klass), GST_TYPE_PSEUDO3D_BASE, GstPseudo3DBaseClass))
#define GST_PSEUDO3D_BASE_GET_CLASS(obj) \
  (G_TYPE_INSTANCE_GET_CLASS((obj), GST_TYPE_PSEUDO3D_BASE, GstPseudo3DBaseClass))

/* Where a negotiated stream is processed. */
typedef enum {
  GST_PSEUDO3D_PATH_CPU = 0,    /* CPU references on mapped memory */
  GST_PSEUDO3D_PATH_GPU = 1,    /* memory:CUDAMemory: kernels on the frames in place */
  GST_PSEUDO3D_PATH_STAGED = 2, /* system memory, GPU present: upload, kernels, download */
} GstPseudo3DPath;

typedef struct _GstPseudo3DBase GstPseudo3DBase;
typedef struct _GstPseudo3DBaseClass GstPseudo3DBaseClass;

struct _GstPseudo3DBase {
  GstBaseTransform parent;

  /* negotiated */
  GstVideoInfo in_info;
  GstVideoInfo out_info;
  gboolean cuda_caps; /* memory:CUDAMemory on the pads */

  /* properties */
  gint device_id;
  GstPseudo3DProcessing processing;

#if HAVE_CUDA
  GstCudaContext *context; /* null: no usable GPU, CPU path */
  cudaStream_t stream;
  p3d::gst::GpuStaging *staging; /* system-memory frames on the GPU */
#endif
  gboolean cpu_notice_logged;
};

struct _GstPseudo3DBaseClass {
  GstBaseTransformClass parent_class;

  /* Size mapping for transform_caps: output = input * num / den per axis
   * (sink to src); 1/1 when the stage keeps the size. Read per call, so a
   * stage may change them with a property (then reconfigure). */
  void (*get_size_ratio)(GstPseudo3DBase *self, gint *w_num, gint *w_den, gint *h_num, gint *h_den);
  /* Formats of the other pad when the stage converts (null: same format). */
  const gchar *src_formats;
  const gchar *sink_formats;
  /* Sets multiview-mode/-flags (and pixel-aspect-ratio) of src caps; null: unchanged. */
  void (*set_src_multiview)(GstPseudo3DBase *self, GstStructure *s);

  gboolean (*set_info)(GstPseudo3DBase *self, GstCaps *incaps, GstVideoInfo *in_info, GstCaps *outcaps,
                       GstVideoInfo *out_info);
  /* Not in place: frames are mapped (device pointers on GST_PSEUDO3D_PATH_GPU). */
  GstFlowReturn (*process)(GstPseudo3DBase *self, GstPseudo3DPath path, GstBuffer *inbuf, GstVideoFrame *in,
                           GstVideoFrame *out);
  /* In place: frame mapped for reading; the stage attaches metas to buf. */
  GstFlowReturn (*process_ip)(GstPseudo3DBase *self, GstPseudo3DPath path, GstBuffer *buf, GstVideoFrame *frame);
  /* Frees the stage's device memory; called in stop() with the context current. */
  void (*release_gpu)(GstPseudo3DBase *self);
};

GType gst_pseudo3d_base_get_type(void);

/* Where frames of the negotiated caps are processed. */
GstPseudo3DPath gst_pseudo3d_base_path(GstPseudo3DBase *self);

#if HAVE_CUDA
/* Posts a GST_ELEMENT_ERROR naming the failed CUDA call; returns GST_FLOW_ERROR. */
GstFlowReturn gst_pseudo3d_base_cuda_error(GstPseudo3DBase *self, const p3d::CudaStatus &st, const char *what);
/* Waits for the element's stream (1.22 has no stream tracking on memory,
 * so a buffer leaves only once the work on it is done). */
GstFlowReturn gst_pseudo3d_base_sync(GstPseudo3DBase *self);
#endif

G_DEFINE_AUTOPTR_CLEANUP_FUNC(GstPseudo3DBase, gst_object_unref)

G_END_DECLS

#if HAVE_CUDA
namespace p3d::gst {
/* The device view of a frame or depth map a stage reads (read = true: a
 * staged frame is uploaded) or writes: the mapped memory itself on
 * GST_PSEUDO3D_PATH_GPU, a staging buffer on GST_PSEUDO3D_PATH_STAGED. */
CudaStatus device_frame(GstPseudo3DBase *self, GstPseudo3DPath path, GpuStaging::Slot slot, const FrameView &frame,
                        bool read, FrameView *dev);
CudaStatus device_depth(GstPseudo3DBase *self, GstPseudo3DPath path, GpuStaging::Slot slot, ImageView<float> depth,
                        bool read, ImageView<float> *dev);
/* After the kernels: a staged result goes back to host memory (no-op on the GPU path). */
CudaStatus frame_to_host(GstPseudo3DBase *self, GstPseudo3DPath path, const FrameView &dev, const FrameView &host);
CudaStatus depth_to_host(GstPseudo3DBase *self, GstPseudo3DPath path, ImageView<const float> dev,
                         ImageView<float> host);
}  // namespace p3d::gst

/* Makes the element's CUDA context current on this thread for the scope. */
class CudaContextScope {
 public:
  explicit CudaContextScope(GstCudaContext *ctx) : pushed_(ctx && gst_cuda_context_push(ctx)) {}
  ~CudaContextScope() {
    if (pushed_) gst_cuda_context_pop(nullptr);
  }
  bool ok() const { return pushed_; }

 private:
  bool pushed_;
};
#endif
