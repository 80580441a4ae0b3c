#include "pspec_clone.h"

namespace p3d::gst {

GParamSpec *clone_pspec(GParamSpec *p) {
  const char *name = g_param_spec_get_name(p), *nick = g_param_spec_get_nick(p), *blurb = g_param_spec_get_blurb(p);
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | (p->flags & (GST_PARAM_MUTABLE_PLAYING | GST_PARAM_MUTABLE_READY)));
  if (G_IS_PARAM_SPEC_ENUM(p)) {
    auto *e = G_PARAM_SPEC_ENUM(p);
    return g_param_spec_enum(name, nick, blurb, p->value_type, e->default_value, flags);
  }
  if (G_IS_PARAM_SPEC_INT(p)) {
    auto *i = G_PARAM_SPEC_INT(p);
    return g_param_spec_int(name, nick, blurb, i->minimum, i->maximum, i->default_value, flags);
  }
  if (G_IS_PARAM_SPEC_FLOAT(p)) {
    auto *f = G_PARAM_SPEC_FLOAT(p);
    return g_param_spec_float(name, nick, blurb, f->minimum, f->maximum, f->default_value, flags);
  }
  if (G_IS_PARAM_SPEC_BOOLEAN(p))
    return g_param_spec_boolean(name, nick, blurb, G_PARAM_SPEC_BOOLEAN(p)->default_value, flags);
  g_return_val_if_reached(nullptr);
}

}  // namespace p3d::gst
