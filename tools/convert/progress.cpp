#include "progress.h"

#include "output_file.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace p3d::convert {

namespace {
constexpr int64_t kPlainMinGapUs = 2 * G_USEC_PER_SEC;   // plain lines: not more often than this
constexpr int64_t kPlainMaxGapUs = 60 * G_USEC_PER_SEC;  // and at least this often
constexpr int64_t kTtyGapUs = G_USEC_PER_SEC / 4;
}  // namespace

std::string format_clock(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const long s = std::lround(seconds);
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  return buf;
}

Progress::Progress(bool enabled, FILE *out) : enabled_(enabled), tty_(isatty(fileno(out)) != 0), out_(out) {}

void Progress::frame(GstClockTime position) {
  int64_t unset = -1;
  first_us_.compare_exchange_strong(unset, g_get_monotonic_time());
  frames_.fetch_add(1);
  if (GST_CLOCK_TIME_IS_VALID(position)) position_.store(std::max<uint64_t>(position_.load(), position));
}

double Progress::seconds() const {
  const int64_t first = first_us_.load();
  return first < 0 ? 0.0 : (g_get_monotonic_time() - first) / 1e6;
}

std::string Progress::line() const {
  const double secs = seconds();
  const double pos = position_.load() / 1e9;
  const uint64_t n = frames_.load();
  const double fps = secs > 0 ? n / secs : 0;
  const bool known = GST_CLOCK_TIME_IS_VALID(total_) && total_ > 0;
  const double total = known ? total_ / 1e9 : 0;
  // Time left from the average speed so far (media seconds per second).
  const double speed = secs >= 1 ? pos / secs : 0;
  const double left = known && pos >= total ? 0 : known && speed > 0 ? (total - pos) / speed : NAN;
  // Rates over less than a second say little: shown from then on.
  char rate[32] = "-- frames/s";
  if (secs >= 1 || finished_) std::snprintf(rate, sizeof rate, "%.1f frames/s", fps);
  char buf[160];
  if (known)
    std::snprintf(buf, sizeof buf, "%5.1f %%  %s of %s  %s  time left %s", std::min(100.0, 100.0 * pos / total),
                  format_clock(pos).c_str(), format_clock(total).c_str(), rate, format_clock(left).c_str());
  else
    std::snprintf(buf, sizeof buf, "%s  %s", format_clock(pos).c_str(), rate);
  return buf;
}

void Progress::tick() {
  if (!enabled_ || first_us_.load() < 0) return;
  const int64_t now = g_get_monotonic_time();
  if (tty_) {
    if (now - last_print_us_ < kTtyGapUs) return;
    std::fprintf(out_, "\r%s\033[K", line().c_str());
    set_terminal_line_open(true);
  } else {
    const bool known = GST_CLOCK_TIME_IS_VALID(total_) && total_ > 0;
    const int decile = known ? static_cast<int>(10.0 * position_.load() / total_) : 0;
    const int64_t gap = now - last_print_us_;
    if (!(gap >= kPlainMaxGapUs || (decile > last_decile_ && gap >= kPlainMinGapUs))) return;
    last_decile_ = decile;
    std::fprintf(out_, "pseudo3d-convert: %s\n", line().c_str());
  }
  std::fflush(out_);
  last_print_us_ = now;
  printed_ = true;
}

void Progress::abandon() {
  if (enabled_ && tty_ && printed_) std::fputc('\n', out_);
  printed_ = false;
  set_terminal_line_open(false);
}

GstClockTime Progress::shortfall() const {
  const uint64_t reached = position_.load();
  return GST_CLOCK_TIME_IS_VALID(total_) && frames_.load() > 0 && reached < total_ ? total_ - reached : 0;
}

void Progress::finish() {
  if (!enabled_) return;
  if (GST_CLOCK_TIME_IS_VALID(total_)) position_.store(total_);  // the piece is done
  finished_ = true;
  if (tty_) {
    std::fprintf(out_, "\r%s\033[K\n", line().c_str());
    set_terminal_line_open(false);
  } else
    std::fprintf(out_, "pseudo3d-convert: %s\n", line().c_str());
  std::fflush(out_);
}

}  // namespace p3d::convert
