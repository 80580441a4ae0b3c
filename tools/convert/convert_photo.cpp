#include "convert_photo.h"

#include <cstdio>
#include <fstream>
#include <iterator>

#include "depth_source.h"
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

// The four stages on one picture, uploaded once and downloaded once when
// they run on the GPU (on_processing, gpu.h). With `depth_png`, a tee after
// pseudo3dfilter hands the depth pseudo3dwarp renders from to
// pseudo3ddepthout (which reads a device depth back itself), and that grey
// picture is encoded as a 16-bit PNG (white = near) into *depth_png.
//   appsrc ! [cudaupload ! video/x-raw(memory:CUDAMemory) !] pseudo3ddepth !
//   pseudo3dfilter ! [tee ! queue !] pseudo3dwarp ! pseudo3dpack ! [cudadownload !]
//   video/x-raw,format=RGBA ! appsink
//   [tee. ! queue ! pseudo3ddepthout ! GRAY16_LE ! videoconvert ! GRAY16_BE ! pngenc ! appsink]
// With --depth, pseudo3ddepthmux takes the place of pseudo3ddepth, fed by
// the depth file's reader (depth_source.h).
// `layout`/`swap` decide the packing. *error names the file at fault
// (the photo, or the depth file when its reader failed).
bool render(const Options &o, Processing processing, const Image &in, const std::string &layout, bool swap,
            Image *out, Bytes *depth_png, std::string *error) {
  const bool depth_file = !o.depth.empty();
  const std::string stages = std::string(depth_file ? "depth.video pseudo3ddepthmux name=depth"
                                                    : "pseudo3ddepth name=depth") +
                             " ! pseudo3dfilter name=filter ! " + (depth_png ? "tee name=t ! queue ! " : "") +
                             "pseudo3dwarp name=warp ! pseudo3dpack name=pack";
  std::string description = "appsrc name=src format=time ! " + on_processing(processing, stages) +
                            " ! video/x-raw,format=RGBA ! appsink name=sink sync=false";
  if (depth_file) description += " " + depth_reader_description("depth.depth");
  if (depth_png)
    description += " t. ! queue ! pseudo3ddepthout ! video/x-raw,format=GRAY16_LE ! videoconvert ! "
                   "video/x-raw,format=GRAY16_BE ! pngenc ! appsink name=depth_png sync=false";
  GstElement *pipeline = launch(description, error);
  if (!pipeline) {
    *error = o.input + ": " + *error;
    return false;
  }
  GstElement *stage_elements[] = {by_name(pipeline, "depth"), by_name(pipeline, "filter"), by_name(pipeline, "warp"),
                                  by_name(pipeline, "pack")};
  for (GstElement *s : stage_elements)
    if (!depth_file || s != stage_elements[0])  // pseudo3ddepthmux runs wherever its frames are
      gst_util_set_object_arg(G_OBJECT(s), "processing", processing_nick(processing));
  if (depth_file) {
    set_depth_location(pipeline, o.depth);
    apply_depth_values(o, stage_elements[0]);
  }
  apply_to_stages(o, stage_elements, 4, layout, swap);
  GstCaps *caps = nullptr;
  GstBuffer *buf = image_to_buffer(in, &caps);
  GstElement *src = by_name(pipeline, "src");
  g_object_set(src, "caps", caps, NULL);
  gst_caps_unref(caps);
  GstElement *sinks[] = {by_name(pipeline, "sink"), depth_png ? by_name(pipeline, "depth_png") : nullptr};
  GstSample *samples[2] = {nullptr, nullptr};
  std::string source;
  bool ok = run_for_samples(pipeline, src, buf, sinks, samples, depth_png ? 2 : 1, error, &source);
  if (ok && !image_from_sample(samples[0], out)) {
    *error = "unexpected output of pseudo3dpack";
    ok = false;
  }
  if (!ok)
    *error = (depth_file && source.find(kDepthReaderMark) != std::string::npos ? o.depth : o.input) + ": " + *error;
  if (ok && depth_png) *depth_png = bytes_of_sample(samples[1]);
  for (GstSample *s : samples)
    if (s) gst_sample_unref(s);
  gst_object_unref(pipeline);
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
  if (!depth_file_readable(o, error)) return false;
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
  Image packed;
  Bytes depth_png;
  if (!render(o, processing, upright, layout, swap, &packed, o.depth_out.empty() ? nullptr : &depth_png, error))
    return false;

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
  if (!o.depth_out.empty() && !write_output(&depth_out, depth_png, error)) return false;
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
