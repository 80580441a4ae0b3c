// One JSON object per line, for the tools' result files (pseudo3d-convert
// --benchmark, pseudo3d-bench, pseudo3d-quality). Non-finite numbers become
// null: JSON has no NaN.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace p3d::tools {

inline std::string json_escape(const std::string &s) {
  std::string o;
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else {
      o += c;
    }
  }
  return o;
}

class JsonLine {
 public:
  JsonLine &str(const std::string &k, const std::string &v) { return raw(k, "\"" + json_escape(v) + "\""); }
  JsonLine &num(const std::string &k, double v) {
    if (!std::isfinite(v)) return raw(k, "null");
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return raw(k, buf);
  }
  JsonLine &integer(const std::string &k, long long v) { return raw(k, std::to_string(v)); }
  JsonLine &raw(const std::string &k, const std::string &v) {
    body_ += (body_.empty() ? "" : ", ") + ("\"" + json_escape(k) + "\": ") + v;
    return *this;
  }
  std::string text() const { return "{" + body_ + "}"; }

 private:
  std::string body_;
};

}  // namespace p3d::tools
