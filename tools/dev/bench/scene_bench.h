// pseudo3d-bench's scene mode (--scenes): the CPU chain (or, with --device
// gpu, the GPU chain) over each generated sequence (scenes.h) with the
// adaptive stages off and on (scene_chain.h, scene_chain_gpu.h),
// the two chains in turn a frame at a time, each frame timed. Reports, per scene, size and reuse tolerance, the
// adaptive chain's cost relative to the full chain of the same run, whether
// its output is byte for byte the full chain's (and its PSNR against it
// where not), the share of tiles that changed, and the time per stage.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "bench_gpu.h"  // StageParams
#include "scenes.h"

namespace p3d::bench {

struct SceneOptions {
  std::vector<std::string> scenes;  // scene_kinds() to run; empty: scene mode off
  int frames = 30;                  // frames a sequence
  int rounds = 1;                   // runs of each sequence; a frame's time is its shortest
  std::vector<float> tolerances = {0.f};
  std::string video;                // the camera scene's file
  bool gpu = false;                 // the GPU chains (scene_chain_gpu.h) instead of the CPU's
};

// What every result line repeats of the run: the header line's run id, the
// date and commit, and the names of the input format and the layout.
struct SceneRunInfo {
  std::string run_id, date, git, format;
};

// Runs every scene at every size and tolerance, prints a table and appends
// a JSON line a result to `out`. Returns the process exit status: 0, or 1
// when an adaptive output differed from the full chain's at tolerance 0.
int run_scenes(const SceneOptions &o, const StageParams &p, PixelFormat format, const std::vector<Size> &sizes,
               const SceneRunInfo &info, std::ostream &out);

}  // namespace p3d::bench
