/* Reading and writing the results that commands exchange: per-vertex radiance as JSON or PLY,
 * and images. */
#include "cli.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

/* Temporary name beside the target; renamed over it only when complete. */
static FILE *open_temp(const char *path, char *tmp, size_t n)
{
    snprintf(tmp, n, "%s.tmp.%ld", path, (long)getpid());
    return fopen(tmp, "wb");
}

static prt_status close_temp(FILE *f, const char *tmp, const char *path)
{
    bool ok = !ferror(f);
    ok &= fclose(f) == 0;
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        return PRT_ERR_IO;
    }
    return PRT_OK;
}

prt_status cli_write_text(const char *path, const char *text)
{
    char tmp[1100];
    FILE *f = open_temp(path, tmp, sizeof tmp);
    if (!f) return PRT_ERR_IO;
    fputs(text, f);
    fputc('\n', f);
    return close_temp(f, tmp, path);
}

prt_status cli_write_vertex_json(const char *path, const char *kind, size_t nv, const cli_vertex_field *fields, int nfields)
{
    char tmp[1100];
    FILE *f = open_temp(path, tmp, sizeof tmp);
    if (!f) return PRT_ERR_IO;
    fprintf(f, "{\"kind\": \"%s\", \"vertex_count\": %zu", kind, nv);
    for (int k = 0; k < nfields; ++k) {
        fprintf(f, ",\n \"%s\": [", fields[k].name);
        const float *p = fields[k].rgb;
        for (size_t v = 0; v < nv; ++v) fprintf(f, "%s[%.7g, %.7g, %.7g]", v ? ", " : "", p[v * 3], p[v * 3 + 1], p[v * 3 + 2]);
        fputc(']', f);
    }
    fputs("}\n", f);
    return close_temp(f, tmp, path);
}

prt_status cli_write_vertex_ply(const char *path, const float *p, const float *n, size_t nv, const uint32_t *idx, size_t nt, const float *rgb)
{
    char tmp[1100];
    FILE *f = open_temp(path, tmp, sizeof tmp);
    if (!f) return PRT_ERR_IO;
    fprintf(f, "ply\nformat binary_little_endian 1.0\ncomment prt: linear radiance\nelement vertex %zu\n"
               "property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
               "property float red\nproperty float green\nproperty float blue\nelement face %zu\nproperty list uchar uint vertex_indices\nend_header\n",
            nv, nt);
    for (size_t v = 0; v < nv; ++v) {
        float rec[9] = {p[v * 3], p[v * 3 + 1], p[v * 3 + 2], n[v * 3], n[v * 3 + 1], n[v * 3 + 2], rgb[v * 3], rgb[v * 3 + 1], rgb[v * 3 + 2]};
        fwrite(rec, sizeof rec, 1, f);
    }
    for (size_t i = 0; i < nt; ++i) {
        unsigned char three = 3;
        fwrite(&three, 1, 1, f);
        fwrite(idx + i * 3, sizeof(uint32_t), 3, f);
    }
    return close_temp(f, tmp, path);
}

void cli_result_free(cli_result *r)
{
    prt_image_free(&r->img);
    free(r->radiance); free(r->indirect); free(r->std_error); free(r->std_error_indirect);
    prt_transfer_release(r->transfer);
    memset(r, 0, sizeof *r);
}

static bool has_ext(const char *path, const char *ext)
{
    const char *dot = strrchr(path, '.');
    return dot && !strcasecmp(dot, ext);
}

/* Reads "name": [[r, g, b], ...] of exactly nv entries; NULL when absent. */
static prt_status read_field(const cJSON *root, const char *name, size_t nv, const char *path, float **out)
{
    *out = NULL;
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(root, name);
    if (!a) return PRT_OK;
    if (!cJSON_IsArray(a) || (size_t)cJSON_GetArraySize(a) != nv) {
        fprintf(stderr, "prt: '%s': \"%s\" must hold %zu [r, g, b] entries\n", path, name, nv);
        return PRT_ERR_FORMAT;
    }
    float *p = malloc(nv * 3 * sizeof(float));
    if (!p) return PRT_ERR_NO_MEMORY;
    size_t v = 0;
    const cJSON *e;
    cJSON_ArrayForEach(e, a) {
        for (int c = 0; c < 3; ++c) {
            const cJSON *x = cJSON_GetArrayItem(e, c);
            if (!cJSON_IsNumber(x) || cJSON_GetArraySize(e) != 3) {
                free(p);
                fprintf(stderr, "prt: '%s': \"%s\"[%zu] is not [r, g, b]\n", path, name, v);
                return PRT_ERR_FORMAT;
            }
            p[v * 3 + c] = (float)x->valuedouble;
        }
        v++;
    }
    *out = p;
    return PRT_OK;
}

/* A .prt relit under the lighting and variant asked for. */
static prt_status relight_file(cli *c, const char *path, const cli_light *light, const char *kind, cli_result *out)
{
    prt_status st;
    if ((st = prt_transfer_load(c->ctx, path, &out->transfer))) return st;
    prt_transfer *t = out->transfer;
    int variant = kind ? prt_transfer_find_variant(t, kind) : prt_transfer_default_variant(t, 0);
    if (variant < 0) return PRT_ERR_INVALID_ARG;
    prt_lighting *lighting = NULL;
    if ((st = cli_lighting(c, light, t, NULL, &lighting))) return st;
    prt_relit r;
    st = cli_relight(c, t, lighting, light, variant, true, true, &r);
    prt_lighting_release(lighting);
    if (st) return st;
    out->nv = prt_transfer_vertex_count(t);
    out->radiance = malloc(out->nv * 3 * sizeof(float));
    if (!out->radiance) { prt_relit_free(&r); return PRT_ERR_NO_MEMORY; }
    /* View-dependent vertices are seen from the auto-framed camera that render uses. */
    cli_view view = CLI_VIEW_DEFAULTS;
    prt_camera cam;
    cli_view_camera(c, &view, prt_transfer_positions(t), out->nv, prt_transfer_indices(t), prt_transfer_triangle_count(t), (float)view.width / view.height, &cam);
    st = prt_relit_shade(c->ctx, t, &r, cam.eye, out->radiance);
    out->indirect = r.indirect;   /* the result takes it over */
    r.indirect = NULL;
    prt_relit_free(&r);
    snprintf(out->what, sizeof out->what, "%s (%s)", path, prt_transfer_variant_name(t, variant));
    return st;
}

static prt_status load(cli *c, const char *path, const cli_light *light_in, const char *kind, cli_result *out)
{
    memset(out, 0, sizeof *out);
    snprintf(out->what, sizeof out->what, "%s", path);
    prt_status st;
    if (has_ext(path, ".prt")) {
        st = relight_file(c, path, light_in, kind, out);
        if (st && !c->reported) cli_error(c, "%s", st == PRT_ERR_NO_MEMORY ? "out of memory" : prt_last_error());
        return st;
    }
    if (has_ext(path, ".json")) {
        void *text = NULL;
        FILE *f = fopen(path, "rb");
        if (!f) { fprintf(stderr, "prt %s: cannot open '%s'\n", c->cmd, path); return PRT_ERR_IO; }
        fseek(f, 0, SEEK_END);
        long len = ftell(f);
        rewind(f);
        text = malloc((size_t)len + 1);
        if (!text || fread(text, 1, (size_t)len, f) != (size_t)len) { fclose(f); free(text); return PRT_ERR_IO; }
        fclose(f);
        cJSON *root = cJSON_ParseWithLength(text, (size_t)len);
        free(text);
        const cJSON *n = cJSON_GetObjectItemCaseSensitive(root, "vertex_count");
        if (!root || !cJSON_IsNumber(n) || n->valuedouble < 1 || n->valuedouble > 1e9) {
            cJSON_Delete(root);
            fprintf(stderr, "prt %s: '%s' is not a per-vertex result (needs \"vertex_count\" and \"radiance\")\n", c->cmd, path);
            return PRT_ERR_FORMAT;
        }
        out->nv = (size_t)n->valuedouble;
        st = read_field(root, "radiance", out->nv, path, &out->radiance);
        if (!st) st = read_field(root, "indirect", out->nv, path, &out->indirect);
        if (!st) st = read_field(root, "std_error", out->nv, path, &out->std_error);
        if (!st) st = read_field(root, "std_error_indirect", out->nv, path, &out->std_error_indirect);
        cJSON_Delete(root);
        if (!st && !out->radiance) {
            fprintf(stderr, "prt %s: '%s' has no \"radiance\"\n", c->cmd, path);
            st = PRT_ERR_FORMAT;
        }
        return st;
    }
    out->image = true;
    st = prt_image_load(path, &out->img);
    if (st) cli_error(c, "%s", prt_last_error());
    return st;
}

prt_status cli_result_load(cli *c, const char *path, const cli_light *light, const char *kind, cli_result *out)
{
    /* Every failure is reported once, where it happens. */
    prt_status st = load(c, path, light, kind, out);
    if (st) cli_result_free(out);
    return st;
}

double cli_rel_l2_above_noise(const float *a, const float *b, const float *err, size_t n)
{
    double se = 0, sb = 0, noise = 0;
    for (size_t i = 0; i < n; ++i) {
        const double d = (double)a[i] - b[i];
        se += d * d;
        sb += (double)b[i] * b[i];
        noise += (double)err[i] * err[i];
    }
    return sb > 0 ? sqrt(fmax(0.0, se - noise) / sb) : INFINITY;
}
