// EBML (RFC 8794) primitives over byte buffers, for editing Matroska files:
// element headers (ID + size), unsigned integers, minimal size fields, the
// CRC-32 element. Every read is bounds-checked against the length it is
// given; nothing throws. No GStreamer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace p3d::ebml {

// The size field "all value bits set": the element runs to the end of its
// parent (only Segment and Cluster may have it in Matroska).
inline constexpr uint64_t kUnknownSize = ~0ull;

inline constexpr uint32_t kIdEbml = 0x1A45DFA3;
inline constexpr uint32_t kIdDocType = 0x4282;
inline constexpr uint32_t kIdDocTypeVersion = 0x4287;
inline constexpr uint32_t kIdMaxIdLength = 0x42F2;
inline constexpr uint32_t kIdMaxSizeLength = 0x42F3;
inline constexpr uint32_t kIdVoid = 0xEC;
inline constexpr uint32_t kIdCrc32 = 0xBF;

struct Header {
  uint32_t id = 0;    // as written, length marker included (0x1A45DFA3, 0xEC...)
  int id_len = 0;     // 1..4
  int size_len = 0;   // 1..8
  uint64_t size = 0;  // data length, or kUnknownSize
  uint64_t header_len() const { return uint64_t(id_len) + uint64_t(size_len); }
};

// Reads the element header at data[0..len). False when it does not fit in
// len bytes or is not valid EBML (a 0x00 first byte, an ID over 4 bytes).
bool read_header(const uint8_t *data, size_t len, Header *h);
// Big-endian unsigned integer of len bytes (0..8; 0 bytes is the value 0).
bool read_uint(const uint8_t *data, size_t len, uint64_t *value);

// Smallest size field (1..8 bytes) that holds `size`; 0 if none does.
// A field of n bytes holds up to 2^(7n) - 2: all ones means "unknown".
int min_size_length(uint64_t size);
// Appends an element ID (its bytes as written: 0xEC -> EC, 0x53B8 -> 53 B8).
void append_id(std::vector<uint8_t> *out, uint32_t id);
// Appends `size` as a size field of exactly `len` bytes; false (nothing
// appended) if it does not fit in len bytes.
bool append_size(std::vector<uint8_t> *out, uint64_t size, int len);
// Appends a whole unsigned-integer element with the fewest data bytes.
void append_uint_element(std::vector<uint8_t> *out, uint32_t id, uint64_t value);
// Appends a Void element of exactly `total` bytes (header included), its
// size field no longer than max_size_len; false if impossible (total < 2:
// an element needs an ID byte and a size byte).
bool append_void(std::vector<uint8_t> *out, uint64_t total, int max_size_len);

// CRC-32 as the EBML CRC-32 element holds it (IEEE 802.3 polynomial,
// reflected, as zlib's crc32), stored little-endian.
uint32_t crc32(const uint8_t *data, size_t len);

}  // namespace p3d::ebml
