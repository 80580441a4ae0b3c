#include "ebml.h"

namespace p3d::ebml {

namespace {

// Length of a variable-size integer from its first byte: the number of
// leading zero bits + 1 (0x80 -> 1, 0x40 -> 2 ... 0x01 -> 8); 0 for 0x00.
int vint_length(uint8_t first) {
  for (int n = 1; n <= 8; ++n)
    if (first & (0x80 >> (n - 1))) return n;
  return 0;
}

}  // namespace

bool read_header(const uint8_t *data, size_t len, Header *h) {
  if (!data || !h || len < 1) return false;
  const int id_len = vint_length(data[0]);
  if (id_len < 1 || id_len > 4 || size_t(id_len) >= len) return false;  // room for at least one size byte
  uint32_t id = 0;
  for (int i = 0; i < id_len; ++i) id = (id << 8) | data[i];
  // RFC 8794 5: the ID's value bits may be neither all zeros nor all ones.
  const uint32_t value_mask = (id_len == 4) ? 0x0FFFFFFFu : ((1u << (7 * id_len)) - 1);
  if ((id & value_mask) == 0 || (id & value_mask) == value_mask) return false;

  const uint8_t *s = data + id_len;
  const int size_len = vint_length(s[0]);
  if (size_len < 1 || size_t(id_len) + size_t(size_len) > len) return false;
  uint64_t size = s[0] & (0xFF >> size_len);  // the first byte without its length marker
  for (int i = 1; i < size_len; ++i) size = (size << 8) | s[i];
  const uint64_t all_ones = (size_len == 8) ? ((1ull << 56) - 1) : ((1ull << (7 * size_len)) - 1);
  h->id = id;
  h->id_len = id_len;
  h->size_len = size_len;
  h->size = (size == all_ones) ? kUnknownSize : size;
  return true;
}

bool read_uint(const uint8_t *data, size_t len, uint64_t *value) {
  if (!value || len > 8 || (len && !data)) return false;
  uint64_t v = 0;
  for (size_t i = 0; i < len; ++i) v = (v << 8) | data[i];
  *value = v;
  return true;
}

int min_size_length(uint64_t size) {
  for (int n = 1; n <= 8; ++n) {
    const uint64_t max = (1ull << (7 * n)) - 2;  // n = 8: 2^56 - 2
    if (size <= max) return n;
  }
  return 0;
}

void append_id(std::vector<uint8_t> *out, uint32_t id) {
  bool started = false;
  for (int shift = 24; shift >= 0; shift -= 8) {
    const uint8_t b = uint8_t(id >> shift);
    if (b || started || shift == 0) {
      out->push_back(b);
      started = true;
    }
  }
}

bool append_size(std::vector<uint8_t> *out, uint64_t size, int len) {
  if (len < 1 || len > 8 || min_size_length(size) == 0 || min_size_length(size) > len) return false;
  for (int i = len - 1; i >= 0; --i) {
    uint8_t b = uint8_t(size >> (8 * i));
    if (i == len - 1) b |= uint8_t(0x80 >> (len - 1));  // length marker in the first byte
    out->push_back(b);
  }
  return true;
}

void append_uint_element(std::vector<uint8_t> *out, uint32_t id, uint64_t value) {
  int bytes = 1;
  while (bytes < 8 && (value >> (8 * bytes))) ++bytes;
  append_id(out, id);
  append_size(out, uint64_t(bytes), 1);
  for (int i = bytes - 1; i >= 0; --i) out->push_back(uint8_t(value >> (8 * i)));
}

bool append_void(std::vector<uint8_t> *out, uint64_t total, int max_size_len) {
  // 1 ID byte + n size bytes + data; pick the shortest size field that
  // can say total - 1 - n.
  for (int n = 1; n <= max_size_len && n <= 8; ++n) {
    if (total < uint64_t(1 + n)) return false;
    const uint64_t data = total - 1 - uint64_t(n);
    if (min_size_length(data) == 0 || min_size_length(data) > n) continue;
    append_id(out, kIdVoid);
    append_size(out, data, n);
    out->insert(out->end(), size_t(data), uint8_t(0));
    return true;
  }
  return false;
}

uint32_t crc32(const uint8_t *data, size_t len) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < len; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

}  // namespace p3d::ebml
