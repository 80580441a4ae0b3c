// pseudo3d-bench's generated input (scenes.h).
#include "scenes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

namespace p3d::bench {

// Colour ramps whose phase moves with k, a few rectangles and discs that
// drift, and mild Gaussian noise: region grouping, the guide's edges and the
// warp's disocclusions all have work to do.
cv::Mat synthetic_bgr(int w, int h, int k, uint64_t layout_seed) {
  cv::Mat img(h, w, CV_8UC3);
  const float phase = 0.07f * static_cast<float>(k);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const float fy = static_cast<float>(y) / static_cast<float>(h);
      cv::Vec3b *row = img.ptr<cv::Vec3b>(y);
      for (int x = 0; x < w; ++x) {
        const float fx = static_cast<float>(x) / static_cast<float>(w);
        const float t = fx * 0.8f + fy * 0.3f + phase;
        row[x] = cv::Vec3b(cv::saturate_cast<uint8_t>(40.f + 150.f * fx),
                           cv::saturate_cast<uint8_t>(60.f + 130.f * fy),
                           cv::saturate_cast<uint8_t>(30.f + 190.f * (t - std::floor(t))));
      }
    }
  });
  cv::RNG layout(layout_seed);  // same shapes in every frame, drifting with k
  const int drift = std::max(1, w / 200) * k;
  for (int i = 0; i < 8; ++i) {
    const int x0 = layout.uniform(0, w), y0 = layout.uniform(0, h);
    const int rw = layout.uniform(w / 20 + 1, w / 4 + 2), rh = layout.uniform(h / 20 + 1, h / 4 + 2);
    const cv::Scalar colour(layout.uniform(0, 256), layout.uniform(0, 256), layout.uniform(0, 256));
    const int dir = i % 2 ? 1 : -1;
    cv::rectangle(img, cv::Rect(x0 + dir * drift, y0, rw, rh), colour, cv::FILLED);
  }
  for (int i = 0; i < 3; ++i) {
    const cv::Point c(layout.uniform(0, w) + drift, layout.uniform(0, h));
    const int r = layout.uniform(std::min(w, h) / 30 + 1, std::min(w, h) / 8 + 2);
    cv::circle(img, c, r, cv::Scalar(layout.uniform(0, 256), layout.uniform(0, 256), layout.uniform(0, 256)),
               cv::FILLED, cv::LINE_AA);
  }
  cv::Mat noise(h, w, CV_16SC3);
  cv::RNG(1000 + k).fill(noise, cv::RNG::NORMAL, 0, 3);
  cv::Mat noisy;
  cv::add(img, noise, noisy, cv::noArray(), CV_8UC3);
  return noisy;
}

const std::vector<std::string> &scene_kinds() {
  static const std::vector<std::string> kinds = {"still", "screen", "camera", "pan", "snow", "cuts", "letterbox"};
  return kinds;
}

namespace {

using FrameFn = std::function<cv::Mat(int k)>;

// ---- screen ---------------------------------------------------------------------

// Screen content scales with the picture: u pixels stand for one pixel of
// a 1080-row desktop, so every size shows the same desktop (the same share
// of its tiles changes).
struct ScreenGeometry {
  int w, h;
  double u;
  // A length of v desktop pixels, at least one.
  int px(double v) const { return std::max(1, static_cast<int>(std::lround(v * u))); }
  cv::Rect rel(double x, double y, double rw, double rh) const {
    return cv::Rect(static_cast<int>(x * w), static_cast<int>(y * h), static_cast<int>(rw * w),
                    static_cast<int>(rh * h));
  }
};

// Lines of random lower-case words in `area`, anti-aliased as a screen
// draws text: fine detail that the guide and the depth blocks see.
void draw_text(cv::Mat &img, cv::Rect area, cv::RNG &rng, const ScreenGeometry &g, cv::Scalar ink) {
  const double scale = 0.45 * g.u;
  const int line = g.px(18), margin = g.px(6), gap = g.px(7), thick = g.px(1);
  for (int y = area.y + line; y <= area.y + area.height - line / 4; y += line) {
    int x = area.x + margin;
    for (;;) {
      std::string word(static_cast<size_t>(rng.uniform(2, 10)), ' ');
      for (char &c : word) c = static_cast<char>('a' + rng.uniform(0, 26));
      int base = 0;
      const cv::Size size = cv::getTextSize(word, cv::FONT_HERSHEY_SIMPLEX, scale, thick, &base);
      if (x + size.width > area.x + area.width - margin) break;
      cv::putText(img, word, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, scale, ink, thick, cv::LINE_AA);
      x += size.width + gap;
    }
    if (rng.uniform(0, 6) == 0) y += line;  // a paragraph break
  }
}

// A window: border, title bar and a body of text.
void draw_window(cv::Mat &img, cv::Rect r, const ScreenGeometry &g, cv::RNG &rng, cv::Scalar body, cv::Scalar ink,
                 cv::Scalar title) {
  const int bar = g.px(28);
  cv::rectangle(img, r, body, cv::FILLED);
  cv::rectangle(img, cv::Rect(r.x, r.y, r.width, bar), title, cv::FILLED);
  cv::putText(img, "untitled - editor", cv::Point(r.x + g.px(8), r.y + bar - g.px(9)), cv::FONT_HERSHEY_SIMPLEX,
              0.5 * g.u, cv::Scalar(255, 255, 255), g.px(1), cv::LINE_AA);
  cv::rectangle(img, r, cv::Scalar(90, 90, 90), g.px(1));
  draw_text(img, cv::Rect(r.x, r.y + bar, r.width, r.height - bar), rng, g, ink);
}

// The desktop: a flat background, a taskbar, a text editor, a terminal and a
// browser-like window whose pane scrolls; per frame the pane moves up by a
// few rows, the clock in the taskbar shows the next hundredths and the
// cursor moves by about ten pixels.
FrameFn screen_frames(Size s, int n) {
  const ScreenGeometry g{s.width, s.height, s.height / 1080.0};
  cv::RNG rng(4242);
  cv::Mat desktop(s.height, s.width, CV_8UC3, cv::Scalar(140, 110, 60));
  const int bar = g.px(40);
  cv::rectangle(desktop, cv::Rect(0, s.height - bar, s.width, bar), cv::Scalar(45, 45, 45), cv::FILLED);
  for (int i = 0; i < 6; ++i)  // taskbar icons
    cv::rectangle(desktop, cv::Rect(g.px(12 + 44 * i), s.height - bar + g.px(6), g.px(28), g.px(28)),
                  cv::Scalar(rng.uniform(60, 230), rng.uniform(60, 230), rng.uniform(60, 230)), cv::FILLED);
  draw_window(desktop, g.rel(0.04, 0.05, 0.40, 0.62), g, rng, cv::Scalar(250, 250, 250), cv::Scalar(30, 30, 30),
              cv::Scalar(150, 90, 40));
  draw_window(desktop, g.rel(0.08, 0.71, 0.34, 0.20), g, rng, cv::Scalar(30, 30, 30), cv::Scalar(120, 220, 120),
              cv::Scalar(70, 70, 70));
  draw_window(desktop, g.rel(0.50, 0.08, 0.46, 0.68), g, rng, cv::Scalar(245, 245, 245), cv::Scalar(60, 40, 20),
              cv::Scalar(120, 80, 30));
  // The pane: a long page of text drawn once, shown `scroll` rows further
  // down each frame.
  const cv::Rect pane = g.rel(0.63, 0.20, 0.24, 0.33);
  const int scroll = g.px(3);
  cv::Mat page(pane.height + scroll * n, pane.width, CV_8UC3, cv::Scalar(255, 252, 245));
  draw_text(page, cv::Rect(0, 0, page.cols, page.rows), rng, g, cv::Scalar(20, 20, 20));
  const cv::Rect clock(s.width - g.px(170), s.height - bar + g.px(4), g.px(160), bar - g.px(8));
  return [=](int k) {
    cv::Mat img = desktop.clone();
    page(cv::Rect(0, k * scroll, pane.width, pane.height)).copyTo(img(pane));
    const int cs = k * 100 / 30;  // 30 frames a second: other hundredths every frame
    char text[32];
    std::snprintf(text, sizeof text, "09:41:%02d.%02d", (7 + cs / 100) % 60, cs % 100);
    cv::rectangle(img, clock, cv::Scalar(60, 60, 60), cv::FILLED);
    cv::putText(img, text, cv::Point(clock.x + g.px(10), clock.y + clock.height - g.px(9)), cv::FONT_HERSHEY_SIMPLEX,
                0.6 * g.u, cv::Scalar(255, 255, 255), g.px(1), cv::LINE_AA);
    const cv::Point tip(static_cast<int>(0.30 * s.width) + g.px(9) * k,
                        static_cast<int>(0.40 * s.height) + g.px(4) * k);
    std::vector<cv::Point> arrow;
    for (const cv::Point p : {cv::Point(0, 0), cv::Point(0, 17), cv::Point(4, 13), cv::Point(7, 20), cv::Point(9, 19),
                              cv::Point(6, 12), cv::Point(12, 12)})
      arrow.push_back(tip + cv::Point(static_cast<int>(std::lround(1.2 * g.u * p.x)),
                                      static_cast<int>(std::lround(1.2 * g.u * p.y))));
    cv::fillPoly(img, std::vector<std::vector<cv::Point>>{arrow}, cv::Scalar(255, 255, 255), cv::LINE_AA);
    cv::polylines(img, std::vector<std::vector<cv::Point>>{arrow}, true, cv::Scalar(0, 0, 0), g.px(1), cv::LINE_AA);
    return img;
  };
}

// ---- the other kinds -----------------------------------------------------------------

// A picture larger than the frame by the pan's travel, seen through a window
// that moves dx across and dx / 2 down each frame.
FrameFn pan_frames(Size s, int n) {
  const int dx = std::max(2, s.width / 480), dy = dx / 2;
  const cv::Mat big = synthetic_bgr(s.width + dx * (n - 1), s.height + dy * (n - 1), 0);
  return [=](int k) { return big(cv::Rect(dx * k, dy * k, s.width, s.height)).clone(); };
}

FrameFn snow_frames(Size s) {
  return [=](int k) {
    cv::Mat img(s.height, s.width, CV_8UC3);
    cv::RNG(777 + k).fill(img, cv::RNG::UNIFORM, 0, 256);
    return img;
  };
}

// Shots of kShotFrames frames, each moving as synthetic_bgr does, from
// kShots unrelated pictures in turn: other shapes, and mirrored, inverted or
// with the colours turned round, so that every cut changes the whole
// picture (the estimator sees a cut, not motion).
constexpr int kShotFrames = 4;
constexpr int kShots = 3;
FrameFn cut_frames(Size s) {
  return [=](int k) {
    const int shot = (k / kShotFrames) % kShots;
    cv::Mat img = synthetic_bgr(s.width, s.height, k, 12345 + 7919 * static_cast<uint64_t>(shot));
    if (shot == 1) {
      cv::flip(img, img, -1);
      cv::bitwise_not(img, img);
    } else if (shot == 2) {
      cv::flip(img, img, 0);
      const int from_to[] = {0, 1, 1, 2, 2, 0};
      cv::Mat turned(img.size(), img.type());
      cv::mixChannels(&img, 1, &turned, 1, from_to, 3);
      img = turned;
    }
    return img;
  };
}

// The first n frames of the video, resized to s.
bool camera_frames(const std::string &video, Size s, int n, std::vector<cv::Mat> *out, std::string *why) {
  cv::VideoCapture cap;
  try {
    cap.open(video);
  } catch (const cv::Exception &e) {
    *why = e.what();
  }
  if (!cap.isOpened()) {
    if (why->empty()) *why = "cv::VideoCapture cannot open " + video;
    return false;
  }
  cv::Mat bgr;
  while (static_cast<int>(out->size()) < n && cap.read(bgr) && !bgr.empty()) {
    cv::Mat sized;
    cv::resize(bgr, sized, cv::Size(s.width, s.height), 0, 0, cv::INTER_LINEAR);
    out->push_back(sized);
  }
  if (out->empty()) *why = video + " has no frame that OpenCV can decode";
  return !out->empty();
}

}  // namespace

bool make_scene(const std::string &kind, Size s, int n, PixelFormat format, const std::string &video,
                std::vector<HostFrame> *frames, std::string *why, std::string *note) {
  frames->clear();
  FrameFn make;
  if (kind == "still") {
    const cv::Mat picture = synthetic_bgr(s.width, s.height, 0);
    make = [picture](int) { return picture; };
  } else if (kind == "screen") {
    make = screen_frames(s, n);
  } else if (kind == "camera") {
    std::vector<cv::Mat> read;
    if (!camera_frames(video, s, n, &read, why)) return false;
    if (static_cast<int>(read.size()) < n)
      *note = std::to_string(read.size()) + " of " + std::to_string(n) + " frames in " + video;
    n = static_cast<int>(read.size());
    make = [read](int k) { return read[static_cast<size_t>(k)]; };
  } else if (kind == "pan") {
    make = pan_frames(s, n);
  } else if (kind == "snow") {
    make = snow_frames(s);
  } else if (kind == "cuts") {
    make = cut_frames(s);
  } else if (kind == "letterbox") {
    // A 2.39:1 film (the pan) in black bars: its height a multiple of 8,
    // as encoders store such films (1920 x 800, 3840 x 1608).
    const int active = std::min(s.height, static_cast<int>(std::lround(s.width / 2.39 / 8)) * 8);
    const int top = (s.height - active) / 2;
    const FrameFn film = pan_frames(Size{s.width, active}, n);
    make = [film, top, s, active](int k) {
      cv::Mat framed;
      cv::copyMakeBorder(film(k), framed, top, s.height - active - top, 0, 0, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
      return framed;
    };
  } else {
    *why = "unknown scene '" + kind + "'";
    return false;
  }
  // Every frame converted on its own, as a decoder hands each one over in a
  // buffer of its own (a still's frames are equal bytes, not one buffer).
  for (int k = 0; k < n; ++k) frames->push_back(HostFrame::from_bgr(make(k), format));
  return true;
}

}  // namespace p3d::bench
