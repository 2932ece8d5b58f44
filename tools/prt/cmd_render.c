#include "cli.h"
#include "probe.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

static const char *HELP =
    "usage: prt render FILE.prt [MORE.prt|IMAGE ...] -o OUT.png|OUT.exr [options]\n"
    "Relights a baked .prt and draws it with OpenGL 3.3 (headless EGL; Mesa llvmpipe without a\n"
    "GPU). Several kinds are drawn side by side, left to right, in the order given; so are\n"
    "several files (each as its kinds, all under the same lighting options and the first\n"
    "file's camera: one scene baked by several methods) and linear images given among them\n"
    "(.exr .hdr .pfm: a prt reference --image of the same view and size, pasted as it is).\n\n"
    "  -o, --output FILE      the image (required): .png (tone-mapped sRGB), .exr (linear half),\n"
    "                         .hdr or .pfm\n"
    "  -k, --kind LIST        comma list of what to draw the file as (prt info lists what it\n"
    "                         holds), or 'all'; default: the richest. View-dependent parts\n"
    "                         (glossy surfaces) are evaluated per pixel\n"
    "      --width N          image width in pixels, per panel (default 800)\n"
    CLI_VIEW_CAMERA_HELP CLI_VIEW_TONE_HELP CLI_VIEW_BACKGROUND_HELP
    CLI_TIME_HELP
    CLI_LIGHT_OPTIONS_HELP
    "Animation (an animated PNG that loops):\n"
    "      --frames N         draw N frames (2..1000) in which the lighting moves: by default it\n"
    "                         turns once about the vertical axis through the scene's centre\n"
    "                         (the environment, and every light's position and direction)\n"
    "      --light-to SPEC    instead, the i-th --light moves in a straight line to this one (a\n"
    "                         light of the same type), from the first frame to the last;\n"
    "                         repeatable, in the order of the --light options\n"
    "      --fps N            frames per second (1..100, default 12)\n"
    "Other:\n"
    "      --probe X,Y,Z[,R]  a grey sphere (radius R; default 3% of the grid) at X,Y,Z, lit by the\n"
    "                         file's neighbourhood transfer (bake --neighbourhood N): shadowed\n"
    "                         and lit by the scene as an object moved there; repeatable (8)\n"
    "      --per-vertex       shade from the vertex sets even where the file has per-texel ones,\n"
    "                         and evaluate view-dependent parts per vertex rather than per pixel\n"
    "      --accumulate W     files whose method has GPU passes (prt info says): where the last\n"
    "                         sums run - cpu (default: threads) or gpu (offset maps binned into\n"
    "                         atlases and blended; the other methods' per-vertex sums - transfer\n"
    "                         rows, CPCA weights, sparse rows, bounces - as transform-feedback\n"
    "                         passes over buffer textures); the same image either way\n"
    "  -j, --threads N        worker threads for relighting\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

#define MAX_PANELS 16

enum { OPT_FRAMES = 2600, OPT_LIGHT_TO, OPT_FPS, OPT_PROBE };

/* One input: a .prt drawn as its kinds, or an image pasted as it is. */
typedef struct source {
    prt_transfer *t;
    prt_transfer *file;       /* --time: the file as loaded (t is its pose), which the camera frames */
    prt_lighting *lighting;   /* what the command line and the file name, at frame 0 */
    prt_image image;
    int variants[MAX_PANELS], count;
} source;

static bool is_image(const char *path)
{
    static const char *const ext[] = {".png", ".exr", ".hdr", ".pfm", ".jpg", ".jpeg"};   /* panels take the linear ones */
    const char *e = strrchr(path, '.');
    for (size_t i = 0; e && i < sizeof ext / sizeof ext[0]; ++i)
        if (!strcasecmp(e, ext[i])) return true;
    return false;
}

static void turn_y(float v[3], const float centre[3], double angle, bool point)
{
    const double c = cos(angle), s = sin(angle);
    const double x = v[0] - (point ? centre[0] : 0), z = v[2] - (point ? centre[2] : 0);
    v[0] = (float)(c * x + s * z + (point ? centre[0] : 0));
    v[2] = (float)(-s * x + c * z + (point ? centre[2] : 0));
}

/* The lighting of frame f of n: base turned about the vertical axis through centre by f/n of a
 * turn, or its first lights moved in a straight line towards `to`. */
static prt_status frame_lighting(const prt_lighting *base, int f, int n, const float centre[3], const prt_light *to, int to_count, prt_lighting **out)
{
    prt_status st = prt_lighting_copy(base, out);
    if (st || n < 2) return st;
    if (to_count) {
        const float s = (float)f / (float)(n - 1);
        for (int i = 0; i < to_count && !st; ++i) {
            prt_light l = *prt_lighting_light(base, i);
            for (int k = 0; k < 3; ++k) {
                l.position[k] += s * (to[i].position[k] - l.position[k]);
                l.direction[k] += s * (to[i].direction[k] - l.direction[k]);
                l.intensity[k] += s * (to[i].intensity[k] - l.intensity[k]);
                l.irradiance[k] += s * (to[i].irradiance[k] - l.irradiance[k]);
                l.radiance[k] += s * (to[i].radiance[k] - l.radiance[k]);
            }
            l.radius += s * (to[i].radius - l.radius);
            l.angle_deg += s * (to[i].angle_deg - l.angle_deg);
            l.falloff_deg += s * (to[i].falloff_deg - l.falloff_deg);
            st = prt_lighting_set(*out, i, &l);
        }
        return st;
    }
    const double angle = 2 * 3.14159265358979323846 * f / n;
    for (int i = 0; i < prt_lighting_count(base) && !st; ++i) {
        prt_light l = *prt_lighting_light(base, i);
        turn_y(l.position, centre, angle, true);
        turn_y(l.direction, centre, angle, false);
        st = prt_lighting_set(*out, i, &l);
    }
    if (!st && prt_lighting_envmap(base)) {
        double r0[9], r[9];
        prt_lighting_rotation(base, r0);
        const double c = cos(angle), s = sin(angle), ry[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r[i * 3 + j] = ry[i * 3] * r0[j] + ry[i * 3 + 1] * r0[3 + j] + ry[i * 3 + 2] * r0[6 + j];
        prt_lighting_set_rotation(*out, r);
    }
    return st;
}

int cmd_render(int argc, char **argv)
{
    cli c = {.cmd = "render"};
    cli_light light = {.intensity = 1.0f};
    cli_kinds kinds = {0};
    char kind_buf[512];
    const char *output = NULL;
    bool per_vertex = false;
    int gpu_asked = 0, gpu_taken = 0;   /* panels relit with --accumulate gpu, and those whose sums the renderer got */
    cli_view view = CLI_VIEW_DEFAULTS;
    int frames = 1, fps = 12, to_count = 0, probe_count = 0;
    float probes[CLI_MAX_PROBES][4];
    bool timed = false;
    double time = 0;
    prt_light to[CLI_MAX_LIGHTS];
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"kind", required_argument, 0, 'k'}, CLI_VIEW_LONG_OPTIONS, CLI_LIGHT_LONG_OPTIONS,
        {"time", required_argument, 0, OPT_TIME}, {"frames", required_argument, 0, OPT_FRAMES}, {"light-to", required_argument, 0, OPT_LIGHT_TO}, {"fps", required_argument, 0, OPT_FPS},
        {"probe", required_argument, 0, OPT_PROBE}, {"threads", required_argument, 0, 'j'}, {"per-vertex", no_argument, 0, 'P'}, {"accumulate", required_argument, 0, 'A'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0}};
    int opt;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:k:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (!r) r = cli_view_option(&c, &view, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case 'P': per_vertex = true; break;
        case 'A':
            if (!cli_parse_accumulate(optarg, &light.gpu_finish)) return cli_usage(&c, "--accumulate takes cpu or gpu");
            break;
        case 'k':
            snprintf(kind_buf, sizeof kind_buf, "%s", optarg);
            if (!cli_relight_kinds(&kinds, kind_buf)) return cli_usage(&c, "--kind takes a comma list of at most 16 names");
            break;
        case OPT_PROBE:
            if (probe_count == CLI_MAX_PROBES) return cli_usage(&c, "at most %d --probe", CLI_MAX_PROBES);
            if (!cli_parse_probe(optarg, probes[probe_count++])) return cli_usage(&c, "--probe takes X,Y,Z or X,Y,Z,R (R > 0), got \"%s\"", optarg);
            break;
        case OPT_TIME:
            if (!cli_parse_time(&c, optarg, &time)) return EXIT_USAGE;
            timed = true;
            break;
        case OPT_FRAMES: if (!cli_parse_int(optarg, 2, 1000, &frames)) return cli_usage(&c, "--frames must be 2..1000"); break;
        case OPT_FPS: if (!cli_parse_int(optarg, 1, 100, &fps)) return cli_usage(&c, "--fps must be 1..100"); break;
        case OPT_LIGHT_TO:
            if (to_count == CLI_MAX_LIGHTS) return cli_usage(&c, "at most %d --light-to", CLI_MAX_LIGHTS);
            if (cli_parse_light(optarg, &to[to_count])) return cli_usage(&c, "--light-to: %s", prt_last_error());
            to_count++;
            break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind >= argc) return cli_usage(&c, "expected a FILE.prt argument");
    const int ninputs = argc - optind;
    if (ninputs > MAX_PANELS) return cli_usage(&c, "at most %d inputs", MAX_PANELS);
    if (!output) return cli_usage(&c, "an output image is required (-o OUT.png)");
    if (view.have_eye != view.have_target) return cli_usage(&c, "--eye and --target go together");
    if (to_count && frames < 2) return cli_usage(&c, "--light-to moves lights over --frames N");
    if (to_count && to_count != light.light_count) return cli_usage(&c, "give one --light-to for each --light (%d --light, %d --light-to)", light.light_count, to_count);
    for (int i = 0; i < to_count; ++i) {
        if (to[i].type != light.lights[i].type) return cli_usage(&c, "--light-to %d is not the same type of light as --light %d", i + 1, i + 1);
        /* Directions are interpolated in a straight line: opposite ones would pass through zero. */
        const float *a = light.lights[i].direction, *b = to[i].direction;
        const float dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2], la = sqrtf(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]), lb = sqrtf(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        if ((to[i].type == PRT_LIGHT_DIRECTIONAL || to[i].type == PRT_LIGHT_SPOT) && !(dot > -0.99f * la * lb))
            return cli_usage(&c, "--light-to %d points the opposite way from --light %d: move it in two animations", i + 1, i + 1);
    }
    if (frames > 1) {
        const char *ext = strrchr(output, '.');
        if (!ext || strcasecmp(ext, ".png")) return cli_usage(&c, "--frames writes an animated PNG: -o must end in .png");
    }
    if (kinds.count && ninputs > 1) return cli_usage(&c, "--kind applies to one file; several files are drawn as their richest kinds");
    const int width = view.width, height = view.height;
    int rc = cli_make_context(&c);
    if (rc) return rc;

    source src[MAX_PANELS];
    memset(src, 0, sizeof src);
    prt_renderer *r = NULL;
    float *rgb = NULL;
    prt_image panel = {0};
    prt_image *sheets = calloc((size_t)frames, sizeof *sheets);
    int count = 0, first = -1;
    prt_status st = sheets ? PRT_OK : PRT_ERR_NO_MEMORY;
    size_t max_nv = 0;
    for (int i = 0; i < ninputs && !st && !rc; ++i) {
        const char *path = argv[optind + i];
        if (is_image(path)) {
            if (frames > 1) { rc = cli_usage(&c, "'%s': an image cannot follow the moving lights of --frames", path); break; }
            const char *e = strrchr(path, '.');
            if (!strcasecmp(e, ".png") || !strcasecmp(e, ".jpg") || !strcasecmp(e, ".jpeg")) {
                rc = cli_usage(&c, "'%s' is already tone-mapped: paste a linear image (.exr, .hdr, .pfm; prt reference --image X.exr)", path);
                break;
            }
            if ((st = prt_image_load(path, &src[i].image))) { cli_error(&c, "'%s': %s", path, prt_last_error()); c.reported = true; break; }
            if (src[i].image.width != width || src[i].image.height != height) {
                cli_error(&c, "'%s' is %dx%d, the panels %dx%d (give the same --width and --height)", path, src[i].image.width, src[i].image.height, width,
                          height);
                rc = EXIT_USAGE;
                break;
            }
            src[i].count = 1;
        } else {
            if ((st = prt_transfer_load(c.ctx, path, &src[i].t))) break;
            if (timed) {
                /* The camera frames the file's first key frame at every time: renders of one
                 * animation share their view (as prt view's does). */
                src[i].file = src[i].t;
                if ((st = prt_transfer_at_time(c.ctx, src[i].file, time, &src[i].t))) {
                    src[i].t = NULL;
                    cli_error(&c, "--time %g: '%s': %s", time, path, prt_last_error());
                    c.reported = true;
                    break;
                }
            }
            if ((src[i].count = cli_relight_resolve(&c, &kinds, src[i].t, 1, src[i].variants, MAX_PANELS)) < 0) { rc = EXIT_USAGE; break; }
            if (light.gpu_finish && !cli_check_accumulate(&c, src[i].t, per_vertex)) { rc = EXIT_USAGE; break; }
            if ((st = cli_lighting(&c, &light, src[i].t, NULL, &src[i].lighting))) break;
            if ((st = cli_check_interrupt(&c))) break;   /* between steps: each can take a second on big inputs */
            if (first < 0) first = i;
            if (prt_transfer_vertex_count(src[i].t) > max_nv) max_nv = prt_transfer_vertex_count(src[i].t);
        }
        count += src[i].count;
        if (count > MAX_PANELS) { rc = cli_usage(&c, "at most %d panels", MAX_PANELS); break; }
    }
    if (!st && !rc && first < 0) rc = cli_usage(&c, "expected a FILE.prt among the inputs (images are only pasted beside it)");
    /* Every frame is kept until the animation is written: say so before running out of memory. */
    const double held = (double)frames * width * height * count * 3 * sizeof(float);
    if (!st && !rc && frames > 1 && held > 4e9)
        rc = cli_usage(&c, "%d frames of %d panels of %dx%d would hold %.1f GB: fewer --frames or a smaller --width", frames, count, width, height, held / 1e9);
    if (!st && !rc) st = prt_renderer_create(c.ctx, &(prt_renderer_desc){width, height, 0}, &r);
    if (!st && !rc) st = cli_check_interrupt(&c);
    if (!st && !rc) {
        rgb = malloc(max_nv * 3 * sizeof(float));
        for (int f = 0; f < frames && !st; ++f) {
            sheets[f].width = width * count;
            sheets[f].height = height;
            sheets[f].rgb = calloc((size_t)sheets[f].width * height * 3, sizeof(float));
            if (!sheets[f].rgb) st = PRT_ERR_NO_MEMORY;
        }
        if (!rgb) st = PRT_ERR_NO_MEMORY;
    }
    prt_camera cam;
    float centre[3] = {0, 0, 0};
    if (!st && !rc) {
        const prt_transfer *t0 = src[first].file ? src[first].file : src[first].t;
        float media[CLI_MAX_MEDIA * 6];
        const int nmedia = view.have_eye ? 0 : cli_transfer_media_boxes(t0, media);
        cli_view_camera_boxes(&c, &view, prt_transfer_positions(t0), prt_transfer_vertex_count(t0), prt_transfer_indices(t0), prt_transfer_triangle_count(t0),
                              media, nmedia, (float)width / height, &cam);
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        const float *p = prt_transfer_positions(t0);
        for (size_t v = 0; v < prt_transfer_vertex_count(t0); ++v)
            for (int k = 0; k < 3; ++k) { lo[k] = fminf(lo[k], p[v * 3 + k]); hi[k] = fmaxf(hi[k], p[v * 3 + k]); }
        for (int k = 0; k < 3; ++k) centre[k] = 0.5f * (lo[k] + hi[k]);
    }
    const bool tty = isatty(2);   /* a frame counter on terminals; logs get the closing line */
    for (int f = 0; f < frames && !st && !rc; ++f) {
        int at = 0;
        for (int i = 0; i < ninputs && !st && !rc; ++i) {
            if (!src[i].t) {
                for (int y = 0; y < height; ++y)
                    memcpy(sheets[f].rgb + ((size_t)y * sheets[f].width + (size_t)at * width) * 3, src[i].image.rgb + (size_t)y * width * 3,
                           (size_t)width * 3 * sizeof(float));
                at++;
                continue;
            }
            prt_lighting *lighting = NULL;
            if ((st = frame_lighting(src[i].lighting, f, frames, centre, to, to_count, &lighting))) break;
            for (int k = 0; k < src[i].count && !st; ++k, ++at) {
                const prt_transfer *t = src[i].t;
                prt_relit relit;
                if ((st = cli_relight(&c, t, lighting, &light, src[i].variants[k], per_vertex, false, &relit))) break;
                if ((st = cli_check_interrupt(&c))) { prt_relit_free(&relit); break; }
                if (light.gpu_finish) {
                    gpu_asked++;
                    gpu_taken += relit.gpu_sums || relit.gpu_passes;
                }
                prt_render_mesh mesh;
                prt_relit_render_mesh(t, &relit, &mesh);
                if (per_vertex && prt_relit_view_dependent(&relit)) {
                    /* The view factor on the CPU, per vertex, towards the camera. */
                    st = prt_relit_shade(c.ctx, t, &relit, cam.eye, rgb);
                    prt_render_mesh plain = {.positions = mesh.positions, .radiance = rgb, .vertex_count = mesh.vertex_count, .indices = mesh.indices,
                                             .triangle_count = mesh.triangle_count, .normals = mesh.normals};
                    mesh = plain;
                }
                cli_probe_mesh held = {0};
                if (!st && probe_count) st = cli_probe_append(&c, t, lighting, (const float(*)[4])probes, probe_count, &mesh, &held, &mesh);
                if (!st) st = prt_render(r, &mesh, &cam, view.background, &panel);
                cli_probe_mesh_free(&held);
                prt_relit_free(&relit);
                if (st) break;
                for (int y = 0; y < height; ++y)
                    memcpy(sheets[f].rgb + ((size_t)y * sheets[f].width + (size_t)at * width) * 3, panel.rgb + (size_t)y * width * 3,
                           (size_t)width * 3 * sizeof(float));
                prt_image_free(&panel);
            }
            prt_lighting_release(lighting);
        }
        if (!st && !rc) st = cli_check_interrupt(&c);
        if (!st && !rc && frames > 1 && !c.quiet && tty) fprintf(stderr, "\rprt render: frame %d of %d", f + 1, frames);
    }
    if (frames > 1 && !c.quiet && tty) fputc('\n', stderr);
    if (!st && !rc) st = cli_check_interrupt(&c);
    if (!st && !rc) st = frames > 1 ? prt_image_save_animation(output, sheets, frames, fps, &view.save) : prt_image_save(output, &sheets[0], &view.save);
    /* Encoding a big image takes a second: Ctrl-C during it still means nothing written. */
    if (!st && !rc && (st = cli_check_interrupt(&c))) remove(output);
    if (!st && !rc && !c.quiet) {
        fprintf(stderr, "prt render: wrote %s (", output);
        int k = 0;
        for (int i = 0; i < ninputs; ++i) {
            if (!src[i].t) { fprintf(stderr, "%s%s", k++ ? ", " : "", argv[optind + i]); continue; }
            for (int v = 0; v < src[i].count; ++v, ++k)
                fprintf(stderr, "%s%s%s%s", k ? ", " : "", ninputs > 1 ? prt_method_name(prt_transfer_method(src[i].t)) : "", ninputs > 1 ? " " : "",
                        prt_transfer_variant_name(src[i].t, src[i].variants[v]));
        }
        fprintf(stderr, "; %s", prt_renderer_name(r));
        /* Where the last sums ran: some relightings keep the CPU path (docs/GPU.md). */
        if (gpu_asked)
            fprintf(stderr, "; %s", gpu_taken == gpu_asked ? (prt_render_sums_on_gpu(r) == 0 ? "sums on the CPU (GPU limits)" : "sums on the GPU")
                                    : gpu_taken ? "sums on the GPU for some panels, the CPU for the rest"
                                                : "sums on the CPU: this relighting keeps the CPU path (docs/GPU.md)");
        if (frames > 1) fprintf(stderr, "; %d frames at %d per second", frames, fps);
        fprintf(stderr, ")\n");
    }
    if (st && !rc) rc = cli_fail(&c, st);
    free(rgb);
    for (int f = 0; sheets && f < frames; ++f) prt_image_free(&sheets[f]);
    free(sheets);
    prt_renderer_release(r);
    for (int i = 0; i < ninputs; ++i) {
        prt_lighting_release(src[i].lighting);
        prt_transfer_release(src[i].t);
        prt_transfer_release(src[i].file);
        prt_image_free(&src[i].image);
    }
    prt_context_release(c.ctx);
    return rc;
}
