// Command-line helpers the tools share (pseudo3d-bench, pseudo3d-quality):
// one usage error (the tool's name, the message, its usage text, exit code),
// the walk over the arguments, and the integer options that end in one.
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

  // Walks argv the way both tools read it: -h/--help prints the usage and
  // exits 0; the one flag `flag` (no value) calls on_flag(); every other
  // option takes the next argument as its value: on_option(name, value),
  // which fail()s on names it does not know. *command_line gets the whole
  // command, for the result files.
  template <class OnFlag, class OnOption>
  void parse(int argc, char **argv, const std::string &flag, std::string *command_line, OnFlag on_flag,
             OnOption on_option) const {
    for (int i = 0; i < argc; ++i) *command_line += (i ? " " : "") + std::string(argv[i]);
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "-h" || a == "--help") {
        usage_(std::cout);
        std::exit(0);
      }
      if (a == flag) {
        on_flag();
        continue;
      }
      if (i + 1 >= argc) fail("missing value after " + a);
      on_option(a, std::string(argv[++i]));
    }
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
