// An output written to a temporary file beside its final name and renamed
// into place only when complete, so that a failure or Ctrl-C never leaves a
// partial OUTPUT (nor clobbers an existing one). The temporary file is in
// the same folder so that the rename is atomic, and it keeps OUTPUT's
// extension because encoders pick the format by it.
#pragma once

#include <string>

namespace p3d::convert {

class OutputFile {
 public:
  OutputFile() = default;
  OutputFile(const OutputFile &) = delete;
  OutputFile &operator=(const OutputFile &) = delete;
  ~OutputFile();  // removes the temporary file unless committed

  // Refuses an existing `path` unless `force`, then creates the temporary
  // file. One-line *error naming the file.
  bool open(const std::string &path, bool force, std::string *error);
  const std::string &temp_path() const { return temp_; }
  const std::string &path() const { return path_; }
  // Moves the finished temporary file to the final name. Without `force`
  // an OUTPUT that appeared meanwhile is not replaced either.
  bool commit(std::string *error);

 private:
  std::string path_, temp_;
  bool force_ = false;
  int slot_ = -1;  // in the interrupt-cleanup table
};

// SIGINT, SIGTERM and SIGHUP remove every open temporary file, print one
// line and leave with status 128 + signal. Call once, before any open().
void install_interrupt_cleanup();

// Whether a progress line is open on the terminal (no newline yet): the
// interrupt message then starts on a new line.
void set_terminal_line_open(bool open);

}  // namespace p3d::convert
