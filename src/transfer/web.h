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
/* A line for the export's report (what the page leaves out, say). */
void prt__web_report(prt__web *w, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
