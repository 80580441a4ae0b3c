// The eye order of an encoded stream's frame-packing SEI (H.264 and H.265
// SEI payload 45, frame_packing_arrangement). x264 always writes
// content_interpretation_type 1 (the first constituent frame is the left
// view), whatever the stream's eye order; pseudo3dsignal rewrites it.
//
// Only the 6-bit content_interpretation_type of messages with
// frame_packing_arrangement_id 0 and the cancel flag clear is touched, in
// place: those two fields put a 1-bit into the payload's first byte, so the
// byte before the rewritten one is never 0x00 and no emulation-prevention
// pattern can appear or disappear. No GStreamer types: plain bytes.
#pragma once

#include <cstddef>
#include <cstdint>

namespace p3d::gst {

enum class NalSyntax { H264, H265 };

// Sets content_interpretation_type to 2 (right view first) or 1 (left view
// first) in every frame-packing SEI message of one NAL unit (header
// included, emulation-prevention bytes as in the stream). Returns how many
// messages it rewrote.
int set_sei_eye_order(uint8_t *nal, size_t size, NalSyntax syntax, bool right_first);

// The same for every NAL unit of an access unit: Annex B start codes
// (length_size 0) or length-prefixed NAL units (avc/hvc1, 1 to 4 bytes).
int set_sei_eye_order_in_buffer(uint8_t *data, size_t size, NalSyntax syntax, int length_size, bool right_first);

}  // namespace p3d::gst
