#include "stage_settings.h"

#include <cstdio>
#include <cstring>

namespace p3d::convert {

namespace {

// Which stage owns each property the command line can set (the bin proxies
// them all under the same names).
const struct {
  const char *property;
  const char *factory;
} kOwners[] = {
    {"layout", "pseudo3dpack"},        {"glasses", "pseudo3dpack"},   {"anaglyph-method", "pseudo3dpack"},
    {"swap-eyes", "pseudo3dpack"},     {"max-disparity", "pseudo3dwarp"}, {"convergence", "pseudo3dwarp"},
    {"hypothesis", "pseudo3ddepth"},   {"crop-bars", "pseudo3ddepth"},
};

const char *owner_of(const std::string &property) {
  for (const auto &o : kOwners)
    if (property == o.property) return o.factory;
  return nullptr;
}

// A property of a plugin element's class (the plugin stays loaded, so the
// pspec stays valid); null if there is none.
GParamSpec *element_pspec(const char *factory, const char *property) {
  GstElementFactory *f = gst_element_factory_find(factory);
  if (!f) return nullptr;
  GstPluginFeature *loaded = gst_plugin_feature_load(GST_PLUGIN_FEATURE(f));
  gst_object_unref(f);
  if (!loaded) return nullptr;
  auto *klass = static_cast<GObjectClass *>(
      g_type_class_ref(gst_element_factory_get_element_type(GST_ELEMENT_FACTORY(loaded))));
  gst_object_unref(loaded);
  GParamSpec *p = g_object_class_find_property(klass, property);
  g_type_class_unref(klass);
  return p;
}

std::string enum_nicks(GParamSpec *p) {
  auto *ec = static_cast<GEnumClass *>(g_type_class_ref(p->value_type));
  std::string s;
  for (guint i = 0; i < ec->n_values; ++i) s += std::string(i ? ", " : "") + ec->values[i].value_nick;
  g_type_class_unref(ec);
  return s;
}

}  // namespace

bool ensure_plugin(std::string *error) {
  GstRegistry *reg = gst_registry_get();
  GstPlugin *plugin = gst_registry_find_plugin(reg, "pseudo3d");
#ifdef P3D_PLUGIN_BUILD_DIR
  // Run from the build folder without installing: the plugin next door.
  if (!plugin) {
    gst_registry_scan_path(reg, P3D_PLUGIN_BUILD_DIR);
    plugin = gst_registry_find_plugin(reg, "pseudo3d");
  }
#endif
  if (!plugin) {
    *error = "the pseudo3d GStreamer plugin was not found (install it, or set GST_PLUGIN_PATH_1_0 to build/gst)";
    return false;
  }
  gst_object_unref(plugin);
  return true;
}

namespace {

// Checks `value` of option --`option` against property pspec p: enum
// nicks, numeric ranges; one-line *error naming the accepted values.
bool check_value(GParamSpec *p, const std::string &option, const std::string &value, std::string *error) {
  GValue v = G_VALUE_INIT;
  g_value_init(&v, p->value_type);
  const bool number =
      G_IS_PARAM_SPEC_FLOAT(p) || G_IS_PARAM_SPEC_DOUBLE(p) || G_IS_PARAM_SPEC_INT(p) || G_IS_PARAM_SPEC_UINT(p);
  const bool parsed = (!number || is_plain_decimal(value, true)) && gst_value_deserialize(&v, value.c_str());
  // g_param_value_validate() returns TRUE when it had to clamp the value.
  const bool in_range = parsed && !g_param_value_validate(p, &v);
  g_value_unset(&v);
  if (in_range) return true;
  std::string accepted;
  if (G_IS_PARAM_SPEC_ENUM(p)) {
    accepted = enum_nicks(p);
  } else if (G_IS_PARAM_SPEC_FLOAT(p)) {
    auto *f = G_PARAM_SPEC_FLOAT(p);
    char range[64];
    std::snprintf(range, sizeof range, "a number from %g to %g", f->minimum, f->maximum);
    accepted = range;
  }
  *error = "invalid value '" + value + "' for --" + option + (accepted.empty() ? "" : " (" + accepted + ")");
  return false;
}

}  // namespace

bool check_stage_values(const Options &o, std::string *error) {
  for (const auto &kv : o.stage_values) {
    GParamSpec *p = element_pspec("pseudo3dconvert", kv.first.c_str());
    if (!p) {
      *error = "the pseudo3d plugin has no property '" + kv.first + "'";
      return false;
    }
    if (!check_value(p, kv.first, kv.second, error)) return false;
  }
  for (const auto &kv : o.depth_values) {
    GParamSpec *p = element_pspec("pseudo3ddepthmux", kv.first.c_str());
    if (!p) {
      *error = "pseudo3ddepthmux has no property '" + kv.first + "'";
      return false;
    }
    if (!check_value(p, "depth-" + kv.first, kv.second, error)) return false;
  }
  return true;
}

std::string effective_layout(const Options &o) {
  return o.stage_value("layout", is_photo(o.kind) ? "side-by-side" : "side-by-side-half");
}

bool right_view_first(const Options &o) { return o.stage_value("swap-eyes", "false") == "true"; }

void apply_to_bin(const Options &o, GstElement *bin) {
  for (const auto &kv : o.stage_values) gst_util_set_object_arg(G_OBJECT(bin), kv.first.c_str(), kv.second.c_str());
  gst_util_set_object_arg(G_OBJECT(bin), "layout", effective_layout(o).c_str());
}

void apply_to_stages(const Options &o, GstElement *const *stages, int n_stages, const std::string &layout,
                     bool swap_eyes) {
  auto set = [&](const std::string &property, const std::string &value) {
    const char *owner = owner_of(property);
    for (int i = 0; i < n_stages; ++i) {
      GstElementFactory *f = gst_element_get_factory(stages[i]);
      if (owner && f && std::strcmp(GST_OBJECT_NAME(f), owner) == 0)
        gst_util_set_object_arg(G_OBJECT(stages[i]), property.c_str(), value.c_str());
    }
  };
  for (const auto &kv : o.stage_values) set(kv.first, kv.second);
  set("layout", layout);
  set("swap-eyes", swap_eyes ? "true" : "false");
}

}  // namespace p3d::convert
