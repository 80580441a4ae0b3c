// JPEG marker segments and the EXIF block: read the orientation of a photo,
// carry its EXIF over to the 3D picture (orientation reset, since the
// pixels are turned upright before the depth is estimated), and put
// segments (APP1 EXIF, APP2 MPF) into an encoded JPEG.
#pragma once

#include <cstdint>
#include <vector>

namespace p3d::convert {

using Bytes = std::vector<uint8_t>;

struct JpegSegment {
  uint8_t marker;  // 0xE1 = APP1, 0xE2 = APP2...
  Bytes payload;   // without marker and length
};

// The APP1 EXIF payload ("Exif\0\0" + TIFF data) of a JPEG file; empty if
// the file is no JPEG or has none.
Bytes find_exif(const Bytes &jpeg);

// Whether `jpeg` holds a whole picture: its markers and scans, walked from
// SOI, reach the end-of-image marker (EOI). A file cut short (a broken
// download or copy) does not, and jpegdec decodes it without a word,
// leaving the missing rows grey; a damaged marker structure fails too.
bool jpeg_complete(const Bytes &jpeg);

// The EXIF Orientation tag (1-8); 1 when absent or unreadable.
int exif_orientation(const Bytes &exif);

// EXIF for a new upright picture of width x height made from the photo:
// Orientation 1, PixelXDimension/PixelYDimension set, the thumbnail (of the
// 2D photo, stored sideways) unlinked. Empty if `exif` cannot be parsed.
Bytes exif_for_output(const Bytes &exif, int width, int height);

// A minimal EXIF block (Orientation 1 and the pixel size), for pictures
// whose source had none where the format expects one (MPO).
Bytes minimal_exif(int width, int height);

// Big-endian writers for TIFF-style data (EXIF, MPF): a 12-byte IFD entry
// holds tag, type, count and a value (a SHORT left-justified).
void append_u16_be(Bytes *b, uint16_t v);
void append_u32_be(Bytes *b, uint32_t v);
void append_ifd_entry(Bytes *b, uint16_t tag, uint16_t type, uint32_t count, uint32_t value);
constexpr uint16_t kTiffShort = 3, kTiffLong = 4, kTiffUndefined = 7;

// `jpeg` with `segments` right after SOI. A JFIF APP0 is dropped when an
// APP1 EXIF comes in (both want to be first), kept first otherwise; an
// existing EXIF or MPF segment is replaced.
Bytes with_segments(const Bytes &jpeg, const std::vector<JpegSegment> &segments);

}  // namespace p3d::convert
