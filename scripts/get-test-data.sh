#!/usr/bin/env bash
# Puts the real test data into data/: the Middlebury "Aloe" stereo pair with
# ground-truth disparity (aloeL.jpg, aloeR.jpg, aloeGT.png: disparity in
# pixels of the left view, 0 = unknown) and vtest.avi, all from Debian's
# opencv-doc package (installed by setup-debian.sh; downloaded and unpacked
# here if it is not installed).
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
dest=$top/data
files=(aloeL.jpg aloeR.jpg aloeGT.png vtest.avi)
src=/usr/share/doc/opencv-doc/examples/data
mkdir -p "$dest"
if [ ! -f "$src/aloeL.jpg" ]; then
  tmp=$(mktemp -d)
  (cd "$tmp" && apt-get download opencv-doc >/dev/null && dpkg -x opencv-doc_*.deb root)
  src=$tmp/root/usr/share/doc/opencv-doc/examples/data
fi
for f in "${files[@]}"; do
  [ -f "$dest/$f" ] || cp "$src/$f" "$dest/$f"
done
echo "test data in $dest: ${files[*]}"
