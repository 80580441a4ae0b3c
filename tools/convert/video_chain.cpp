#include "video_chain.h"

#include <gst/video/video.h>

#include <cstdio>
#include <string>
#include <vector>

#include "depth_source.h"
#include "gpu.h"
#include "gst_run.h"
#include "input_probe.h"
#include "progress.h"
#include "stage_settings.h"

namespace p3d::convert {

namespace {

struct FrameCounter {
  Progress *progress;
  GstClockTime start;
  GstSegment segment;
};

GstPadProbeReturn count_probe(GstPad *, GstPadProbeInfo *info, gpointer data) {
  auto *c = static_cast<FrameCounter *>(data);
  if (info->type & GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM) {
    GstEvent *ev = GST_PAD_PROBE_INFO_EVENT(info);
    if (GST_EVENT_TYPE(ev) == GST_EVENT_SEGMENT) gst_event_copy_segment(ev, &c->segment);
    return GST_PAD_PROBE_OK;
  }
  // Where the frame ends (its start where it has no duration): a last
  // frame held for seconds (a slideshow, variable frame rate) still
  // reaches the end of the piece.
  GstBuffer *buf = GST_PAD_PROBE_INFO_BUFFER(info);
  GstClockTime end = GST_BUFFER_PTS(buf);
  if (GST_CLOCK_TIME_IS_VALID(end) && GST_BUFFER_DURATION_IS_VALID(buf)) end += GST_BUFFER_DURATION(buf);
  GstClockTime pos = GST_CLOCK_TIME_NONE;
  if (GST_CLOCK_TIME_IS_VALID(end) && c->segment.format == GST_FORMAT_TIME) {
    const guint64 st = gst_segment_to_stream_time(&c->segment, GST_FORMAT_TIME, end);
    if (st != GST_CLOCK_TIME_NONE) pos = st > c->start ? st - c->start : 0;
  }
  c->progress->frame(pos);
  return GST_PAD_PROBE_OK;
}

GstElement *make(const char *factory, std::string *missing) {
  GstElement *e = gst_element_factory_make(factory, nullptr);
  if (!e && missing->empty()) *missing = factory;
  return e;
}

// A new element of `factory` in `bin`, in the bin's state (streaming
// thread: the bin already runs); null if missing.
GstElement *add_to_bin(GstElement *bin, const char *factory) {
  GstElement *e = gst_element_factory_make(factory, nullptr);
  if (!e) return nullptr;
  gst_bin_add(GST_BIN(bin), e);
  gst_element_sync_state_with_parent(e);
  return e;
}

}  // namespace

GstElement *make_frame_queue(guint frames) {
  GstElement *q = gst_element_factory_make("queue", nullptr);
  if (q)
    g_object_set(q, "max-size-buffers", frames, "max-size-bytes", 0u, "max-size-time", G_GUINT64_CONSTANT(0), NULL);
  return q;
}

VideoChain::~VideoChain() {
  if (head_sink_) gst_object_unref(head_sink_);
  if (counted_) gst_object_unref(counted_);
}

bool VideoChain::build(GstElement *bin, const Options &o, Processing processing, const std::string &raw_format,
                       std::string *error) {
  bin_ = bin;
  processing_ = processing;
  std::string missing;
  head_ = make_frame_queue(8);
  if (o.depth.empty()) {
    convert_ = make("pseudo3dconvert", &missing);
  } else if (!(convert_ = make_depth_file_chain(o, processing, error))) {
    if (head_) gst_object_unref(gst_object_ref_sink(head_));
    return false;
  }
  // System memory after the 3D stages: the CPU encoders and videoconvert
  // take nothing else (pseudo3dconvert downloads once when on the GPU), in
  // the encoder's format where the bin's warp can pack into it.
  GstElement *to_system = make("capsfilter", &missing);
  GstElement *q2 = make_frame_queue(4);
  GstElement *vconv = make("videoconvert", &missing);
  tail_ = make("capsfilter", &missing);
  GstElement *all[] = {head_, convert_, to_system, q2, vconv, tail_};
  if (!missing.empty() || !head_ || !q2) {
    for (GstElement *e : all)
      if (e) gst_object_unref(gst_object_ref_sink(e));
    *error = "GStreamer element " + (missing.empty() ? std::string("queue") : missing) + " is missing";
    return false;
  }
  if (o.depth.empty()) {  // the depth file's chain is set up already
    apply_to_bin(o, convert_);
    gst_util_set_object_arg(G_OBJECT(convert_), "processing", processing_nick(processing));
  }
  to_system_ = to_system;
  use_format(raw_format);
  g_object_set(vconv, "n-threads", 0u, NULL);  // 0 = one per core
  for (GstElement *e : all) gst_bin_add(GST_BIN(bin), e);
  if (!gst_element_link_many(convert_, to_system, q2, vconv, tail_, NULL)) {
    *error = "could not link the 3D conversion to the encoder's format";
    return false;
  }
  head_sink_ = gst_element_get_static_pad(head_, "sink");
  return true;
}

std::string VideoChain::feed_encoder(const EncoderChoice &encoder, const GstCaps *decoded) {
  if (!has_deep_samples(decoded)) return encoder.raw_format;
  if (!encoder.deep_format.empty()) {
    use_format(encoder.deep_format);
    return encoder.deep_format;
  }
  const GstCapsFeatures *f = gst_caps_is_empty(decoded) ? nullptr : gst_caps_get_features(decoded, 0);
  const bool cuda = f && gst_caps_features_contains(f, "memory:CUDAMemory");
  // An 8-bit encoder: CUDA frames are narrowed on the device by
  // cudaconvert where it is registered, and always for formats the 10-bit
  // stages cannot pack on CUDA memory (an anaglyph's 4:4:4, which would
  // otherwise go through 4:2:0); else the stages keep 10 bits to the end.
  const bool yuv420 = encoder.raw_format == "I420" || encoder.raw_format == "NV12";
  narrow_before_stages_ = cuda && (!yuv420 || have_element("cudaconvert"));
  use_format(encoder.raw_format, cuda && !narrow_before_stages_);
  return encoder.raw_format;
}

void VideoChain::use_format(const std::string &raw_format, bool deep_input) {
  // The bin's warp packs into 4:2:0 itself (8 or 10 bits), as pseudo3dpack
  // would (on the GPU when the frames are there): a third of the bytes to
  // download and no CPU conversion; the videoconvert after it then passes
  // frames through. The stages keep their input's depth, so 10-bit input
  // for an 8-bit encoder is packed into I420_10LE, which videoconvert
  // narrows. Other encoder formats (Y444 for anaglyphs) still go through
  // videoconvert.
  const bool eight_bit_yuv = raw_format == "I420" || raw_format == "NV12";
  const std::string stages_format = deep_input && eight_bit_yuv ? "I420_10LE" : raw_format;
  const bool packed_yuv = eight_bit_yuv || stages_format == "I420_10LE" || stages_format == "P010_10LE";
  subsampled_ = packed_yuv;
  GstCaps *sys = packed_yuv ? gst_caps_new_simple("video/x-raw", "format", G_TYPE_STRING, stages_format.c_str(), NULL)
                            : gst_caps_from_string("video/x-raw");
  g_object_set(to_system_, "caps", sys, NULL);
  gst_caps_unref(sys);
  GstCaps *fmt = gst_caps_new_simple("video/x-raw", "format", G_TYPE_STRING, raw_format.c_str(), NULL);
  g_object_set(tail_, "caps", fmt, NULL);
  gst_caps_unref(fmt);
}

GstCaps *video_caps_for(Processing processing) {
  // CUDA memory only where the GPU path runs, in the formats the stages
  // take; system memory in any format (a videoconvert goes in front).
  if (processing == Processing::Gpu)
    return gst_caps_from_string(
        "video/x-raw(memory:CUDAMemory), format=(string){ NV12, I420, RGBA, BGRA, RGBx, BGRx, P010_10LE, I420_10LE }; "
        "video/x-raw");
  return gst_caps_from_string("video/x-raw");
}

GstCaps *VideoChain::accepted_caps() const { return video_caps_for(processing_); }

namespace {

// The GPU path's probe on the decoded video for orientation tags that
// probe_input() did not find: NVDEC's CUDA frames cannot go through
// videoflip (system memory only in GStreamer 1.22, whose CUDA converters
// cannot rotate), and this chain is already linked on the device, so the
// tag is refused with the reason, once, instead of converting the picture
// as stored (its depth hypotheses and stereo layout would describe the
// stored, not the upright, scene); the frames after it are dropped while
// the pipeline stops.
struct RotationGuard {
  GstElement *poster;  // the chain's first element, which posts the error
  bool refused = false;
};

GstPadProbeReturn refuse_rotation(GstPad *, GstPadProbeInfo *info, gpointer user_data) {
  auto *guard = static_cast<RotationGuard *>(user_data);
  if (guard->refused) return GST_PAD_PROBE_DROP;  // buffers and events alike: the run is over
  if (!(GST_PAD_PROBE_INFO_TYPE(info) & GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM)) return GST_PAD_PROBE_OK;
  GstEvent *event = GST_PAD_PROBE_INFO_EVENT(info);
  if (GST_EVENT_TYPE(event) != GST_EVENT_TAG) return GST_PAD_PROBE_OK;
  GstTagList *tags = nullptr;
  gst_event_parse_tag(event, &tags);
  const std::string rotation = tagged_rotation(tags);
  if (rotation.empty()) return GST_PAD_PROBE_OK;
  guard->refused = true;
  post_error(guard->poster, "the GPU path cannot apply the video's orientation tag " + rotation +
                                " (NVDEC's CUDA frames do not go through videoflip): use --processing cpu");
  return GST_PAD_PROBE_DROP;
}

}  // namespace

namespace {

bool known_interlaced(const GstCaps *caps, GstVideoInfo *info = nullptr) {
  GstVideoInfo local;
  GstVideoInfo *i = info ? info : &local;
  return gst_caps_is_fixed(caps) && gst_video_info_from_caps(i, caps) && GST_VIDEO_INFO_IS_INTERLACED(i);
}

}  // namespace

std::string deinterlacing_note(const GstCaps *decoded) {
  GstVideoInfo info;
  if (!known_interlaced(decoded, &info)) return "";
  char text[200];
  const int n = GST_VIDEO_INFO_FPS_N(&info), d = GST_VIDEO_INFO_FPS_D(&info);
  const double fps = d ? static_cast<double>(n) / d : 0;
  if (fps > 0)
    std::snprintf(text, sizeof text,
                  "the video is interlaced (%g frames/s): it is deinterlaced to %g frames/s, a frame for each field",
                  fps, 2 * fps);
  else
    std::snprintf(text, sizeof text, "the video is interlaced: it is deinterlaced, a frame for each field");
  return text;
}

bool VideoChain::attach(GstPad *decoded, const GstCaps *caps) {
  GstCapsFeatures *features = gst_caps_get_features(caps, 0);
  cuda_input_ = features && gst_caps_features_contains(features, "memory:CUDAMemory");
  // 4:2:0 encoders refuse odd sizes (x264: "Can not initialize"), and every
  // layout of an even picture is even: the last column or row of an odd one
  // is cropped before the 3D stages (and before a rotation, whose sizes it
  // was measured in). A pad exposed before any frame was decoded (a file
  // cut off in its first frame) has unfixed caps and no size: no frame
  // follows, so there is nothing to crop.
  GstVideoInfo info;
  const bool known = gst_caps_is_fixed(caps) && gst_video_info_from_caps(&info, caps);
  const int crop_right = known && subsampled_ ? GST_VIDEO_INFO_WIDTH(&info) % 2 : 0;
  const int crop_bottom = known && subsampled_ ? GST_VIDEO_INFO_HEIGHT(&info) % 2 : 0;
  // GStreamer 1.22 has no deinterlacer, crop or rotation for CUDA memory:
  // NVDEC's frames that need one (interlaced video, an odd size for a
  // 4:2:0 encoder, an orientation tag found by probe_input) are
  // downloaded and take the system-memory route below, where
  // pseudo3dconvert deinterlaces them and uploads them again for the GPU
  // stages.
  const bool download = cuda_input_ && (known_interlaced(caps) || crop_right || crop_bottom || rotated_);
  if (cuda_input_ && !download) {
    // An orientation tag the probe did not see (an input read as a
    // stream) is refused, once, with the reason. Before linking, so that
    // no event passes unseen (the decoder's sticky tags reach head_sink_
    // after the link).
    gst_pad_add_probe(head_sink_,
                      static_cast<GstPadProbeType>(GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM | GST_PAD_PROBE_TYPE_BUFFER |
                                                   GST_PAD_PROBE_TYPE_BUFFER_LIST),
                      refuse_rotation, new RotationGuard{head_},
                      [](gpointer p) { delete static_cast<RotationGuard *>(p); });
    if (gst_pad_link(decoded, head_sink_) != GST_PAD_LINK_OK) return false;
    // Formats the stages do not take (NVDEC's P016 of 12-bit video, its
    // 4:4:4 formats), and deep frames feed_encoder() narrows, are converted
    // on the device by nvcodec's cudaconvert where it is registered (it
    // needs NVRTC); otherwise the frames are downloaded, converted by
    // videoconvert and uploaded again by pseudo3dconvert. Narrowed frames
    // pass a filter of the 8-bit formats.
    GstElement *last = head_;
    GstCaps *taken = video_caps_for(Processing::Gpu);
    const bool convert_format = known && (narrow_before_stages_ || !gst_caps_can_intersect(caps, taken));
    gst_caps_unref(taken);
    if (convert_format) {
      std::vector<GstElement *> converters;
      if (GstElement *on_device = add_to_bin(bin_, "cudaconvert")) {
        converters.push_back(on_device);
      } else {
        GstElement *down = add_to_bin(bin_, "cudadownload"), *vconv = add_to_bin(bin_, "videoconvert");
        if (!down || !vconv) return false;
        g_object_set(vconv, "n-threads", 0u, NULL);
        converters = {down, vconv};
      }
      if (narrow_before_stages_) {
        GstElement *eight = add_to_bin(bin_, "capsfilter");
        if (!eight) return false;
        GstCaps *formats = gst_caps_from_string(
            "video/x-raw(memory:CUDAMemory), format=(string){ NV12, I420, RGBA, BGRA, RGBx, BGRx }; "
            "video/x-raw, format=(string){ NV12, I420, RGBA, BGRA, RGBx, BGRx }");
        g_object_set(eight, "caps", formats, NULL);
        gst_caps_unref(formats);
        converters.push_back(eight);
      }
      for (GstElement *c : converters) {
        if (!gst_element_link(last, c)) return false;
        last = c;
      }
    }
    return gst_element_link(last, convert_);
  }
  if (gst_pad_link(decoded, head_sink_) != GST_PAD_LINK_OK) return false;
  // System memory: videoconvert passes the formats the stages take through
  // untouched and converts the rest (4:2:2, 12-bit, and 10-bit for an
  // 8-bit encoder...).
  std::vector<GstElement *> links = {head_};
  if (download) {
    GstElement *down = add_to_bin(bin_, "cudadownload");
    if (!down) return false;
    links.push_back(down);
  }
  GstElement *vconv = add_to_bin(bin_, "videoconvert");
  if (!vconv) return false;
  g_object_set(vconv, "n-threads", 0u, NULL);
  links.push_back(vconv);
  if (crop_right || crop_bottom) {
    GstElement *crop = add_to_bin(bin_, "videocrop");
    if (!crop) return false;
    g_object_set(crop, "right", crop_right, "bottom", crop_bottom, NULL);
    links.push_back(crop);
    cropped_ = true;
  }
  // Phone videos are stored sideways with a rotation tag: turn the picture
  // upright (videoflip follows the stream's image-orientation tag and passes
  // frames through untouched without one), since the depth hypotheses
  // describe the upright scene and the output carries no rotation.
  GstElement *flip = add_to_bin(bin_, "videoflip");
  if (!flip) return false;
  gst_util_set_object_arg(G_OBJECT(flip), "video-direction", "auto");
  links.push_back(flip);
  links.push_back(convert_);
  for (size_t i = 0; i + 1 < links.size(); ++i)
    if (!gst_element_link(links[i], links[i + 1])) return false;
  return true;
}

gulong count_frames_at(GstPad *pad, Progress *progress, GstClockTime start) {
  auto *c = new FrameCounter{progress, start, {}};
  gst_segment_init(&c->segment, GST_FORMAT_UNDEFINED);
  return gst_pad_add_probe(pad,
                           static_cast<GstPadProbeType>(GST_PAD_PROBE_TYPE_BUFFER | GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM),
                           count_probe, c, [](gpointer p) { delete static_cast<FrameCounter *>(p); });
}

void VideoChain::count_frames(Progress *progress, GstClockTime start) {
  progress_ = progress;
  counted_ = gst_element_get_static_pad(tail_, "src");
  count_probe_ = count_frames_at(counted_, progress, start);
}

bool VideoChain::hold_still(int frames) {
  GstElement *freeze = gst_element_factory_make("imagefreeze", nullptr);
  GstElement *rate = gst_element_factory_make("capsfilter", nullptr);
  if (!freeze || !rate) {
    if (freeze) gst_object_unref(gst_object_ref_sink(freeze));
    if (rate) gst_object_unref(gst_object_ref_sink(rate));
    refusal_ = "GStreamer element imagefreeze is missing (gstreamer1.0-plugins-good)";
    return false;
  }
  // Set before the element starts: imagefreeze takes its count on the way
  // to PAUSED.
  g_object_set(freeze, "num-buffers", frames, NULL);
  GstCaps *caps = gst_caps_new_simple("video/x-raw", "framerate", GST_TYPE_FRACTION, kStillFrameRate, 1, NULL);
  g_object_set(rate, "caps", caps, NULL);
  gst_caps_unref(caps);
  gst_bin_add_many(GST_BIN(bin_), freeze, rate, NULL);
  gst_element_sync_state_with_parent(freeze);
  gst_element_sync_state_with_parent(rate);
  // tail_ ! imagefreeze ! capsfilter ! (what tail_ fed: the encoder).
  GstPad *out = gst_element_get_static_pad(tail_, "src");
  GstPad *next = gst_pad_get_peer(out);
  if (next) gst_pad_unlink(out, next);
  GstPad *rate_src = gst_element_get_static_pad(rate, "src");
  const bool linked = next && gst_element_link_many(tail_, freeze, rate, NULL) &&
                      gst_pad_link(rate_src, next) == GST_PAD_LINK_OK;
  gst_object_unref(out);
  if (next) gst_object_unref(next);
  // The frames the encoder gets are counted: the still video's.
  if (linked && counted_) {
    gst_pad_remove_probe(counted_, count_probe_);
    gst_object_unref(counted_);
    counted_ = GST_PAD(gst_object_ref(rate_src));
    count_probe_ = count_frames_at(counted_, progress_, 0);  // the still's own time
  }
  gst_object_unref(rate_src);
  return linked;
}

}  // namespace p3d::convert
