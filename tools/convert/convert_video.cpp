#include "convert_video.h"

#include <gst/pbutils/pbutils.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <vector>

#include "encoder.h"
#include "gpu.h"
#include "gst_run.h"
#include "input_probe.h"
#include "media_source.h"
#include "container_stereo.h"
#include "depth_source.h"
#include "output_file.h"
#include "progress.h"
#include "stage_settings.h"
#include "stall_watch.h"
#include "stream_copy.h"
#include "video_chain.h"

namespace p3d::convert {

namespace {

const char *muxer_for(OutputKind k) {
  return k == OutputKind::Mkv ? "matroskamux" : k == OutputKind::Mov ? "qtmux" : "mp4mux";
}

std::string codec_name(const GstCaps *caps) {
  gchar *d = gst_pb_utils_get_codec_description(caps);
  std::string s = d ? d : gst_structure_get_name(gst_caps_get_structure(caps, 0));
  g_free(d);
  return s;
}

struct Job {
  explicit Job(const Options &opts) : o(opts), progress(!opts.quiet) {}
  ~Job() {
    if (pipeline) gst_object_unref(pipeline);
  }

  const Options &o;
  Processing processing = Processing::Cpu;
  std::string layout;
  EncoderChoice encoder;
  GstElement *pipeline = nullptr, *mux = nullptr;
  MediaSource source;
  VideoChain chain;
  Progress progress;
  std::atomic<bool> video_linked{false};
  std::atomic<bool> still{false};  // the input is a picture, written as a still video
  std::mutex lock;  // streams, notes: written by streaming threads
  std::vector<std::string> streams, notes;

  void note(const std::string &s) {
    std::lock_guard<std::mutex> l(lock);
    notes.push_back(s);
  }
  void stream(const std::string &s) {
    std::lock_guard<std::mutex> l(lock);
    streams.push_back(s);
  }

  // Streaming thread: one decodebin pad.
  void pad_added(GstPad *pad, GstCaps *caps) {
    const std::string name = gst_structure_get_name(gst_caps_get_structure(caps, 0));
    if (name.rfind("video/", 0) == 0) {
      if (video_linked.exchange(true)) {
        note("an extra video stream (" + codec_name(caps) + ") is left out");
        link_to_fakesink(pipeline, pad);
        return;
      }
      if (source.still_picture() && !hold_still()) {
        post_error(pipeline, chain.refusal());
        return;
      }
      source.gate_pad(pad, false);
      chain.feed_encoder(encoder, caps);
      for (const std::string &n : {colour_loss(caps, encoder), deinterlacing_note(caps)})
        if (!n.empty()) note(n);
      if (!chain.attach(pad, caps))
        post_error(pipeline, chain.refusal().empty() ? "could not link the decoded video to the 3D conversion"
                                                     : chain.refusal());
      return;
    }
    const StreamRoute route = route_stream(caps, o.kind);
    if (route.action == StreamAction::Drop) {
      note(route.why + ": that stream is left out");
      link_to_fakesink(pipeline, pad);
      return;
    }
    source.gate_pad(pad, route.action == StreamAction::Copy);
    std::string error;
    GstPad *head = link_stream_branch(pipeline, pad, caps, route, o.kind, mux, &error);
    if (!head) {
      post_error(pipeline, error);
      return;
    }
    gst_object_unref(head);
    const bool audio = name.rfind("audio/", 0) == 0;
    // A re-encoded stream arrives decoded: name the codec it had.
    GstCaps *encoded = route.action == StreamAction::Encode ? MediaSource::encoded_caps(pad) : nullptr;
    stream(std::string(audio ? "audio " : "subtitles ") +
           (route.action == StreamAction::Encode ? "re-encoded from " : "copied, ") + codec_name(encoded ? encoded : caps));
    if (encoded) gst_caps_unref(encoded);
  }

  GstClockTime still_duration() const {
    return GST_CLOCK_TIME_IS_VALID(o.duration) ? o.duration : kStillDuration;
  }

  // A picture into a video file: its 3D frame repeated for still_duration()
  // (a lone frame of no duration plays as nothing), with no piece to seek.
  bool hold_still() {
    still = true;
    source.set_piece(GST_CLOCK_TIME_NONE, GST_CLOCK_TIME_NONE);
    const double seconds = static_cast<double>(still_duration()) / GST_SECOND;
    const int frames = std::max(1, static_cast<int>(std::lround(seconds * kStillFrameRate)));
    char what[160];
    std::snprintf(what, sizeof what,
                  "the input is a still picture: it becomes a %g s still video "
                  "at %d frames/s (--duration sets the length)",
                  seconds, kStillFrameRate);
    note(what);
    return chain.hold_still(frames);
  }

  // Main thread, once every stream is linked.
  bool ready(std::string *error) {
    if (!video_linked) {
      *error = "no video stream";
      return false;
    }
    if (still && GST_CLOCK_TIME_IS_VALID(o.start)) {
      *error = "--start does not apply to a still picture (--duration sets the length of its video)";
      return false;
    }
    progress.set_total(still ? still_duration() : source.total_time(chain.sink_pad()));
    if (source.has_piece() && !source.seek_to_piece(chain.sink_pad())) {
      *error = "cannot seek for --start/--duration (the file is not seekable)";
      return false;
    }
    if (chain.cropped_to_even())
      note("the picture's odd width or height loses its last column or row (the encoder's 4:2:0 needs even sizes)");
    if (!o.quiet) print_plan();
    return true;
  }

  // "(decoder avdec_h264, CUDA memory)": what is known of the decoding;
  // empty when nothing is (no decoder was plugged yet).
  std::string decoding() const {
    std::vector<std::string> parts;
    const std::string decoder = source.video_decoder();
    if (!decoder.empty()) parts.push_back("decoder " + decoder);
    if (chain.on_gpu_memory()) parts.push_back("CUDA memory");
    std::string s;
    for (const std::string &p : parts) s += (s.empty() ? " (" : ", ") + p;
    return s.empty() ? s : s + ")";
  }

  void print_plan() {
    const int crf = o.crf >= 0 ? o.crf : default_crf(o.codec);
    std::string line = "pseudo3d-convert: " + o.input + " -> " + o.output + ": " + layout + ", " + encoder.factory +
                       " crf " + std::to_string(crf) + " preset " + (o.preset.empty() ? "medium" : o.preset) +
                       ", 3D on the " + (processing == Processing::Gpu ? "GPU" : "CPU") + decoding();
    std::lock_guard<std::mutex> l(lock);
    for (const std::string &s : streams) line += "; " + s;
    std::fprintf(stderr, "%s\n", line.c_str());
    for (const std::string &n : notes) std::fprintf(stderr, "pseudo3d-convert: note: %s\n", n.c_str());
    if (is_stereo_layout(layout) && !encoder.writes_stereo_sei)
      std::fprintf(stderr, "pseudo3d-convert: note: %s writes no frame-packing SEI, so the 3D layout is signalled %s\n",
                   encoder.factory.c_str(), container_only_signal().c_str());
  }

  // Where the layout is signalled when the stream carries no SEI.
  std::string container_only_signal() const {
    if (o.kind == OutputKind::Mkv) return "in the Matroska container only";
    return mp4_stereo_box_says(layout, right_view_first(o))
               ? "in the MP4 st3d box only (which GStreamer does not read)"
               : "nowhere (use .mkv or --codec h264)";
  }

  // encoder ! parser ! pseudo3dsignal ! queue ! mux ! filesink.
  bool build(const std::string &temp_path, std::string *error) {
    pipeline = gst_pipeline_new("pseudo3d-convert");
    mux = gst_element_factory_make(muxer_for(o.kind), "mux");
    GstElement *sink = gst_element_factory_make("filesink", "sink");
    GstElement *enc = make_encoder(encoder, o);
    GstElement *parse = gst_element_factory_make(encoder.parser.c_str(), nullptr);
    GstElement *signal = gst_element_factory_make("pseudo3dsignal", nullptr);
    GstElement *q = make_frame_queue(8);
    GstElement *all[] = {mux, sink, enc, parse, signal, q};
    const char *names[] = {muxer_for(o.kind), "filesink", encoder.factory.c_str(), encoder.parser.c_str(),
                           "pseudo3dsignal", "queue"};
    for (size_t i = 0; i < G_N_ELEMENTS(all); ++i)
      if (!all[i]) {
        for (GstElement *e : all)
          if (e) gst_object_unref(gst_object_ref_sink(e));
        mux = nullptr;
        *error = std::string("GStreamer element ") + names[i] + " is missing";
        return false;
      }
    g_object_set(sink, "location", temp_path.c_str(), NULL);
    gst_bin_add_many(GST_BIN(pipeline), mux, sink, enc, parse, signal, q, NULL);
    if (!chain.build(pipeline, o, processing, encoder.raw_format, error)) return false;
    GstPad *mux_video = gst_element_request_pad_simple(mux, "video_%u");
    GstPad *q_src = gst_element_get_static_pad(q, "src");
    const bool linked = gst_element_link_many(chain.tail(), enc, parse, signal, q, NULL) && mux_video &&
                        gst_pad_link(q_src, mux_video) == GST_PAD_LINK_OK && gst_element_link(mux, sink);
    gst_object_unref(q_src);
    if (mux_video) gst_object_unref(mux_video);
    if (!linked) {
      *error = "could not link " + encoder.factory + " to " + muxer_for(o.kind);
      return false;
    }
    source.set_piece(o.start, o.duration);
    chain.count_frames(&progress, source.piece_start());
    MediaSource::Hooks hooks;
    hooks.keep_encoded = [this](const GstCaps *caps) { return keep_encoded(caps, o.kind); };
    hooks.video_caps = [this]() { return chain.accepted_caps(); };
    hooks.pad_added = [this](GstPad *pad, GstCaps *caps) { pad_added(pad, caps); };
    hooks.no_more_pads = [this]() { post_ready(pipeline); };
    return source.build(pipeline, o.input, hooks, error);
  }
};

}  // namespace

bool convert_video(const Options &given, std::string *error) {
  Processing processing;
  if (!resolve_processing(given.processing, &processing, error)) return false;
  if (processing == Processing::Gpu) prefer_gpu_decoders();
  Options o = given;
  const InputFacts facts = probe_input(o.input);
  if (!settle_codec(&o, processing, facts.bits, error)) return false;
  Job job(o);
  job.processing = processing;
  job.chain.expect_rotation(facts.rotated);
  job.layout = effective_layout(o);
  if (!depth_file_readable(o, error)) return false;
  if (!choose_encoder(o, job.processing, job.layout, &job.encoder, error)) return false;
  OutputFile out;
  if (!out.open(o.output, o.force, error)) return false;
  if (!job.build(out.temp_path(), error)) return false;

  // Two minutes without a frame: longer than any frame takes (an 8K frame
  // is about 1.5 s through the CPU stages), short enough to end a hang.
  const bool watch = !job.source.reads_stream();
  StallWatch stall(120);
  bool stall_posted = false;
  const LoopResult r = run_main_loop(
      job.pipeline, [&job](std::string *e) { return job.ready(e); },
      [&]() {
        job.progress.tick();
        if (watch && !stall_posted && stall.stalled(job.progress.frames(), g_get_monotonic_time())) {
          stall_posted = true;
          post_error(job.pipeline, "no frame came for " + format_clock(stall.limit_seconds()) +
                                       ": the decoders stalled (a damaged file?)");
        }
      });
  if (!r.ok) {
    job.progress.abandon();
    const bool from_depth = !o.depth.empty() && r.source.find(kDepthReaderMark) != std::string::npos;
    const std::string no_decoder = "no GStreamer decoder for " + r.missing_plugin + " is installed";
    if (from_depth)
      *error = o.depth + ": " + (r.missing_plugin.empty() ? r.error : no_decoder);
    else if (!r.missing_plugin.empty() && !job.video_linked)
      *error = o.input + ": " + no_decoder;
    else
      *error = (r.from_filesink ? o.output : o.input) + ": " + r.error;
    return false;
  }
  if (job.progress.frames() == 0) {
    job.progress.abandon();
    // --start is blamed only when it was given (and is past 0): otherwise
    // no frame means that none could be decoded.
    const bool past_start = GST_CLOCK_TIME_IS_VALID(o.start) && o.start > 0;
    *error = o.input + ": no video frames to convert" +
             (past_start ? " (--start is at or past the end of the video)"
                         : " (none could be decoded: a truncated or damaged file?)");
    return false;
  }
  // Frames are counted by where they end: a last frame a second or more
  // short of the announced end means frames are missing at the end.
  const GstClockTime short_by = job.progress.shortfall();
  if (o.kind == OutputKind::Mkv &&
      !set_mkv_container_stereo_mode(out.temp_path(), job.layout, right_view_first(o), error))
    return false;
  if ((o.kind == OutputKind::Mp4 || o.kind == OutputKind::Mov) &&
      !set_mp4_stereo_box(out.temp_path(), job.layout, right_view_first(o), error))
    return false;
  if (!out.commit(error)) return false;
  job.progress.finish();
  if (short_by >= GST_SECOND)
    std::fprintf(stderr,
                 "pseudo3d-convert: warning: %s: the video ended %s before the end its file announces (a truncated "
                 "file, or sound that outlasts the picture)\n",
                 o.input.c_str(), format_clock(static_cast<double>(short_by) / GST_SECOND).c_str());
  if (!o.quiet) {
    const double secs = job.progress.seconds();
    std::fprintf(stderr, "pseudo3d-convert: wrote %s: %llu frames in %s (%.1f frames/s)\n", o.output.c_str(),
                 static_cast<unsigned long long>(job.progress.frames()), format_clock(secs).c_str(),
                 secs > 0 ? job.progress.frames() / secs : 0.0);
  }
  return true;
}

}  // namespace p3d::convert
