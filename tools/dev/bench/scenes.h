// pseudo3d-bench's generated input: the picture the stage timings rotate
// through (synthetic_bgr) and the sequences of the scene mode, one per kind
// of content the adaptive stages meet (scene_kinds()). Every sequence is
// deterministic (fixed seeds), so runs on different machines and commits
// time the same frames.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "host_frame.h"

namespace p3d::bench {

struct Size {
  int width, height;
};

// A smooth picture with edges, different per frame k but related like
// consecutive video frames (pseudo3d_bench.cpp's stage inputs). layout_seed
// places its rectangles and discs: another seed, another picture.
cv::Mat synthetic_bgr(int w, int h, int k, uint64_t layout_seed = 12345);

// The scene kinds, in the order `--scenes all` runs them:
//   still   one picture repeated (a still, paused video, a slide);
//   screen  a desktop where a cursor moves, a clock changes and a pane
//           scrolls: about a tenth of the picture a frame;
//   camera  vtest.avi (static camera, people walking), resized;
//   pan     a large picture panned a few pixels a frame;
//   snow    new random noise every frame;
//   cuts    moving pictures that cut to an unrelated one every few frames;
//   letterbox  the pan as a 2.39:1 film in black bars (timed crop-bars=auto
//           against off, scene_bench.h).
const std::vector<std::string> &scene_kinds();

// n frames of `kind` at size s in `format` into *frames. video: the file the
// camera scene reads. False, with *why, when the scene cannot be made (the
// video cannot be read); *note gets what the sequence holds where it is not
// what was asked (fewer frames in the video).
bool make_scene(const std::string &kind, Size s, int n, PixelFormat format, const std::string &video,
                std::vector<HostFrame> *frames, std::string *why, std::string *note);

}  // namespace p3d::bench
