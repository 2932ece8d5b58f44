/* Bake and export options as the user gave them, checked against the method's declarations. */
#include "transfer/method.h"

#include <errno.h>

#define MAX_VALUES 64

struct prt_options {
    const prt_method *method;
    bool exporting;   /* checked against the method's export options, not its bake options */
    bool keyframe;    /* a key frame's bake (prt_bake_frames): the join compresses, not the bake */
    int count;
    const prt_option_desc *desc[MAX_VALUES];
    char *value[MAX_VALUES];
};

prt_status prt_options_create(const prt_method *m, prt_options **out)
{
    if (!m || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_options_create: method and out are required");
    *out = prt__calloc(1, sizeof **out);
    if (!*out) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    (*out)->method = m;
    return PRT_OK;
}

prt_status prt_export_options_create(const prt_method *m, prt_options **out)
{
    prt_status st = prt_options_create(m, out);
    if (!st) (*out)->exporting = true;
    return st;
}

bool prt__options_exporting(const prt_options *o) { return o && o->exporting; }

bool prt__options_keyframe(const prt_options *o) { return o && o->keyframe; }

prt_status prt__options_keyframe_copy(const prt_method *m, const prt_options *o, prt_options **out)
{
    prt_status st = prt_options_create(m, out);
    if (st) return st;
    (*out)->keyframe = true;
    for (int i = 0; o && i < o->count; ++i) {
        (*out)->desc[i] = o->desc[i];
        if (o->value[i] && !((*out)->value[i] = strdup(o->value[i]))) {
            prt_options_release(*out);
            *out = NULL;
            return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
        }
        (*out)->count = i + 1;
    }
    return PRT_OK;
}

static const prt_option_desc *declared(const prt_method *m, bool exporting, const char *name)
{
    return exporting ? prt_method_export_option(m, name) : prt_method_option(m, name);
}

void prt_options_release(prt_options *o)
{
    if (!o) return;
    for (int i = 0; i < o->count; ++i) free(o->value[i]);
    free(o);
}

const prt_method *prt_options_method(const prt_options *o) { return o ? o->method : NULL; }

/* Is item one of the '|'-separated choices? */
static bool in_choices(const char *choices, const char *item, size_t len)
{
    for (const char *c = choices; c && *c;) {
        const char *bar = strchr(c, '|');
        size_t n = bar ? (size_t)(bar - c) : strlen(c);
        if (n == len && !strncmp(c, item, len)) return true;
        c = bar ? bar + 1 : NULL;
    }
    return false;
}

/* "a, b or c" from "a|b|c". */
static void readable_choices(const char *choices, char *out, size_t size)
{
    size_t at = 0;
    out[0] = 0;
    for (const char *c = choices; c && *c && at < size;) {
        const char *bar = strchr(c, '|');
        int n = bar ? (int)(bar - c) : (int)strlen(c);
        at += (size_t)snprintf(out + at, size - at, "%s%.*s", at ? (bar ? ", " : " or ") : "", n, c);
        c = bar ? bar + 1 : NULL;
    }
}

static prt_status check(const prt_option_desc *d, const char *v)
{
    char *end;
    errno = 0;
    switch (d->type) {
    case PRT_OPTION_FLAG:
        if (v) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s takes no value", d->name);
        return PRT_OK;
    case PRT_OPTION_INT: {
        long x = v ? strtol(v, &end, 10) : 0;
        if (!v || errno || end == v || *end || x < d->min || x > d->max)
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s must be an integer in %.0f..%.0f", d->name, d->min, d->max);
        return PRT_OK;
    }
    case PRT_OPTION_FLOAT: {
        double x = v ? strtod(v, &end) : 0;
        if (!v || errno || end == v || *end || !isfinite(x) || x < d->min || x > d->max)
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s must be a number in %g..%g", d->name, d->min, d->max);
        return PRT_OK;
    }
    case PRT_OPTION_CHOICE: {
        char list[256];
        readable_choices(d->choices, list, sizeof list);
        if (!v || !in_choices(d->choices, v, strlen(v))) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s must be %s (got '%s')", d->name, list, v ? v : "");
        return PRT_OK;
    }
    case PRT_OPTION_LIST: {
        if (!v || !*v) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s needs a comma list", d->name);
        for (const char *s = v; s;) {
            const char *comma = strchr(s, ',');
            size_t n = comma ? (size_t)(comma - s) : strlen(s);
            if (!in_choices(d->choices, s, n)) {
                char list[256];
                readable_choices(d->choices, list, sizeof list);
                return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s: '%.*s' is not one of %s", d->name, (int)n, s, list);
            }
            s = comma ? comma + 1 : NULL;
        }
        return PRT_OK;
    }
    case PRT_OPTION_TEXT:
        if (!v || !*v) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s needs a value", d->name);
        return PRT_OK;
    }
    return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s: unknown option type", d->name);
}

prt_status prt_options_set(prt_options *o, const char *name, const char *value)
{
    if (!o || !name) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_options_set: options and name are required");
    const prt_option_desc *d = declared(o->method, o->exporting, name);
    if (!d) {
        char owners[256] = "";
        size_t at = 0;
        for (int i = 0; i < prt_method_count(); ++i)
            if (declared(prt_method_at(i), o->exporting, name) && at < sizeof owners)
                at += (size_t)snprintf(owners + at, sizeof owners - at, "%s%s", at ? ", " : "", prt_method_name(prt_method_at(i)));
        const char *what = o->exporting ? "an export option" : "an option";
        if (owners[0])
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "--%s is %s of method %s, not of method %s", name, what, owners, o->method->name);
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "method %s has no %s --%s", o->method->name, o->exporting ? "export option" : "option", name);
    }
    prt_status st = check(d, value);
    if (st) return st;
    char *copy = strdup(value ? value : "");
    if (!copy) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    for (int i = 0; i < o->count; ++i)
        if (o->desc[i] == d) { free(o->value[i]); o->value[i] = copy; return PRT_OK; }
    if (o->count == MAX_VALUES) { free(copy); return prt__fail(NULL, PRT_ERR_INVALID_ARG, "too many options"); }
    o->desc[o->count] = d;
    o->value[o->count++] = copy;
    return PRT_OK;
}

const char *prt_options_get(const prt_options *o, const char *name)
{
    for (int i = 0; o && name && i < o->count; ++i)
        if (!strcmp(o->desc[i]->name, name)) return o->value[i];
    return NULL;
}

const char *prt__opt(const prt_options *o, const char *name) { return prt_options_get(o, name); }

int prt_options_light_map(const prt_options *o)
{
    if (!o || o->exporting) return 0;
    if (o->method->light_map) return 1;
    const char *v = o->method->light_map_option ? prt_options_get(o, o->method->light_map_option) : NULL;
    return v && strtol(v, NULL, 10) != 0;
}

int prt__opt_int(const prt_options *o, const char *name, int fallback)
{
    const char *v = prt_options_get(o, name);
    return v ? (int)strtol(v, NULL, 10) : fallback;
}

float prt__opt_float(const prt_options *o, const char *name, float fallback)
{
    const char *v = prt_options_get(o, name);
    return v ? strtof(v, NULL) : fallback;
}

bool prt__opt_flag(const prt_options *o, const char *name) { return prt_options_get(o, name) != NULL; }

int prt__opt_choice(const prt_options *o, const char *name, int fallback)
{
    const char *v = prt_options_get(o, name);
    const prt_option_desc *d = o ? declared(o->method, o->exporting, name) : NULL;
    if (!v || !d) return fallback;
    int index = 0;
    for (const char *c = d->choices; c && *c; ++index) {
        const char *bar = strchr(c, '|');
        size_t n = bar ? (size_t)(bar - c) : strlen(c);
        if (n == strlen(v) && !strncmp(c, v, n)) return index;
        c = bar ? bar + 1 : NULL;
    }
    return fallback;
}

void prt__options_fingerprint(const prt_options *o, prt__fingerprint *fp)
{
    if (!o) return;
    int order[MAX_VALUES];
    for (int i = 0; i < o->count; ++i) order[i] = i;
    for (int i = 1; i < o->count; ++i)   /* a handful of options: insertion sort */
        for (int k = i; k > 0 && strcmp(o->desc[order[k - 1]]->name, o->desc[order[k]]->name) > 0; --k) {
            int tmp = order[k]; order[k] = order[k - 1]; order[k - 1] = tmp;
        }
    for (int i = 0; i < o->count; ++i) {
        const char *name = o->desc[order[i]]->name, *value = o->value[order[i]];
        prt__fingerprint_add(fp, name, strlen(name) + 1);
        prt__fingerprint_add(fp, value, strlen(value) + 1);
    }
}
