#include "mkv_stereo.h"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <vector>

#include "ebml.h"

namespace p3d {

namespace {

using Bytes = std::vector<uint8_t>;
using ebml::Header;

// Matroska element IDs (ebml_matroska.xml).
constexpr uint32_t kIdSegment = 0x18538067;
constexpr uint32_t kIdSeekHead = 0x114D9B74;
constexpr uint32_t kIdSeek = 0x4DBB;
constexpr uint32_t kIdSeekId = 0x53AB;
constexpr uint32_t kIdSeekPosition = 0x53AC;
constexpr uint32_t kIdTracks = 0x1654AE6B;
constexpr uint32_t kIdTrackEntry = 0xAE;
constexpr uint32_t kIdTrackType = 0x83;
constexpr uint32_t kIdVideo = 0xE0;
constexpr uint32_t kIdPixelWidth = 0xB0;
constexpr uint32_t kIdPixelHeight = 0xBA;
constexpr uint32_t kIdDisplayWidth = 0x54B0;
constexpr uint32_t kIdDisplayHeight = 0x54BA;
constexpr uint32_t kIdDisplayUnit = 0x54B2;
constexpr uint32_t kIdStereoMode = 0x53B8;
constexpr uint64_t kTrackTypeVideo = 1;
constexpr uint64_t kDisplayUnitUnknown = 4;

// Limits against absurd sizes in corrupt files (real ones are a few KB).
constexpr uint64_t kMaxSmallElement = 1 << 20;  // EBML header, SeekHead
constexpr uint64_t kMaxTracks = 64ull << 20;
constexpr int kMaxDepth = 8;  // Tracks > TrackEntry > Video > Colour > MasteringMetadata is 4

// The master elements that can occur inside Tracks: their children are
// parsed (and their size fields shortened); everything else is copied
// byte for byte.
bool is_tracks_master(uint32_t id) {
  switch (id) {
    case kIdTrackEntry:
    case kIdVideo:
    case 0x41E4:  // BlockAdditionMapping
    case 0x6624:  // TrackTranslate
    case 0x55B0:  // Colour
    case 0x55D0:  // MasteringMetadata
    case 0x7670:  // Projection
    case 0xE1:    // Audio
    case 0xE2:    // TrackOperation
    case 0xE3:    // TrackCombinePlanes
    case 0xE4:    // TrackPlane
    case 0xE9:    // TrackJoinBlocks
    case 0x6D80:  // ContentEncodings
    case 0x6240:  // ContentEncoding
    case 0x5034:  // ContentCompression
    case 0x5035:  // ContentEncryption
    case 0x47E7:  // ContentEncAESSettings
      return true;
    default:
      return false;
  }
}

// An element inside an in-memory buffer.
struct Element {
  Header h;
  size_t offset = 0;  // first byte of the ID
  size_t data() const { return offset + size_t(h.header_len()); }
  size_t end() const { return data() + size_t(h.size); }
};

// The elements that exactly tile buf[begin, end); false if one does not
// fit or has an unknown size (not allowed inside Tracks).
bool parse_children(const Bytes &buf, size_t begin, size_t end, std::vector<Element> *out) {
  out->clear();
  if (begin > end || end > buf.size()) return false;
  size_t pos = begin;
  while (pos < end) {
    Element e;
    e.offset = pos;
    if (!ebml::read_header(buf.data() + pos, end - pos, &e.h)) return false;
    if (e.h.size == ebml::kUnknownSize || e.h.size > end - pos - e.h.header_len()) return false;
    out->push_back(e);
    pos = e.end();
  }
  return true;
}

bool element_uint(const Bytes &buf, const Element &e, uint64_t *v) {
  return e.h.size <= 8 && ebml::read_uint(buf.data() + e.data(), size_t(e.h.size), v);
}

// The file, read-only checks first; every read is bounded by its size.
class MkvFile {
 public:
  bool open(const std::string &path, std::string *err) {
    errno = 0;
    f_.open(path, std::ios::in | std::ios::out | std::ios::binary);
    if (!f_) {
      *err = std::string("cannot open for reading and writing: ") + (errno ? std::strerror(errno) : "unknown error");
      return false;
    }
    f_.seekg(0, std::ios::end);
    const std::streamoff n = f_.tellg();
    if (n < 0) {
      *err = "cannot determine the file size";
      return false;
    }
    size_ = uint64_t(n);
    return true;
  }
  uint64_t size() const { return size_; }
  bool read(uint64_t offset, uint64_t len, Bytes *out) {
    if (offset > size_ || len > size_ - offset) return false;
    out->assign(size_t(len), 0);
    f_.clear();
    f_.seekg(std::streamoff(offset));
    f_.read(reinterpret_cast<char *>(out->data()), std::streamsize(len));
    return bool(f_);
  }
  // Element header at `offset`, which must end before `limit`.
  bool header_at(uint64_t offset, uint64_t limit, Header *h) {
    if (limit > size_ || offset >= limit) return false;
    Bytes b;
    const uint64_t n = std::min<uint64_t>(12, limit - offset);  // 4-byte ID + 8-byte size at most
    return read(offset, n, &b) && ebml::read_header(b.data(), b.size(), h);
  }
  bool write(uint64_t offset, const Bytes &data) {
    f_.clear();
    f_.seekp(std::streamoff(offset));
    f_.write(reinterpret_cast<const char *>(data.data()), std::streamsize(data.size()));
    f_.flush();
    return bool(f_);
  }

 private:
  std::fstream f_;
  uint64_t size_ = 0;
};

struct EbmlInfo {
  std::string doctype;
  uint64_t doctype_version = 1;  // default when absent
  uint64_t version_offset = 0;   // file offset of DocTypeVersion's data
  uint64_t version_len = 0;      // 0: absent
  int max_size_len = 8;
  uint64_t end = 0;  // file offset after the EBML header
};

bool read_ebml_header(MkvFile &f, EbmlInfo *info, std::string *err) {
  Header h;
  if (!f.header_at(0, f.size(), &h) || h.id != ebml::kIdEbml) {
    *err = "not a Matroska/WebM file (no EBML header)";
    return false;
  }
  if (h.size == ebml::kUnknownSize || h.size > kMaxSmallElement || h.header_len() + h.size > f.size()) {
    *err = "corrupt or truncated EBML header";
    return false;
  }
  Bytes buf;
  std::vector<Element> kids;
  if (!f.read(0, h.header_len() + h.size, &buf) || !parse_children(buf, size_t(h.header_len()), buf.size(), &kids)) {
    *err = "corrupt EBML header";
    return false;
  }
  for (const Element &k : kids) {
    uint64_t v = 0;
    if (k.h.id == ebml::kIdDocType) {
      info->doctype.assign(reinterpret_cast<const char *>(buf.data() + k.data()), size_t(k.h.size));
      info->doctype.erase(info->doctype.find_last_not_of('\0') + 1);  // strings may be NUL-padded
    } else if (k.h.id == ebml::kIdDocTypeVersion && element_uint(buf, k, &v)) {
      info->doctype_version = v;
      info->version_offset = k.data();
      info->version_len = k.h.size;
    } else if (k.h.id == ebml::kIdMaxSizeLength && element_uint(buf, k, &v)) {
      if (v < 1 || v > 8) {
        *err = "unsupported EBMLMaxSizeLength " + std::to_string(v);
        return false;
      }
      info->max_size_len = int(v);
    } else if (k.h.id == ebml::kIdMaxIdLength && element_uint(buf, k, &v) && v > 4) {
      *err = "unsupported EBMLMaxIDLength " + std::to_string(v);
      return false;
    }
  }
  if (info->doctype != "matroska" && info->doctype != "webm") {
    *err = "not a Matroska/WebM file (DocType \"" + info->doctype + "\")";
    return false;
  }
  info->end = buf.size();
  return true;
}

// The Tracks position named by a SeekHead element, or 0.
uint64_t seekhead_tracks(MkvFile &f, uint64_t offset, const Header &h, uint64_t segment_data) {
  Bytes buf;
  std::vector<Element> seeks, kids;
  if (h.size > kMaxSmallElement || !f.read(offset, h.header_len() + h.size, &buf) ||
      !parse_children(buf, size_t(h.header_len()), buf.size(), &seeks))
    return 0;
  for (const Element &s : seeks) {
    if (s.h.id != kIdSeek || !parse_children(buf, s.data(), s.end(), &kids)) continue;
    uint64_t id = 0, pos = 0;
    bool has_id = false, has_pos = false;
    for (const Element &k : kids) {
      if (k.h.id == kIdSeekId) has_id = element_uint(buf, k, &id);
      if (k.h.id == kIdSeekPosition) has_pos = element_uint(buf, k, &pos);
    }
    if (has_id && has_pos && id == kIdTracks && pos < UINT64_MAX - segment_data) return segment_data + pos;
  }
  return 0;
}

// Finds the Tracks element of the first Segment: by the top-level elements
// in order (they have sizes), taking the SeekHead's pointer when one comes
// first (mkvpropedit may have moved Tracks behind the Clusters).
bool find_tracks(MkvFile &f, uint64_t from, uint64_t *tracks, Header *tracks_header, uint64_t *segment_end,
                 std::string *err) {
  Header h;
  uint64_t pos = from;
  while (pos < f.size() && f.header_at(pos, f.size(), &h) && h.id == ebml::kIdVoid && h.size != ebml::kUnknownSize &&
         h.size <= f.size() - pos - h.header_len())
    pos += h.header_len() + h.size;  // Void between the EBML header and the Segment
  if (!f.header_at(pos, f.size(), &h) || h.id != kIdSegment) {
    *err = "corrupt: no Segment after the EBML header";
    return false;
  }
  const uint64_t seg_data = pos + h.header_len();
  uint64_t seg_end = f.size();  // unknown size (unfinished or live): to the end of the file
  if (h.size != ebml::kUnknownSize) {
    if (h.size > f.size() - seg_data) {
      *err = "truncated: the Segment is longer than the file";
      return false;
    }
    seg_end = seg_data + h.size;
  }
  *segment_end = seg_end;
  bool seekhead_tried = false;
  pos = seg_data;
  while (pos < seg_end) {
    if (!f.header_at(pos, seg_end, &h)) {
      *err = "corrupt: bad element header at offset " + std::to_string(pos);
      return false;
    }
    if (h.id == kIdTracks) {
      *tracks = pos;
      *tracks_header = h;
      return true;
    }
    if (h.size == ebml::kUnknownSize) break;  // an unknown-size Cluster: its end is not known
    if (h.size > seg_end - pos - h.header_len()) {
      *err = "corrupt or truncated: element at offset " + std::to_string(pos) + " runs past the Segment";
      return false;
    }
    if (h.id == kIdSeekHead && !seekhead_tried) {
      seekhead_tried = true;
      const uint64_t t = seekhead_tracks(f, pos, h, seg_data);
      Header th;
      if (t && t < seg_end && f.header_at(t, seg_end, &th) && th.id == kIdTracks) {
        *tracks = t;
        *tracks_header = th;
        return true;
      }
    }
    pos += h.header_len() + h.size;
  }
  *err = "no Tracks element";
  return false;
}

// What the rebuild puts into the chosen Video master.
struct Rebuild {
  const Bytes &buf;          // the old Tracks element
  size_t video_offset;       // offset of the Video element to patch
  Bytes video_tail;          // StereoMode, DisplayWidth, DisplayHeight, DisplayUnit
  int video_extra_size = 0;  // extra bytes on the Video size field (see mkv_set_stereo_mode)
  int max_size_len = 8;
};

bool is_replaced_video_child(uint32_t id) {
  return id == kIdStereoMode || id == kIdDisplayWidth || id == kIdDisplayHeight || id == kIdDisplayUnit;
}

// The children of `e` rebuilt: Voids dropped (their room goes to the one
// Void at the end of Tracks), masters rebuilt recursively, other elements
// copied byte for byte; the CRC-32 element, if any, recomputed over the
// new data and put first, where the spec wants it.
bool rebuild_children(Rebuild &r, const Element &e, int depth, Bytes *content, bool *had_crc);

// The element `e` rebuilt into *out: masters get the shortest size field
// (matroskamux writes them 8 bytes long, which is where the room comes
// from), everything else is copied byte for byte.
bool rebuild_element(Rebuild &r, const Element &e, int depth, Bytes *out) {
  if (!is_tracks_master(e.h.id)) {
    out->insert(out->end(), r.buf.begin() + std::ptrdiff_t(e.offset), r.buf.begin() + std::ptrdiff_t(e.end()));
    return true;
  }
  if (depth > kMaxDepth) return false;
  Bytes content;
  bool had_crc = false;
  if (!rebuild_children(r, e, depth, &content, &had_crc)) return false;
  Bytes data;
  if (had_crc) {
    const uint32_t crc = ebml::crc32(content.data(), content.size());
    ebml::append_id(&data, ebml::kIdCrc32);
    ebml::append_size(&data, 4, 1);
    for (int i = 0; i < 4; ++i) data.push_back(uint8_t(crc >> (8 * i)));  // little-endian
  }
  data.insert(data.end(), content.begin(), content.end());
  const int extra = (e.offset == r.video_offset) ? r.video_extra_size : 0;
  const int len = ebml::min_size_length(data.size()) + extra;
  if (len > r.max_size_len) return false;
  ebml::append_id(out, e.h.id);
  if (!ebml::append_size(out, data.size(), len)) return false;
  out->insert(out->end(), data.begin(), data.end());
  return true;
}

bool rebuild_children(Rebuild &r, const Element &e, int depth, Bytes *content, bool *had_crc) {
  std::vector<Element> kids;
  if (!parse_children(r.buf, e.data(), e.end(), &kids)) return false;
  const bool is_video = e.offset == r.video_offset;
  for (const Element &k : kids) {
    if (k.h.id == ebml::kIdVoid) continue;
    if (k.h.id == ebml::kIdCrc32) {
      if (k.h.size != 4) return false;
      *had_crc = true;
      continue;
    }
    if (is_video && is_replaced_video_child(k.h.id)) continue;
    if (!rebuild_element(r, k, depth + 1, content)) return false;
  }
  if (is_video) content->insert(content->end(), r.video_tail.begin(), r.video_tail.end());
  return true;
}

// The Video element of the first TrackEntry with TrackType 1, and its pixel size.
bool find_video(const Bytes &buf, const Element &tracks, Element *video, uint64_t *width, uint64_t *height,
                std::string *err) {
  std::vector<Element> entries, kids, vkids;
  if (!parse_children(buf, tracks.data(), tracks.end(), &entries)) {
    *err = "corrupt Tracks element";
    return false;
  }
  for (const Element &t : entries) {
    if (t.h.id != kIdTrackEntry) continue;
    if (!parse_children(buf, t.data(), t.end(), &kids)) {
      *err = "corrupt TrackEntry";
      return false;
    }
    uint64_t type = 0;
    const Element *v = nullptr;
    for (const Element &k : kids) {
      if (k.h.id == kIdTrackType && !element_uint(buf, k, &type)) {
        *err = "corrupt TrackType";
        return false;
      }
      if (k.h.id == kIdVideo && !v) v = &k;
    }
    if (type != kTrackTypeVideo) continue;
    if (!v || !parse_children(buf, v->data(), v->end(), &vkids)) {
      *err = v ? "corrupt Video element" : "the video track has no Video element";
      return false;
    }
    *width = *height = 0;
    for (const Element &k : vkids) {
      if (k.h.id == kIdPixelWidth && !element_uint(buf, k, width)) *width = 0;
      if (k.h.id == kIdPixelHeight && !element_uint(buf, k, height)) *height = 0;
    }
    if (!*width || !*height) {
      *err = "the video track has no valid PixelWidth/PixelHeight";
      return false;
    }
    *video = *v;
    return true;
  }
  *err = "no video track";
  return false;
}

enum class Fit { Ok, NoRoom, Error };

// The new Tracks element with `available` bytes of data (its old size, or
// more when it takes in the Void behind it), the ID and the size field's
// length unchanged: so it is exactly as long as what it replaces.
Fit rebuild_tracks(const Bytes &buf, const Element &tracks, const Element &video, const Bytes &tail, int max_size_len,
                   uint64_t available, Bytes *out, std::string *err) {
  // A Void needs 2 bytes at least; when exactly 1 byte would be left,
  // the Video size field is written 1 byte longer than needed instead.
  for (int extra = 0; extra <= 1; ++extra) {
    Rebuild r{buf, video.offset, tail, extra, max_size_len};
    Bytes content;
    bool had_crc = false;
    if (!rebuild_children(r, tracks, 0, &content, &had_crc)) {
      *err = "corrupt element inside Tracks (or nested too deep)";
      return Fit::Error;
    }
    const uint64_t crc_len = had_crc ? 6 : 0;
    const uint64_t used = content.size() + crc_len;
    if (used > available) {
      *err = "no room in the Tracks element for the stereo fields (" + std::to_string(used - available) +
             " more bytes needed)";
      return Fit::NoRoom;
    }
    const uint64_t left = available - used;
    if (left == 1) continue;
    if (left > 0 && !ebml::append_void(&content, left, max_size_len)) {
      *err = "cannot fill " + std::to_string(left) + " bytes with a Void element";
      return Fit::Error;
    }
    out->clear();
    ebml::append_id(out, tracks.h.id);
    if (!ebml::append_size(out, available, tracks.h.size_len)) {
      *err = "the Tracks size field is too short for the room taken in";
      return Fit::NoRoom;
    }
    if (had_crc) {  // first, over all the data after it (Void included)
      const uint32_t crc = ebml::crc32(content.data(), content.size());
      ebml::append_id(out, ebml::kIdCrc32);
      ebml::append_size(out, 4, 1);
      for (int i = 0; i < 4; ++i) out->push_back(uint8_t(crc >> (8 * i)));  // little-endian
    }
    out->insert(out->end(), content.begin(), content.end());
    if (out->size() != tracks.h.header_len() + available) {
      *err = "internal error: rebuilt Tracks has the wrong length";
      return Fit::Error;
    }
    return Fit::Ok;
  }
  *err = "no room in the Tracks element for the stereo fields (1 more byte needed)";
  return Fit::NoRoom;
}

}  // namespace

MkvStereoLayout mkv_stereo_layout_of(PackLayout layout) {
  switch (layout) {
    case PackLayout::SideBySide:
    case PackLayout::SideBySideHalf: return MkvStereoLayout::SideBySide;
    case PackLayout::TopBottom:
    case PackLayout::TopBottomHalf: return MkvStereoLayout::TopBottom;
    case PackLayout::RowInterleaved: return MkvStereoLayout::RowInterleaved;
    case PackLayout::ColumnInterleaved: return MkvStereoLayout::ColumnInterleaved;
    case PackLayout::Checkerboard: return MkvStereoLayout::Checkerboard;
    case PackLayout::Anaglyph:
    case PackLayout::Left:
    case PackLayout::Right: return MkvStereoLayout::Mono;
  }
  return MkvStereoLayout::Mono;
}

bool mkv_stereo_layout_from_name(const std::string &name, MkvStereoLayout *layout) {
  PackLayout packed;
  if (name == "mono") {
    *layout = MkvStereoLayout::Mono;
  } else if (enum_from_nick(kPackLayoutNames, name, &packed)) {
    *layout = mkv_stereo_layout_of(packed);
  } else {
    return false;
  }
  return true;
}

int mkv_stereo_mode_value(MkvStereoLayout layout, bool right_first) {
  switch (layout) {
    case MkvStereoLayout::Mono:
      return 0;
    case MkvStereoLayout::SideBySide:
      return right_first ? 11 : 1;
    case MkvStereoLayout::TopBottom:
      return right_first ? 2 : 3;
    case MkvStereoLayout::Checkerboard:
      return right_first ? 4 : 5;
    case MkvStereoLayout::RowInterleaved:
      return right_first ? 6 : 7;
    case MkvStereoLayout::ColumnInterleaved:
      return right_first ? 8 : 9;
  }
  return 0;
}

bool mkv_stereo_mode_written(MkvStereoLayout layout, bool right_first) {
  // GStreamer's matroskademux (1.22, unchanged on main) takes 9 for side by
  // side right eye first (its GST_MATROSKA_STEREO_MODE_SBS_RL), and
  // h264parse prefers the container's layout to the SEI's.
  return mkv_stereo_mode_value(layout, right_first) != 9;
}

bool mkv_set_stereo_mode(const std::string &path, MkvStereoLayout layout, bool right_first, std::string *error) {
  std::string err;
  auto fail = [&](const std::string &m) {
    if (error) *error = m;
    return false;
  };
  MkvFile f;
  EbmlInfo info;
  if (!f.open(path, &err) || !read_ebml_header(f, &info, &err)) return fail(err);
  if (info.doctype == "webm" && layout != MkvStereoLayout::Mono && layout != MkvStereoLayout::SideBySide &&
      layout != MkvStereoLayout::TopBottom)
    return fail("WebM allows StereoMode only for mono, side-by-side and top-bottom");

  uint64_t tracks_pos = 0, segment_end = 0;
  Header th;
  if (!find_tracks(f, info.end, &tracks_pos, &th, &segment_end, &err)) return fail(err);
  if (th.size == ebml::kUnknownSize || th.size > kMaxTracks || th.size > segment_end - tracks_pos - th.header_len())
    return fail("corrupt or truncated Tracks element");
  Bytes buf;
  if (!f.read(tracks_pos, th.header_len() + th.size, &buf)) return fail("cannot read the Tracks element");
  Element tracks{th, 0};

  Element video;
  uint64_t width = 0, height = 0;
  if (!find_video(buf, tracks, &video, &width, &height, &err)) return fail(err);
  Bytes tail;
  if (mkv_stereo_mode_written(layout, right_first))
    ebml::append_uint_element(&tail, kIdStereoMode, uint64_t(mkv_stereo_mode_value(layout, right_first)));
  ebml::append_uint_element(&tail, kIdDisplayWidth, width);
  ebml::append_uint_element(&tail, kIdDisplayHeight, height);
  ebml::append_uint_element(&tail, kIdDisplayUnit, kDisplayUnitUnknown);
  Bytes patched;
  Fit fit = rebuild_tracks(buf, tracks, video, tail, info.max_size_len, th.size, &patched, &err);
  if (fit == Fit::NoRoom) {
    // A Void right behind Tracks (mkvmerge reserves one there) can be taken
    // in: nothing points into a Void, so still no other offset changes.
    const uint64_t next = tracks_pos + buf.size();
    Header vh;
    if (next < segment_end && f.header_at(next, segment_end, &vh) && vh.id == ebml::kIdVoid &&
        vh.size != ebml::kUnknownSize && vh.size <= segment_end - next - vh.header_len() &&
        vh.header_len() + vh.size <= kMaxTracks - th.size) {
      std::string void_err;
      fit = rebuild_tracks(buf, tracks, video, tail, info.max_size_len, th.size + vh.header_len() + vh.size, &patched,
                           &void_err);
      err = void_err;
    }
  }
  if (fit != Fit::Ok) return fail(err);

  // The DocTypeVersion first: if the Tracks write then failed, the file
  // would still be valid, only claiming a newer version than it uses.
  if (info.doctype == "matroska" && info.version_len > 0 && info.doctype_version < 3) {
    Bytes v(size_t(info.version_len), 0);
    v.back() = 3;
    if (!f.write(info.version_offset, v)) return fail("cannot write DocTypeVersion");
  }
  // One write: every other offset in the file stays valid.
  Bytes check;
  if (!f.write(tracks_pos, patched) || !f.read(tracks_pos, patched.size(), &check) || check != patched)
    return fail("writing the Tracks element failed");
  return true;
}

}  // namespace p3d
