#include "jpeg_meta.h"

#include <cstring>

namespace p3d::convert {

namespace {

constexpr uint8_t kSoi = 0xD8, kEoi = 0xD9, kSos = 0xDA, kApp0 = 0xE0, kApp1 = 0xE1, kApp2 = 0xE2;
constexpr char kExifId[] = "Exif\0";  // 6 bytes with the implicit NUL
constexpr size_t kExifIdSize = 6;
constexpr uint16_t kTagOrientation = 0x0112, kTagExifIfd = 0x8769, kTagPixelX = 0xA002, kTagPixelY = 0xA003;

// Marker segments before the scan: {marker, offset of payload, payload size}.
struct Span {
  uint8_t marker;
  size_t at, size;
};

bool scan_segments(const Bytes &j, std::vector<Span> *spans, size_t *scan_start) {
  if (j.size() < 4 || j[0] != 0xFF || j[1] != kSoi) return false;
  size_t i = 2;
  while (i + 4 <= j.size()) {
    if (j[i] != 0xFF) return false;
    while (i < j.size() && j[i] == 0xFF) ++i;  // fill bytes
    if (i + 3 > j.size()) return false;
    const uint8_t marker = j[i];
    const size_t len = (j[i + 1] << 8) | j[i + 2];
    if (len < 2 || i + 1 + len > j.size()) return false;
    if (marker == kSos) {
      *scan_start = i - 1;
      return true;
    }
    spans->push_back({marker, i + 3, len - 2});
    i += 1 + len;
  }
  return false;
}

// Markers that stand alone, without a length: TEM and the restarts RST0-7.
bool is_standalone(uint8_t marker) { return marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7); }

// The offset of the marker that ends the entropy-coded data starting at
// `i` (0xFF followed by neither a stuffed 0x00, a fill 0xFF nor a restart
// marker); j.size() when the data run to the end of the file.
size_t end_of_entropy_data(const Bytes &j, size_t i) {
  for (; i + 1 < j.size(); ++i)
    if (j[i] == 0xFF && j[i + 1] != 0x00 && j[i + 1] != 0xFF && !is_standalone(j[i + 1])) return i;
  return j.size();
}

bool is_exif(const Bytes &j, const Span &s) {
  return s.marker == kApp1 && s.size >= kExifIdSize && std::memcmp(&j[s.at], kExifId, kExifIdSize) == 0;
}

bool is_mpf(const Bytes &j, const Span &s) {
  return s.marker == kApp2 && s.size >= 4 && std::memcmp(&j[s.at], "MPF", 4) == 0;
}

bool is_jfif(const Bytes &j, const Span &s) {
  return s.marker == kApp0 && s.size >= 5 && std::memcmp(&j[s.at], "JFIF", 5) == 0;
}

// TIFF data inside an EXIF block, in its byte order, bounds-checked.
class Tiff {
 public:
  explicit Tiff(Bytes *exif) : b_(exif) {
    ok_ = b_->size() >= kExifIdSize + 8 && ((at(0) == 'I' && at(1) == 'I') || (at(0) == 'M' && at(1) == 'M'));
    little_ = ok_ && at(0) == 'I';
  }
  bool ok() const { return ok_; }
  size_t size() const { return b_->size() - kExifIdSize; }
  bool u16(size_t off, uint16_t *v) const {
    if (off + 2 > size()) return false;
    *v = little_ ? at(off) | at(off + 1) << 8 : at(off) << 8 | at(off + 1);
    return true;
  }
  bool u32(size_t off, uint32_t *v) const {
    uint16_t a, b;
    if (!u16(off, &a) || !u16(off + 2, &b)) return false;
    *v = little_ ? a | static_cast<uint32_t>(b) << 16 : static_cast<uint32_t>(a) << 16 | b;
    return true;
  }
  void put16(size_t off, uint16_t v) {
    set(off, little_ ? v & 0xFF : v >> 8);
    set(off + 1, little_ ? v >> 8 : v & 0xFF);
  }
  void put32(size_t off, uint32_t v) {
    put16(off + (little_ ? 0 : 2), static_cast<uint16_t>(v & 0xFFFF));
    put16(off + (little_ ? 2 : 0), static_cast<uint16_t>(v >> 16));
  }
  // Offset of the 12-byte entry for `tag` in the IFD at `ifd`; 0 if none.
  size_t find(size_t ifd, uint16_t tag) const {
    uint16_t n;
    if (!u16(ifd, &n)) return 0;
    for (uint16_t k = 0; k < n; ++k) {
      const size_t e = ifd + 2 + 12u * k;
      uint16_t t;
      if (!u16(e, &t) || e + 12 > size()) return 0;
      if (t == tag) return e;
    }
    return 0;
  }
  // Writes a SHORT or LONG value of count 1 into an entry.
  void put_number(size_t entry, uint32_t v) {
    uint16_t type;
    if (!u16(entry + 2, &type)) return;
    if (type == kTiffShort && v <= 0xFFFF) put16(entry + 8, static_cast<uint16_t>(v));
    if (type == kTiffLong) put32(entry + 8, v);
  }

 private:
  uint8_t at(size_t off) const { return (*b_)[kExifIdSize + off]; }
  void set(size_t off, unsigned v) { (*b_)[kExifIdSize + off] = static_cast<uint8_t>(v); }
  Bytes *b_;
  bool ok_ = false, little_ = false;
};

}  // namespace

void append_u16_be(Bytes *b, uint16_t v) {
  b->push_back(static_cast<uint8_t>(v >> 8));
  b->push_back(static_cast<uint8_t>(v & 0xFF));
}

void append_u32_be(Bytes *b, uint32_t v) {
  append_u16_be(b, static_cast<uint16_t>(v >> 16));
  append_u16_be(b, static_cast<uint16_t>(v & 0xFFFF));
}

void append_ifd_entry(Bytes *b, uint16_t tag, uint16_t type, uint32_t count, uint32_t value) {
  append_u16_be(b, tag);
  append_u16_be(b, type);
  append_u32_be(b, count);
  if (type == kTiffShort) {
    append_u16_be(b, static_cast<uint16_t>(value));
    append_u16_be(b, 0);
  } else {
    append_u32_be(b, value);
  }
}

bool jpeg_complete(const Bytes &j) {
  if (j.size() < 4 || j[0] != 0xFF || j[1] != kSoi) return false;
  size_t i = 2;
  while (i + 2 <= j.size()) {
    if (j[i] != 0xFF) return false;
    while (i + 2 < j.size() && j[i + 1] == 0xFF) ++i;  // fill bytes
    const uint8_t marker = j[i + 1];
    if (marker == kEoi) return true;
    if (is_standalone(marker)) {
      i += 2;
      continue;
    }
    if (i + 4 > j.size()) return false;
    const size_t len = (j[i + 2] << 8) | j[i + 3];
    if (len < 2 || i + 2 + len > j.size()) return false;
    i += 2 + len;
    if (marker == kSos) i = end_of_entropy_data(j, i);
  }
  return false;
}

Bytes find_exif(const Bytes &jpeg) {
  std::vector<Span> spans;
  size_t scan = 0;
  if (!scan_segments(jpeg, &spans, &scan)) return {};
  for (const Span &s : spans)
    if (is_exif(jpeg, s)) return Bytes(jpeg.begin() + s.at, jpeg.begin() + s.at + s.size);
  return {};
}

int exif_orientation(const Bytes &exif) {
  Bytes copy = exif;
  Tiff t(&copy);
  uint32_t ifd0;
  uint16_t v;
  if (!t.ok() || !t.u32(4, &ifd0)) return 1;
  const size_t e = t.find(ifd0, kTagOrientation);
  if (!e || !t.u16(e + 8, &v) || v < 1 || v > 8) return 1;
  return v;
}

Bytes exif_for_output(const Bytes &exif, int width, int height) {
  Bytes out = exif;
  Tiff t(&out);
  uint32_t ifd0;
  uint16_t n;
  if (!t.ok() || !t.u32(4, &ifd0) || !t.u16(ifd0, &n) || ifd0 + 2 + 12u * n + 4 > t.size()) return {};
  if (const size_t e = t.find(ifd0, kTagOrientation)) t.put16(e + 8, 1);
  uint32_t sub;
  if (const size_t e = t.find(ifd0, kTagExifIfd); e && t.u32(e + 8, &sub)) {
    if (const size_t x = t.find(sub, kTagPixelX)) t.put_number(x, static_cast<uint32_t>(width));
    if (const size_t y = t.find(sub, kTagPixelY)) t.put_number(y, static_cast<uint32_t>(height));
  }
  t.put32(ifd0 + 2 + 12u * n, 0);  // no IFD1: the thumbnail shows the 2D photo, maybe sideways
  return out;
}

Bytes minimal_exif(int width, int height) {
  // "Exif\0\0", big-endian TIFF header, IFD0 {Orientation, ExifIFD}, Exif
  // IFD {PixelXDimension, PixelYDimension}.
  Bytes b = {'E', 'x', 'i', 'f', 0, 0, 'M', 'M', 0, 42};
  append_u32_be(&b, 8);  // IFD0
  append_u16_be(&b, 2);
  append_ifd_entry(&b, kTagOrientation, kTiffShort, 1, 1);
  append_ifd_entry(&b, kTagExifIfd, kTiffLong, 1, 8 + 2 + 2 * 12 + 4);
  append_u32_be(&b, 0);
  append_u16_be(&b, 2);
  append_ifd_entry(&b, kTagPixelX, kTiffLong, 1, static_cast<uint32_t>(width));
  append_ifd_entry(&b, kTagPixelY, kTiffLong, 1, static_cast<uint32_t>(height));
  append_u32_be(&b, 0);
  return b;
}

Bytes with_segments(const Bytes &jpeg, const std::vector<JpegSegment> &segments) {
  std::vector<Span> spans;
  size_t scan = 0;
  if (!scan_segments(jpeg, &spans, &scan)) return jpeg;
  bool new_exif = false;
  for (const JpegSegment &s : segments)
    new_exif |= s.marker == kApp1 && s.payload.size() >= kExifIdSize && std::memcmp(s.payload.data(), kExifId, kExifIdSize) == 0;
  Bytes out = {0xFF, kSoi};
  auto copy_span = [&](const Span &s) { out.insert(out.end(), jpeg.begin() + s.at - 4, jpeg.begin() + s.at + s.size); };
  size_t first = 0;
  if (!spans.empty() && is_jfif(jpeg, spans[0])) {
    if (!new_exif) copy_span(spans[0]);
    first = 1;
  }
  for (const JpegSegment &s : segments) {
    out.push_back(0xFF);
    out.push_back(s.marker);
    append_u16_be(&out, static_cast<uint16_t>(s.payload.size() + 2));
    out.insert(out.end(), s.payload.begin(), s.payload.end());
  }
  for (size_t k = first; k < spans.size(); ++k)
    if (!is_exif(jpeg, spans[k]) && !is_mpf(jpeg, spans[k]) && !(new_exif && is_jfif(jpeg, spans[k])))
      copy_span(spans[k]);
  out.insert(out.end(), jpeg.begin() + scan, jpeg.end());
  return out;
}

}  // namespace p3d::convert
