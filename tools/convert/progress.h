// Progress of a conversion: percent of the media time done, frames per
// second and time left. On a terminal one line is rewritten in place; into a
// file or pipe, plain lines at most every few seconds (each tenth of the
// work, or once a minute), so logs stay readable.
#pragma once

#include <gst/gst.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <string>

namespace p3d::convert {

class Progress {
 public:
  explicit Progress(bool enabled, FILE *out = stderr);

  // Media time the conversion covers (GST_CLOCK_TIME_NONE: unknown).
  void set_total(GstClockTime total) { total_ = total; }
  // One frame done, ending at `position` (media time from the start of the
  // piece converted). Any thread.
  void frame(GstClockTime position);
  // Prints when due. The main loop calls it a few times a second.
  void tick();
  // Ends the in-place line (terminal) or prints the last plain line.
  void finish();
  // After a failure: ends an in-place line so the error gets its own.
  void abandon();

  uint64_t frames() const { return frames_.load(); }
  // Media time from the last frame converted to the end set_total()
  // announced (0 when unknown or reached). Before finish(), which counts
  // the piece as done.
  GstClockTime shortfall() const;
  // Seconds from the first frame to now.
  double seconds() const;
  std::string line() const;  // the current status, without decoration

 private:
  bool enabled_, tty_;
  FILE *out_;
  GstClockTime total_ = GST_CLOCK_TIME_NONE;
  std::atomic<uint64_t> frames_{0};
  std::atomic<uint64_t> position_{0};
  std::atomic<int64_t> first_us_{-1};
  int64_t last_print_us_ = 0;
  int last_decile_ = 0;
  bool printed_ = false;
  bool finished_ = false;
};

// "1:02:03" / "2:03" (hours only when needed).
std::string format_clock(double seconds);

}  // namespace p3d::convert
