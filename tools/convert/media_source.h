// The input side of a video run: filesrc ! decodebin (fdsrc for a FIFO or
// a device, opened once), with
//  * the streams the output takes as they are left encoded (autoplug-continue),
//  * video decoders told what the 3D chain takes before it is linked
//    (autoplug-query), so NVDEC hands over CUDA memory when the GPU runs,
//  * the decoder in use recorded, missing-plugin messages made readable,
//  * a stream larger than the 3D stages take refused from its parsed caps,
//    before it is decoded (too_large(), gst_run.h),
//  * --start/--duration as one accurate seek once every stream is linked:
//    buffers decoded before it are dropped at the branch heads (gate_pad),
//    so only the piece reaches the encoders and the muxer.
#pragma once

#include <gst/gst.h>

#include <atomic>
#include <functional>
#include <mutex>
#include <string>

namespace p3d::convert {

class MediaSource {
 public:
  struct Hooks {
    // True for caps decodebin should expose still encoded.
    std::function<bool(const GstCaps *)> keep_encoded;
    // The caps the video chain takes (new ref), answered to video decoders'
    // caps queries while decodebin's pads are not linked yet.
    std::function<GstCaps *()> video_caps;
    // A decodebin pad and its caps (streaming thread); unfixed caps when
    // the stream ended before its first frame was decoded.
    std::function<void(GstPad *, GstCaps *)> pad_added;
    // All pads are there (streaming thread).
    std::function<void()> no_more_pads;
  };

  MediaSource() = default;
  // Closes the input it opened itself; the pipeline is stopped by then.
  ~MediaSource();
  MediaSource(const MediaSource &) = delete;
  MediaSource &operator=(const MediaSource &) = delete;

  // Adds filesrc (fdsrc) ! decodebin for `input` to `pipeline`.
  bool build(GstElement *pipeline, const std::string &input, Hooks hooks, std::string *error);

  // The piece to convert: [start, start + duration); NONE for either end
  // means the file's own. Set before the pipeline starts.
  void set_piece(GstClockTime start, GstClockTime duration);
  bool has_piece() const { return GST_CLOCK_TIME_IS_VALID(start_) || GST_CLOCK_TIME_IS_VALID(duration_); }
  GstClockTime piece_start() const { return GST_CLOCK_TIME_IS_VALID(start_) ? start_ : 0; }
  // Drops what reaches `pad` (a branch's first sink pad) before the piece's
  // seek has flushed it; `encoded` branches also drop packets that start
  // before the piece (decoders clip decoded streams themselves).
  void gate_pad(GstPad *pad, bool encoded);
  // Main thread, after no_more_pads: the accurate seek to the piece, sent
  // upstream from `pad` (a linked branch head). False if the input cannot seek.
  bool seek_to_piece(GstPad *pad);

  // Media time of the whole conversion (the piece, or the file), from the
  // demuxer's duration; NONE if unknown. Ask through a linked branch head.
  GstClockTime total_time(GstPad *pad) const;

  std::string video_decoder() const;
  // Whether the input is a picture (decodebin's typefind found an image/*
  // type: a photo, not a video file), known before the first pad is added.
  bool still_picture() const;
  // Whether build() reads a FIFO or device (fdsrc) rather than a file.
  bool reads_stream() const { return fd_ >= 0; }
  // decodebin's missing-plugin description, if one was posted ("" if not).
  static std::string missing_plugin(GstMessage *msg);
  // The caps a decoded decodebin pad's stream had before decoding (new ref):
  // the first caps upstream of it that are not raw; null if none (the
  // stream came raw), so that a re-encoded stream is named by its codec.
  static GstCaps *encoded_caps(GstPad *decoded_pad);

 private:
  static gboolean on_autoplug_continue(GstElement *bin, GstPad *pad, GstCaps *caps, gpointer self);
  static gboolean on_autoplug_query(GstElement *, GstPad *, GstElement *element, GstQuery *query, gpointer self);
  static void on_pad_added(GstElement *bin, GstPad *pad, gpointer self);
  static void on_no_more_pads(GstElement *, gpointer self);
  static void on_element_added(GstBin *, GstElement *element, gpointer self);

  Hooks hooks_;
  GstClockTime start_ = GST_CLOCK_TIME_NONE, duration_ = GST_CLOCK_TIME_NONE;
  mutable std::mutex lock_;
  std::string video_decoder_;
  std::string input_type_;  // the media type typefind found
  std::atomic<bool> refused_{false};  // a stream too large for the 3D stages (too_large())
  int fd_ = -1;  // a FIFO or device input, opened by build()
};

}  // namespace p3d::convert
