#include "cli.h"

#include <dirent.h>

#include <cjson/cJSON.h>
#include <errno.h>
#include <sys/stat.h>

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *HELP =
    "usage: prt relight FILE.prt -o OUT.glb|.gltf|.ply|.obj|.json [options]\n"
    "       prt relight FILE.prt --texels -o MAP.exr|.hdr|.pfm|.png [options]\n"
    "Evaluates per-vertex exit radiance of a baked .prt under a lighting and hands the mesh\n"
    "with it to other tools: glTF 2.0 (.glb, .gltf) with the radiance as COLOR_0 (linear, as\n"
    "the format says; three.js, Godot, Unity, Blender read it), PLY and OBJ with sRGB-encoded\n"
    "vertex colours (what MeshLab and Blender show as is; --colors linear for PLY writes float\n"
    "linear red/green/blue instead). Colours are clamped to [0, 1] after --exposure. JSON holds\n"
    "{\"kind\", \"vertex_count\", \"radiance\": [[r,g,b], ...]} unclamped and, where the method\n"
    "separates them, \"indirect\" (the light that bounced at least once) and \"direct\".\n\n"
    "  -o, --output FILE      .glb, .gltf, .ply, .obj or .json; with --texels .exr, .hdr, .pfm or\n"
    "                         .png (required; written atomically)\n"
    "      --colors C         srgb or linear (default: linear for glTF, srgb for PLY and OBJ)\n"
    "      --exposure STOPS   scale radiance by 2^STOPS before clamping colours (default 0)\n"
    "  -k, --kind K           what to relight the file as (prt info lists what it holds: for SH\n"
    "                         files unshadowed | shadowed | interreflected | glossy-shadowed |\n"
    "                         glossy-interreflected); default: the richest view-independent one\n"
    "      --eye X,Y,Z        the viewpoint each vertex's colour is seen from; needed when the\n"
    "                         result depends on the view (glossy surfaces)\n"
    "      --texels           write the per-texel radiance map (top row = v 1) instead\n"
    CLI_LIGHT_OPTIONS_HELP
    "Other:\n"
    "  -j, --threads N        worker threads\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

static const char *HELP_EXPORT =
    "usage: prt export FILE.prt -o OUT.glb|.gltf|.ply|.obj [options]\n"
    "       prt export FILE.prt --maps DIR\n"
    "Hands a baked .prt to other tools as a mesh with its exit radiance under a lighting as\n"
    "vertex colours: glTF 2.0 COLOR_0 (linear, as the format says; three.js, Godot, Unity,\n"
    "Blender read it), or sRGB-encoded colours in PLY and OBJ. With --sh the glTF also carries\n"
    "the SH transfer itself, so that a renderer relights it under any distant lighting: the first\n"
    "9 coefficients (order 3; fewer for lower orders) of each channel as custom attributes _SH0,\n"
    "_SH1, ... (VEC4 float, zero-padded; channel-major: all of red's, then green's, then blue's),\n"
    "and for one-channel kinds the albedo as _ALBEDO; --glsl writes the shader function that dots\n"
    "them with the lighting's SH (the lighting exported under is its default; COLOR_0 is then\n"
    "relit at order 3 too, so both agree). Otherwise the same as prt relight to a mesh.\n\n"
    "  -o, --output FILE      .glb, .gltf, .ply or .obj (required; written atomically)\n"
    "      --colors C         srgb or linear (default: linear for glTF, srgb for PLY and OBJ)\n"
    "      --exposure STOPS   scale radiance by 2^STOPS before clamping colours (default 0)\n"
    "  -k, --kind K           what to relight the file as (prt info lists what it holds);\n"
    "                         default: the richest view-independent one\n"
    "      --eye X,Y,Z        the viewpoint each vertex's colour is seen from (glossy surfaces)\n"
    "      --sh               glTF only, SH files: add the transfer as custom attributes\n"
    "      --glsl FILE        write the GLSL that relights those attributes (implies --sh)\n"
    "      --maps DIR         offset files: each transfer map as an OpenEXR file cropped to its\n"
    "                         non-zero box, and DIR/index.json naming kind, offset and box (with\n"
    "                         or without -o); replaces what an earlier export left in DIR\n"
    CLI_LIGHT_OPTIONS_HELP
    "Other:\n"
    "  -j, --threads N        worker threads\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

/* Removes what an earlier export left in dir (its maps, medium.exr, index.json), so that a file
 * with fewer maps or kinds never leaves stale maps beside its index; other files stay. */
static prt_status clear_offset_maps(cli *c, const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) { cli_error(c, "cannot read '%s': %s", dir, strerror(errno)); return PRT_ERR_IO; }
    prt_status st = PRT_OK;
    for (struct dirent *e; !st && (e = readdir(d));) {
        const char *n = e->d_name;
        /* kind_NNNN.exr, four digits or more (%04d) */
        const char *digits = !strncmp(n, "radiosity_", 10) ? n + 10 : !strncmp(n, "subsurface_", 11) ? n + 11 : NULL;
        size_t nd = 0;
        while (digits && digits[nd] >= '0' && digits[nd] <= '9') nd++;
        const bool map = digits && nd >= 4 && !strcmp(digits + nd, ".exr");
        if (!map && strcmp(n, "medium.exr") && strcmp(n, "surface.exr") && strcmp(n, "index.json")) continue;
        char path[4200];
        snprintf(path, sizeof path, "%s/%s", dir, n);
        if (remove(path) != 0 && errno != ENOENT) { cli_error(c, "cannot remove the earlier export's '%s': %s", path, strerror(errno)); st = PRT_ERR_IO; }
    }
    closedir(d);
    return st;
}

/* The offset transfer maps as OpenEXR files (each cropped to its non-zero box) and an index
 * that names each file's kind, offset and box: the paper's pipeline hands these to its binning
 * and rendering programs. */
static prt_status write_offset_maps(cli *c, const prt_transfer *t, const char *dir)
{
    prt_offset_info info;
    if (!prt_transfer_offset_info(t, &info)) { cli_error(c, "--maps writes the maps of offset transfer files (bake with --method offset)"); return PRT_ERR_INVALID_ARG; }
    if (mkdir(dir, 0777) != 0 && errno != EEXIST) { cli_error(c, "cannot create '%s': %s", dir, strerror(errno)); c->reported = true; return PRT_ERR_IO; }
    if (clear_offset_maps(c, dir)) { c->reported = true; return PRT_ERR_IO; }
    const int W = info.width, H = info.height;
    float *map = malloc((size_t)W * H * 3 * sizeof *map);
    cJSON *index = cJSON_CreateObject(), *kinds = index ? cJSON_AddObjectToObject(index, "kinds") : NULL;
    prt_status st = map && kinds ? PRT_OK : PRT_ERR_NO_MEMORY;
    if (!st) {
        cJSON_AddNumberToObject(index, "width", W);
        cJSON_AddNumberToObject(index, "height", H);
        cJSON_AddStringToObject(index, "layout", "each file holds the box crop = [x0, y0, w, h] of its map (texel rows from v = 0 at the image's bottom). "
                                                 "A pass over a kind's maps: out(t) = sum over its maps of in(s(t + offset)) * map(t), where s(u) = u on the surface (surface.exr "
                                                 "above 0) and otherwise the surface texel that fills u's gutter: rings grow outwards from the "
                                                 "charts, each texel taking the source of its first neighbour (left, right, down, up) in the ring before. subsurface: in = "
                                                 "irradiance / pi, and out replaces albedo * in on the texels of medium.exr above 0; radiosity: in = the "
                                                 "first-order light map; maps holding map_bounces > 1 bounces give them all in one pass (final = first + "
                                                 "out), maps of 1 are a pass per bounce over what the last one gave (final = first + every pass)");
        cJSON_AddNumberToObject(index, "map_bounces", info.map_bounces);
    }
    static const char *const names[2] = {"radiosity", "subsurface"};
    size_t files = 0;
    for (int kind = 0; kind < 2 && !st; ++kind) {
        if (!info.has[kind]) continue;
        cJSON *list = cJSON_AddArrayToObject(kinds, names[kind]);
        for (int k = 0; k < info.count && !st; ++k) {
            int off[2];
            if ((st = prt_transfer_offset_map(t, (prt_offset_kind)kind, k, off, map))) break;
            int x0 = W, y0 = H, x1 = -1, y1 = -1;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    const float *v = map + ((size_t)y * W + x) * 3;
                    if (v[0] == 0 && v[1] == 0 && v[2] == 0) continue;
                    x0 = x < x0 ? x : x0; x1 = x > x1 ? x : x1; y0 = y < y0 ? y : y0; y1 = y > y1 ? y : y1;
                }
            cJSON *e = cJSON_CreateObject();
            cJSON *o = cJSON_AddArrayToObject(e, "offset");
            cJSON_AddItemToArray(o, cJSON_CreateNumber(off[0]));
            cJSON_AddItemToArray(o, cJSON_CreateNumber(off[1]));
            cJSON_AddItemToArray(list, e);
            if (x1 < 0) { cJSON_AddNullToObject(e, "file"); continue; }   /* carries nothing */
            const int w = x1 - x0 + 1, h = y1 - y0 + 1;
            prt_image img = {w, h, malloc((size_t)w * h * 3 * sizeof(float))};
            if (!img.rgb) { st = PRT_ERR_NO_MEMORY; break; }
            for (int y = 0; y < h; ++y)   /* texel row 0 is v near 0: the image's bottom */
                memcpy(img.rgb + (size_t)(h - 1 - y) * w * 3, map + ((size_t)(y0 + y) * W + x0) * 3, (size_t)w * 3 * sizeof(float));
            char name[64], path[4200];
            snprintf(name, sizeof name, "%s_%04d.exr", names[kind], k);
            snprintf(path, sizeof path, "%s/%s", dir, name);
            st = prt_image_save(path, &img, NULL);
            prt_image_free(&img);
            if (st) { cli_error(c, "cannot write '%s': %s", path, prt_last_error()); break; }
            files++;
            cJSON_AddStringToObject(e, "file", name);
            cJSON *crop = cJSON_AddArrayToObject(e, "crop");
            const int box[4] = {x0, y0, w, h};
            for (int i = 0; i < 4; ++i) cJSON_AddItemToArray(crop, cJSON_CreateNumber(box[i]));
        }
    }
    if (!st) {   /* which texels are on the surface */
        int32_t *src = malloc((size_t)W * H * sizeof *src);
        prt_image img = {W, H, malloc((size_t)W * H * 3 * sizeof(float))};
        st = src && img.rgb ? prt_transfer_offset_sources(t, src) : PRT_ERR_NO_MEMORY;
        for (int y = 0; !st && y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int ch = 0; ch < 3; ++ch) img.rgb[((size_t)(H - 1 - y) * W + x) * 3 + ch] = src[(size_t)y * W + x] == y * W + x ? 1.0f : 0.0f;
        char path[4200];
        snprintf(path, sizeof path, "%s/surface.exr", dir);
        if (!st && (st = prt_image_save(path, &img, NULL))) cli_error(c, "cannot write '%s': %s", path, prt_last_error());
        if (!st) cJSON_AddStringToObject(index, "surface", "surface.exr");
        free(src);
        prt_image_free(&img);
    }
    if (!st && info.has[PRT_OFFSET_SUBSURFACE]) {   /* which texels the subsurface pass replaces */
        float *med = malloc((size_t)W * H * sizeof *med);
        prt_image img = {W, H, malloc((size_t)W * H * 3 * sizeof(float))};
        st = med && img.rgb ? prt_transfer_offset_medium(t, med) : PRT_ERR_NO_MEMORY;
        for (int y = 0; !st && y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int ch = 0; ch < 3; ++ch) img.rgb[((size_t)(H - 1 - y) * W + x) * 3 + ch] = med[(size_t)y * W + x];
        char path[4200];
        snprintf(path, sizeof path, "%s/medium.exr", dir);
        if (!st && (st = prt_image_save(path, &img, NULL))) cli_error(c, "cannot write '%s': %s", path, prt_last_error());
        if (!st) cJSON_AddStringToObject(index, "medium", "medium.exr");
        free(med);
        prt_image_free(&img);
    }
    char *text = !st ? cJSON_Print(index) : NULL;
    if (!st && !text) st = PRT_ERR_NO_MEMORY;
    if (!st) {
        char path[4200];
        snprintf(path, sizeof path, "%s/index.json", dir);
        if ((st = cli_write_text(path, text))) cli_error(c, "cannot write '%s'", path);
        else if (!c->quiet) fprintf(stderr, "prt export: wrote %zu maps and %s\n", files, path);
    }
    cJSON_free(text);
    cJSON_Delete(index);
    free(map);
    if (st == PRT_ERR_NO_MEMORY) cli_error(c, "out of memory writing the maps");
    if (st && st != PRT_ERR_INVALID_ARG) c->reported = true;   /* every failure above said why in its one line */
    return st;
}

#define SH_EXPORT_COEFFS 9   /* order 3: what a vertex attribute budget of 7 VEC4s holds for RGB */

/* The SH transfer of `kind` as attributes for prt_mesh_export: channel-major coefficients
 * (order 3 of whatever order the file has: the projection the lighting's order 3 dots) in
 * VEC4 groups, then for one-channel kinds the albedo. */
static prt_status sh_attributes(const prt_transfer *t, prt_transfer_kind kind, float **out, int *groups, int *channels, int *coeffs)
{
    prt_transfer_info info;
    prt_transfer_get_info(t, &info);
    const int ch = prt_transfer_channels(t, kind), n = info.order * info.order, m = n < SH_EXPORT_COEFFS ? n : SH_EXPORT_COEFFS;
    const size_t nv = info.vertex_count;
    if (ch != 1 && ch != 3) return PRT_ERR_INVALID_ARG;
    const int sh_groups = (ch * m + 3) / 4, total = sh_groups + (ch == 1);
    float *all = malloc(nv * (size_t)ch * n * sizeof *all), *attr = calloc(nv * (size_t)total * 4, sizeof *attr);
    prt_status st = all && attr ? prt_transfer_reconstruct(t, kind, all) : PRT_ERR_NO_MEMORY;
    if (st) { free(all); free(attr); return st; }
    const float *albedo = prt_transfer_albedo(t);
    for (size_t v = 0; v < nv; ++v) {
        float *a = attr + v * (size_t)total * 4;
        for (int c = 0; c < ch; ++c)
            for (int i = 0; i < m; ++i) a[c * m + i] = all[(v * ch + c) * n + i];
        if (ch == 1)
            for (int c = 0; c < 3; ++c) a[sh_groups * 4 + c] = albedo[v * 3 + c];
    }
    free(all);
    *out = attr;
    *groups = total;
    *channels = ch;
    *coeffs = m;
    return PRT_OK;
}

/* GLSL that evaluates the exported attributes under SH lighting; the lighting the file was
 * exported under is the default. */
static prt_status write_glsl(const char *path, const char *source, const char *kind, int channels, int coeffs, int groups,
                             const prt_sh_light *sh)
{
    char *text = malloc(16384);
    if (!text) return PRT_ERR_NO_MEMORY;
    size_t at = 0;
#define PUT(...) (at += (size_t)snprintf(text + at, at < 16384 ? 16384 - at : 0, __VA_ARGS__))
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
    const prt_status st = at < 16384 ? cli_write_text(path, text) : PRT_ERR_NO_MEMORY;
    free(text);
    return st;
}

static prt_status write_texels(const cli *c, const prt_relit *r, const char *output)
{
    const int w = r->texel_width, h = r->texel_height;
    prt_image img = {w, h, malloc((size_t)w * h * 3 * sizeof(float))};
    if (!img.rgb) return PRT_ERR_NO_MEMORY;
    for (int y = 0; y < h; ++y)   /* texel row 0 is v near 0: the image's bottom */
        memcpy(img.rgb + (size_t)(h - 1 - y) * w * 3, r->texels + (size_t)y * w * 3, (size_t)w * 3 * sizeof(float));
    prt_status st = prt_image_save(output, &img, NULL);
    if (!st && !c->quiet) fprintf(stderr, "prt relight: wrote %s (%d x %d texels)\n", output, w, h);
    prt_image_free(&img);
    return st;
}

static int relight_main(int argc, char **argv, bool exporting)
{
    cli c = {.cmd = exporting ? "export" : "relight"};
    cli_light light = {.intensity = 1.0f};
    const char *output = NULL, *kind = NULL;
    static const struct option opts[] = {{"output", required_argument, 0, 'o'}, {"kind", required_argument, 0, 'k'},
                                         {"eye", required_argument, 0, 'e'}, {"texels", no_argument, 0, 'T'}, CLI_LIGHT_LONG_OPTIONS,
                                         {"colors", required_argument, 0, 'C'}, {"exposure", required_argument, 0, 'E'},
                                         {"sh", no_argument, 0, 'S'}, {"glsl", required_argument, 0, 'G'}, {"maps", required_argument, 0, 'M'},
                                         {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'},
                                         {0, 0, 0, 0}};
    int opt;
    float eye[3] = {0, 0, 0};
    bool have_eye = false, texels = false, sh_attrs = false;
    const char *glsl = NULL, *maps_dir = NULL;
    prt_colour_encoding encoding = PRT_COLOURS_DEFAULT;
    float exposure = 0;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:k:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case 'k': kind = optarg; break;
        case 'T': texels = true; break;
        case 'S': sh_attrs = true; break;
        case 'G': glsl = optarg; sh_attrs = true; break;
        case 'M': maps_dir = optarg; break;
        case 'C':
            if (!strcasecmp(optarg, "srgb")) encoding = PRT_COLOURS_SRGB;
            else if (!strcasecmp(optarg, "linear")) encoding = PRT_COLOURS_LINEAR;
            else return cli_usage(&c, "--colors must be srgb or linear");
            break;
        case 'E': if (!cli_parse_float(optarg, &exposure) || fabsf(exposure) > 64) return cli_usage(&c, "--exposure takes stops in [-64, 64]"); break;
        case 'e': if (!cli_parse_vec3(optarg, false, eye)) return cli_usage(&c, "--eye takes X,Y,Z"); have_eye = true; break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(exporting ? HELP_EXPORT : HELP, stdout); return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    if (maps_dir && !exporting) return cli_usage(&c, "--maps belongs to prt export");
    if (maps_dir && !output) {   /* only the maps */
        int rc = cli_make_context(&c);
        if (rc) return rc;
        prt_transfer *t = NULL;
        prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
        if (!st) st = write_offset_maps(&c, t, maps_dir);
        rc = st == PRT_ERR_INVALID_ARG ? EXIT_USAGE : st ? (c.reported ? EXIT_FAILURE_INPUT : cli_fail(&c, st)) : EXIT_OK;
        prt_transfer_release(t);
        prt_context_release(c.ctx);
        return rc;
    }
    if (!output) return cli_usage(&c, "an output file is required (-o OUT.glb, .gltf, .ply, .obj or .json)");
    const char *ext = strrchr(output, '.');
    bool json = ext && !strcasecmp(ext, ".json");
    const bool ply = ext && !strcasecmp(ext, ".ply"),
               mesh = ext && (ply || !strcasecmp(ext, ".glb") || !strcasecmp(ext, ".gltf") || !strcasecmp(ext, ".obj"));
    if (exporting && (texels || json)) return cli_usage(&c, "prt export writes meshes (.glb .gltf .ply .obj): prt relight writes %s", texels ? "texel maps" : "JSON");
    if (!exporting && sh_attrs) return cli_usage(&c, "--sh and --glsl belong to prt export");
    const bool gltf_out = ext && (!strcasecmp(ext, ".glb") || !strcasecmp(ext, ".gltf"));
    if (sh_attrs && !gltf_out) return cli_usage(&c, "--sh needs glTF output (.glb or .gltf): PLY and OBJ have no custom attributes");
    if (!texels && !json && !mesh) return cli_usage(&c, "output must end in .glb, .gltf, .ply, .obj or .json");
    if (texels && (json || mesh)) return cli_usage(&c, "--texels writes an image: .exr, .hdr, .pfm or .png");
    if (texels && have_eye) return cli_usage(&c, "--eye applies to per-vertex results seen from a viewpoint, not to --texels maps");
    if ((encoding || exposure != 0) && !mesh) return cli_usage(&c, "--colors and --exposure apply to mesh outputs (.glb .gltf .ply .obj)");
    int rc = cli_make_context(&c);
    if (rc) return rc;
    prt_transfer *t = NULL;
    prt_lighting *lighting = NULL;
    prt_relit r;
    memset(&r, 0, sizeof r);
    float *rgb = NULL;
    int variant = -1;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (!st && maps_dir && !prt_transfer_offset_info(t, NULL))   /* before the mesh is written */
        rc = cli_usage(&c, "--maps writes the maps of offset transfer files (bake with --method offset)");
    if (!st && !rc) {
        variant = kind ? prt_transfer_find_variant(t, kind) : prt_transfer_default_variant(t, 0);
        if (variant < 0) rc = cli_usage(&c, "%s", prt_last_error());
    }
    /* What --sh exports: per-vertex diffuse SH transfer of the chosen kind (files of other methods
     * hold none: prt_transfer_channels is 0 for them). */
    prt_transfer_kind sh_kind = 0;
    const bool sh_sets = !st && !rc && !prt_transfer_kind_parse(prt_transfer_variant_name(t, variant), &sh_kind) &&
                         !strstr(prt_transfer_variant_name(t, variant), "glossy") && prt_transfer_channels(t, sh_kind) > 0;
    /* The exported transfer is order 3 (what seven VEC4 attributes hold for RGB): COLOR_0 is relit
     * at the same order, so that the GLSL gives exactly the colours in the file. */
    if (!st && !rc && sh_attrs && sh_sets) {
        int k = 0;
        while (k < light.control_count && strcmp(light.control[k].name, "order")) ++k;
        if (k < light.control_count && light.control[k].value > 3) {
            rc = cli_usage(&c, "--sh exports SH order 3: --control order must be 1..3 with it");
        } else if (k == light.control_count && light.control_count < PRT_MAX_CONTROLS) {
            prt_transfer_info info;
            prt_transfer_get_info(t, &info);
            snprintf(light.control[k].name, sizeof light.control[k].name, "order");
            light.control[k].value = info.order < 3 ? info.order : 3;
            light.control_count++;
        }
    }
    if (!st && !rc) st = cli_lighting(&c, &light, t, NULL, &lighting);
    if (!st && !rc) st = cli_relight(&c, t, lighting, &light, variant, !texels, json && !texels, &r);
    if (!st && !rc) st = cli_check_interrupt(&c);
    if (!st && !rc && texels) {
        if (!r.texels) {
            cli_error(&c, "'%s' has no per-texel %s transfer (bake with --texels N)", argv[optind], prt_transfer_variant_name(t, variant));
            rc = EXIT_FAILURE_INPUT;
        } else {
            st = write_texels(&c, &r, output);
        }
    } else if (!st && !rc) {
        const bool view_dependent = prt_relit_view_dependent(&r);
        if (view_dependent && !have_eye) {
            cli_error(&c, "'%s' relit as %s is view-dependent: give --eye X,Y,Z", argv[optind], prt_transfer_variant_name(t, variant));
            rc = EXIT_USAGE;
        } else if (!view_dependent && have_eye) {
            cli_error(&c, "--eye applies to view-dependent results only ('%s' relit as %s does not depend on the view)", argv[optind],
                      prt_transfer_variant_name(t, variant));
            rc = EXIT_USAGE;
        }
        const size_t nv = prt_transfer_vertex_count(t);
        if (!rc && !(rgb = malloc(nv * 3 * sizeof(float)))) st = PRT_ERR_NO_MEMORY;
        if (!rc && !st) st = prt_relit_shade(c.ctx, t, &r, eye, rgb);
        if (!rc && !st) st = cli_check_interrupt(&c);
        if (!rc && !st) {
            if (json) {
                /* Where the method separates bounced light, the direct part too: what relighting
                 * with direct light only gives (seen from the same eye). */
                float *direct = NULL;
                if (r.indirect) {
                    prt_relight_desc dd = {.variant = variant, .component = PRT_COMPONENT_DIRECT, .per_vertex = 1};
                    int controls[PRT_MAX_CONTROLS];
                    const int nc = cli_controls(&c, &light, t, controls);
                    dd.controls = nc > 0 ? controls : NULL;
                    dd.brdf = light.have_brdf ? &light.brdf : NULL;
                    float *albedo = NULL;
                    prt_relit rd;
                    if (nc >= 0 && !cli_painted_albedo(&c, &light, t, &albedo) && (dd.albedo = albedo, !prt_relight(c.ctx, t, lighting, &dd, &rd))) {
                        if ((direct = malloc(nv * 3 * sizeof(float))) && prt_relit_shade(c.ctx, t, &rd, eye, direct)) { free(direct); direct = NULL; }
                        prt_relit_free(&rd);
                    }
                    free(albedo);
                }
                cli_vertex_field f[3] = {{"radiance", rgb}, {"indirect", r.indirect}, {"direct", direct}};
                st = cli_write_vertex_json(output, prt_transfer_variant_name(t, variant), nv, f, r.indirect ? (direct ? 3 : 2) : 1);
                free(direct);
            } else if (ply && encoding == PRT_COLOURS_LINEAR) {
                /* Float colours keep what 8 bits would lose; assimp's PLY writer has 8 bits only. */
                const float k = exp2f(exposure);
                for (size_t i = 0; i < nv * 3; ++i) rgb[i] = fminf(fmaxf(rgb[i] * k, 0.0f), 1.0f);
                st = cli_write_vertex_ply(output, prt_transfer_positions(t), prt_transfer_normals(t), nv, prt_transfer_indices(t),
                                          prt_transfer_triangle_count(t), rgb);
            } else {
                prt_mesh_export_desc ed = {prt_transfer_positions(t), prt_transfer_normals(t), nv, prt_transfer_indices(t),
                                           prt_transfer_triangle_count(t), rgb, encoding, exposure, 0, NULL, NULL};
                static const char *const names[8][7] = {{0}, {"_SH0", "_ALBEDO"}, {"_SH0", "_SH1", "_ALBEDO"}, {"_SH0", "_SH1", "_SH2", "_ALBEDO"},
                                                        {0}, {0}, {0}, {"_SH0", "_SH1", "_SH2", "_SH3", "_SH4", "_SH5", "_SH6"}};
                float *attr = NULL;
                int groups = 0, channels = 0, coeffs = 0;
                const prt_transfer_kind tk = sh_kind;
                const char *vname = prt_transfer_variant_name(t, variant);
                if (sh_attrs) {
                    if (!sh_sets) {
                        cli_error(&c, "--sh exports per-vertex diffuse SH transfer (unshadowed, shadowed, interreflected): '%s' relit as %s has none",
                                  argv[optind], vname);
                        rc = EXIT_USAGE;
                    } else if ((st = sh_attributes(t, tk, &attr, &groups, &channels, &coeffs))) {
                        st = PRT_OK;
                        cli_error(&c, "cannot read the %s transfer of '%s'", vname, argv[optind]);
                        rc = EXIT_FAILURE_INPUT;
                    } else {
                        ed.attribute_count = groups;
                        ed.attributes = attr;
                        ed.attribute_names = channels == 3 ? names[7] : names[groups - 1];
                    }
                }
                /* The shader first: a mesh whose shader could not be written is not left behind. */
                if (!rc && glsl) {
                    prt_sh_light sh;
                    if (prt_lighting_sh(lighting, 3, &sh) || write_glsl(glsl, argv[optind], vname, channels, coeffs, groups, &sh)) {
                        cli_error(&c, "cannot write '%s'", glsl);
                        rc = EXIT_FAILURE_INPUT;
                    }
                }
                if (!rc) {
                    st = prt_mesh_export(output, &ed);
                    if (st) {
                        cli_error(&c, "%s", prt_last_error());
                        rc = EXIT_FAILURE_INPUT;
                        st = PRT_OK;
                        if (glsl) remove(glsl);
                    } else if (glsl && !c.quiet) {
                        fprintf(stderr, "prt export: wrote %s (prtRadiance() from the %d attributes)\n", glsl, groups);
                    }
                }
                free(attr);
            }
            if (st) { cli_error(&c, "cannot write '%s'", output); rc = EXIT_FAILURE_INPUT; st = PRT_OK; }
            else if (!rc && !c.quiet)
                fprintf(stderr, "prt %s: wrote %s (%s, %zu vertices%s)\n", c.cmd, output, prt_transfer_variant_name(t, variant), nv,
                        sh_attrs ? ", SH transfer as _SH attributes" : "");
        }
    }
    if (!st && !rc && maps_dir && write_offset_maps(&c, t, maps_dir)) rc = EXIT_FAILURE_INPUT;
    if (st && !rc) rc = cli_fail(&c, st);
    free(rgb);
    prt_relit_free(&r);
    prt_lighting_release(lighting);
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return rc;
}

int cmd_relight(int argc, char **argv) { return relight_main(argc, argv, false); }
int cmd_export(int argc, char **argv) { return relight_main(argc, argv, true); }
