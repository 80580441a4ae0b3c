// The resident threads an SM holds, for the minimum-blocks argument of
// __launch_bounds__: 1024 on Turing (sm_75), 1536 or more on every later
// architecture the build targets (sm_80 and up, Jetson Orin's sm_87
// included). A bound asking for more blocks than an SM can hold is ignored,
// with a ptxas warning, so kernels ask for P3D_THREADS_PER_SM / their block
// size.
#pragma once

#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ == 750
#define P3D_THREADS_PER_SM 1024
#else
#define P3D_THREADS_PER_SM 1536
#endif

// The most threads an SM can hold, for kernels whose blocks are worth
// packing as tightly as an SM allows (the warp's row kernel, bound by
// instructions, gains from every further resident block): 2048 on A100
// (sm_80), Hopper (sm_90) and the data-centre Blackwells (sm_100); 1536 on
// the others from Ampere on (sm_86, Jetson Orin's sm_87, sm_89, sm_120);
// 1024 on Turing. A card runs the bound its machine code was built with:
// the default gpu_arch list has no sm_100, so a B200 compiles the embedded
// compute_75 PTX, with Turing's bound, unless the build names 100.
#if defined(__CUDA_ARCH__) && (__CUDA_ARCH__ == 800 || __CUDA_ARCH__ == 900 || __CUDA_ARCH__ == 1000)
#define P3D_MAX_THREADS_PER_SM 2048
#else
#define P3D_MAX_THREADS_PER_SM P3D_THREADS_PER_SM
#endif
