#include "cuda_check.h"

#include <string>

namespace p3d {

std::string CudaStatus::message() const {
  if (ok()) return "no error";
  std::string s = call ? call : "CUDA call";
  s += " failed: ";
  s += cudaGetErrorName(code);
  s += " (";
  s += cudaGetErrorString(code);
  s += ")";
  if (bytes) s += " allocating " + std::to_string(bytes) + " bytes";
  if (file) s += " at " + std::string(file) + ":" + std::to_string(line);
  return s;
}

namespace detail {
std::atomic<int> g_fault_countdown{0};

cudaError_t fault_tick(cudaError_t err) {
  // fetch_sub returns the value before: the call that takes it from 1 to 0 fails.
  const int before = g_fault_countdown.fetch_sub(1, std::memory_order_relaxed);
  if (before == 1) return cudaErrorLaunchFailure;
  if (before <= 0) g_fault_countdown.store(0, std::memory_order_relaxed);  // raced past zero: stay disarmed
  return err;
}
}  // namespace detail

void cuda_fault_inject_after(int n) { detail::g_fault_countdown.store(n > 0 ? n : 0, std::memory_order_relaxed); }

}  // namespace p3d
