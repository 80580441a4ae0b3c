#include "mpo.h"

#include <cstring>

namespace p3d::convert {

namespace {

constexpr uint16_t kTagMpfVersion = 0xB000, kTagNumberOfImages = 0xB001, kTagMpEntry = 0xB002,
                   kTagIndividualNum = 0xB101, kTagBaseViewpoint = 0xB204;
constexpr uint16_t kTypeLong = 4, kTypeUndefined = 7;
constexpr size_t kIfdSize3 = 2 + 3 * 12 + 4;  // an IFD of three entries
constexpr size_t kEntrySize = 16;              // one MP entry

// Big-endian ("MM") MP data, offsets from the MP header's first byte.
void put16(Bytes *b, uint16_t v) {
  b->push_back(v >> 8);
  b->push_back(v & 0xFF);
}
void put32(Bytes *b, uint32_t v) {
  put16(b, v >> 16);
  put16(b, v & 0xFFFF);
}
void entry(Bytes *b, uint16_t tag, uint16_t type, uint32_t count, uint32_t value) {
  put16(b, tag);
  put16(b, type);
  put32(b, count);
  put32(b, value);
}
void version_entry(Bytes *b) {
  put16(b, kTagMpfVersion);
  put16(b, kTypeUndefined);
  put32(b, 4);
  b->insert(b->end(), {'0', '1', '0', '0'});
}
void attribute_ifd(Bytes *b, uint32_t individual_num) {
  put16(b, 3);
  version_entry(b);
  entry(b, kTagIndividualNum, kTypeLong, 1, individual_num);
  entry(b, kTagBaseViewpoint, kTypeLong, 1, 1);  // the left view is the base viewpoint
  put32(b, 0);
}
Bytes mpf_header() {
  Bytes b = {'M', 'P', 'F', 0, 'M', 'M', 0, 42};
  put32(&b, 8);  // first IFD right after the header
  return b;
}

// APP2 of the first image (the sizes and the second offset are known once
// both images are assembled: made twice, same length).
Bytes first_app2(uint32_t size1, uint32_t size2, uint32_t offset2) {
  Bytes b = mpf_header();
  const uint32_t entries_at = 8 + kIfdSize3, attributes_at = entries_at + 2 * kEntrySize;
  put16(&b, 3);
  version_entry(&b);
  entry(&b, kTagNumberOfImages, kTypeLong, 1, 2);
  entry(&b, kTagMpEntry, kTypeUndefined, 2 * kEntrySize, entries_at);
  put32(&b, attributes_at);  // next IFD: this image's attributes
  put32(&b, kMpFlagRepresentative | kMpTypeDisparity);
  put32(&b, size1);
  put32(&b, 0);  // the first image's offset is 0 by definition
  put32(&b, 0);  // no dependent images
  put32(&b, kMpTypeDisparity);
  put32(&b, size2);
  put32(&b, offset2);
  put32(&b, 0);
  attribute_ifd(&b, 1);
  return b;
}

Bytes second_app2() {
  Bytes b = mpf_header();
  attribute_ifd(&b, 2);
  return b;
}

}  // namespace

Bytes make_mpo(const Bytes &left, const Bytes &right, const Bytes &exif) {
  auto segments = [&exif](Bytes app2) {
    std::vector<JpegSegment> s;
    if (!exif.empty()) s.push_back({0xE1, exif});
    s.push_back({0xE2, std::move(app2)});
    return s;
  };
  const Bytes image2 = with_segments(right, segments(second_app2()));
  Bytes image1 = with_segments(left, segments(first_app2(0, 0, 0)));
  // Offsets count from the MP header (after APP2's marker, length, "MPF\0").
  size_t header_at = 0;
  for (size_t i = 2; i + 8 <= image1.size() && !header_at; ++i)
    if (image1[i] == 0xFF && image1[i + 1] == 0xE2 && std::memcmp(&image1[i + 4], "MPF", 4) == 0) header_at = i + 8;
  const Bytes app2 = first_app2(static_cast<uint32_t>(image1.size()), static_cast<uint32_t>(image2.size()),
                                static_cast<uint32_t>(image1.size() - header_at));
  std::memcpy(&image1[header_at - 4], app2.data(), app2.size());  // same size: only values change
  image1.insert(image1.end(), image2.begin(), image2.end());
  return image1;
}

}  // namespace p3d::convert
