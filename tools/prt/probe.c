/* Probe spheres lit by a file's neighbourhood transfer (prt_transfer_light_at): what an object moved
 * through a baked scene looks like there - in its shadow, in the light it reflects. Drawn by
 * prt render --probe as part of the scene's mesh. */
#include "probe.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RINGS 16
#define SEGMENTS 24
#define ALBEDO 0.8
#define PROBE_PI 3.14159265358979323846

bool cli_parse_probe(const char *arg, float out[4])
{
    int used = 0;
    out[3] = 0;
    int n = sscanf(arg, "%f,%f,%f%n", &out[0], &out[1], &out[2], &used);
    if (n != 3) return false;
    if (arg[used] == ',') {
        int more = 0;
        if (sscanf(arg + used + 1, "%f%n", &out[3], &more) != 1) return false;
        used += 1 + more;
        n = 4;
    }
    if (arg[used] != 0) return false;   /* nothing after the numbers */
    for (int k = 0; k < 4; ++k)
        if (!isfinite(out[k])) return false;
    return n == 3 || out[3] > 0;
}

void cli_probe_mesh_free(cli_probe_mesh *p)
{
    free(p->positions);
    free(p->radiance);
    free(p->normals);
    free(p->indices);
    memset(p, 0, sizeof *p);
}

prt_status cli_probe_arriving(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float p[3], prt_sh_light *out)
{
    return prt_transfer_light_at(ctx, t, l, p, out);
}

float cli_probe_radius(const prt_transfer *t)
{
    float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    prt_transfer_light_at_box(t, lo, hi);
    return 0.03f * fmaxf(hi[0] - lo[0], fmaxf(hi[1] - lo[1], hi[2] - lo[2]));
}

bool cli_probe_spheres(const prt_render_mesh *in, const float (*probes)[4], const prt_sh_light *arriving, int count, float radius, cli_probe_mesh *keep,
                       prt_render_mesh *out)
{
    memset(keep, 0, sizeof *keep);
    const size_t per = (size_t)(RINGS - 1) * SEGMENTS + 2, tris = (size_t)SEGMENTS * 2 * (RINGS - 1);
    const size_t nv = in->vertex_count + per * count, nt = in->triangle_count + tris * count;
    keep->positions = malloc(nv * 3 * sizeof(float));
    keep->radiance = malloc(nv * 3 * sizeof(float));
    keep->normals = malloc(nv * 3 * sizeof(float));
    keep->indices = malloc(nt * 3 * sizeof(uint32_t));
    if (!keep->positions || !keep->radiance || !keep->normals || !keep->indices) { cli_probe_mesh_free(keep); return false; }
    memcpy(keep->positions, in->positions, in->vertex_count * 3 * sizeof(float));
    memcpy(keep->radiance, in->radiance, in->vertex_count * 3 * sizeof(float));
    if (in->normals) memcpy(keep->normals, in->normals, in->vertex_count * 3 * sizeof(float));
    else memset(keep->normals, 0, in->vertex_count * 3 * sizeof(float));
    memcpy(keep->indices, in->indices, in->triangle_count * 3 * sizeof(uint32_t));
    size_t v = in->vertex_count, f = in->triangle_count;
    for (int k = 0; k < count; ++k) {
        const float *pc = probes[k], r = probes[k][3] > 0 ? probes[k][3] : radius;
        const int order = arriving[k].order;
        double zh[PRT_SH_MAX_ORDER];
        prt_sh_clamped_cosine_zh(order, zh);
        const uint32_t base = (uint32_t)v;
        for (size_t i = 0; i < per; ++i, ++v) {
            /* The poles, then rings from the top. */
            double n[3];
            if (i == 0 || i == per - 1) { n[0] = 0; n[1] = i == 0 ? 1 : -1; n[2] = 0; }
            else {
                const size_t ring = (i - 1) / SEGMENTS + 1, seg = (i - 1) % SEGMENTS;
                const double th = PROBE_PI * (double)ring / RINGS, ph = 2 * PROBE_PI * (double)seg / SEGMENTS;
                n[0] = sin(th) * cos(ph); n[1] = cos(th); n[2] = sin(th) * sin(ph);
            }
            double y[PRT_SH_MAX_COEFFS];
            prt_sh_eval(order, n, y);
            for (int ch = 0; ch < 3; ++ch) {
                double E = 0;   /* irradiance: the arriving light convolved with the clamped cosine */
                for (int l2 = 0; l2 < order; ++l2)
                    for (int q = l2 * l2; q < (l2 + 1) * (l2 + 1); ++q) E += sqrt(4 * PROBE_PI / (2 * l2 + 1)) * zh[l2] * arriving[k].coeffs[ch][q] * y[q];
                keep->radiance[v * 3 + ch] = (float)fmax(0.0, ALBEDO / PROBE_PI * E);
                keep->positions[v * 3 + ch] = pc[ch] + r * (float)n[ch];
                keep->normals[v * 3 + ch] = (float)n[ch];
            }
        }
        for (uint32_t s = 0; s < SEGMENTS; ++s) {
            const uint32_t s1 = (s + 1) % SEGMENTS, last = base + (uint32_t)per - 1;
            uint32_t *ix = keep->indices + f * 3;
            /* Caps, then quads between rings; wound outwards. */
            ix[0] = base; ix[1] = base + 1 + s1; ix[2] = base + 1 + s; ix += 3; f++;
            const uint32_t low = base + 1 + (RINGS - 2) * SEGMENTS;
            ix[0] = last; ix[1] = low + s; ix[2] = low + s1; ix += 3; f++;
            for (uint32_t ring = 0; ring + 2 < RINGS; ++ring) {
                const uint32_t a = base + 1 + ring * SEGMENTS, b = a + SEGMENTS;
                ix[0] = a + s; ix[1] = a + s1; ix[2] = b + s1;
                ix[3] = a + s; ix[4] = b + s1; ix[5] = b + s;
                f += 2;
                ix += 6;
            }
        }
    }
    *out = *in;
    out->positions = keep->positions;
    out->radiance = keep->radiance;
    out->normals = in->normals ? keep->normals : NULL;
    out->vertex_count = nv;
    out->indices = keep->indices;
    out->triangle_count = nt;
    return true;
}

bool cli_probe_drawable(const prt_render_mesh *in) { return !in->exit_sh && !in->texel_radiance && !in->kvec_terms && !in->gpu_passes; }

prt_status cli_probe_append(cli *c, const prt_transfer *t, const prt_lighting *l, const float (*probes)[4], int count, const prt_render_mesh *in,
                            cli_probe_mesh *keep, prt_render_mesh *out)
{
    memset(keep, 0, sizeof *keep);
    if (!cli_probe_drawable(in)) {
        cli_error(c, "--probe draws over per-vertex radiance: add --per-vertex, or draw a kind without per-pixel parts");
        c->reported = true;
        return PRT_ERR_INVALID_ARG;
    }
    if (!prt_transfer_light_at_box(t, NULL, NULL)) {
        cli_error(c, "'%s' holds no neighbourhood transfer for --probe: bake it with --neighbourhood N (SH)", prt_transfer_source(t));
        c->reported = true;
        return PRT_ERR_EMPTY;   /* the file lacks it: bad input, not a bad command */
    }
    prt_sh_light arriving[CLI_MAX_PROBES];
    for (int k = 0; k < count; ++k) {
        prt_status st = cli_probe_arriving(c->ctx, t, l, probes[k], &arriving[k]);
        if (st) return st;
    }
    return cli_probe_spheres(in, probes, arriving, count, cli_probe_radius(t), keep, out) ? PRT_OK : PRT_ERR_NO_MEMORY;
}
