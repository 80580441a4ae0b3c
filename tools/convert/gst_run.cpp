#include "gst_run.h"

#include <gst/pbutils/pbutils.h>

#include "frame.h"

namespace p3d::convert {

std::string error_text(GstMessage *msg) {
  GError *err = nullptr;
  gchar *dbg = nullptr;
  gst_message_parse_error(msg, &err, &dbg);
  std::string text = err ? err->message : "unknown error";
  // "Internal data stream error." says nothing by itself; the reason does.
  if (dbg) {
    const char *reason = g_strstr_len(dbg, -1, "reason ");
    if (reason) {
      std::string r(reason + 7);
      const size_t end = r.find_first_of(" )\n");
      text += " (" + r.substr(0, end) + ")";
    }
  }
  if (!text.empty() && text.back() == '.') text.pop_back();
  g_clear_error(&err);
  g_free(dbg);
  return text;
}

void post_error(GstElement *element, const std::string &text) {
  GError *err = g_error_new_literal(GST_CORE_ERROR, GST_CORE_ERROR_FAILED, text.c_str());
  gst_element_post_message(element, gst_message_new_error(GST_OBJECT(element), err, nullptr));
  g_error_free(err);
}

bool have_element(const char *factory) {
  GstElementFactory *f = gst_element_factory_find(factory);
  if (f) gst_object_unref(f);
  return f != nullptr;
}

bool too_large(const GstCaps *caps, std::string *message) {
  if (!caps || gst_caps_is_empty(caps) || gst_caps_is_any(caps)) return false;
  const GstStructure *s = gst_caps_get_structure(caps, 0);
  int w = 0, h = 0;
  if (!gst_structure_get_int(s, "width", &w) || !gst_structure_get_int(s, "height", &h)) return false;
  if (w <= kMaxFrameSide && h <= kMaxFrameSide) return false;
  *message = "the picture is " + std::to_string(w) + "x" + std::to_string(h) + " pixels, more than the " +
             std::to_string(kMaxFrameSide) + " a side the 3D stages take";
  return true;
}

bool run_until_eos(GstElement *pipeline, std::string *error) {
  GstBus *bus = gst_element_get_bus(pipeline);
  const bool started = gst_element_set_state(pipeline, GST_STATE_PLAYING) != GST_STATE_CHANGE_FAILURE;
  // A failed start posts its reason as an error: wait for that too.
  GstMessage *msg = gst_bus_timed_pop_filtered(bus, started ? GST_CLOCK_TIME_NONE : 0,
                                               static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR));
  bool ok = started && msg && GST_MESSAGE_TYPE(msg) == GST_MESSAGE_EOS;
  if (!ok) *error = msg && GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR ? error_text(msg) : "the pipeline did not start";
  if (msg) gst_message_unref(msg);
  gst_object_unref(bus);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  return ok;
}

namespace {
constexpr const char *kReady = "p3d-ready";

struct LoopState {
  GMainLoop *loop;
  GstElement *pipeline;
  const std::function<bool(std::string *)> *on_ready;
  LoopResult result;
  bool failed = false;
};

void fail(LoopState *s, const std::string &error, bool from_filesink, const std::string &source = "") {
  if (!s->failed) {
    s->failed = true;
    s->result.error = error;
    s->result.from_filesink = from_filesink;
    s->result.source = source;
  }
  g_main_loop_quit(s->loop);
}

gboolean on_bus(GstBus *, GstMessage *msg, gpointer data) {
  auto *s = static_cast<LoopState *>(data);
  switch (GST_MESSAGE_TYPE(msg)) {
    case GST_MESSAGE_EOS:
      g_main_loop_quit(s->loop);
      break;
    case GST_MESSAGE_ERROR: {
      GstElementFactory *f = GST_IS_ELEMENT(GST_MESSAGE_SRC(msg)) ? gst_element_get_factory(GST_ELEMENT(GST_MESSAGE_SRC(msg))) : nullptr;
      fail(s, error_text(msg), f && g_strcmp0(GST_OBJECT_NAME(f), "filesink") == 0, message_source_path(msg));
      break;
    }
    case GST_MESSAGE_ELEMENT:
      if (gst_is_missing_plugin_message(msg) && s->result.missing_plugin.empty()) {
        gchar *d = gst_missing_plugin_message_get_description(msg);
        s->result.missing_plugin = d ? d : "";
        g_free(d);
      }
      break;
    case GST_MESSAGE_APPLICATION:
      if (gst_message_has_name(msg, kReady) && *s->on_ready) {
        std::string error;
        if (!(*s->on_ready)(&error)) fail(s, error, false);
      }
      break;
    default:
      break;
  }
  return TRUE;
}
}  // namespace

std::string message_source_path(GstMessage *msg) {
  if (!GST_MESSAGE_SRC(msg)) return "";
  gchar *path = gst_object_get_path_string(GST_MESSAGE_SRC(msg));
  std::string s = path ? path : "";
  g_free(path);
  return s;
}

void post_ready(GstElement *pipeline) {
  gst_element_post_message(pipeline, gst_message_new_application(GST_OBJECT(pipeline), gst_structure_new_empty(kReady)));
}

LoopResult run_main_loop(GstElement *pipeline, const std::function<bool(std::string *)> &on_ready,
                         const std::function<void()> &tick) {
  LoopState s{g_main_loop_new(nullptr, FALSE), pipeline, &on_ready, {}};
  GstBus *bus = gst_element_get_bus(pipeline);
  const guint watch = gst_bus_add_watch(bus, on_bus, &s);
  auto tick_fn = [](gpointer data) -> gboolean {
    auto *f = static_cast<const std::function<void()> *>(data);
    if (*f) (*f)();
    return G_SOURCE_CONTINUE;
  };
  const guint timer = g_timeout_add(250, tick_fn, const_cast<std::function<void()> *>(&tick));
  // A failed start posts its reason as an error message: give the bus a
  // moment to deliver it (the callback keeps its source, removed below).
  guint grace = 0;
  if (gst_element_set_state(pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE)
    grace = g_timeout_add(
        2000, [](gpointer l) -> gboolean { g_main_loop_quit(static_cast<GMainLoop *>(l)); return G_SOURCE_CONTINUE; },
        s.loop);
  g_main_loop_run(s.loop);
  if (grace) {
    g_source_remove(grace);
    if (!s.failed) fail(&s, "the pipeline did not start", false);
  }
  g_source_remove(timer);
  g_source_remove(watch);
  gst_object_unref(bus);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  g_main_loop_unref(s.loop);
  s.result.ok = !s.failed;
  return s.result;
}

}  // namespace p3d::convert
