/* prt_transfer: accessors and bookkeeping; baking, files and relighting live in their layers. */
#include "core/transfer_set.h"

#include <stdio.h>
#include <string.h>
#include <strings.h>

int prt__kind_index(prt_transfer_kind kind)
{
    switch (kind) {
    case PRT_TRANSFER_UNSHADOWED: return 0;
    case PRT_TRANSFER_SHADOWED: return 1;
    case PRT_TRANSFER_INTERREFLECTED: return 2;
    case PRT_TRANSFER_GLOSSY_SHADOWED: return 3;
    case PRT_TRANSFER_GLOSSY_INTERREFLECTED: return 4;
    case PRT_TRANSFER_WAVELET: return -1;   /* not an SH set */
    }
    return -1;
}

prt_transfer_kind prt__kind_from_index(int index) { return (prt_transfer_kind)(1u << index); }

const char *prt_transfer_kind_name(prt_transfer_kind kind)
{
    static const char *names[PRT__KIND_COUNT] = {"unshadowed", "shadowed", "interreflected", "glossy-shadowed",
                                                 "glossy-interreflected"};
    if (kind == PRT_TRANSFER_WAVELET) return "wavelet";
    int i = prt__kind_index(kind);
    return i < 0 ? "unknown" : names[i];
}

prt_status prt_transfer_kind_parse(const char *name, prt_transfer_kind *out)
{
    for (int i = 0; i < PRT__KIND_COUNT; ++i) {
        prt_transfer_kind k = prt__kind_from_index(i);
        const char *full = prt_transfer_kind_name(k);
        if (!strcasecmp(name, full) || (i < 3 && name[0] && !name[1] && name[0] == full[0])) { *out = k; return PRT_OK; }
    }
    if (!strcasecmp(name, "wavelet")) { *out = PRT_TRANSFER_WAVELET; return PRT_OK; }
    return prt__fail(NULL, PRT_ERR_INVALID_ARG,
                     "unknown transfer kind '%s' (use unshadowed, shadowed, interreflected, glossy-shadowed, glossy-interreflected or wavelet)", name);
}

void prt_transfer_release(prt_transfer *t)
{
    if (!t) return;
    prt__mesh_free(&t->mesh);
    for (int i = 0; i < PRT__KIND_COUNT; ++i) {
        free(t->sets[i].coeffs);
        prt__cpca_free(t->sets[i].cpca);
    }
    prt__texel_sets_free(&t->texels);
    prt__wavelet_set_free(t->wavelet);
    free(t);
}

void prt_transfer_get_info(const prt_transfer *t, prt_transfer_info *info)
{
    memset(info, 0, sizeof *info);
    info->vertex_count = t->mesh.vertex_count;
    info->triangle_count = t->mesh.triangle_count;
    info->order = t->order;
    info->samples = t->samples;
    info->bounces = t->bounces;
    info->seed = t->seed;
    info->bake_seconds = t->bake_seconds;
    info->threads = t->threads;
    for (int i = 0; i < PRT__KIND_COUNT; ++i)
        if (t->sets[i].channels) {
            prt_compress_info ci;
            info->kinds |= prt__kind_from_index(i);
            prt_transfer_compress_info(t, prt__kind_from_index(i), &ci);
            info->transfer_bytes += ci.bytes;
        }
    const prt__texel_sets *tx = &t->texels;
    info->texel_width = tx->width;
    info->texel_height = tx->height;
    if (tx->width) {
        size_t ntex = (size_t)tx->width * tx->height;
        info->texel_bytes = ntex * (3 * sizeof(float) + 1);
        for (int k = 0; k < 3; ++k) info->texel_bytes += ntex * (size_t)tx->channels[k] * t->order * t->order * sizeof(float);
        info->transfer_bytes += info->texel_bytes;
    }
    if (t->wavelet) {
        info->kinds |= PRT_TRANSFER_WAVELET;
        info->transfer_bytes += prt__sparse_bytes(&t->wavelet->store);
    }
    snprintf(info->source, sizeof info->source, "%s", t->source);
}

int prt_transfer_channels(const prt_transfer *t, prt_transfer_kind kind)
{
    if (kind == PRT_TRANSFER_WAVELET) return t->wavelet ? 3 : 0;
    int i = prt__kind_index(kind);
    return i < 0 ? 0 : t->sets[i].channels;
}

const float *prt_transfer_coeffs(const prt_transfer *t, prt_transfer_kind kind)
{
    int i = prt__kind_index(kind);
    return i < 0 || !t->sets[i].channels ? NULL : t->sets[i].coeffs;   /* NULL for compressed sets */
}

int prt_transfer_environment(const prt_transfer *t, prt_environment_desc *out)
{
    if (t->has_env) *out = t->env;
    return t->has_env;
}

size_t prt_transfer_vertex_count(const prt_transfer *t) { return t->mesh.vertex_count; }
size_t prt_transfer_triangle_count(const prt_transfer *t) { return t->mesh.triangle_count; }
const float *prt_transfer_positions(const prt_transfer *t) { return t->mesh.positions; }
const float *prt_transfer_normals(const prt_transfer *t) { return t->mesh.normals; }
const float *prt_transfer_albedo(const prt_transfer *t) { return t->mesh.albedo; }
const uint32_t *prt_transfer_indices(const prt_transfer *t) { return t->mesh.indices; }

int prt_transfer_kind_is_glossy(prt_transfer_kind kind) { return kind == PRT_TRANSFER_GLOSSY_SHADOWED || kind == PRT_TRANSFER_GLOSSY_INTERREFLECTED; }

prt_transfer_kind prt_transfer_kind_diffuse_part(prt_transfer_kind glossy)
{
    return glossy == PRT_TRANSFER_GLOSSY_INTERREFLECTED ? PRT_TRANSFER_INTERREFLECTED : PRT_TRANSFER_SHADOWED;
}

size_t prt_transfer_set_floats(const prt_transfer *t, prt_transfer_kind kind)
{
    int i = prt__kind_index(kind);
    return i < 0 ? 0 : prt__set_dim(t, i);
}

int prt_transfer_glossy_mirror(const prt_transfer *t) { return !t->glossy_exit; }
int prt_transfer_brdf_count(const prt_transfer *t) { return t->brdf_count; }
const prt_brdf *prt_transfer_brdf(const prt_transfer *t, int k) { return k >= 1 && k <= t->brdf_count ? &t->brdfs[k - 1] : NULL; }
const uint8_t *prt_transfer_materials(const prt_transfer *t) { return t->mesh.material; }

prt_status prt__mesh_copy(prt__mesh *dst, const prt__mesh *src)
{
    prt_status st = prt__mesh_append(dst, src->positions, src->normals, src->albedo, (float[3]){0, 0, 0}, src->vertex_count,
                                     src->indices, src->triangle_count);
    if (!st && src->material) memcpy(dst->material, src->material, src->vertex_count);
    if (!st && src->uv) memcpy(dst->uv, src->uv, src->vertex_count * 2 * sizeof(float));
    if (!st && src->emission && !prt__mesh_emission(dst)) st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory copying a mesh");
    if (!st && src->emission) memcpy(dst->emission, src->emission, src->vertex_count * 3 * sizeof(float));
    return st;
}

int prt_transfer_texel_size(const prt_transfer *t, int *width, int *height)
{
    if (width) *width = t->texels.width;
    if (height) *height = t->texels.height;
    return t->texels.width > 0;
}

const float *prt_transfer_texel_coeffs(const prt_transfer *t, prt_transfer_kind kind, int *channels)
{
    int i = prt__kind_index(kind);
    if (i < 0 || i > 2 || !t->texels.coeffs[i]) return NULL;
    if (channels) *channels = t->texels.channels[i];
    return t->texels.coeffs[i];
}

const float *prt_transfer_uvs(const prt_transfer *t) { return prt__mesh_has_uv(&t->mesh) ? t->mesh.uv : NULL; }

void prt__texel_sets_free(prt__texel_sets *s)
{
    for (int k = 0; k < 3; ++k) free(s->coeffs[k]);
    free(s->albedo);
    free(s->covered);
    memset(s, 0, sizeof *s);
}

prt_status prt__texel_sets_copy(prt__texel_sets *dst, const prt__texel_sets *src, int order)
{
    memset(dst, 0, sizeof *dst);
    if (!src->width) return PRT_OK;
    const size_t ntex = (size_t)src->width * src->height, nc = (size_t)order * order;
    dst->width = src->width;
    dst->height = src->height;
    dst->albedo = malloc(ntex * 3 * sizeof(float));
    dst->covered = malloc(ntex);
    bool ok = dst->albedo && dst->covered;
    if (ok) { memcpy(dst->albedo, src->albedo, ntex * 3 * sizeof(float)); memcpy(dst->covered, src->covered, ntex); }
    for (int k = 0; k < 3 && ok; ++k) {
        if (!src->coeffs[k]) continue;
        dst->channels[k] = src->channels[k];
        size_t bytes = ntex * (size_t)src->channels[k] * nc * sizeof(float);
        ok = (dst->coeffs[k] = malloc(bytes)) != NULL;
        if (ok) memcpy(dst->coeffs[k], src->coeffs[k], bytes);
    }
    if (!ok) { prt__texel_sets_free(dst); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory copying texel sets"); }
    return PRT_OK;
}

void prt__wavelet_set_free(prt__wavelet_set *w)
{
    if (!w) return;
    free(w->term_count);
    free(w->vec_start);
    free(w->view_maps);
    free(w->vertex_set);
    prt__sparse_free(&w->store);
    for (int k = 0; k < PRT__MAX_BRDFS; ++k) prt_brdf_factors_release(w->factors[k]);
    free(w);
}

bool prt__wavelet_index(prt__wavelet_set *w, size_t vertex_count, size_t *vectors)
{
    size_t at = 0;
    for (size_t v = 0; v < vertex_count; ++v) {
        if (w->term_count[v] < 1 || w->term_count[v] > PRT_BRDF_MAX_TERMS) return false;
        w->vec_start[v] = at;
        at += w->term_count[v];
    }
    w->vec_start[vertex_count] = at;
    *vectors = at;
    return true;
}

int prt_transfer_wavelet_info(const prt_transfer *t, prt_wavelet_info *info)
{
    if (info) memset(info, 0, sizeof *info);
    if (!t || !t->wavelet) return 0;
    const prt__wavelet_set *w = t->wavelet;
    if (info) {
        info->terms = w->terms;
        info->coefficients = w->store.n;
        info->bits = w->store.bits;
        info->supersample = w->supersample;
        info->bounces = w->bounces;
        info->gather_resolution = w->gather_resolution;
        info->brdf_resolution = w->brdf_resolution;
        info->param = w->param;
        info->vectors = w->store.vectors;
        info->bytes = prt__sparse_bytes(&w->store);
        for (int k = 0; k < PRT__MAX_BRDFS; ++k) info->glossy_materials += w->factors[k] != NULL;
    }
    return 1;
}

int prt_transfer_wavelet_vertex_terms(const prt_transfer *t, size_t v)
{
    return t && t->wavelet && v < t->mesh.vertex_count ? t->wavelet->term_count[v] : 0;
}

const prt_brdf_factors *prt_transfer_wavelet_factors(const prt_transfer *t, int k)
{
    return t && t->wavelet && k >= 1 && k <= PRT__MAX_BRDFS ? t->wavelet->factors[k - 1] : NULL;
}

int prt_transfer_wavelet_vector(const prt_transfer *t, size_t v, int k, int *index, float *rgb)
{
    if (!t || !t->wavelet || v >= t->mesh.vertex_count || k < 0 || k >= t->wavelet->term_count[v]) return 0;
    const prt__wavelet_set *w = t->wavelet;
    const size_t vec = w->vec_start[v] + (size_t)k;
    for (int i = 0; i < w->store.n; ++i) prt__sparse_get(&w->store, vec, i, &index[i], rgb + 3 * i);
    return w->store.n;
}

int prt_wavelet_view_maps(const prt_transfer *t, const float **maps, int *sets, int *resolution, int *polar, const uint8_t **vertex_set)
{
    if (!t || !t->wavelet) return 0;
    prt__wavelet_set *w = t->wavelet;
    if (!w->view_maps) {
        /* Gather the factored materials' first `terms` view maps into one array; vertices point
         * at their material's slot. Built once, kept with the (otherwise read-only) set. */
        int slot[PRT__MAX_BRDFS] = {0}, n = 0, res = 0;
        for (int k = 0; k < PRT__MAX_BRDFS; ++k)
            if (w->factors[k]) { slot[k] = ++n; res = w->factors[k]->resolution; }
        if (!n) return 0;
        const size_t cells = (size_t)res * res, per_set = (size_t)w->terms * 3 * cells;
        float *m = prt__calloc((size_t)n * per_set, sizeof(float));
        uint8_t *vs = prt__calloc(t->mesh.vertex_count, 1);
        if (!m || !vs) { free(m); free(vs); return 0; }
        for (int k = 0; k < PRT__MAX_BRDFS; ++k) {
            const prt_brdf_factors *f = w->factors[k];
            if (!f) continue;
            for (int term = 0; term < f->terms && term < w->terms; ++term)
                for (int c = 0; c < 3; ++c)
                    memcpy(m + (size_t)(slot[k] - 1) * per_set + ((size_t)term * 3 + c) * cells, f->view + ((size_t)c * f->computed + term) * cells,
                           cells * sizeof(float));
        }
        for (size_t v = 0; v < t->mesh.vertex_count; ++v) {
            uint8_t mat = t->mesh.material[v];
            vs[v] = mat ? (uint8_t)slot[mat - 1] : 0;
        }
        w->view_maps = m;
        w->vertex_set = vs;
        w->view_sets = n;
    }
    int res = 0;
    for (int k = 0; k < PRT__MAX_BRDFS && !res; ++k)
        if (w->factors[k]) res = w->factors[k]->resolution;
    if (maps) *maps = w->view_maps;
    if (sets) *sets = w->view_sets;
    if (resolution) *resolution = res;
    if (polar) *polar = w->param == PRT_BRDF_PARAM_POLAR;
    if (vertex_set) *vertex_set = w->vertex_set;
    return 1;
}
