#include "frame_packing_sei.h"

namespace p3d::gst {

namespace {

constexpr unsigned kFramePackingPayload = 45;
constexpr unsigned kH264Sei = 6;
constexpr unsigned kH265SeiPrefix = 39;
constexpr unsigned kH265SeiSuffix = 40;

// Reads the RBSP of a NAL unit (emulation-prevention bytes skipped) while
// remembering where each byte sits in the raw NAL.
class RbspReader {
 public:
  RbspReader(uint8_t *nal, size_t size, size_t start) : nal_(nal), size_(size), pos_(start) {}
  bool next(uint8_t *byte, size_t *raw_pos) {
    if (pos_ < size_ && zeros_ >= 2 && nal_[pos_] == 0x03) {  // emulation prevention
      zeros_ = 0;
      ++pos_;
    }
    if (pos_ >= size_) return false;
    *raw_pos = pos_;
    *byte = nal_[pos_++];
    zeros_ = *byte == 0 ? zeros_ + 1 : 0;
    return true;
  }
  // More RBSP data before the trailing bits (a last byte of 0x80).
  bool more() const { return pos_ + 1 < size_ || (pos_ < size_ && nal_[pos_] != 0x80); }

 private:
  uint8_t *nal_;
  size_t size_, pos_;
  int zeros_ = 0;
};

// An ff-coded SEI number (payload type or size); false at the end of the data.
bool read_sei_number(RbspReader &r, unsigned *value) {
  *value = 0;
  uint8_t b = 0;
  size_t at = 0;
  do {
    if (!r.next(&b, &at)) return false;
    *value += b;
  } while (b == 0xff);
  return true;
}

}  // namespace

int set_sei_eye_order(uint8_t *nal, size_t size, NalSyntax syntax, bool right_first) {
  size_t header = 0;
  if (syntax == NalSyntax::H264) {
    if (size < 2 || (nal[0] & 0x1f) != kH264Sei) return 0;
    header = 1;
  } else {
    const unsigned type = size >= 3 ? (nal[0] >> 1) & 0x3f : 0;
    if (type != kH265SeiPrefix && type != kH265SeiSuffix) return 0;
    header = 2;
  }
  const uint8_t wanted = right_first ? 2 : 1;
  RbspReader r(nal, size, header);
  int rewritten = 0;
  while (r.more()) {
    unsigned type = 0, payload = 0;
    if (!read_sei_number(r, &type) || !read_sei_number(r, &payload)) break;
    uint8_t b0 = 0, b1 = 0;
    size_t at0 = 0, at1 = 0;
    unsigned consumed = 0;
    if (type == kFramePackingPayload && payload >= 2) {
      if (!r.next(&b0, &at0) || !r.next(&b1, &at1)) break;
      consumed = 2;
      // b0: ue(v) id == 0 is the single bit 1, then cancel flag 0.
      if ((b0 & 0xc0) == 0x80 && (b1 & 0x3f) != wanted && (b1 & 0x3f) != 0) {
        nal[at1] = static_cast<uint8_t>((b1 & 0xc0) | wanted);
        ++rewritten;
      }
    }
    for (; consumed < payload; ++consumed)
      if (!r.next(&b0, &at0)) return rewritten;
  }
  return rewritten;
}

int set_sei_eye_order_in_buffer(uint8_t *data, size_t size, NalSyntax syntax, int length_size, bool right_first) {
  int rewritten = 0;
  if (length_size > 0) {
    size_t i = 0;
    while (i + length_size <= size) {
      size_t len = 0;
      for (int k = 0; k < length_size; ++k) len = (len << 8) | data[i + k];
      i += length_size;
      if (len > size - i) break;
      rewritten += set_sei_eye_order(data + i, len, syntax, right_first);
      i += len;
    }
    return rewritten;
  }
  // Annex B: NAL units between 00 00 01 start codes (a 00 00 00 01 start
  // code leaves a trailing zero on the previous unit, which is harmless).
  size_t i = 0;
  auto start_code_at = [&](size_t k) { return k + 2 < size && data[k] == 0 && data[k + 1] == 0 && data[k + 2] == 1; };
  while (i < size && !start_code_at(i)) ++i;
  while (i < size) {
    const size_t begin = i + 3;
    size_t end = begin;
    while (end < size && !start_code_at(end)) ++end;
    rewritten += set_sei_eye_order(data + begin, end - begin, syntax, right_first);
    i = end;
  }
  return rewritten;
}

}  // namespace p3d::gst
