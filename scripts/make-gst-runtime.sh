#!/usr/bin/env bash
# Make a relocatable GStreamer runtime (libraries + plugins + gst tools) out of
# this machine's Debian packages, so that a GPU machine without GStreamer can
# run the project's GPU tests and benchmarks (scripts/gpu-check.sh prepare).
#
#   make-gst-runtime.sh DEST [EXTRA_ELF...]
#
# DEST gets lib/ (shared libraries), lib/gstreamer-1.0/ (plugins), bin/ (gst
# tools) and env.sh. EXTRA_ELF are more binaries or shared objects (for
# example the project's own plugin or test programs) whose library needs are
# added to lib/ too; they are not copied themselves.
#
# On the GPU machine:   source DEST/env.sh
# (sets LD_LIBRARY_PATH, PATH and the GST_* variables; append the project's
#  build folder to GST_PLUGIN_PATH yourself).
set -euo pipefail
dest=${1:?usage: make-gst-runtime.sh DEST [EXTRA_ELF...]}; shift || true
multiarch=/usr/lib/x86_64-linux-gnu
plugdir=$multiarch/gstreamer-1.0
scanner=$multiarch/gstreamer1.0/gstreamer-1.0/gst-plugin-scanner

# Plugins worth having for tests, benchmarks and example pipelines.
plugins=${GST_RUNTIME_PLUGINS:-"coreelements videotestsrc videoconvertscale app
  playback typefindfunctions isomp4 matroska videoparsersbad nvcodec x264 x265
  png jpeg multifile debugutilsbad coretracers imagefreeze videorate pnm
  rawparse videofilter autodetect deinterlace"}

need() { command -v "$1" >/dev/null || { echo "missing $1: apt-get install $2" >&2; exit 1; }; }
need gst-launch-1.0 gstreamer1.0-tools
[ -x "$scanner" ] || { echo "missing $scanner: apt-get install libgstreamer1.0-0" >&2; exit 1; }

rm -rf "$dest"; mkdir -p "$dest/lib/gstreamer-1.0" "$dest/bin"
elves=()
for p in $plugins; do
  f=$plugdir/libgst$p.so
  [ -f "$f" ] || { echo "plugin $p not installed ($f)" >&2; exit 1; }
  cp -L "$f" "$dest/lib/gstreamer-1.0/"; elves+=("$f")
done
for t in gst-launch-1.0 gst-inspect-1.0 gst-discoverer-1.0; do
  if command -v $t >/dev/null; then cp -L "$(command -v $t)" "$dest/bin/"; elves+=("$(command -v $t)"); fi
done
cp -L "$scanner" "$dest/bin/"; elves+=("$scanner")
elves+=("$@")

# Libraries the GPU machine has itself, or must take from its own driver.
skip='^(linux-vdso|ld-linux|libc\.so|libm\.so|libpthread|libdl\.so|librt\.so|libresolv|libstdc\+\+|libgcc_s|libcuda\.so|libnvidia-|libnvcuvid)'
ldd "${elves[@]}" 2>/dev/null | awk '/=> \//{print $1, $3}' | sort -u |
while read -r name path; do
  [[ $name =~ $skip ]] && continue
  cp -Ln "$path" "$dest/lib/$name" 2>/dev/null || true
done

# Debug symbols are not needed there; they double the size.
find "$dest" -type f \( -name '*.so*' -o -path "$dest/bin/*" \) -exec strip --strip-unneeded {} + 2>/dev/null || true

cat > "$dest/env.sh" <<'ENV'
# source this file: GStreamer from this folder, registry in /tmp.
_gstrt=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
export LD_LIBRARY_PATH="$_gstrt/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export PATH="$_gstrt/bin:$PATH"
export GST_PLUGIN_SYSTEM_PATH_1_0="$_gstrt/lib/gstreamer-1.0"
export GST_PLUGIN_SCANNER_1_0="$_gstrt/bin/gst-plugin-scanner"
export GST_REGISTRY_1_0="${TMPDIR:-/tmp}/gst-registry-$(id -u).bin"
unset _gstrt
ENV
echo "$dest: $(du -sh "$dest" | cut -f1), $(ls "$dest/lib" | wc -l) libraries, $(ls "$dest/lib/gstreamer-1.0" | wc -l) plugins"
