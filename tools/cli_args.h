// Command-line helpers the tools share (pseudo3d-bench, pseudo3d-quality):
// one usage error (the tool's name, the message, its usage text, exit code)
// and the integer options that end in one.
#pragma once

#include <cstdlib>
#include <iostream>
#include <string>

namespace p3d::tools {

class Cli {
 public:
  using UsageFn = void (*)(std::ostream &);
  Cli(const char *tool, UsageFn usage, int exit_code) : tool_(tool), usage_(usage), exit_code_(exit_code) {}

  // "<tool>: <msg>", the usage text on stderr, exit.
  [[noreturn]] void fail(const std::string &msg) const {
    std::cerr << tool_ << ": " << msg << "\n";
    usage_(std::cerr);
    std::exit(exit_code_);
  }

  // The integer in `v`, which must be one in lo..hi (else fail()).
  int integer(const std::string &opt, const std::string &v, int lo, int hi) const {
    char *end = nullptr;
    const long n = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0' || n < lo || n > hi)
      fail(opt + " wants an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got '" + v + "'");
    return static_cast<int>(n);
  }

 private:
  const char *tool_;
  UsageFn usage_;
  int exit_code_;
};

}  // namespace p3d::tools
