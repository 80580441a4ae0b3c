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
  if (file) s += " at " + std::string(file) + ":" + std::to_string(line);
  return s;
}

}  // namespace p3d
