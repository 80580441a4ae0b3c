# Sourced by the pipeline scripts: use the plugin from the build folder
# unless pseudo3d is installed system-wide.
_p3d_top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if ! gst-inspect-1.0 pseudo3d >/dev/null 2>&1; then
  export GST_PLUGIN_PATH_1_0="$_p3d_top/build/gst${GST_PLUGIN_PATH_1_0:+:$GST_PLUGIN_PATH_1_0}"
fi
unset _p3d_top
