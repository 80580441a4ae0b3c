#include "convert_photo.h"

#include <gst/app/gstappsink.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>

#include "depth_meta.h"
#include "gpu.h"
#include "image_io.h"
#include "jpeg_meta.h"
#include "mpo.h"
#include "output_file.h"
#include "stage_settings.h"

namespace p3d::convert {

namespace {

bool read_file(const std::string &path, Bytes *out) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  out->assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  return true;
}

bool write_file(const std::string &path, const Bytes &data) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char *>(data.data()), static_cast<std::streamsize>(data.size()));
  return static_cast<bool>(f);
}

// The depth plane on the buffer pseudo3dwarp receives, as 16-bit grey (big
// endian, as pngenc takes it; white = near). The plugin is a loaded module,
// so the meta is found by its registered API name.
struct DepthCapture {
  Image depth;
};

GstPadProbeReturn capture_depth(GstPad *, GstPadProbeInfo *info, gpointer data) {
  auto *c = static_cast<DepthCapture *>(data);
  const GType api = g_type_from_name("Pseudo3DDepthMetaAPI");
  auto *meta = api ? reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_get_meta(GST_PAD_PROBE_INFO_BUFFER(info), api))
                   : nullptr;
  if (!meta || !meta->plane || !*meta->plane || (*meta->plane)->on_device) return GST_PAD_PROBE_OK;
  const p3d::gst::DepthPlane &d = **meta->plane;
  Image &out = c->depth;
  out.width = d.width;
  out.height = d.height;
  out.format = "GRAY16_BE";
  out.data.resize(static_cast<size_t>(d.width) * d.height * 2);
  for (size_t i = 0; i < static_cast<size_t>(d.width) * d.height; ++i) {
    const float v = std::fmin(1.f, std::fmax(0.f, d.host[i]));
    const auto g = static_cast<uint16_t>(std::lround(v * 65535.f));
    out.data[2 * i] = static_cast<uint8_t>(g >> 8);
    out.data[2 * i + 1] = static_cast<uint8_t>(g & 0xFF);
  }
  return GST_PAD_PROBE_OK;
}

// Runs the four stages on one picture. `layout`/`swap` decide the packing.
bool render(const Options &o, Processing processing, const Image &in, const std::string &layout, bool swap,
            Image *out, Image *depth, std::string *error) {
  GstElement *pipeline = gst_pipeline_new("pseudo3d-photo");
  const char *factories[] = {"appsrc", "pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp", "pseudo3dpack", "appsink"};
  GstElement *e[6];
  for (int i = 0; i < 6; ++i) {
    e[i] = gst_element_factory_make(factories[i], nullptr);
    if (!e[i]) {
      *error = std::string("GStreamer element ") + factories[i] + " is missing";
      gst_object_unref(pipeline);  // holds the ones made so far
      return false;
    }
    gst_bin_add(GST_BIN(pipeline), e[i]);
  }
  GstElement *stages[] = {e[1], e[2], e[3], e[4]};
  for (GstElement *s : stages)
    gst_util_set_object_arg(G_OBJECT(s), "processing", processing == Processing::Gpu ? "gpu" : "cpu");
  apply_to_stages(o, stages, 4, layout, swap);
  GstCaps *caps = nullptr;
  GstBuffer *buf = image_to_buffer(in, &caps);
  g_object_set(e[0], "caps", caps, "format", GST_FORMAT_TIME, NULL);
  gst_caps_unref(caps);
  GstCaps *rgba = gst_caps_from_string("video/x-raw,format=RGBA");
  g_object_set(e[5], "caps", rgba, "sync", FALSE, NULL);
  gst_caps_unref(rgba);
  gst_element_link_many(e[0], e[1], e[2], e[3], e[4], e[5], NULL);
  DepthCapture capture;
  GstPad *warp_sink = gst_element_get_static_pad(e[3], "sink");
  gst_pad_add_probe(warp_sink, GST_PAD_PROBE_TYPE_BUFFER, capture_depth, &capture, nullptr);
  gst_object_unref(warp_sink);
  GstSample *s = run_for_one_sample(pipeline, e[0], buf, e[5], error);
  const bool ok = s && image_from_sample(s, out);
  if (s && !ok) *error = "unexpected output of pseudo3dpack";
  if (s) gst_sample_unref(s);
  gst_object_unref(pipeline);
  *depth = std::move(capture.depth);
  return ok;
}

// Encodes and writes one file through its temporary name.
bool write_output(OutputFile *file, const Bytes &bytes, std::string *error) {
  if (!write_file(file->temp_path(), bytes)) {
    *error = file->path() + ": cannot write";
    return false;
  }
  return true;
}

bool encode_failed(const std::string &path, std::string *error) {
  *error = path + ": could not encode (" + *error + ")";
  return false;
}

}  // namespace

bool convert_photo(const Options &o, std::string *error) {
  Processing processing;
  if (!resolve_processing(o.processing, &processing, error)) return false;
  Bytes source;
  if (!read_file(o.input, &source)) {
    *error = o.input + ": cannot read";
    return false;
  }
  const Bytes exif = find_exif(source);
  Image upright;
  if (!read_image(o.input, exif_orientation(exif), &upright, error)) {
    *error = o.input + ": " + *error;
    return false;
  }

  // MPO takes the two views apart, JPS is the cross-eyed pair: both render
  // a full side-by-side frame.
  const bool pair = o.kind == OutputKind::Mpo || o.kind == OutputKind::Jps;
  const std::string layout = pair ? "side-by-side" : effective_layout(o);
  const bool swap = right_view_first(o) != (o.kind == OutputKind::Jps);
  OutputFile out, depth_out;
  if (!out.open(o.output, o.force, error)) return false;
  if (!o.depth_out.empty() && !depth_out.open(o.depth_out, o.force, error)) return false;
  Image packed, depth;
  if (!render(o, processing, upright, layout, swap, &packed, &depth, error)) {
    *error = o.input + ": " + *error;
    return false;
  }

  Bytes bytes;
  const bool anaglyph = layout == "anaglyph";
  if (o.kind == OutputKind::Mpo) {
    const int w = packed.width / 2;
    Bytes first, second;
    if (!encode_image(packed.crop_columns(0, w), "jpeg", false, &first, error) ||
        !encode_image(packed.crop_columns(w, w), "jpeg", false, &second, error))
      return encode_failed(o.output, error);
    Bytes meta = exif.empty() ? Bytes() : exif_for_output(exif, w, packed.height);
    if (meta.empty()) meta = minimal_exif(w, packed.height);
    bytes = make_mpo(first, second, meta);
  } else if (o.kind == OutputKind::Png) {
    if (!encode_image(packed, "png", false, &bytes, error)) return encode_failed(o.output, error);
  } else {
    if (!encode_image(packed, "jpeg", anaglyph, &bytes, error)) return encode_failed(o.output, error);
    const Bytes meta = exif.empty() ? Bytes() : exif_for_output(exif, packed.width, packed.height);
    if (!meta.empty()) bytes = with_segments(bytes, {{0xE1, meta}});
  }
  if (!write_output(&out, bytes, error)) return false;
  if (!o.depth_out.empty()) {
    Bytes png;
    if (depth.data.empty()) {
      *error = o.depth_out + ": the depth map could not be read (it stayed in GPU memory)";
      return false;
    }
    if (!encode_image(depth, "png", false, &png, error)) return encode_failed(o.depth_out, error);
    if (!write_output(&depth_out, png, error)) return false;
  }
  if (!out.commit(error) || (!o.depth_out.empty() && !depth_out.commit(error))) return false;
  if (!o.quiet) {
    const std::string what = o.kind == OutputKind::Mpo   ? "left and right view"
                             : o.kind == OutputKind::Jps ? "cross-eyed side-by-side"
                                                         : layout;
    std::fprintf(stderr, "pseudo3d-convert: wrote %s (%s, %dx%d, 3D on the %s)%s%s\n", o.output.c_str(), what.c_str(),
                 o.kind == OutputKind::Mpo ? packed.width / 2 : packed.width, packed.height,
                 processing == Processing::Gpu ? "GPU" : "CPU", o.depth_out.empty() ? "" : " and ", o.depth_out.c_str());
  }
  return true;
}

}  // namespace p3d::convert
