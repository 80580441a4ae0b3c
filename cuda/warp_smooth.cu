// BackgroundSmooth's sums of 8-bit anchors (cuda/warp_smooth.cuh, Px = Rgba).
#include "warp_smooth.cuh"

namespace p3d {
namespace warp_detail {

template <>
CudaStatus launch_smooth<Rgba>(const SmoothPlan &plan, const SmoothScratch &sc, const FrameView &out, int W, int H,
                               cudaStream_t stream, int smem_optin, std::vector<const void *> *attributes_set,
                               SmoothSumsLaunch *threads_cache) {
  return launch_smooth_of<Rgba>(plan, sc, out, W, H, stream, smem_optin, attributes_set, threads_cache);
}

}  // namespace warp_detail
}  // namespace p3d
