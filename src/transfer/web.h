/* prt export --web: the page's framework (transfer/web.c, transfer/web.js) and what a method adds
 * to it (methods/NAME/web.c and web.js): arrays the page decodes, parameters, and the script that
 * relights. The framework draws the mesh, holds the camera and tone mapping and builds the panel;
 * a method's script registers with PRT.method(...) (see transfer/web.js). */
#ifndef PRT_TRANSFER_WEB_H
#define PRT_TRANSFER_WEB_H

#include "prt/method.h"

#include <stdbool.h>
#include <stdint.h>

#include <cjson/cJSON.h>
#include <stddef.h>

typedef struct prt__web prt__web;

/* A little-endian array the page reads as api.array(name): Float32Array or Uint32Array. Names
 * are the method's own; the framework's are positions, normals, indices. False when out of memory. */
bool prt__web_floats(prt__web *w, const char *name, const float *v, size_t count);
bool prt__web_uints(prt__web *w, const char *name, const uint32_t *v, size_t count);
/* The same for 8- and 16-bit integers: type "u8", "i8", "u16" or "i16" (Uint8Array ... Int16Array). */
bool prt__web_small(prt__web *w, const char *name, const char *type, const void *v, size_t count);
/* The method's parameters (api.meta in the page): add fields to it. */
cJSON *prt__web_meta(prt__web *w);
/* The method's script (static text, PRT.method(...)): written as method.js. */
void prt__web_script(prt__web *w, const char *js);
/* True when the lighting's rotation is the yaw, pitch and roll its environment was named with:
 * the page starts there and rotates from it. */
bool prt__web_rotation_named(const prt_lighting *l);
/* PRT_OK, or the one-line refusal of an environment whose rotation the page cannot start at. */
prt_status prt__web_require_named_rotation(prt_context *ctx, const prt_lighting *l);
/* PRT_OK when every light is a point light and there are at most max (0: any number); else a
 * one-line error that starts with what ("the offset page lights with point lights"). */
prt_status prt__web_point_lights_only(prt_context *ctx, const prt_lighting *l, const char *what, int max);
/* The environment's SH as the page rotates and scales it (unrotated, intensity 1; lights left
 * out) at the given order, into sh. */
prt_status prt__web_unit_environment_sh(prt_context *ctx, const prt_lighting *l, int order, prt_sh_light *sh);
/* meta.lights: the lighting's point lights as [{position, intensity}] (api.pointLights's list).
 * False when out of memory. */
bool prt__web_point_lights_meta(cJSON *meta, const prt_lighting *l);
/* A line for the export's report (what the page leaves out, say). */
void prt__web_report(prt__web *w, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
