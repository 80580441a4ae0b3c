#include "mp4_stereo.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

namespace p3d {

namespace {

constexpr uint32_t fourcc(const char (&s)[5]) {
  return (uint32_t(uint8_t(s[0])) << 24) | (uint32_t(uint8_t(s[1])) << 16) | (uint32_t(uint8_t(s[2])) << 8) |
         uint32_t(uint8_t(s[3]));
}

uint32_t be32(const uint8_t *p) { return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3]; }
uint64_t be64(const uint8_t *p) { return (uint64_t(be32(p)) << 32) | be32(p + 4); }
void put32(uint8_t *p, uint32_t v) {
  p[0] = uint8_t(v >> 24);
  p[1] = uint8_t(v >> 16);
  p[2] = uint8_t(v >> 8);
  p[3] = uint8_t(v);
}
void put64(uint8_t *p, uint64_t v) {
  put32(p, uint32_t(v >> 32));
  put32(p + 4, uint32_t(v));
}

// A box at `offset` in a buffer: its size (header included), header size
// and type.
struct Box {
  size_t offset = 0;
  uint64_t size = 0;
  unsigned header = 8;
  uint32_t type = 0;
  size_t end() const { return offset + size; }
  size_t body() const { return offset + header; }
};

// The box at `offset` within [offset, end) of `b`; false if it does not fit.
bool box_at(const std::vector<uint8_t> &b, size_t offset, size_t end, Box *box) {
  if (end - offset < 8) return false;
  box->offset = offset;
  box->size = be32(&b[offset]);
  box->type = be32(&b[offset + 4]);
  box->header = 8;
  if (box->size == 1) {
    if (end - offset < 16) return false;
    box->size = be64(&b[offset + 8]);
    box->header = 16;
  } else if (box->size == 0) {
    box->size = end - offset;
  }
  return box->size >= box->header && box->size <= end - offset;
}

// The first child of type `type` in [from, to).
bool child(const std::vector<uint8_t> &b, size_t from, size_t to, uint32_t type, Box *found) {
  Box c;
  for (size_t at = from; at < to && box_at(b, at, to, &c); at = c.end())
    if (c.type == type) {
      *found = c;
      return true;
    }
  return false;
}

void grow(std::vector<uint8_t> &b, const Box &box, int64_t delta) {
  if (box.header == 16)
    put64(&b[box.offset + 8], box.size + delta);
  else
    put32(&b[box.offset], uint32_t(box.size + delta));
}

// Adds `delta` to the chunk offsets of every track in moov `b` that point
// at or after `from` (the old end of moov: data before it does not move).
bool shift_chunk_offsets(std::vector<uint8_t> &b, int64_t delta, uint64_t from, std::string *error) {
  Box moov, trak, mdia, minf, stbl, table;
  box_at(b, 0, b.size(), &moov);
  for (size_t at = moov.body(); at < moov.end() && box_at(b, at, moov.end(), &trak); at = trak.end()) {
    if (trak.type != fourcc("trak")) continue;
    if (!child(b, trak.body(), trak.end(), fourcc("mdia"), &mdia) ||
        !child(b, mdia.body(), mdia.end(), fourcc("minf"), &minf) ||
        !child(b, minf.body(), minf.end(), fourcc("stbl"), &stbl))
      continue;
    const bool wide = child(b, stbl.body(), stbl.end(), fourcc("co64"), &table);
    if (!wide && !child(b, stbl.body(), stbl.end(), fourcc("stco"), &table)) continue;
    const size_t first = table.body() + 8, width = wide ? 8 : 4;
    const uint32_t count = table.size >= table.header + 8 ? be32(&b[table.body() + 4]) : 0;
    if (first + uint64_t(count) * width > table.end()) {
      *error = "a chunk offset table is cut short";
      return false;
    }
    for (uint32_t i = 0; i < count; ++i) {
      uint8_t *p = &b[first + i * width];
      const uint64_t offset = wide ? be64(p) : be32(p);
      if (offset < from) continue;
      const uint64_t moved = offset + delta;
      if (!wide && moved > UINT32_MAX) {
        *error = "the chunk offsets would pass 4 GiB in a 32-bit table";
        return false;
      }
      if (wide)
        put64(p, moved);
      else
        put32(p, uint32_t(moved));
    }
  }
  return true;
}

// moov (the whole box in `b`) with st3d written into its video sample
// entry; *delta is how much it grew.
bool edit_moov(std::vector<uint8_t> &b, Mp4StereoMode mode, int64_t *delta, std::string *error) {
  Box moov, trak, mdia, hdlr, minf, stbl, stsd, entry;
  if (!box_at(b, 0, b.size(), &moov)) {
    *error = "the movie box is damaged";
    return false;
  }
  bool found = false;
  for (size_t at = moov.body(); !found && at < moov.end() && box_at(b, at, moov.end(), &trak); at = trak.end()) {
    if (trak.type != fourcc("trak") || !child(b, trak.body(), trak.end(), fourcc("mdia"), &mdia)) continue;
    // hdlr: version and flags, pre_defined, then the handler type.
    if (!child(b, mdia.body(), mdia.end(), fourcc("hdlr"), &hdlr) || hdlr.size < hdlr.header + 12 ||
        be32(&b[hdlr.body() + 8]) != fourcc("vide"))
      continue;
    // stsd: version and flags, entry count, then the entries.
    found = child(b, mdia.body(), mdia.end(), fourcc("minf"), &minf) &&
            child(b, minf.body(), minf.end(), fourcc("stbl"), &stbl) &&
            child(b, stbl.body(), stbl.end(), fourcc("stsd"), &stsd) && stsd.size >= stsd.header + 8 &&
            box_at(b, stsd.body() + 8, stsd.end(), &entry);
  }
  // A visual sample entry's boxes follow its 78 bytes of fields.
  constexpr size_t kVisualFields = 78;
  if (!found || entry.size < entry.header + kVisualFields) {
    *error = "no video track with a sample entry";
    return false;
  }
  const size_t first = entry.body() + kVisualFields;
  *delta = 0;
  Box old;
  if (child(b, first, entry.end(), fourcc("st3d"), &old)) {
    b.erase(b.begin() + old.offset, b.begin() + old.end());
    *delta -= int64_t(old.size);
    entry.size -= old.size;
  }
  Box config;
  size_t insert_at = first;
  if (child(b, first, entry.end(), fourcc("avcC"), &config) || child(b, first, entry.end(), fourcc("hvcC"), &config))
    insert_at = config.end();
  const uint8_t st3d[13] = {0, 0, 0, 13, 's', 't', '3', 'd', 0, 0, 0, 0, uint8_t(mode)};
  b.insert(b.begin() + insert_at, st3d, st3d + sizeof st3d);
  *delta += int64_t(sizeof st3d);
  // The boxes around the insertion start before it: their offsets hold.
  for (const Box *around : {&moov, &trak, &mdia, &minf, &stbl, &stsd}) grow(b, *around, *delta);
  grow(b, entry, int64_t(sizeof st3d));  // its size already lost the old box
  return true;
}

bool read_range(std::FILE *f, uint64_t offset, uint64_t size, std::vector<uint8_t> *out) {
  out->resize(size);
  return fseeko(f, off_t(offset), SEEK_SET) == 0 && (size == 0 || std::fread(out->data(), 1, size, f) == size);
}

bool copy_range(std::FILE *from, uint64_t offset, uint64_t size, std::FILE *to) {
  if (fseeko(from, off_t(offset), SEEK_SET) != 0) return false;
  std::vector<char> chunk(1 << 20);
  while (size > 0) {
    const size_t n = size < chunk.size() ? size_t(size) : chunk.size();
    if (std::fread(chunk.data(), 1, n, from) != n || std::fwrite(chunk.data(), 1, n, to) != n) return false;
    size -= n;
  }
  return true;
}

}  // namespace

bool mp4_set_stereo_box(const std::string &path, Mp4StereoMode mode, std::string *error) {
  std::FILE *f = std::fopen(path.c_str(), "r+b");
  if (!f) {
    *error = path + ": cannot open for writing";
    return false;
  }
  // The top-level boxes: where moov is and whether an mdat follows it.
  fseeko(f, 0, SEEK_END);
  const uint64_t file_size = uint64_t(ftello(f));
  uint64_t moov_at = 0, moov_size = 0, at = 0;
  bool have_moov = false, mdat_after_moov = false, fragmented = false;
  while (at + 8 <= file_size) {
    std::vector<uint8_t> h;
    if (!read_range(f, at, file_size - at >= 16 ? 16 : 8, &h)) break;
    uint64_t size = be32(h.data());
    const uint32_t type = be32(&h[4]);
    if (size == 1 && h.size() == 16) size = be64(&h[8]);
    if (size == 0) size = file_size - at;
    if (size < 8 || size > file_size - at) break;
    if (type == fourcc("moov")) {
      have_moov = true;
      moov_at = at;
      moov_size = size;
    } else if (type == fourcc("mdat") && have_moov) {
      mdat_after_moov = true;
    } else if (type == fourcc("moof") || type == fourcc("mfra")) {
      fragmented = true;
    }
    at += size;
  }
  std::vector<uint8_t> moov;
  int64_t delta = 0;
  std::string why = "not an MP4/MOV file with a movie box";
  // A walk that stops short of the end may have missed an mdat after moov,
  // whose chunk offsets would then be left unshifted: such files are refused.
  if (have_moov && at != file_size) why = "its boxes are damaged or cut short";
  // Fragments hold absolute offsets (tfra, base_data_offset) this does not move.
  if (fragmented) why = "a fragmented MP4, which is not edited";
  if (!have_moov || at != file_size || fragmented || !read_range(f, moov_at, moov_size, &moov) || !edit_moov(moov, mode, &delta, &why) ||
      !shift_chunk_offsets(moov, delta, moov_at + moov_size, &why)) {
    std::fclose(f);
    *error = path + ": " + why;
    return false;
  }
  const uint64_t tail_at = moov_at + moov_size, tail_size = file_size - tail_at;
  bool ok;
  if (!mdat_after_moov) {
    // Only moov and the small boxes after it (udta, uuid) are rewritten.
    std::vector<uint8_t> tail;
    ok = read_range(f, tail_at, tail_size, &tail) && fseeko(f, off_t(moov_at), SEEK_SET) == 0 &&
         std::fwrite(moov.data(), 1, moov.size(), f) == moov.size() &&
         (tail.empty() || std::fwrite(tail.data(), 1, tail.size(), f) == tail.size()) && std::fflush(f) == 0 &&
         (delta >= 0 || ftruncate(fileno(f), off_t(file_size + delta)) == 0);
    ok = std::fclose(f) == 0 && ok;
  } else {
    // A new file beside it, with its permissions, renamed over it.
    std::string temp = path + ".st3d-XXXXXX";
    const int fd = mkstemp(&temp[0]);
    struct stat st;
    std::FILE *out = fd >= 0 ? fdopen(fd, "wb") : nullptr;
    if (fd >= 0 && !out) close(fd);
    ok = out && fstat(fileno(f), &st) == 0 && fchmod(fileno(out), st.st_mode & 07777) == 0 &&
         copy_range(f, 0, moov_at, out) && std::fwrite(moov.data(), 1, moov.size(), out) == moov.size() &&
         copy_range(f, tail_at, tail_size, out);
    if (out) ok = std::fclose(out) == 0 && ok;
    std::fclose(f);
    ok = ok && std::rename(temp.c_str(), path.c_str()) == 0;
    if (!ok) std::remove(temp.c_str());
  }
  if (!ok) *error = path + ": could not write the stereo box";
  return ok;
}

}  // namespace p3d
