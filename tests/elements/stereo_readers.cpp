#include "stereo_readers.h"

#include <sstream>

#include <sys/wait.h>

#include <gst/gst.h>

#include "element_helpers.h"

namespace p3d::test {

bool have_program(const char *name) {
  gchar *path = g_find_program_in_path(name);
  const bool found = path != nullptr;
  g_free(path);
  return found;
}

int run_program(const std::vector<std::string> &argv, std::string *out, std::string *err, const std::string &cwd,
                const std::vector<std::string> &env) {
  std::vector<char *> args;
  for (const std::string &a : argv) args.push_back(const_cast<char *>(a.c_str()));
  args.push_back(nullptr);
  gchar **envp = nullptr;  // null: this process's environment as it is
  if (!env.empty()) {
    envp = g_get_environ();
    for (const std::string &entry : env) {
      const size_t eq = entry.find('=');
      envp = g_environ_setenv(envp, entry.substr(0, eq).c_str(), entry.substr(eq + 1).c_str(), TRUE);
    }
  }
  gchar *o = nullptr, *e = nullptr;
  gint status = 0;
  GError *error = nullptr;
  const gboolean ran = g_spawn_sync(cwd.empty() ? nullptr : cwd.c_str(), args.data(), envp, G_SPAWN_SEARCH_PATH,
                                    nullptr, nullptr, &o, &e, &status, &error);
  g_strfreev(envp);
  if (!ran) {
    if (err) *err = error ? error->message : "spawn failed";
    g_clear_error(&error);
    return -1;
  }
  if (out) *out = o ? o : "";
  if (err) *err = e ? e : "";
  g_free(o);
  g_free(e);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

namespace {

void read_multiview(GstPad *pad, std::string *mode, unsigned *flags, int *par_n, int *par_d) {
  GstCaps *caps = pad ? gst_pad_get_current_caps(pad) : nullptr;
  if (!caps) return;
  const GstStructure *s = gst_caps_get_structure(caps, 0);
  if (const char *m = gst_structure_get_string(s, "multiview-mode")) *mode = m;
  const GValue *f = gst_structure_get_value(s, "multiview-flags");
  if (f && GST_VALUE_HOLDS_FLAG_SET(f)) *flags = gst_value_get_flagset_flags(f);
  if (par_n && par_d) gst_structure_get_fraction(s, "pixel-aspect-ratio", par_n, par_d);
  gst_caps_unref(caps);
}

std::string quoted(const std::string &path) { return "\"" + path + "\""; }

}  // namespace

GstStereo gst_parsed_stereo(const std::string &file) {
  GstStereo r;
  const bool mp4 = g_str_has_suffix(file.c_str(), ".mp4") || g_str_has_suffix(file.c_str(), ".mov");
  const std::string launch = "filesrc location=" + quoted(file) + (mp4 ? " ! qtdemux name=d" : " ! matroskademux name=d") +
                             " d.video_0 ! h264parse name=p ! fakesink sync=false";
  r.error = run_to_eos(launch, 60, [&](GstElement *pipeline) {
    GstElement *p = gst_bin_get_by_name(GST_BIN(pipeline), "p");
    if (!p) return;
    GstPad *sink = gst_element_get_static_pad(p, "sink");
    GstPad *src = gst_element_get_static_pad(p, "src");
    read_multiview(sink, &r.demux_mode, &r.demux_flags, nullptr, nullptr);
    read_multiview(src, &r.mode, &r.flags, &r.par_n, &r.par_d);
    gst_object_unref(sink);
    gst_object_unref(src);
    gst_object_unref(p);
  });
  return r;
}

int gst_decoded_frames(const std::string &file, bool has_audio, std::string *error) {
  std::string launch = "filesrc location=" + quoted(file) +
                       " ! decodebin name=d d. ! video/x-raw ! fakesink name=v sync=false";
  if (has_audio) launch += " d. ! audio/x-raw ! fakesink sync=false";
  guint64 rendered = 0;
  const std::string err = run_to_eos(launch, 60, [&](GstElement *pipeline) {
    GstElement *v = gst_bin_get_by_name(GST_BIN(pipeline), "v");
    GstStructure *stats = nullptr;
    if (v) g_object_get(v, "stats", &stats, nullptr);  // GstBaseSink: buffers rendered so far
    if (stats) gst_structure_get_uint64(stats, "rendered", &rendered);
    if (stats) gst_structure_free(stats);
    if (v) gst_object_unref(v);
  });
  if (!err.empty()) {
    if (error) *error = err;
    return -1;
  }
  return int(rendered);
}

FfprobeVideo ffprobe_video(const std::string &file) {
  FfprobeVideo r;
  std::string out;
  if (run_program({"ffprobe", "-v", "error", "-select_streams", "v:0", "-show_streams", "-of", "default=nw=1", file},
                  &out) != 0)
    return r;
  r.ok = true;
  std::istringstream lines(out);
  bool in_stereo = false;  // within the stream's "Stereo 3D" side data
  for (std::string line; std::getline(lines, line);) {
    const std::string sar = "sample_aspect_ratio=", tag = "TAG:stereo_mode=", side = "side_data_type=";
    if (line.rfind(sar, 0) == 0) r.sar = line.substr(sar.size());
    if (line.rfind(tag, 0) == 0) r.stereo_mode = line.substr(tag.size());
    if (line.rfind(side, 0) == 0) in_stereo = line == side + "Stereo 3D";
    if (in_stereo && line.rfind("type=", 0) == 0) r.stereo_side_data = line.substr(5);
  }
  return r;
}

std::vector<std::string> ffmpeg_frame_stereo(const std::string &file) {
  std::string out, err;
  run_program({"ffmpeg", "-hide_banner", "-nostdin", "-i", file, "-an", "-frames:v", "1", "-vf", "showinfo", "-f",
               "null", "-"},
              &out, &err);
  std::vector<std::string> found;
  const std::string key = "stereoscopic information: type - ";
  std::istringstream lines(err);
  for (std::string line; std::getline(lines, line);) {
    const size_t at = line.find(key);
    if (at != std::string::npos) found.push_back(line.substr(at + key.size()));
  }
  return found;
}

std::map<std::string, std::string> mkvinfo_video(const std::string &file) {
  std::map<std::string, std::string> fields;
  std::string out;
  // --all: without it mkvinfo stops at the first Cluster.
  if (run_program({"mkvinfo", "--all", file}, &out) != 0) return fields;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    for (const char *name :
         {"Stereo mode", "Display width", "Display height", "Display unit", "Pixel width", "Pixel height"}) {
      const std::string key = std::string("+ ") + name + ": ";
      const size_t at = line.find(key);
      if (at != std::string::npos && !fields.count(name)) fields[name] = line.substr(at + key.size());
    }
  }
  return fields;
}

}  // namespace p3d::test
