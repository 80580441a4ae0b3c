#include "depth_source.h"

#include <glib/gstdio.h>
#include <unistd.h>

#include "gpu.h"
#include "image_io.h"
#include "stage_settings.h"

namespace p3d::convert {

std::string depth_reader_description(const std::string &tail) {
  return "filesrc name=depth_file ! decodebin name=depth_decoder ! videoconvert ! video/x-raw,format={ GRAY16_LE, GRAY8 } ! queue" +
         (tail.empty() ? std::string() : " ! " + tail);
}

void set_depth_location(GstElement *pipeline, const std::string &path) {
  if (GstElement *src = gst_bin_get_by_name(GST_BIN(pipeline), "depth_file")) {
    g_object_set(src, "location", path.c_str(), NULL);
    gst_object_unref(src);
  }
}

bool depth_file_readable(const Options &o, std::string *error) {
  if (o.depth.empty() || (g_file_test(o.depth.c_str(), G_FILE_TEST_IS_REGULAR) &&
                          g_access(o.depth.c_str(), R_OK) == 0))
    return true;
  *error = o.depth + ": cannot read the depth file";
  return false;
}

void apply_depth_values(const Options &o, GstElement *mux) {
  for (const auto &kv : o.depth_values) gst_util_set_object_arg(G_OBJECT(mux), kv.first.c_str(), kv.second.c_str());
}

namespace {

// The first unlinked src pad on the bin's own children: the chain's end
// (decodebin has no src pad yet). Not gst_bin_find_unlinked_pad(), which
// also looks inside child bins: it would take decodebin's typefind:src,
// which decodebin is about to link.
GstPad *unlinked_child_src(GstBin *bin) {
  GstPad *found = nullptr;
  for (GList *e = GST_BIN_CHILDREN(bin); e && !found; e = e->next)
    for (GList *p = GST_ELEMENT(e->data)->srcpads; p && !found; p = p->next)
      if (!gst_pad_is_linked(GST_PAD(p->data))) found = GST_PAD(gst_object_ref(p->data));
  return found;
}

// Ghosts `target` (taken) as the bin's pad `name`.
bool add_ghost(GstElement *bin, GstPad *target, const char *name) {
  if (!target) return false;
  GstPad *ghost = gst_ghost_pad_new(name, target);
  gst_object_unref(target);
  return ghost && gst_element_add_pad(bin, ghost);
}

}  // namespace

GstElement *make_depth_file_chain(const Options &o, Processing processing, std::string *error) {
  const std::string stages = "m.video pseudo3ddepthmux name=m ! pseudo3dfilter name=filter ! pseudo3dwarp name=warp";
  const std::string description =
      "deinterlace name=head ! " + on_processing(processing, stages) + " " + depth_reader_description("m.depth");
  GError *err = nullptr;
  GstElement *bin = gst_parse_bin_from_description(description.c_str(), FALSE, &err);
  if (!bin || err) {
    *error = std::string("could not build the chain for --depth: ") + (err ? err->message : "unknown error");
    g_clear_error(&err);
    if (bin) gst_object_unref(gst_object_ref_sink(bin));
    return nullptr;
  }
  GstElement *head = by_name(bin, "head");
  if (!head || !add_ghost(bin, gst_element_get_static_pad(head, "sink"), "sink") ||
      !add_ghost(bin, unlinked_child_src(GST_BIN(bin)), "src")) {
    *error = "could not build the chain for --depth: no free pad";
    gst_object_unref(gst_object_ref_sink(bin));
    return nullptr;
  }
  set_depth_location(bin, o.depth);
  GstElement *stages_found[] = {by_name(bin, "m"), by_name(bin, "filter"), by_name(bin, "warp")};
  apply_depth_values(o, stages_found[0]);
  for (GstElement *s : {stages_found[1], stages_found[2]})
    gst_util_set_object_arg(G_OBJECT(s), "processing", processing_nick(processing));
  // Every command-line value that applies with --depth is the warp's: its
  // own, and the pack's, which it has as the bin does (the estimate's are
  // refused with --depth).
  apply_to_bin(o, stages_found[2]);
  return bin;
}

}  // namespace p3d::convert
