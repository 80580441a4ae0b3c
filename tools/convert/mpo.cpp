#include "mpo.h"

#include <cstring>

namespace p3d::convert {

namespace {

constexpr uint16_t kTagMpfVersion = 0xB000, kTagNumberOfImages = 0xB001, kTagMpEntry = 0xB002,
                   kTagIndividualNum = 0xB101, kTagBaseViewpoint = 0xB204;
constexpr size_t kIfdSize3 = 2 + 3 * 12 + 4;  // an IFD of three entries
constexpr size_t kEntrySize = 16;              // one MP entry

// MP data is written big-endian ("MM"), offsets from the MP header's first byte.
void version_entry(Bytes *b) {
  append_u16_be(b, kTagMpfVersion);
  append_u16_be(b, kTiffUndefined);
  append_u32_be(b, 4);
  for (const char c : {'0', '1', '0', '0'}) b->push_back(static_cast<uint8_t>(c));
}
void attribute_ifd(Bytes *b, uint32_t individual_num) {
  append_u16_be(b, 3);
  version_entry(b);
  append_ifd_entry(b, kTagIndividualNum, kTiffLong, 1, individual_num);
  append_ifd_entry(b, kTagBaseViewpoint, kTiffLong, 1, 1);  // the left view is the base viewpoint
  append_u32_be(b, 0);
}
Bytes mpf_header() {
  Bytes b = {'M', 'P', 'F', 0, 'M', 'M', 0, 42};
  append_u32_be(&b, 8);  // first IFD right after the header
  return b;
}

// APP2 of the first image (the sizes and the second offset are known once
// both images are assembled: made twice, same length).
Bytes first_app2(uint32_t size1, uint32_t size2, uint32_t offset2) {
  Bytes b = mpf_header();
  const uint32_t entries_at = 8 + kIfdSize3, attributes_at = entries_at + 2 * kEntrySize;
  append_u16_be(&b, 3);
  version_entry(&b);
  append_ifd_entry(&b, kTagNumberOfImages, kTiffLong, 1, 2);
  append_ifd_entry(&b, kTagMpEntry, kTiffUndefined, 2 * kEntrySize, entries_at);
  append_u32_be(&b, attributes_at);  // next IFD: this image's attributes
  append_u32_be(&b, kMpFlagRepresentative | kMpTypeDisparity);
  append_u32_be(&b, size1);
  append_u32_be(&b, 0);  // the first image's offset is 0 by definition
  append_u32_be(&b, 0);  // no dependent images
  append_u32_be(&b, kMpTypeDisparity);
  append_u32_be(&b, size2);
  append_u32_be(&b, offset2);
  append_u32_be(&b, 0);
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
