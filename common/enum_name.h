// The name users see for each value of a public parameter enum, with its
// description. Each enum's table sits beside the enum's definition (pack.h,
// warp.h, bilateral.h, depth_estimate.h, depth_grey.h) and is the only list
// of its names: the GStreamer enum types (gst/enums.cpp), every tool's
// options and messages, and the range checks read it. A new value (a
// layout, a fill, an anaglyph method...) is its enumerator, its line in the
// table, its pixel code and its tests.
//
// A table is in enumerator order from 0 (P3D_CHECK_ENUM_NAMES): a value's
// entry is table[value], and the table's size is the count.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace p3d {

template <typename E>
struct EnumName {
  E value;
  const char *nick;         // the property value and the tools' option value
  const char *description;  // gst-inspect's text
};

// Whether the table lists its enum's values in order from 0.
template <typename E, std::size_t N>
constexpr bool in_enumerator_order(const EnumName<E> (&table)[N]) {
  for (std::size_t i = 0; i < N; ++i)
    if (static_cast<std::size_t>(table[i].value) != i) return false;
  return true;
}
#define P3D_CHECK_ENUM_NAMES(table) static_assert(::p3d::in_enumerator_order(table), #table " is out of order")

// Whether `value` is one of the table's enumerators (a value read from a
// file, an option or a cast int).
template <typename E, std::size_t N>
constexpr bool enum_valid(const EnumName<E> (&)[N], E value) {
  return static_cast<int>(value) >= 0 && static_cast<std::size_t>(value) < N;
}

// The value's nick; "?" for a value outside the table.
template <typename E, std::size_t N>
constexpr const char *enum_nick(const EnumName<E> (&table)[N], E value) {
  return enum_valid(table, value) ? table[static_cast<std::size_t>(value)].nick : "?";
}

// The value whose nick is `nick`; false when there is none.
template <typename E, std::size_t N>
bool enum_from_nick(const EnumName<E> (&table)[N], std::string_view nick, E *value) {
  for (const EnumName<E> &e : table)
    if (nick == e.nick) {
      *value = e.value;
      return true;
    }
  return false;
}

// "a, b, c": the nicks for a usage text or an error message.
template <typename E, std::size_t N>
std::string enum_nicks(const EnumName<E> (&table)[N], const char *separator = ", ") {
  std::string s;
  for (const EnumName<E> &e : table) s += (s.empty() ? "" : separator) + std::string(e.nick);
  return s;
}

}  // namespace p3d
