/* prt export of SH files (--sh, --glsl FILE): the transfer itself as custom glTF attributes, so
 * that another renderer relights the mesh under any distant lighting, and the GLSL function that
 * dots them with the lighting's SH. */
#include "methods/sh/sh.h"

#define EXPORT_COEFFS 9   /* order 3: what a vertex attribute budget of 7 VEC4s holds for RGB */
#define EXPORT_ORDER 3

/* The SH transfer of `kind` as attributes for prt_mesh_export: channel-major coefficients (order
 * 3 of whatever order the file has: the projection the lighting's order 3 dots) in VEC4 groups,
 * then for one-channel kinds the albedo. */
static prt_status attributes(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, prt_export_result *out, int *channels, int *coeffs)
{
    const prt__sh_state *s = t->state;
    const int ch = prt_transfer_channels(t, kind), n = s->order * s->order, m = n < EXPORT_COEFFS ? n : EXPORT_COEFFS;
    const size_t nv = t->mesh.vertex_count;
    const int sh_groups = (ch * m + 3) / 4, total = sh_groups + (ch == 1);
    float *all = malloc(nv * (size_t)ch * n * sizeof *all), *attr = prt__calloc(nv * (size_t)total * 4, sizeof *attr);
    prt_status st = all && attr ? prt_transfer_reconstruct(t, kind, all) : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (st) { free(all); free(attr); return st; }
    for (size_t v = 0; v < nv; ++v) {
        float *a = attr + v * (size_t)total * 4;
        for (int c = 0; c < ch; ++c)
            for (int i = 0; i < m; ++i) a[c * m + i] = all[(v * ch + c) * n + i];
        if (ch == 1)
            for (int c = 0; c < 3; ++c) a[sh_groups * 4 + c] = t->mesh.albedo[v * 3 + c];
    }
    free(all);
    static const char *const names[8][7] = {{0}, {"_SH0", "_ALBEDO"}, {"_SH0", "_SH1", "_ALBEDO"}, {"_SH0", "_SH1", "_SH2", "_ALBEDO"},
                                            {0}, {0}, {0}, {"_SH0", "_SH1", "_SH2", "_SH3", "_SH4", "_SH5", "_SH6"}};
    out->attributes = attr;
    out->attribute_count = total;
    out->attribute_names = ch == 3 ? names[7] : names[total - 1];
    *channels = ch;
    *coeffs = m;
    return PRT_OK;
}

/* GLSL that evaluates the exported attributes under SH lighting; the lighting the file was
 * exported under is the default. */
static prt_status write_glsl(prt_context *ctx, const char *path, const char *source, const char *kind, int channels, int coeffs, int groups,
                             const prt_sh_light *sh)
{
    enum { SIZE = 16384 };
    char *text = malloc(SIZE);
    if (!text) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    size_t at = 0;
#define PUT(...) (at += (size_t)snprintf(text + at, at < SIZE ? SIZE - at : 0, __VA_ARGS__))
    PUT("// prt transfer from %s, kind %s: %d SH coefficient%s (order %d) per %s.\n", source, kind, coeffs, coeffs == 1 ? "" : "s",
        coeffs == 1 ? 1 : coeffs == 4 ? 2 : 3, channels == 1 ? "vertex (one channel, times _ALBEDO)" : "colour channel");
    PUT("// Exit radiance = sum_i T[i] * L[i] per channel, L the distant lighting's SH coefficients in\n"
        "// prt's real SH basis (index l*(l+1)+m; prt env PROBE --order 3 prints them), world frame.\n"
        "// Attributes as the glTF names them (three.js's GLTFLoader lower-cases custom names: _sh0 ...).\n");
    for (int g = 0; g < groups; ++g) {
        if (channels == 1 && g == groups - 1) PUT("in vec4 _ALBEDO;\n");
        else PUT("in vec4 _SH%d;\n", g);
    }
    PUT("\n// The lighting exported under (COLOR_0 holds its result at this order, before exposure and clamping).\n");
    PUT("const vec3 prtDefaultLight[%d] = vec3[%d](\n", coeffs, coeffs);
    for (int i = 0; i < coeffs; ++i)
        PUT("    vec3(%.9g, %.9g, %.9g)%s\n", sh->coeffs[0][i], sh->coeffs[1][i], sh->coeffs[2][i], i + 1 < coeffs ? "," : "");
    PUT(");\n\nvec3 prtRadiance(vec3 light[%d])\n{\n", coeffs);
    PUT("    float t[%d] = float[%d](", (groups - (channels == 1)) * 4, (groups - (channels == 1)) * 4);
    for (int g = 0; g < groups - (channels == 1); ++g)
        PUT("%s_SH%d.x, _SH%d.y, _SH%d.z, _SH%d.w", g ? ", " : "", g, g, g, g);
    PUT(");\n    vec3 sum = vec3(0.0);\n");
    if (channels == 1) {
        PUT("    for (int i = 0; i < %d; ++i) sum += t[i] * light[i];\n    return sum * _ALBEDO.rgb;\n}\n", coeffs);
    } else {
        PUT("    for (int i = 0; i < %d; ++i) sum += vec3(t[i], t[%d + i], t[%d + i]) * light[i];\n    return sum;\n}\n", coeffs, coeffs, 2 * coeffs);
    }
#undef PUT
    prt_status st = at < SIZE ? prt__atomic_write_text(path, text) : prt__fail(ctx, PRT_ERR_NO_MEMORY, "the shader outgrew its buffer");
    free(text);
    return st ? prt__fail(ctx, st, "%s", prt_last_error()) : PRT_OK;
}

prt_status prt__sh_export(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt_export_result *out)
{
    const char *glsl = prt__opt(d->options, "glsl");
    if (!glsl && !prt__opt_flag(d->options, "sh")) return PRT_OK;
    if (d->mesh != PRT_EXPORT_MESH_GLTF)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--sh adds attributes to a glTF mesh (-o OUT.glb or .gltf)%s",
                         d->mesh == PRT_EXPORT_MESH_OTHER ? ": PLY and OBJ have no custom attributes" : "");
    const prt__sh_state *s = t->state;
    const char *vname = prt_transfer_variant_name(t, d->variant);
    prt_transfer_kind kind = 0;
    if (prt_transfer_kind_parse(vname, &kind) || prt_transfer_kind_is_glossy(kind) || !prt_transfer_channels(t, kind))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--sh exports per-vertex diffuse SH transfer (unshadowed, shadowed, interreflected): "
                         "this file relit as %s has none", vname);
    /* The attributes hold order 3 (what seven VEC4s hold for RGB): the mesh's colours are relit
     * at the same order, so that the shader gives exactly the colours in the file. */
    if (d->controls && d->controls[0] > EXPORT_ORDER)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--sh exports SH order %d: --control order must be 1..%d with it", EXPORT_ORDER, EXPORT_ORDER);
    /* The shader dots one lighting vector for every vertex: lights with a position differ per
     * vertex, so colours relit with them could not agree with it. They are left out of the
     * colours and the shader alike, and the export says so (a scene's lamps should not stop an
     * export of its distant lighting). */
    prt_lighting *distant = NULL;
    const int local = prt__sh_local_count(d->lighting);
    prt_status st = prt_lighting_copy(d->lighting, &distant);
    for (int i = prt_lighting_count(distant) - 1; !st && i >= 0; --i)
        if (prt__sh_light_positioned(prt_lighting_light(distant, i))) st = prt_lighting_remove(distant, i);
    if (st) { prt_lighting_release(distant); return prt__fail(ctx, st, "%s", prt_last_error()); }
    if (local)
        prt__export_report(out, "left out %d point, spot, sphere or IES light%s: --sh exports transfer for distant lighting (environment, directional "
                           "lights), one vector for every vertex, and their light differs per vertex", local, local == 1 ? "" : "s");
    const int controls[2] = {d->controls && d->controls[0] >= 1 ? d->controls[0] : s->order < EXPORT_ORDER ? s->order : EXPORT_ORDER,
                             PRT__SH_WINDOW_NONE};   /* the shader's lighting is prt_lighting_sh's, unwindowed */
    prt_relight_desc rd = {.variant = d->variant, .per_vertex = 1, .controls = controls};
    prt_relit r;
    st = prt_relight(ctx, t, distant, &rd, &r);
    if (st) { prt_lighting_release(distant); return st; }
    out->radiance = r.radiance;   /* taken from r */
    r.radiance = NULL;
    prt_relit_free(&r);
    int channels = 0, coeffs = 0;
    if ((st = attributes(ctx, t, kind, out, &channels, &coeffs))) { prt_lighting_release(distant); return st; }
    prt__export_report(out, "the SH transfer (%s, order %d) as %d glTF attributes", vname, coeffs == 1 ? 1 : coeffs == 4 ? 2 : 3, out->attribute_count);
    if (glsl) {
        prt_sh_light sh;
        st = prt_lighting_sh(distant, EXPORT_ORDER, &sh);
        if (st) { prt_lighting_release(distant); return prt__fail(ctx, st, "%s", prt_last_error()); }
        if ((st = write_glsl(ctx, glsl, d->source ? d->source : t->source, vname, channels, coeffs, out->attribute_count, &sh))) {
            prt_lighting_release(distant);
            return st;
        }
        if (!prt__export_file(out, glsl)) { remove(glsl); prt_lighting_release(distant); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
        prt__export_report(out, "wrote %s (prtRadiance() from the %d attributes)", glsl, out->attribute_count);
    }
    prt_lighting_release(distant);
    return PRT_OK;
}
