#include "benchmark.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <fstream>

#include "encoder.h"
#include "gpu.h"
#include "gst_run.h"
#include "input_probe.h"
#include "json_line.h"
#include "media_source.h"
#include "progress.h"
#include "stage_settings.h"
#include "stream_copy.h"
#include "video_chain.h"

namespace p3d::convert {

namespace {

struct Measure {
  std::string mode;
  uint64_t frames = 0;
  double seconds = 0;       // first frame to EOS
  double wall_seconds = 0;  // PLAYING to EOS
  int width = 0, height = 0;
  std::string decoder;
  bool cuda_memory = false;
  std::string encoder_format;  // what the chain fed the encoder's stand-in
  double fps() const { return seconds > 0 ? frames / seconds : 0; }
};

GstPadProbeReturn read_frame(GstPad *, GstPadProbeInfo *info, gpointer) {
  GstBuffer *b = GST_PAD_PROBE_INFO_BUFFER(info);
  GstMapInfo map;
  if (gst_buffer_map(b, &map, GST_MAP_READ)) gst_buffer_unmap(b, &map);
  return GST_PAD_PROBE_OK;
}

// One timed run; `convert` selects the full video chain.
bool measure(const Options &o, Processing processing, const EncoderChoice &encoder, const InputFacts &facts,
             bool convert, Measure *m, std::string *error) {
  GstElement *pipeline = gst_pipeline_new("pseudo3d-benchmark");
  MediaSource source;
  VideoChain chain;
  chain.expect_rotation(facts.rotated);
  Progress counter(false);
  GstElement *vsink = gst_element_factory_make("fakesink", "video-sink");
  g_object_set(vsink, "sync", FALSE, NULL);
  gst_bin_add(GST_BIN(pipeline), vsink);
  GstPad *head = nullptr;  // where decodebin's video pad links
  GstElement *queue = nullptr;
  bool ok = true;
  m->encoder_format = encoder.raw_format;
  if (convert) {
    ok = chain.build(pipeline, o, processing, encoder.raw_format, error) && gst_element_link(chain.tail(), vsink);
    if (ok) chain.count_frames(&counter, source.piece_start());
    // The encoder's stand-in reads every frame, as an encoder would: a
    // frame still in device memory is downloaded here, inside the timing.
    GstPad *sinkpad = gst_element_get_static_pad(vsink, "sink");
    gst_pad_add_probe(sinkpad, GST_PAD_PROBE_TYPE_BUFFER, read_frame, nullptr, nullptr);
    gst_object_unref(sinkpad);
  } else {
    queue = make_frame_queue(8);
    gst_bin_add(GST_BIN(pipeline), queue);
    gst_element_link(queue, vsink);
    head = gst_element_get_static_pad(queue, "sink");
    GstPad *sinkpad = gst_element_get_static_pad(vsink, "sink");
    count_frames_at(sinkpad, &counter, 0);
    gst_object_unref(sinkpad);
  }
  std::atomic<bool> linked{false};
  source.set_piece(o.start, o.duration);
  MediaSource::Hooks hooks;
  hooks.keep_encoded = [](const GstCaps *caps) {
    const std::string name = gst_structure_get_name(gst_caps_get_structure(caps, 0));
    return name.rfind("audio/", 0) == 0 || name.rfind("text/", 0) == 0 || name.rfind("subpicture/", 0) == 0 ||
           name.rfind("application/x-ass", 0) == 0 || name.rfind("application/x-ssa", 0) == 0;
  };
  hooks.video_caps = [processing]() { return video_caps_for(processing); };
  hooks.pad_added = [&](GstPad *pad, GstCaps *caps) {
    const GstStructure *s = gst_caps_get_structure(caps, 0);
    if (!gst_structure_has_name(s, "video/x-raw") || linked.exchange(true)) {
      link_to_fakesink(pipeline, pad);
      return;
    }
    gst_structure_get_int(s, "width", &m->width);
    gst_structure_get_int(s, "height", &m->height);
    GstCapsFeatures *f = gst_caps_get_features(caps, 0);
    m->cuda_memory = f && gst_caps_features_contains(f, "memory:CUDAMemory");
    source.gate_pad(pad, false);
    if (convert) m->encoder_format = chain.feed_encoder(encoder, caps);  // as convert_video.cpp feeds it
    const bool attached = convert ? chain.attach(pad, caps) : gst_pad_link(pad, head) == GST_PAD_LINK_OK;
    if (!attached) post_error(pipeline, "could not link the decoded video");
  };
  hooks.no_more_pads = [pipeline]() { post_ready(pipeline); };
  ok = ok && source.build(pipeline, o.input, hooks, error);
  if (ok) {
    const gint64 t0 = g_get_monotonic_time();
    const LoopResult r = run_main_loop(
        pipeline,
        [&](std::string *e) {
          if (!linked) {
            *e = "no video stream";
            return false;
          }
          GstPad *p = convert ? chain.sink_pad() : head;
          if (source.has_piece() && !source.seek_to_piece(p)) {
            *e = "cannot seek for --start/--duration";
            return false;
          }
          return true;
        },
        nullptr);
    m->wall_seconds = (g_get_monotonic_time() - t0) / 1e6;
    // seconds() runs to now: taken right after EOS, before anything else.
    m->seconds = counter.seconds();
    m->frames = counter.frames();
    ok = r.ok;
    if (!ok) *error = o.input + ": " + r.error;
  }
  m->mode = convert ? "convert-fakesink" : "decode-only";
  m->decoder = source.video_decoder();
  if (head) gst_object_unref(head);
  gst_object_unref(pipeline);
  return ok;
}

}  // namespace

bool run_benchmark(const Options &o, std::string *error) {
  Processing processing;
  if (!resolve_processing(o.processing, &processing, error)) return false;
  if (processing == Processing::Gpu) prefer_gpu_decoders();
  Options conv = o;
  conv.kind = OutputKind::Mp4;  // the conversion a film gets: side-by-side-half unless --layout
  const InputFacts facts = probe_input(o.input);
  if (!settle_codec(&conv, processing, facts.bits, error)) return false;
  const std::string layout = effective_layout(conv);
  EncoderChoice encoder;
  if (!choose_encoder(conv, processing, layout, &encoder, error)) return false;

  std::FILE *jsonl = nullptr;
  if (!o.benchmark_out.empty() && !(jsonl = std::fopen(o.benchmark_out.c_str(), "a"))) {
    *error = o.benchmark_out + ": cannot write";
    return false;
  }
  char host[256] = "";
  gethostname(host, sizeof host - 1);
  double best[2] = {0, 0};
  bool ok = true;
  for (int run = 1; run <= o.benchmark_runs && ok; ++run) {
    for (int convert = 0; convert < 2 && ok; ++convert) {
      Measure m;
      ok = measure(conv, processing, encoder, facts, convert != 0, &m, error);
      if (!ok) break;
      best[convert] = std::max(best[convert], m.fps());
      std::printf("run %d  %-17s %6llu frames  %8.3f s  %8.1f frames/s  (wall %.3f s; %dx%d, %s%s)\n", run,
                  m.mode.c_str(), static_cast<unsigned long long>(m.frames), m.seconds, m.fps(), m.wall_seconds,
                  m.width, m.height, m.decoder.c_str(), m.cuda_memory ? ", CUDA memory" : "");
      std::fflush(stdout);
      if (jsonl)
        std::fprintf(jsonl, "%s\n",
                     tools::JsonLine()
                         .str("bench", "pseudo3d-convert")
                         .str("mode", m.mode)
                         .integer("run", run)
                         .str("input", o.input)
                         .integer("width", m.width)
                         .integer("height", m.height)
                         .str("decoder", m.decoder)
                         .raw("cuda_memory", m.cuda_memory ? "true" : "false")
                         .str("processing", processing_nick(processing))
                         .str("layout", layout)
                         .str("encoder_format", m.encoder_format)
                         .integer("frames", static_cast<long long>(m.frames))
                         .num("seconds", m.seconds)
                         .num("fps", m.fps())
                         .num("wall_seconds", m.wall_seconds)
                         .str("host", host)
                         .text()
                         .c_str());
    }
  }
  if (ok) {
    const double ratio = best[0] > 0 ? best[1] / best[0] : 0;
    std::printf("best decode-only %.1f frames/s, convert-fakesink %.1f frames/s: %.1f %% of decoding\n", best[0],
                best[1], 100 * ratio);
    if (jsonl)
      std::fprintf(jsonl, "%s\n",
                   tools::JsonLine()
                       .str("bench", "pseudo3d-convert")
                       .str("mode", "summary")
                       .str("input", o.input)
                       .str("layout", layout)
                       .str("processing", processing_nick(processing))
                       .num("decode_fps", best[0])
                       .num("convert_fps", best[1])
                       .num("ratio", ratio)
                       .str("host", host)
                       .text()
                       .c_str());
  }
  if (jsonl) std::fclose(jsonl);
  return ok;
}

}  // namespace p3d::convert
