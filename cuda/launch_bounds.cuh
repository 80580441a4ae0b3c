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
