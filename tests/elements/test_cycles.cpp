// 1000 NULL -> PLAYING -> NULL cycles of pipelines holding every element,
// with GStreamer's leaks tracer watching: no GstObject or GstMiniObject
// (buffers, caps, events, pools, metas' buffers...) may survive the cycles.
// Its own executable: the tracer must be set before gst_init().
#include <gst/gst.h>
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "element_helpers.h"

namespace {

GstTracer *leaks_tracer() {
  GList *tracers = gst_tracing_get_active_tracers();
  GstTracer *found = nullptr;
  for (GList *l = tracers; l; l = l->next)
    if (g_str_has_prefix(G_OBJECT_TYPE_NAME(l->data), "GstLeaksTracer")) found = GST_TRACER(gst_object_ref(l->data));
  g_list_free_full(tracers, gst_object_unref);
  return found;
}

// Objects created minus objects destroyed since the last checkpoint, by type
// name (the tracer's activity tracking; counting never touches the objects).
std::map<std::string, int> net_objects(GstTracer *tracer) {
  GstStructure *cp = nullptr;
  g_signal_emit_by_name(tracer, "activity-get-checkpoint", &cp);
  std::map<std::string, int> net;
  for (const char *field : {"objects-created-list", "objects-removed-list"}) {
    const GValue *list = gst_structure_get_value(cp, field);
    const int sign = g_str_equal(field, "objects-created-list") ? 1 : -1;
    for (guint i = 0; list && i < gst_value_list_get_size(list); ++i) {
      const GstStructure *o = gst_value_get_structure(gst_value_list_get_value(list, i));
      const gchar *type = gst_structure_get_string(o, "type-name");
      net[type ? type : "?"] += sign;
    }
  }
  gst_structure_free(cp);
  return net;
}

// The first error on the pipeline's bus, if any.
std::string bus_error(GstElement *pipeline) { return p3d::test::first_bus_error(pipeline); }

void cycle(GstElement *pipeline) {
  ASSERT_NE(gst_element_set_state(pipeline, GST_STATE_PLAYING), GST_STATE_CHANGE_FAILURE) << bus_error(pipeline);
  ASSERT_EQ(gst_element_get_state(pipeline, nullptr, nullptr, 10 * GST_SECOND), GST_STATE_CHANGE_SUCCESS)
      << bus_error(pipeline);
  ASSERT_EQ(gst_element_set_state(pipeline, GST_STATE_NULL), GST_STATE_CHANGE_SUCCESS);
}

}  // namespace

TEST(Cycles, ThousandNullPlayingNullLeakNothing) {
  GstTracer *tracer = leaks_tracer();
  ASSERT_NE(tracer, nullptr) << "the leaks tracer is not active";
  const char *launches[] = {
      "videotestsrc ! video/x-raw,width=64,height=48,format=NV12 ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! "
      "pseudo3dpack layout=side-by-side-half ! fakesink",
      "videotestsrc ! video/x-raw,width=48,height=32 ! pseudo3dconvert layout=top-bottom ! fakesink",
      "videotestsrc ! video/x-raw,width=64,height=48,format=I420 ! pseudo3dconvert layout=side-by-side ! "
      "videoconvert ! video/x-raw,format=I420 ! x264enc speed-preset=ultrafast frame-packing=auto ! h264parse ! "
      "pseudo3dsignal ! fakesink"};
  std::vector<GstElement *> pipelines;
  for (const char *l : launches) {
    GError *err = nullptr;
    GstElement *p = gst_parse_launch(l, &err);
    ASSERT_NE(p, nullptr) << l;
    ASSERT_EQ(err, nullptr) << err->message;
    pipelines.push_back(p);
  }
  // Warm-up: one-time allocations (types, allocators, pools' first buffers).
  for (size_t k = 0; k < pipelines.size(); ++k) {
    SCOPED_TRACE(launches[k]);
    for (int i = 0; i < 3; ++i) cycle(pipelines[k]);
  }
  g_signal_emit_by_name(tracer, "activity-start-tracking");
  int cycles = 0;
  for (int i = 0; i < 1000; ++i, ++cycles) {
    cycle(pipelines[i % 2]);
    if (i % 50 == 0) cycle(pipelines[2]);  // the encoder is slow to start: fewer cycles
    if (HasFailure()) break;
  }
  EXPECT_EQ(cycles, 1000);
  // A pad task's last reference goes when its pooled thread finishes, just
  // after the state change returned: let it.
  g_usleep(200 * 1000);
  for (const auto &[type, n] : net_objects(tracer)) EXPECT_LE(n, 0) << n << " more " << type << " objects alive after the cycles";
  g_signal_emit_by_name(tracer, "activity-stop-tracking");
  for (GstElement *p : pipelines) gst_object_unref(p);
  gst_object_unref(tracer);
}

int main(int argc, char **argv) {
  g_setenv("GST_TRACERS", "leaks", TRUE);
  gst_init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
