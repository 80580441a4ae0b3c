// The warp's 8-bit row kernels (cuda/warp_rows.cuh, Px = Rgba): the
// launch of a frame's key place and row groups, and the residency queries
// that cuda/warp_plan.h chooses the kernels from.
#include "warp_rows.cuh"

namespace p3d {
namespace warp_detail {

// The row kernel for the run's key place, row groups and fill.
template <>
CudaStatus launch_row_kernel<Rgba>(const RowLaunch &l) {
  switch (l.keys) {
    case KeyPlace::NarrowSharedPerEye:
      if (l.group_rows == 1) return launch_rows<NarrowKeys, true, true, RowBlock::Row>(l);
      if (l.rows_together)
        return l.fused.out.plane[0] ? launch_rows<NarrowKeys, true, true, RowBlock::RowsTogether, true>(l)
                                    : launch_rows<NarrowKeys, true, true, RowBlock::RowsTogether>(l);
      return l.wide_groups ? launch_rows<NarrowKeys, true, true, RowBlock::WideGroup>(l)
                           : launch_rows<NarrowKeys, true, true, RowBlock::Group>(l);
    case KeyPlace::NarrowShared:
      return launch_rows<NarrowKeys, true, false, RowBlock::Row>(l);
    case KeyPlace::WideShared:
      return launch_rows<WideKeys, true, false, RowBlock::Row>(l);
    case KeyPlace::WideGlobal:
      return launch_rows<WideKeys, false, false, RowBlock::Row>(l);
  }
  return CudaStatus{cudaErrorInvalidValue, "KeyPlace", __FILE__, __LINE__};
}
template <>
CudaStatus query_row_kernels<Rgba>(HoleFill fill, int W, int smem_optin, std::vector<const void *> *attributes_set,
                                   RowKernelChoice *choice) {
  return query_row_kernels_of<Rgba>(fill, W, smem_optin, attributes_set, choice);
}

}  // namespace warp_detail
}  // namespace p3d
