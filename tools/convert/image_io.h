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

// Tightly packed rows: RGBA (4 bytes a pixel) or GRAY16_BE (2).
struct Image {
  int width = 0, height = 0;
  std::string format = "RGBA";
  std::vector<uint8_t> data;
  int bytes_per_pixel() const { return format == "RGBA" ? 4 : 2; }
  // Columns [x0, x0 + w) as a new image.
  Image crop_columns(int x0, int w) const;
};

// The first picture of `path` as RGBA, turned upright for the EXIF
// orientation (1-8; 1 = as stored). A picture larger than the 3D stages
// take is refused from its header (too_large(), gst_run.h). *error says
// why, without the file's name.
bool read_image(const std::string &path, int exif_orientation, Image *out, std::string *error);

// Encodes an image. codec "jpeg" (4:2:0, or 4:4:4 with `full_chroma`,
// quality 95) or "png" (RGB, or 16-bit grey for GRAY16_BE).
bool encode_image(const Image &image, const std::string &codec, bool full_chroma, std::vector<uint8_t> *bytes,
                  std::string *error);

// A buffer and caps for an image (rows laid out as GstVideoInfo wants).
GstBuffer *image_to_buffer(const Image &image, GstCaps **caps);
// The picture of a raw video sample (RGBA or GRAY16_BE).
bool image_from_sample(GstSample *sample, Image *out);

// Starts `pipeline`, pushes `buffer` (if any) and EOS into `appsrc`, and
// returns the first sample of `appsink` (null with *error on failure or
// when no sample came). Leaves the pipeline in NULL.
GstSample *run_for_one_sample(GstElement *pipeline, GstElement *appsrc, GstBuffer *buffer, GstElement *appsink,
                              std::string *error);

}  // namespace p3d::convert
