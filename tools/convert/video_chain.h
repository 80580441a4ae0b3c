// The video branch between decodebin and the encoder:
//   queue ! [videoconvert ! (videocrop) ! videoflip] ! pseudo3dconvert !
//   video/x-raw ! queue ! videoconvert ! video/x-raw,format=F !
//   (encoder, or fakesink to benchmark)
// (the bracket on system memory: videocrop for odd sizes and 4:2:0
// encoders, videoflip turning rotation-tagged video upright)
// With --depth FILE, the depth file's chain (depth_source.h) stands where
// pseudo3dconvert stands.
// On the GPU path NVDEC's CUDA memory goes straight into pseudo3dconvert,
// which keeps every stage on the device and downloads once (a rotation tag
// there is refused: nothing on CUDA memory turns it upright); the formats the
// stages do not take get a videoconvert in front. The queues let decoding,
// the 3D stages and the encoder run in parallel threads. The frame counter
// for the progress sits on the encoder's input.
#pragma once

#include <gst/gst.h>

#include <string>

#include "encoder.h"
#include "options.h"

namespace p3d::convert {

class Progress;

class VideoChain {
 public:
  // Adds the elements to `bin`, unlinked to decodebin. `raw_format`: what
  // the encoder takes (I420, Y444).
  bool build(GstElement *bin, const Options &o, Processing processing, const std::string &raw_format,
             std::string *error);
  // Links decodebin's video pad (streaming thread). False: not linked,
  // with refusal() saying why when the chain refused the stream.
  bool attach(GstPad *decoded, const GstCaps *caps);
  const std::string &refusal() const { return refusal_; }
  // The format the encoder is fed for the decoded caps, set before
  // attach(), while no caps have passed the chain: its deep_format for
  // deep video where it has one (Main10), else its raw_format. NVDEC's
  // deep frames reach the stages as they are, and the stages keep their
  // depth: for an 8-bit 4:2:0 encoder they pack 10-bit 4:2:0, which
  // videoconvert narrows, unless cudaconvert can narrow the frames on the
  // device first; an 8-bit 4:4:4 encoder (anaglyphs) gets frames narrowed
  // before the stages (system memory is narrowed before them in any case).
  // Returns the format fed.
  std::string feed_encoder(const EncoderChoice &encoder, const GstCaps *decoded);
  // What the chain takes, for decoders' caps queries (new ref).
  GstCaps *accepted_caps() const;
  // Counts frames reaching the encoder into `progress`, with their position
  // in the piece that starts at `start` (media time).
  void count_frames(Progress *progress, GstClockTime start);
  // Makes the one frame of a picture a still video of `frames` frames at
  // kStillFrameRate: imagefreeze after the 3D stages repeats their frame,
  // so they run once. Streaming thread, before attach(): nothing has
  // passed the chain yet. False with refusal() set if imagefreeze is missing.
  bool hold_still(int frames);

  GstPad *sink_pad() const { return head_sink_; }  // the first queue's sink pad
  GstElement *tail() const { return tail_; }       // links to the encoder
  GstElement *converter() const { return convert_; }
  // Before attach: whether the input's video carries an orientation tag
  // (probe_input), so that its CUDA frames are downloaded for videoflip.
  void expect_rotation(bool rotated) { rotated_ = rotated; }
  bool on_gpu_memory() const { return cuda_input_; }  // decoded frames arrive in CUDA memory
  // The odd width or height cropped to even for a 4:2:0 encoder (attach()).
  bool cropped_to_even() const { return cropped_; }

  ~VideoChain();

 private:
  // Feeds the encoder `raw_format`; deep_input: the stages see deep frames.
  void use_format(const std::string &raw_format, bool deep_input = false);
  GstElement *bin_ = nullptr, *head_ = nullptr, *convert_ = nullptr, *tail_ = nullptr, *to_system_ = nullptr;
  GstPad *head_sink_ = nullptr;
  GstPad *counted_ = nullptr;  // where count_frames() counts, and its probe
  gulong count_probe_ = 0;
  Progress *progress_ = nullptr;
  Processing processing_ = Processing::Cpu;
  bool subsampled_ = false;  // the encoder takes 4:2:0, which needs even sizes
  bool cuda_input_ = false, cropped_ = false;
  bool rotated_ = false;  // expect_rotation()
  bool narrow_before_stages_ = false;  // deep CUDA frames narrowed to 8 bits before the stages (feed_encoder)
  std::string refusal_;
};

// What the video chain takes from decoders for a processing: CUDA memory
// (NVDEC's output) first on the GPU path, system memory in any format.
GstCaps *video_caps_for(Processing processing);

// What happens to interlaced video, as a note for the user ("" for
// progressive video): pseudo3dconvert deinterlaces it, a frame for each
// field.
std::string deinterlacing_note(const GstCaps *decoded);

// A bounded queue (frames): keeps the threads apart without holding much video.
GstElement *make_frame_queue(guint frames);

// Counts the buffers passing `pad` into `progress`, with their media time
// from `start` (the segment's stream time, so a seek's piece counts from 0).
// Returns the probe's id.
gulong count_frames_at(GstPad *pad, Progress *progress, GstClockTime start);

}  // namespace p3d::convert
