/* The method table: the one place that lists prt's methods. Adding a method = its own files
 * plus one line here (docs/ARCHITECTURE.md). */
#include "methods/sh/sh.h"
#include "methods/spectral/spectral.h"
#include "methods/lightcloud/lightcloud.h"
#include "methods/offset/offset.h"
#include "methods/wavelet/wavelet.h"
#include "methods/ao/ao.h"

static const prt__method *const table[] = {
    &prt__method_sh,
    &prt__method_wavelet,
    &prt__method_spectral,
    &prt__method_lightcloud,
    &prt__method_offset,
    &prt__method_ao,
};

#define COUNT ((int)(sizeof table / sizeof table[0]))

int prt_method_count(void) { return COUNT; }
const prt_method *prt_method_at(int i) { return i >= 0 && i < COUNT ? table[i] : NULL; }
const prt_method *prt_method_default(void) { return table[0]; }

const prt_method *prt_method_find(const char *name)
{
    for (int i = 0; name && i < COUNT; ++i)
        if (!strcmp(table[i]->name, name)) return table[i];
    return NULL;
}

const char *prt_method_name(const prt_method *m) { return m ? m->name : ""; }
const char *prt_method_title(const prt_method *m) { return m ? m->title : ""; }
const char *prt_method_summary(const prt_method *m) { return m ? m->summary : ""; }
unsigned prt_method_lighting(const prt_method *m) { return m ? m->lighting : 0; }
int prt_method_runtime_albedo(const prt_method *m) { return m && m->runtime_albedo; }
const char *prt_method_baked_albedo_why(const prt_method *m) { return m && !m->runtime_albedo ? m->baked_albedo_why : NULL; }
int prt_method_sharp_environment(const prt_method *m) { return m && m->sharp_environment; }
int prt_method_light_map(const prt_method *m) { return m && m->light_map; }
int prt_method_gpu_passes(const prt_method *m) { return m && m->gpu_passes; }
int prt_method_web(const prt_method *m) { return m && m->web; }
const char *prt_method_light_map_option(const prt_method *m) { return m ? m->light_map_option : NULL; }

int prt_method_options(const prt_method *m, const prt_option_desc **out)
{
    if (out) *out = m ? m->options : NULL;
    return m ? m->option_count : 0;
}

int prt_method_export_options(const prt_method *m, const prt_option_desc **out)
{
    if (out) *out = m ? m->export_options : NULL;
    return m ? m->export_option_count : 0;
}

const prt_option_desc *prt_method_export_option(const prt_method *m, const char *name)
{
    for (int i = 0; m && name && i < m->export_option_count; ++i)
        if (!strcmp(m->export_options[i].name, name)) return &m->export_options[i];
    return NULL;
}

const prt_option_desc *prt_method_option(const prt_method *m, const char *name)
{
    for (int i = 0; m && name && i < m->option_count; ++i)
        if (!strcmp(m->options[i].name, name)) return &m->options[i];
    return NULL;
}

void prt_methods_relighting(unsigned what, char *buf, size_t size)
{
    size_t at = 0;
    if (size) buf[0] = 0;
    for (int i = 0; i < COUNT; ++i)
        if ((table[i]->lighting & what) == what && at < size) at += (size_t)snprintf(buf + at, size - at, "%s%s", at ? ", " : "", table[i]->name);
}

prt_status prt_method_check_lighting(const prt_method *m, unsigned what)
{
    if (!m) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "no method given");
    const unsigned missing = what & ~m->lighting;
    if (!missing) return PRT_OK;
    char names[512];
    prt_lights_names(missing, " and ", names, sizeof names);
    char others[256];
    prt_methods_relighting(missing, others, sizeof others);
    if (others[0])
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "method '%s' cannot relight %s; method%s %s can (bake with --method)", m->name, names,
                         strchr(others, ',') ? "s" : "", others);
    return prt__fail(NULL, PRT_ERR_INVALID_ARG,
                     "method '%s' cannot relight %s, and no method of this prt does yet; prt reference path-traces them", m->name, names);
}
