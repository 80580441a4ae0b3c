#include "output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <vector>

namespace p3d::convert {

namespace {

// The temporary files a signal handler must remove. Fixed storage: the
// handler may only call async-signal-safe functions (unlink, write, _exit).
constexpr int kSlots = 4;
constexpr size_t kPathMax = 4096;
char g_temp_paths[kSlots][kPathMax];
volatile sig_atomic_t g_slot_used[kSlots];
volatile sig_atomic_t g_line_open = 0;

void on_signal(int sig) {
  for (int i = 0; i < kSlots; ++i)
    if (g_slot_used[i]) unlink(g_temp_paths[i]);
  static const char msg[] = "\npseudo3d-convert: interrupted; no output written\n";
  const size_t skip = g_line_open ? 0 : 1;  // the newline ends an open progress line
  ssize_t ignored = write(STDERR_FILENO, msg + skip, sizeof msg - 1 - skip);
  (void)ignored;
  _exit(128 + sig);
}

int register_temp(const std::string &path) {
  if (path.size() >= kPathMax) return -1;
  for (int i = 0; i < kSlots; ++i)
    if (!g_slot_used[i]) {
      std::memcpy(g_temp_paths[i], path.c_str(), path.size() + 1);
      g_slot_used[i] = 1;
      return i;
    }
  return -1;
}

void unregister_temp(int slot) {
  if (slot >= 0) g_slot_used[slot] = 0;
}

std::string errno_text() { return std::strerror(errno); }

}  // namespace

void set_terminal_line_open(bool open) { g_line_open = open ? 1 : 0; }

void install_interrupt_cleanup() {
  struct sigaction sa = {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
}

OutputFile::~OutputFile() {
  if (!temp_.empty()) {
    unregister_temp(slot_);
    unlink(temp_.c_str());
  }
}

bool OutputFile::open(const std::string &path, bool force, std::string *error) {
  path_ = path;
  force_ = force;
  struct stat st;
  if (stat(path.c_str(), &st) == 0) {
    if (!force) {
      *error = path + ": already exists (use --force to overwrite)";
      return false;
    }
    if (S_ISDIR(st.st_mode)) {
      *error = path + ": is a folder";
      return false;
    }
  }
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = base.find_last_of('.');
  const std::string ext = dot == std::string::npos ? "" : base.substr(dot);
  // ".NAME.p3d-XXXXXX.EXT": hidden, unique, same folder, same extension.
  std::string tmpl = dir + "." + base + ".p3d-XXXXXX" + ext;
  std::vector<char> buf(tmpl.begin(), tmpl.end());
  buf.push_back('\0');
  const int fd = mkstemps(buf.data(), static_cast<int>(ext.size()));
  if (fd < 0) {
    *error = path + ": cannot create a file in " + (dir.empty() ? std::string("the current folder") : dir) + ": " +
             errno_text();
    return false;
  }
  // mkstemps makes the file private (0600); the result gets the usual mode.
  const mode_t mask = umask(0);
  umask(mask);
  fchmod(fd, 0666 & ~mask);
  close(fd);
  temp_ = buf.data();
  slot_ = register_temp(temp_);
  return true;
}

bool OutputFile::commit(std::string *error) {
  int rc;
  if (force_) {
    rc = rename(temp_.c_str(), path_.c_str());
  } else {
    rc = renameat2(AT_FDCWD, temp_.c_str(), AT_FDCWD, path_.c_str(), RENAME_NOREPLACE);
    if (rc != 0 && (errno == EINVAL || errno == ENOSYS)) {
      // A filesystem without RENAME_NOREPLACE: a hard link fails on an
      // existing name as well; without hard links (FAT) check, then rename.
      rc = link(temp_.c_str(), path_.c_str());
      if (rc == 0) {
        unlink(temp_.c_str());
      } else if (errno == EPERM || errno == EOPNOTSUPP) {
        struct stat st;
        if (stat(path_.c_str(), &st) == 0) {
          errno = EEXIST;
        } else {
          rc = rename(temp_.c_str(), path_.c_str());
        }
      }
    }
  }
  if (rc != 0) {
    *error = path_ + (errno == EEXIST ? ": appeared while converting; not replaced (use --force)"
                                     : ": cannot write: " + errno_text());
    return false;
  }
  unregister_temp(slot_);
  slot_ = -1;
  temp_.clear();
  return true;
}

}  // namespace p3d::convert
