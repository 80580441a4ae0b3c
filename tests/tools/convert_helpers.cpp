#include "convert_helpers.h"

#include <dirent.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <sstream>

#include <gst/gst.h>

#include "element_helpers.h"
#include "stereo_readers.h"

namespace p3d::test {

std::string convert_program() {
  const char *env = std::getenv("P3D_CONVERT");
  return env && *env ? env : P3D_CONVERT_BIN;
}

ToolRun run_convert(const std::vector<std::string> &args) { return run_convert_in("", args); }

ToolRun run_convert_in(const std::string &cwd, const std::vector<std::string> &args,
                       const std::vector<std::string> &env) {
  std::vector<std::string> argv{convert_program()};
  argv.insert(argv.end(), args.begin(), args.end());
  ToolRun r;
  r.status = run_program(argv, &r.out, &r.err, cwd, env);
  return r;
}

std::string make_clip(const std::string &launch) { return run_to_eos(launch, 120); }

namespace {

struct ReadState {
  ReadBack *r;
  GstElement *pipeline;
  std::mutex lock;
  GstSegment video_segment, audio_segment;
};

// Times as a player sees them: running time of the demuxer's segment (it
// holds the MP4 edit list, e.g. the B-frame delay of the video track).
void add_time(const GstSegment &seg, GstBuffer *b, double *start, double *end) {
  if (!GST_BUFFER_PTS_IS_VALID(b) || seg.format != GST_FORMAT_TIME) return;
  const guint64 rt = gst_segment_to_running_time(&seg, GST_FORMAT_TIME, GST_BUFFER_PTS(b));
  if (rt == GST_CLOCK_TIME_NONE) return;
  const double t = rt / 1e9, d = GST_BUFFER_DURATION_IS_VALID(b) ? GST_BUFFER_DURATION(b) / 1e9 : 0;
  if (*start < 0 || t < *start) *start = t;
  if (t + d > *end) *end = t + d;
}

uint64_t fnv1a(uint64_t h, const uint8_t *p, size_t n) {
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

// A probed stream's events: keeps its segment and caps (as text, and the
// structure while the event lives). True for an event.
bool stream_event(GstPadProbeInfo *info, GstSegment *segment, std::string *caps_text,
                  const GstStructure **structure) {
  if (!(info->type & GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM)) return false;
  GstEvent *ev = GST_PAD_PROBE_INFO_EVENT(info);
  if (GST_EVENT_TYPE(ev) == GST_EVENT_SEGMENT) gst_event_copy_segment(ev, segment);
  if (GST_EVENT_TYPE(ev) == GST_EVENT_CAPS) {
    GstCaps *caps;
    gst_event_parse_caps(ev, &caps);
    gchar *str = gst_caps_to_string(caps);
    *caps_text = str;
    g_free(str);
    *structure = gst_caps_get_structure(caps, 0);
  }
  return true;
}

GstPadProbeReturn video_probe(GstPad *, GstPadProbeInfo *info, gpointer data) {
  auto *s = static_cast<ReadState *>(data);
  std::lock_guard<std::mutex> l(s->lock);
  ReadBack &r = *s->r;
  const GstStructure *st = nullptr;
  if (stream_event(info, &s->video_segment, &r.video_caps, &st)) {
    if (st) {
      const char *mode = gst_structure_get_string(st, "multiview-mode");
      r.multiview_mode = mode ? mode : "";
      guint flags = 0, mask = 0;
      if (gst_structure_get_flagset(st, "multiview-flags", &flags, &mask)) r.multiview_flags = flags & mask;
      gst_structure_get_int(st, "width", &r.width);
      gst_structure_get_int(st, "height", &r.height);
    }
    return GST_PAD_PROBE_OK;
  }
  GstBuffer *b = GST_PAD_PROBE_INFO_BUFFER(info);
  ++r.video_frames;
  add_time(s->video_segment, b, &r.video_start, &r.video_end);
  return GST_PAD_PROBE_OK;
}

GstPadProbeReturn audio_probe(GstPad *, GstPadProbeInfo *info, gpointer data) {
  auto *s = static_cast<ReadState *>(data);
  std::lock_guard<std::mutex> l(s->lock);
  ReadBack &r = *s->r;
  const GstStructure *st = nullptr;
  if (stream_event(info, &s->audio_segment, &r.audio_caps, &st)) return GST_PAD_PROBE_OK;
  GstBuffer *b = GST_PAD_PROBE_INFO_BUFFER(info);
  if (GST_BUFFER_FLAG_IS_SET(b, GST_BUFFER_FLAG_HEADER)) return GST_PAD_PROBE_OK;
  ++r.audio_buffers;
  GstMapInfo map;
  if (gst_buffer_map(b, &map, GST_MAP_READ)) {
    r.audio_checksum = fnv1a(r.audio_checksum ? r.audio_checksum : 1469598103934665603ull, map.data, map.size);
    gst_buffer_unmap(b, &map);
  }
  add_time(s->audio_segment, b, &r.audio_start, &r.audio_end);
  return GST_PAD_PROBE_OK;
}

const auto kProbeMask = static_cast<GstPadProbeType>(GST_PAD_PROBE_TYPE_BUFFER | GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM);

void on_demux_pad(GstElement *, GstPad *pad, gpointer data) {
  auto *s = static_cast<ReadState *>(data);
  GstCaps *caps = gst_pad_query_caps(pad, nullptr);
  const std::string name = gst_structure_get_name(gst_caps_get_structure(caps, 0));
  gst_caps_unref(caps);
  // A queue per stream: each sink prerolls in its own thread (one demuxer
  // thread blocked in the first sink's preroll would starve the other).
  GstElement *queue = gst_element_factory_make("queue", nullptr);
  GstElement *sink = gst_element_factory_make("fakesink", nullptr);
  g_object_set(sink, "sync", FALSE, NULL);
  gst_bin_add_many(GST_BIN(s->pipeline), queue, sink, NULL);
  GstElement *last = queue;
  if (name == "video/x-h264" || name == "video/x-h265") {
    GstElement *parse = gst_element_factory_make(name == "video/x-h264" ? "h264parse" : "h265parse", nullptr);
    gst_bin_add(GST_BIN(s->pipeline), parse);
    gst_element_link(queue, parse);
    GstPad *src = gst_element_get_static_pad(parse, "src");
    gst_pad_add_probe(src, kProbeMask, video_probe, s, nullptr);
    gst_object_unref(src);
    last = parse;
  } else if (name.rfind("audio/", 0) == 0) {
    GstPad *in = gst_element_get_static_pad(sink, "sink");
    gst_pad_add_probe(in, kProbeMask, audio_probe, s, nullptr);
    gst_object_unref(in);
  }
  gst_element_link(last, sink);
  gst_element_sync_state_with_parent(sink);
  if (last != queue) gst_element_sync_state_with_parent(last);
  gst_element_sync_state_with_parent(queue);
  GstPad *in = gst_element_get_static_pad(queue, "sink");
  gst_pad_link(pad, in);
  gst_object_unref(in);
}

}  // namespace

ReadBack read_back(const std::string &path) {
  ReadBack r;
  const bool mkv = path.size() > 4 && path.compare(path.size() - 4, 4, ".mkv") == 0;
  GstElement *pipeline = gst_pipeline_new(nullptr);
  GstElement *src = gst_element_factory_make("filesrc", nullptr);
  GstElement *demux = gst_element_factory_make(mkv ? "matroskademux" : "qtdemux", nullptr);
  g_object_set(src, "location", path.c_str(), NULL);
  gst_bin_add_many(GST_BIN(pipeline), src, demux, NULL);
  gst_element_link(src, demux);
  ReadState state{&r, pipeline, {}, {}, {}};
  gst_segment_init(&state.video_segment, GST_FORMAT_UNDEFINED);
  gst_segment_init(&state.audio_segment, GST_FORMAT_UNDEFINED);
  g_signal_connect(demux, "pad-added", G_CALLBACK(on_demux_pad), &state);
  GstBus *bus = gst_element_get_bus(pipeline);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  GstMessage *msg = gst_bus_timed_pop_filtered(bus, 60 * GST_SECOND,
                                               static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR));
  if (!msg) {
    r.error = "timeout";
  } else if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR) {
    GError *e = nullptr;
    gst_message_parse_error(msg, &e, nullptr);
    r.error = e->message;
    g_error_free(e);
  }
  if (msg) gst_message_unref(msg);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(pipeline);
  return r;
}

std::string ffprobe_stream(const std::string &path, const std::string &selector, const std::string &entries) {
  std::string out;
  run_program({"ffprobe", "-v", "error", "-select_streams", selector, "-show_entries", "stream=" + entries, "-of",
               "default=nw=1", path},
              &out);
  return out;
}

std::string ffprobe_value(const std::string &text, const std::string &key) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + "=", 0) == 0) return line.substr(key.size() + 1);
  return "";
}

std::vector<uint8_t> read_bytes(const std::string &path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

namespace {

// APP segments before the scan: {marker, payload offset, payload size}.
struct Segment {
  uint8_t marker;
  size_t at, size;
};
std::vector<Segment> segments(const std::vector<uint8_t> &j, size_t from = 0) {
  std::vector<Segment> out;
  if (j.size() < from + 4 || j[from] != 0xFF || j[from + 1] != 0xD8) return out;
  size_t i = from + 2;
  while (i + 4 <= j.size() && j[i] == 0xFF) {
    const uint8_t m = j[i + 1];
    const size_t len = (j[i + 2] << 8) | j[i + 3];
    if (m == 0xDA || len < 2) break;
    out.push_back({m, i + 4, len - 2});
    i += 2 + len;
  }
  return out;
}

struct Tiff {
  const uint8_t *p;
  size_t n;
  bool le;
  uint32_t u16(size_t o) const { return o + 2 > n ? 0 : le ? p[o] | p[o + 1] << 8 : p[o] << 8 | p[o + 1]; }
  uint32_t u32(size_t o) const {
    return le ? u16(o) | u16(o + 2) << 16 : u16(o) << 16 | u16(o + 2);
  }
};

}  // namespace

MpoIndex parse_mpo(const std::vector<uint8_t> &file) {
  MpoIndex idx;
  for (const Segment &s : segments(file)) {
    if (s.marker != 0xE2 || s.size < 12 || std::memcmp(&file[s.at], "MPF", 4) != 0) continue;
    idx.found = true;
    const size_t header = s.at + 4;
    const Tiff t{&file[header], s.size - 4, file[header] == 'I'};
    const uint32_t ifd = t.u32(4);
    const uint32_t count = t.u16(ifd);
    uint32_t entries_at = 0, entries_size = 0;
    for (uint32_t k = 0; k < count; ++k) {
      const size_t e = ifd + 2 + 12 * k;
      const uint32_t tag = t.u16(e);
      if (tag == 0xB001) idx.number_of_images = t.u32(e + 8);
      if (tag == 0xB002) {
        entries_size = t.u32(e + 4);
        entries_at = t.u32(e + 8);
      }
    }
    for (uint32_t k = 0; k * 16 + 16 <= entries_size; ++k) {
      MpoEntry m;
      m.attribute = t.u32(entries_at + 16 * k);
      m.size = t.u32(entries_at + 16 * k + 4);
      m.offset = t.u32(entries_at + 16 * k + 8);
      m.file_offset = m.offset == 0 ? 0 : header + m.offset;
      idx.entries.push_back(m);
    }
    return idx;
  }
  idx.error = "no APP2 MPF segment in the first image";
  return idx;
}

namespace {
const Segment *exif_segment(const std::vector<uint8_t> &j, const std::vector<Segment> &segs) {
  for (const Segment &s : segs)
    if (s.marker == 0xE1 && s.size > 14 && std::memcmp(&j[s.at], "Exif\0", 6) == 0) return &s;
  return nullptr;
}
}  // namespace

int jpeg_exif_orientation(const std::vector<uint8_t> &jpeg) {
  const std::vector<Segment> segs = segments(jpeg);
  const Segment *s = exif_segment(jpeg, segs);
  if (!s) return 0;
  const Tiff t{&jpeg[s->at + 6], s->size - 6, jpeg[s->at + 6] == 'I'};
  const uint32_t ifd = t.u32(4);
  for (uint32_t k = 0; k < t.u16(ifd); ++k)
    if (t.u16(ifd + 2 + 12 * k) == 0x0112) return static_cast<int>(t.u16(ifd + 2 + 12 * k + 8));
  return 0;
}

bool jpeg_exif_contains(const std::vector<uint8_t> &jpeg, const std::string &marker) {
  const std::vector<Segment> segs = segments(jpeg);
  const Segment *s = exif_segment(jpeg, segs);
  if (!s) return false;
  const std::string payload(jpeg.begin() + s->at, jpeg.begin() + s->at + s->size);
  return payload.find(marker) != std::string::npos;
}

std::vector<uint8_t> add_exif(const std::vector<uint8_t> &jpeg, int orientation, const std::string &make) {
  // "Exif\0\0", "II*\0", IFD0 at 8: {Orientation SHORT, Make ASCII at 38}, no IFD1.
  std::vector<uint8_t> e;
  for (const char c : std::string("Exif\0\0II", 8)) e.push_back(static_cast<uint8_t>(c));
  auto u16 = [&e](uint32_t v) { e.push_back(v & 0xFF), e.push_back(v >> 8 & 0xFF); };
  auto u32 = [&](uint32_t v) { u16(v & 0xFFFF), u16(v >> 16); };
  u16(42), u32(8), u16(2);
  u16(0x0112), u16(3), u32(1), u16(static_cast<uint32_t>(orientation)), u16(0);
  u16(0x010F), u16(2), u32(static_cast<uint32_t>(make.size() + 1)), u32(38);
  u32(0);
  e.insert(e.end(), make.begin(), make.end());
  e.push_back(0);
  std::vector<uint8_t> out;
  out.reserve(jpeg.size() + e.size() + 4);
  for (const uint8_t b : {0xFF, 0xD8, 0xFF, 0xE1}) out.push_back(b);
  out.push_back(static_cast<uint8_t>((e.size() + 2) >> 8));
  out.push_back(static_cast<uint8_t>((e.size() + 2) & 0xFF));
  out.insert(out.end(), e.begin(), e.end());
  out.insert(out.end(), jpeg.begin() + 2, jpeg.end());
  return out;
}

std::vector<std::string> files_containing(const std::string &dir, const std::string &part) {
  std::vector<std::string> out;
  if (DIR *d = opendir(dir.c_str())) {
    while (dirent *e = readdir(d))
      if (std::strstr(e->d_name, part.c_str())) out.push_back(e->d_name);
    closedir(d);
  }
  return out;
}

}  // namespace p3d::test
