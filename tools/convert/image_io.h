// Still pictures in and out through GStreamer (decodebin, jpegenc, pngenc)
// rather than an image library, so the converter carries no dependency
// beyond GStreamer (it runs from a bundled GStreamer runtime on machines
// without one), and a frame travels appsrc -> elements -> appsink.
#pragma once

#include <gst/gst.h>

#include <cstdint>
#include <string>
#include <vector>

namespace p3d::convert {

// RGBA, tightly packed rows (4 bytes a pixel).
struct Image {
  static constexpr int kBytesPerPixel = 4;
  int width = 0, height = 0;
  std::vector<uint8_t> data;
  // Columns [x0, x0 + w) as a new image.
  Image crop_columns(int x0, int w) const;
};

// The first picture of `path` as RGBA, turned upright for the EXIF
// orientation (1-8; 1 = as stored). A picture larger than the 3D stages
// take is refused from its header (too_large(), gst_run.h). *error says
// why, without the file's name.
bool read_image(const std::string &path, int exif_orientation, Image *out, std::string *error);

// Encodes an image. codec "jpeg" (4:2:0, or 4:4:4 with `full_chroma`,
// quality 95) or "png" (RGB).
bool encode_image(const Image &image, const std::string &codec, bool full_chroma, std::vector<uint8_t> *bytes,
                  std::string *error);

// A buffer and caps for an image (rows laid out as GstVideoInfo wants).
GstBuffer *image_to_buffer(const Image &image, GstCaps **caps);
// The picture of a raw RGBA video sample.
bool image_from_sample(GstSample *sample, Image *out);
// The bytes of a sample's buffer (an encoder's output).
std::vector<uint8_t> bytes_of_sample(GstSample *sample);

// gst_parse_launch of a pipeline description; null with *error on failure.
GstElement *launch(const std::string &description, std::string *error);
// The element named `name` in `pipeline`, which keeps it alive (no new ref).
GstElement *by_name(GstElement *pipeline, const char *name);

// Starts `pipeline`, pushes `buffer` (if any) and EOS into `appsrc`, and
// waits for the first sample of each of the `n` appsinks `sinks` into
// `samples` (new refs). False with *error, and no sample, on an error or
// when one of them got none; *error_source (if given) is then the path of
// the element that posted the error (message_source_path(), gst_run.h).
// Leaves the pipeline in NULL.
bool run_for_samples(GstElement *pipeline, GstElement *appsrc, GstBuffer *buffer, GstElement *const *sinks,
                     GstSample **samples, int n, std::string *error, std::string *error_source = nullptr);
// The same for one appsink: its sample, or null with *error.
GstSample *run_for_one_sample(GstElement *pipeline, GstElement *appsrc, GstBuffer *buffer, GstElement *appsink,
                              std::string *error);

}  // namespace p3d::convert
