// The Matroska StereoMode editor (tools/support/mkv_stereo.h) and its EBML
// primitives: where the room comes from, what is kept, and that corrupt,
// truncated or foreign files give an error and stay byte-identical. Plus
// the pseudo3d-mkvstereo command line. The readers' view of the patched
// files is in test_mkv_readback.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <random>

#include "ebml.h"
#include "mkv_files.h"
#include "stereo_readers.h"
#include "mkv_stereo.h"

namespace p3d::test {
namespace {

// --- EBML primitives -------------------------------------------------------

TEST(Ebml, Crc32CheckValue) {
  const char *s = "123456789";  // the standard CRC-32 check input
  EXPECT_EQ(ebml::crc32(reinterpret_cast<const uint8_t *>(s), 9), 0xCBF43926u);
}

TEST(Ebml, ReadHeader) {
  ebml::Header h;
  const uint8_t segment[] = {0x18, 0x53, 0x80, 0x67, 0x01, 0, 0, 0, 0, 0, 0x01, 0x02};
  ASSERT_TRUE(ebml::read_header(segment, sizeof segment, &h));
  EXPECT_EQ(h.id, 0x18538067u);
  EXPECT_EQ(h.id_len, 4);
  EXPECT_EQ(h.size_len, 8);
  EXPECT_EQ(h.size, 0x102u);
  const uint8_t unknown[] = {0x1F, 0x43, 0xB6, 0x75, 0xFF};
  ASSERT_TRUE(ebml::read_header(unknown, sizeof unknown, &h));
  EXPECT_EQ(h.size, ebml::kUnknownSize);
  const uint8_t two_byte_size[] = {0xAE, 0x40, 0x92};
  ASSERT_TRUE(ebml::read_header(two_byte_size, sizeof two_byte_size, &h));
  EXPECT_EQ(h.size, 0x92u);
  EXPECT_EQ(h.size_len, 2);
  for (size_t n = 0; n < sizeof segment; ++n) EXPECT_FALSE(ebml::read_header(segment, n, &h)) << n;  // cut short
  const uint8_t zero_id[] = {0x00, 0x81}, zero_size[] = {0xEC, 0x00}, ones_id[] = {0xFF, 0x81};
  EXPECT_FALSE(ebml::read_header(zero_id, 2, &h));
  EXPECT_FALSE(ebml::read_header(zero_size, 2, &h));
  EXPECT_FALSE(ebml::read_header(ones_id, 2, &h));
}

TEST(Ebml, SizeFields) {
  EXPECT_EQ(ebml::min_size_length(0), 1);
  EXPECT_EQ(ebml::min_size_length(126), 1);
  EXPECT_EQ(ebml::min_size_length(127), 2);  // 0xFF would mean "unknown"
  EXPECT_EQ(ebml::min_size_length((1ull << 56) - 2), 8);
  EXPECT_EQ(ebml::min_size_length((1ull << 56) - 1), 0);
  std::vector<uint8_t> b;
  EXPECT_FALSE(ebml::append_size(&b, 127, 1));
  EXPECT_TRUE(b.empty());
  ASSERT_TRUE(ebml::append_size(&b, 0x92, 8));
  EXPECT_EQ(b, (std::vector<uint8_t>{0x01, 0, 0, 0, 0, 0, 0, 0x92}));
}

TEST(Ebml, VoidOfEveryLength) {
  for (uint64_t total = 0; total < 20000; total += (total < 300 ? 1 : 97)) {
    std::vector<uint8_t> v;
    const bool ok = ebml::append_void(&v, total, 8);
    if (total < 2) {
      EXPECT_FALSE(ok) << total;
      continue;
    }
    ASSERT_TRUE(ok) << total;
    ebml::Header h;
    ASSERT_EQ(v.size(), total);
    ASSERT_TRUE(ebml::read_header(v.data(), v.size(), &h));
    EXPECT_EQ(h.id, ebml::kIdVoid);
    EXPECT_EQ(h.header_len() + h.size, total);
  }
}

// --- synthetic files ---------------------------------------------------------
// Built here byte by byte (not with the code under test), all size fields
// as short as possible unless a length is given.

Bytes id_bytes(uint32_t id) {
  Bytes b;
  for (int shift = 24; shift >= 0; shift -= 8)
    if ((id >> shift) & 0xFF || !b.empty()) b.push_back(uint8_t(id >> shift));
  return b;
}

Bytes el(uint32_t id, const Bytes &data, int size_len = 0) {
  Bytes out = id_bytes(id);
  if (size_len == 0) size_len = data.size() < 127 ? 1 : (data.size() < 16383 ? 2 : 8);
  for (int i = size_len - 1; i >= 0; --i)
    out.push_back(uint8_t(data.size() >> (8 * i)) | (i == size_len - 1 ? uint8_t(0x80 >> (size_len - 1)) : 0));
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

Bytes uint_el(uint32_t id, uint64_t v, int bytes = 0) {
  Bytes d;
  if (!bytes) bytes = v > 0xFFFF ? 4 : (v > 0xFF ? 2 : 1);
  for (int i = bytes - 1; i >= 0; --i) d.push_back(uint8_t(v >> (8 * i)));
  return el(id, d);
}

Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const Bytes &p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

Bytes void_el(size_t total) {  // total >= 2, < 129
  return el(0xEC, Bytes(total - 2, 0));
}

Bytes crc_el(const Bytes &data) {
  const uint32_t c = ebml::crc32(data.data(), data.size());
  return el(0xBF, {uint8_t(c), uint8_t(c >> 8), uint8_t(c >> 16), uint8_t(c >> 24)});
}

struct Synthetic {
  std::string doctype = "matroska";
  uint64_t track_type = 1;
  Bytes extra_video;           // more children of Video
  size_t void_in_tracks = 0;   // total bytes of a Void at the end of Tracks (0: none)
  size_t void_after_tracks = 0;
  bool crc = false;            // CRC-32 first in Tracks and in the TrackEntry
};

Bytes video_el(const Synthetic &s) {
  return el(0xE0, cat({uint_el(0xB0, 320), uint_el(0xBA, 180), s.extra_video}));
}

Bytes synthetic_mkv(const Synthetic &s) {
  const Bytes header = el(0x1A45DFA3, cat({uint_el(0x4286, 1), uint_el(0x42F7, 1), uint_el(0x42F2, 4),
                                          uint_el(0x42F3, 8), el(0x4282, Bytes(s.doctype.begin(), s.doctype.end())),
                                          uint_el(0x4287, 2), uint_el(0x4285, 2)}));
  Bytes entry = cat({uint_el(0xD7, 1), uint_el(0x83, s.track_type), el(0x86, Bytes{'V', '_', 'M', 'S'}), video_el(s)});
  if (s.crc) entry = cat({crc_el(entry), entry});
  Bytes tracks_data = cat({el(0xAE, entry), s.void_in_tracks ? void_el(s.void_in_tracks) : Bytes{}});
  if (s.crc) tracks_data = cat({crc_el(tracks_data), tracks_data});
  const Bytes cluster = el(0x1F43B675, cat({uint_el(0xE7, 0), el(0xA3, Bytes{0x81, 0, 0, 0x80, 1, 2, 3})}));
  const Bytes segment = cat({el(0x1549A966, uint_el(0x2AD7B1, 1000000)), el(0x1654AE6B, tracks_data),
                             s.void_after_tracks ? void_el(s.void_after_tracks) : Bytes{}, cluster});
  return cat({header, el(0x18538067, segment, 8)});
}

// The direct children of data[begin, end) as (id, [data begin, data end)),
// walked with the primitives tested above; fails the test if they do not
// tile the range.
struct Kid {
  uint32_t id;
  size_t data, end;
};
std::vector<Kid> kids_of(const Bytes &b, size_t begin, size_t end) {
  std::vector<Kid> out;
  size_t pos = begin;
  while (pos < end) {
    ebml::Header h;
    if (!ebml::read_header(b.data() + pos, end - pos, &h) || h.size > end - pos - h.header_len()) {
      ADD_FAILURE() << "bad element at " << pos;
      return out;
    }
    out.push_back({h.id, pos + size_t(h.header_len()), pos + size_t(h.header_len() + h.size)});
    pos = out.back().end;
  }
  return out;
}

uint64_t uint_of(const Bytes &b, const Kid &k) {
  uint64_t v = 0;
  for (size_t i = k.data; i < k.end; ++i) v = (v << 8) | b[i];
  return v;
}

// Video children of the first TrackEntry: id -> values (all occurrences).
std::multimap<uint32_t, uint64_t> video_fields(const Bytes &file) {
  std::multimap<uint32_t, uint64_t> out;
  const TopLevel t = tracks_element(file);
  ebml::Header h;
  if (!t.end || !ebml::read_header(file.data() + t.begin, file.size() - t.begin, &h)) return out;
  for (const Kid &entry : kids_of(file, size_t(t.begin + h.header_len()), size_t(t.end)))
    if (entry.id == 0xAE)
      for (const Kid &k : kids_of(file, entry.data, entry.end))
        if (k.id == 0xE0) {
          for (const Kid &v : kids_of(file, k.data, k.end))
            if (v.end - v.data <= 8) out.insert({v.id, uint_of(file, v)});
          return out;
        }
  return out;
}

// One field's value; -1 when absent.
int64_t field(const std::multimap<uint32_t, uint64_t> &fields, uint32_t id) {
  const auto it = fields.find(id);
  return it == fields.end() ? -1 : int64_t(it->second);
}

std::string scratch(const std::string &name) { return mkv_out_dir() + "/" + name; }

// Writes `bytes`, runs the editor, returns its result; *after = the file then.
bool patch_bytes(const std::string &name, const Bytes &bytes, MkvStereoLayout layout, bool right_first, Bytes *after,
                 std::string *error = nullptr) {
  const std::string path = scratch(name);
  EXPECT_TRUE(write_bytes(path, bytes));
  std::string err;
  const bool ok = mkv_set_stereo_mode(path, layout, right_first, &err);
  if (error) *error = err;
  *after = read_bytes(path);
  return ok;
}

// The stereo fields cost 17 bytes here (StereoMode 4, DisplayWidth 5,
// DisplayHeight 4, DisplayUnit 4) and the synthetic masters are already as
// short as they get: a Void of 17 bytes or more in Tracks is needed. 18
// leaves exactly 1 byte, which a Void cannot fill.
TEST(MkvStereo, RoomFromVoidInTracks) {
  for (size_t v : {0, 2, 3, 10, 15, 16, 17, 18, 19, 20, 40}) {
    Synthetic s;
    s.void_in_tracks = v;
    const Bytes before = synthetic_mkv(s);
    const TopLevel t = tracks_element(before);
    Bytes after;
    std::string error;
    const bool ok = patch_bytes("room.mkv", before, MkvStereoLayout::SideBySide, true, &after, &error);
    EXPECT_EQ(ok, v >= 17) << "void " << v << ": " << error;
    if (!ok) {
      EXPECT_EQ(after, before) << "void " << v;
      EXPECT_NE(error.find("no room"), std::string::npos) << error;
      continue;
    }
    ASSERT_EQ(after.size(), before.size());
    EXPECT_EQ(tracks_element(after).end, t.end);
    EXPECT_TRUE(std::equal(after.begin() + std::ptrdiff_t(t.end), after.end(), before.begin() + std::ptrdiff_t(t.end)));
    const auto f = video_fields(after);
    EXPECT_EQ(f.count(0x53B8), 1u);
    EXPECT_EQ(field(f, 0x53B8), 11);
    EXPECT_EQ(field(f, 0x54B0), 320);
    EXPECT_EQ(field(f, 0x54BA), 180);
    EXPECT_EQ(field(f, 0x54B2), 4);
    EXPECT_EQ(field(f, 0xB0), 320);
  }
}

TEST(MkvStereo, RoomFromVoidBehindTracks) {
  for (size_t v : {10, 17, 18, 30}) {
    Synthetic s;
    s.void_after_tracks = v;
    const Bytes before = synthetic_mkv(s);
    const TopLevel t = tracks_element(before);
    Bytes after;
    const bool ok = patch_bytes("room_behind.mkv", before, MkvStereoLayout::TopBottom, false, &after);
    EXPECT_EQ(ok, v >= 17) << v;
    if (!ok) {
      EXPECT_EQ(after, before);
      continue;
    }
    ASSERT_EQ(after.size(), before.size());
    const size_t cluster = size_t(t.end + v);
    EXPECT_EQ(tracks_element(after).end, cluster) << "Tracks takes in the Void";
    EXPECT_TRUE(std::equal(after.begin() + std::ptrdiff_t(cluster), after.end(), before.begin() + std::ptrdiff_t(cluster)));
    EXPECT_EQ(field(video_fields(after), 0x53B8), 3);
  }
}

TEST(MkvStereo, CrcRecomputed) {
  Synthetic s;
  s.void_in_tracks = 40;
  s.crc = true;
  Bytes after;
  ASSERT_TRUE(patch_bytes("crc.mkv", synthetic_mkv(s), MkvStereoLayout::RowInterleaved, false, &after));
  const TopLevel t = tracks_element(after);
  ebml::Header h;
  ASSERT_TRUE(ebml::read_header(after.data() + t.begin, after.size() - t.begin, &h));
  // Checks a master's CRC-32 (its first child) against the rest of its data.
  auto check = [&](size_t data, size_t end, std::vector<Kid> *k) {
    *k = kids_of(after, data, end);
    ASSERT_FALSE(k->empty());
    ASSERT_EQ((*k)[0].id, 0xBFu);
    ASSERT_EQ((*k)[0].end - (*k)[0].data, 4u);
    const uint32_t want = ebml::crc32(after.data() + (*k)[0].end, end - (*k)[0].end);
    uint32_t got = 0;
    for (int i = 3; i >= 0; --i) got = (got << 8) | after[(*k)[0].data + size_t(i)];
    EXPECT_EQ(got, want);
  };
  std::vector<Kid> kids, entry;
  check(size_t(t.begin + h.header_len()), size_t(t.end), &kids);
  ASSERT_GE(kids.size(), 2u);
  ASSERT_EQ(kids[1].id, 0xAEu);
  check(kids[1].data, kids[1].end, &entry);
  EXPECT_EQ(field(video_fields(after), 0x53B8), 7);
}

TEST(MkvStereo, ReplacesExistingFieldsAndKeepsOthers) {
  Synthetic s;
  s.void_in_tracks = 10;
  // StereoMode 9 (GStreamer's side by side right first), a display size
  // from a 2/1 PAR, DisplayUnit 0, and an Interlaced flag to keep.
  s.extra_video = cat({uint_el(0x53B8, 9), uint_el(0x54B0, 640), uint_el(0x54BA, 180), uint_el(0x54B2, 0),
                       uint_el(0x9A, 2)});
  Bytes after;
  ASSERT_TRUE(patch_bytes("replace.mkv", synthetic_mkv(s), MkvStereoLayout::SideBySide, true, &after));
  const auto f = video_fields(after);
  for (uint32_t id : {0x53B8u, 0x54B0u, 0x54BAu, 0x54B2u, 0x9Au}) EXPECT_EQ(f.count(id), 1u) << std::hex << id;
  EXPECT_EQ(field(f, 0x53B8), 11);
  EXPECT_EQ(field(f, 0x54B0), 320);
  EXPECT_EQ(field(f, 0x54B2), 4);
  EXPECT_EQ(field(f, 0x9A), 2);
}

TEST(MkvStereo, ColumnInterleavedLeftFirstWritesNoStereoMode) {
  Synthetic s;
  s.void_in_tracks = 30;
  s.extra_video = uint_el(0x53B8, 1);
  Bytes after;
  ASSERT_TRUE(patch_bytes("col_lr.mkv", synthetic_mkv(s), MkvStereoLayout::ColumnInterleaved, false, &after));
  const auto f = video_fields(after);
  EXPECT_EQ(f.count(0x53B8), 0u);
  EXPECT_EQ(field(f, 0x54B2), 4);
  EXPECT_FALSE(mkv_stereo_mode_written(MkvStereoLayout::ColumnInterleaved, false));
  EXPECT_TRUE(mkv_stereo_mode_written(MkvStereoLayout::ColumnInterleaved, true));
}

// Matroska spec values (RFC 9559 5.1.4.1.28.3), odd = left eye first.
TEST(MkvStereo, SpecValues) {
  const struct {
    MkvStereoLayout l;
    int lr, rl;
  } table[] = {{MkvStereoLayout::Mono, 0, 0},           {MkvStereoLayout::SideBySide, 1, 11},
               {MkvStereoLayout::TopBottom, 3, 2},      {MkvStereoLayout::Checkerboard, 5, 4},
               {MkvStereoLayout::RowInterleaved, 7, 6}, {MkvStereoLayout::ColumnInterleaved, 9, 8}};
  for (const auto &t : table) {
    EXPECT_EQ(mkv_stereo_mode_value(t.l, false), t.lr);
    EXPECT_EQ(mkv_stereo_mode_value(t.l, true), t.rl);
  }
}

TEST(MkvStereo, DocTypeVersionRaisedForMatroskaOnly) {
  for (const char *doctype : {"matroska", "webm"}) {
    Synthetic s;
    s.doctype = doctype;
    s.void_in_tracks = 30;
    const Bytes before = synthetic_mkv(s);
    Bytes after;
    ASSERT_TRUE(patch_bytes("doctype.mkv", before, MkvStereoLayout::SideBySide, false, &after));
    const uint8_t version_id[] = {0x42, 0x87, 0x81};
    const auto at = std::search(after.begin(), after.begin() + 64, std::begin(version_id), std::end(version_id));
    ASSERT_NE(at, after.begin() + 64);
    EXPECT_EQ(at[3], std::strcmp(doctype, "matroska") == 0 ? 3 : 2) << doctype;
  }
}

TEST(MkvStereo, RefusedFilesStayIdentical) {
  std::mt19937 rng(7);
  Bytes noise(4000);
  for (uint8_t &b : noise) b = uint8_t(rng());
  Synthetic webm, audio, foo;
  webm.doctype = "webm";
  webm.void_in_tracks = 40;
  audio.track_type = 2;
  audio.void_in_tracks = 40;
  foo.doctype = "foo";
  Bytes ebml_then_noise = synthetic_mkv(Synthetic{});
  ebml_then_noise.resize(40);  // the EBML header and part of the Segment's header
  ebml_then_noise.insert(ebml_then_noise.end(), noise.begin(), noise.end());
  const struct {
    const char *name;
    Bytes bytes;
    MkvStereoLayout layout;
    const char *error;
  } cases[] = {
      {"empty", {}, MkvStereoLayout::SideBySide, "not a Matroska"},
      {"text", Bytes{'h', 'e', 'l', 'l', 'o', '\n'}, MkvStereoLayout::SideBySide, "not a Matroska"},
      {"noise", noise, MkvStereoLayout::SideBySide, "not a Matroska"},
      {"mp4", cat({Bytes{0, 0, 0, 0x18}, Bytes{'f', 't', 'y', 'p', 'i', 's', 'o', 'm'}, Bytes(12, 0)}),
       MkvStereoLayout::SideBySide, "not a Matroska"},
      {"doctype_foo", synthetic_mkv(foo), MkvStereoLayout::SideBySide, "DocType"},
      {"ebml_then_noise", ebml_then_noise, MkvStereoLayout::SideBySide, ""},
      {"no_video_track", synthetic_mkv(audio), MkvStereoLayout::SideBySide, "no video track"},
      {"webm_row", synthetic_mkv(webm), MkvStereoLayout::RowInterleaved, "WebM"},
  };
  for (const auto &c : cases) {
    Bytes after;
    std::string error;
    EXPECT_FALSE(patch_bytes(std::string("refused_") + c.name + ".mkv", c.bytes, c.layout, false, &after, &error))
        << c.name;
    EXPECT_EQ(after, c.bytes) << c.name;
    EXPECT_NE(error.find(c.error), std::string::npos) << c.name << ": " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
  std::string error;
  EXPECT_FALSE(mkv_set_stereo_mode(scratch("does-not-exist.mkv"), MkvStereoLayout::SideBySide, false, &error));
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;
  Bytes after;
  EXPECT_TRUE(patch_bytes("webm_sbs.mkv", synthetic_mkv(webm), MkvStereoLayout::SideBySide, true, &after));
}

// --- a GStreamer-written file -----------------------------------------------

class MkvStereoReal : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    StereoClip clip;
    clip.mode = "side-by-side";
    clip.flags = 0x4001;
    clip.frames = 2;
    const std::string path = scratch("real_source.mkv");
    const std::string err = make_stereo_mkv(path, clip);
    if (err.empty()) source_ = read_bytes(path);
    error_ = err;
  }
  void SetUp() override {
    ASSERT_EQ(error_, "");
    ASSERT_FALSE(source_.empty());
    tracks_ = tracks_element(source_);
    ASSERT_GT(tracks_.end, 0u);
  }
  static Bytes source_;
  static std::string error_;
  TopLevel tracks_;
};
Bytes MkvStereoReal::source_;
std::string MkvStereoReal::error_;

// Only the Tracks element changes (and DocTypeVersion 2 -> 3); a second
// run writes the same bytes again.
TEST_F(MkvStereoReal, OnlyTracksChangesAndTwiceIsOnce) {
  Bytes once, twice;
  std::string error;
  ASSERT_TRUE(patch_bytes("real_once.mkv", source_, MkvStereoLayout::SideBySide, true, &once, &error)) << error;
  ASSERT_EQ(once.size(), source_.size());
  EXPECT_EQ(tracks_element(once).begin, tracks_.begin);
  EXPECT_EQ(tracks_element(once).end, tracks_.end);
  std::vector<size_t> outside;
  for (size_t i = 0; i < once.size(); ++i)
    if (once[i] != source_[i] && (i < tracks_.begin || i >= tracks_.end)) outside.push_back(i);
  ASSERT_EQ(outside.size(), 1u) << "bytes changed outside Tracks";
  EXPECT_LT(outside[0], 64u);  // DocTypeVersion in the EBML header
  EXPECT_EQ(once[outside[0]], 3);
  ASSERT_TRUE(patch_bytes("real_twice.mkv", once, MkvStereoLayout::SideBySide, true, &twice, &error)) << error;
  EXPECT_EQ(twice, once);
  EXPECT_EQ(video_fields(source_).count(0x53B8), 0u) << "the source already had a StereoMode";
  EXPECT_EQ(field(video_fields(once), 0x53B8), 11);
}

TEST_F(MkvStereoReal, TruncatedFilesAreRefused) {
  for (size_t len = 0; len < source_.size(); len += (len < tracks_.end + 64 ? 1 : 997)) {
    const Bytes cut(source_.begin(), source_.begin() + std::ptrdiff_t(len));
    Bytes after;
    std::string error;
    EXPECT_FALSE(patch_bytes("truncated.mkv", cut, MkvStereoLayout::TopBottom, false, &after, &error)) << len;
    EXPECT_EQ(after, cut) << len;
    EXPECT_FALSE(error.empty()) << len;
  }
}

// Every byte up to the end of Tracks, changed three ways: never a crash;
// refused files stay identical, accepted ones keep their length.
TEST_F(MkvStereoReal, CorruptedHeadersNeverCrash) {
  int refused = 0, accepted = 0;
  for (size_t i = 0; i < tracks_.end; ++i)
    for (int how = 0; how < 3; ++how) {
      Bytes bad = source_;
      bad[i] = how == 0 ? 0x00 : how == 1 ? 0xFF : uint8_t(bad[i] ^ 0x80);
      if (bad[i] == source_[i]) continue;
      Bytes after;
      std::string error;
      if (patch_bytes("corrupt.mkv", bad, MkvStereoLayout::Checkerboard, true, &after, &error)) {
        ++accepted;
        EXPECT_EQ(after.size(), bad.size()) << i;
      } else {
        ++refused;
        EXPECT_EQ(after, bad) << i << ": " << error;
      }
    }
  EXPECT_GT(refused, 0);
  EXPECT_GT(accepted, 0);  // e.g. a changed UID or name still parses
}

// --- the command line ----------------------------------------------------------

TEST(MkvStereoCli, HelpUsageAndErrors) {
  std::string out, err;
  EXPECT_EQ(run_program({P3D_MKVSTEREO, "--help"}, &out, &err), 0);
  EXPECT_NE(out.find("LAYOUT"), std::string::npos);
  EXPECT_NE(out.find("Half or full"), std::string::npos);
  EXPECT_EQ(run_program({P3D_MKVSTEREO}, &out, &err), 2);

  const std::string bogus = scratch("cli_not_mkv.mkv");
  ASSERT_TRUE(write_bytes(bogus, Bytes{'n', 'o', 'p', 'e'}));
  EXPECT_EQ(run_program({P3D_MKVSTEREO, bogus, "diagonal"}, &out, &err), 2);
  EXPECT_NE(err.find(bogus), std::string::npos) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << err;
  EXPECT_EQ(run_program({P3D_MKVSTEREO, bogus, "side-by-side", "--right-first"}, &out, &err), 1);
  EXPECT_NE(err.find(bogus), std::string::npos) << err;
  EXPECT_NE(err.find("not a Matroska"), std::string::npos) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << err;
  EXPECT_EQ(read_bytes(bogus), (Bytes{'n', 'o', 'p', 'e'}));

  Synthetic s;
  s.void_in_tracks = 40;
  const std::string good = scratch("cli_good.mkv");
  ASSERT_TRUE(write_bytes(good, synthetic_mkv(s)));
  EXPECT_EQ(run_program({P3D_MKVSTEREO, good, "top-bottom", "--right-first"}, &out, &err), 0) << err;
  EXPECT_EQ(field(video_fields(read_bytes(good)), 0x53B8), 2);
  EXPECT_EQ(run_program({P3D_MKVSTEREO, good, "mono"}, &out, &err), 0) << err;
  EXPECT_EQ(field(video_fields(read_bytes(good)), 0x53B8), 0);
}

}  // namespace
}  // namespace p3d::test
