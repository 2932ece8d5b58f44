#define _XOPEN_SOURCE 700   /* realpath */
#include "cli.h"

#include <cjson/cJSON.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *HELP_HEAD =
    "usage: prt bake SCENE -o OUT.prt [--method M] [options]\n"
    "       prt bake --frames FRAME0 FRAME1 ... -o OUT.prt [--method M] [options]\n"
    "Precomputes radiance transfer for every vertex of SCENE (a mesh file assimp reads,\n"
    "or a .json scene, see docs/SCENE.md) and writes it to OUT.prt.\n\n"
    "  -o, --output FILE      the .prt file to write (required; written atomically)\n"
    "      --frames           the scenes given are key frames of one animated object (same\n"
    "                         vertex and triangle counts and indices; moved vertices): each is\n"
    "                         baked, and OUT.prt holds them all, compressed across frames\n"
    "                         (relight, render and view --time T pose it between them). The\n"
    "                         meshes are kept as they are (no refinement, --winding keep unless\n"
    "                         given), no checkpoint\n"
    "      --resume           continue an interrupted bake (Ctrl-C, kill, power cut) from\n"
    "                         OUT.prt.checkpoint: finished work is taken, not redone, and the\n"
    "                         result is the same file an uninterrupted bake writes\n"
    "      --no-checkpoint    do not keep OUT.prt.checkpoint while baking (it holds every\n"
    "                         finished work unit, can be as large as the bake's memory, and is\n"
    "                         deleted once OUT.prt is written)\n"
    "      --memory-limit SIZE\n"
    "                         the memory the bake may hold (4G, 512M, 'none'; default: half the\n"
    "                         machine's physical memory). Each method estimates its peak before\n"
    "                         any work: over the limit, a method that can streams its largest\n"
    "                         data through a scratch file in TMPDIR (the same file results),\n"
    "                         and a bake that cannot fit is refused at once, saying what it\n"
    "                         needs and which option lowers it. The peak resident memory is\n"
    "                         printed at the end and kept in OUT.prt (prt info)\n"
    "      --summary FILE     also write a JSON summary: input, output, method, mesh, storage,\n"
    "                         each stage's seconds (compression among them) and the total\n"
    "      --refine           split triangles where transfer changes faster than the vertices\n"
    "                         sample it (contact shadows, shadow edges of the scene's lights and,\n"
    "                         for all-frequency methods, of the default sky's sun),\n"
    "                         level by level, before baking. Per-vertex bakes do it by default\n"
    "                         when a quick sample finds 1%% of the triangles or more (at least\n"
    "                         20) that need it, within a budget of as many new vertices as the\n"
    "                         mesh has (10,000 to 100,000); --refine refines whatever it finds\n"
    "      --no-refine        keep the mesh as it is (what the bake's vertices are is then\n"
    "                         exactly the scene's)\n"
    "      --refine-vertices N\n"
    "                         at most N new vertices (default: as many as the mesh has, at\n"
    "                         least 100,000; implies --refine)\n"
    "      --refine-threshold T\n"
    "                         probe difference (occlusion, shadowed share of a light) that\n"
    "                         splits, in (0, 1) (default 0.1; lower refines more; implies --refine)\n"
    "      --light SPEC       a light of the scene, repeatable; replaces the lights a JSON scene\n"
    "                         names ('none': no lights). Stored in OUT.prt (what relight, render\n"
    "                         and view light it with by default), probed by refinement, and a\n"
    "                         closed room around it keeps facing inwards (--winding auto):\n"
    "                         point:X,Y,Z:R,G,B  spot:X,Y,Z:DX,DY,DZ:ANGLE[,FALLOFF]:R,G,B\n"
    "                         directional:DX,DY,DZ:R,G,B  sphere:X,Y,Z:RADIUS:R,G,B\n"
    "      --brdf-set NAME=SPEC[,SPEC...]\n"
    "                         BRDFs the surface NAME can switch among at run time (--brdf-of,\n"
    "                         the viewer's r), beside what it wears, as a scene material's\n"
    "                         \"brdfs\" (spectral files keep them); repeatable\n"
    "      --shard I/N        compute slice I of N of the next stage that can be spread over\n"
    "                         machines and write it to -o FILE, a shard for prt merge\n"
    "                         (docs/CLUSTER.md); stages before it come from --from\n"
    "      --stage K          with --shard: the stage must be K (an error otherwise); alone,\n"
    "                         as the last option or followed by another, list the bake's stages\n"
    "                         on stdout up to the first one --from does not hold (no -o needed)\n"
    "      --from FILE        the stages prt merge put together (its -o when stages remained)\n"
    "      --method M         the PRT method (default: the first listed); each has the options\n"
    "                         listed below\n"
    "                         (prt bake --method M --help shows one method's)\n";

static const char *HELP_TAIL =
    "Other:\n"
    "  -j, --threads N        worker threads (default: all cores; results do not change)\n"
    CLI_PROGRESS_HELP
    "  -q, --quiet            no progress or messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

enum { OPT_KEY_FRAMES = 1490, OPT_SHARD = 1495, OPT_STAGE, OPT_FROM, OPT_BRDF_SET = 1498, OPT_BAKE_LIGHT = 1499, OPT_METHOD = 1500, OPT_RESUME, OPT_NO_CHECKPOINT, OPT_SUMMARY, OPT_REFINE, OPT_REFINE_VERTICES, OPT_REFINE_THRESHOLD,
       OPT_NO_REFINE, OPT_MEMORY_LIMIT, OPT_METHOD_OPTION = 3000 };

/* "NAME  summary" at the description column, the summary wrapped at 100 columns. */
static void print_method_line(const prt_method *m)
{
    cli_print_wrapped(stdout, printf("%25s%-10s  ", "", prt_method_name(m)), 37, prt_method_summary(m));
}

static void help(const prt_method *only)
{
    fputs(HELP_HEAD, stdout);
    if (cli_cluster_build())
        fputs("Under mpirun (this build has MPI): the processes share each stage that can be spread,\n"
              "  rank 0 handing out work units as the others ask; only rank 0 writes OUT.prt, the\n"
              "  same bytes as one process's (docs/CLUSTER.md)\n", stdout);
    for (int i = 0; i < prt_method_count(); ++i)
        if (!only || prt_method_at(i) == only) print_method_line(prt_method_at(i));
    fputs("Scene:\n" CLI_SCENE_FILE_HELP, stdout);
    for (int i = 0; i < prt_method_count(); ++i)
        if (!only || prt_method_at(i) == only) cli_print_method_options(stdout, prt_method_at(i), prt_method_options, "Method %s:", true);
    fputs(HELP_TAIL, stdout);
}

static int collect_options(const prt_method *chosen, struct option *opts, int max, const char **names, int max_names)
{
    static const struct option fixed[] = {
        {"output", required_argument, 0, 'o'}, {"method", required_argument, 0, OPT_METHOD}, {"resume", no_argument, 0, OPT_RESUME},
        {"no-checkpoint", no_argument, 0, OPT_NO_CHECKPOINT}, {"summary", required_argument, 0, OPT_SUMMARY},
        {"memory-limit", required_argument, 0, OPT_MEMORY_LIMIT}, {"refine", no_argument, 0, OPT_REFINE}, {"no-refine", no_argument, 0, OPT_NO_REFINE}, {"refine-vertices", required_argument, 0, OPT_REFINE_VERTICES},
        {"refine-threshold", required_argument, 0, OPT_REFINE_THRESHOLD}, {"light", required_argument, 0, OPT_BAKE_LIGHT},
        {"brdf-set", required_argument, 0, OPT_BRDF_SET}, {"frames", no_argument, 0, OPT_KEY_FRAMES}, {"shard", required_argument, 0, OPT_SHARD},
        {"stage", optional_argument, 0, OPT_STAGE}, {"from", required_argument, 0, OPT_FROM}, CLI_SCENE_LONG_OPTIONS,
        {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}};
    int n = 0;
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; ++i) opts[n++] = fixed[i];
    return cli_collect_method_options(chosen, prt_method_options, opts, n, max, names, max_names, OPT_METHOD_OPTION);
}

/* Transfer lives at vertices: where big triangles cover much of the surface (a teapot of a few
 * hundred triangles, the floor and walls of an interior), shading is blocky there. Suggests an
 * edge length that splits them, with the triangle count it would give. */
static void coarse_mesh_warning(const prt_method *m, const prt_scene *scene)
{
    float lo[3], hi[3];
    prt_scene_bounds(scene, lo, hi);
    const double diag = sqrt((double)(hi[0] - lo[0]) * (hi[0] - lo[0]) + (double)(hi[1] - lo[1]) * (hi[1] - lo[1]) + (double)(hi[2] - lo[2]) * (hi[2] - lo[2]));
    const float *p = prt_scene_positions(scene);
    const uint32_t *ix = prt_scene_indices(scene);
    const size_t nt = prt_scene_triangle_count(scene);
    const double big = diag / 25;
    double area = 0, big_area = 0;
    size_t big_count = 0;
    for (size_t t = 0; t < nt; ++t) {
        const float *a = p + ix[t * 3] * 3, *b = p + ix[t * 3 + 1] * 3, *c = p + ix[t * 3 + 2] * 3;
        double e[3][3], longest = 0;
        for (int k = 0; k < 3; ++k) {
            e[0][k] = b[k] - a[k]; e[1][k] = c[k] - b[k]; e[2][k] = a[k] - c[k];
        }
        for (int j = 0; j < 3; ++j) longest = fmax(longest, sqrt(e[j][0] * e[j][0] + e[j][1] * e[j][1] + e[j][2] * e[j][2]));
        const double cx = e[0][1] * e[2][2] - e[0][2] * e[2][1], cy = e[0][2] * e[2][0] - e[0][0] * e[2][2], cz = e[0][0] * e[2][1] - e[0][1] * e[2][0];
        const double ta = 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
        area += ta;
        if (longest > big) { big_area += ta; big_count++; }
    }
    if (!(area > 0) || big_area < 0.2 * area) return;
    /* diag / 100, coarser while that would give more than 4x the triangles (or 250k): a global
     * edge length multiplies an interior's triangles many times over. */
    double edge = diag / 100, after = 0;
    for (int tries = 0; tries < 8; ++tries, edge *= 1.5) {
        after = 0;
        for (size_t t = 0; t < nt; ++t) {
            const float *a = p + ix[t * 3] * 3, *b = p + ix[t * 3 + 1] * 3, *c = p + ix[t * 3 + 2] * 3;
            double longest = 0;
            for (int j = 0; j < 3; ++j) {
                const float *u = j == 0 ? a : j == 1 ? b : c, *v = j == 0 ? b : j == 1 ? c : a;
                longest = fmax(longest, sqrt((double)(v[0] - u[0]) * (v[0] - u[0]) + (double)(v[1] - u[1]) * (v[1] - u[1]) + (double)(v[2] - u[2]) * (v[2] - u[2])));
            }
            const double split = ceil(longest / edge);
            after += split * split;   /* splitting edges below `edge` makes about split^2 triangles of one */
        }
        if (after <= fmax(4.0 * nt, 250000.0)) break;
    }
    const char *map = prt_method_light_map_option(m);
    fprintf(stderr, "prt bake: warning: %zu large triangles (edges over %.3g) cover %.0f%% of the surface; per-vertex transfer will look "
            "blocky there (try --max-edge %.3g: about %.0f triangles%s%s%s)\n", big_count, big, 100 * big_area / area, edge, after,
            map ? ", or --" : "", map ? map : "", map ? " N for a light map" : "");
}

static prt_status refine_scene(cli *c, prt_scene *scene, const prt_refine_desc *desc)
{
    const size_t before = prt_scene_vertex_count(scene);
    prt_refine_stats rs;
    prt_refine_desc rd = *desc;
    rd.progress = cli_progress;
    rd.progress_user = c;
    prt_status st = prt_scene_refine(c->ctx, scene, &rd, &rs);
    if (st || c->quiet) return st;
    if (!rs.new_vertices) {
        fprintf(stderr, "prt %s: refine: no edge differs by more than the threshold (%zu points probed): the mesh is kept\n", c->cmd, rs.probes);
        return PRT_OK;
    }
    fprintf(stderr, "prt %s: refine: %d levels added %zu vertices (%.0f%%), now %zu vertices, %zu triangles (%zu points probed)%s\n", c->cmd,
            rs.levels, rs.new_vertices, 100.0 * (double)rs.new_vertices / (double)before, prt_scene_vertex_count(scene), rs.triangles,
            rs.probes, rs.budget_spent ? "; the vertex budget stopped it (raise --refine-vertices for more)" : "");
    return PRT_OK;
}

/* The procedural sky's sun, which the file will be relit under by default (the scene names no
 * probe and no lights), for methods that draw its sharp shadow (low-order SH blurs it away):
 * its shadow edges are refined like a light's. 0 when there is no such sun. */
static int sky_sun(const prt_method *m, const prt_scene *scene, prt_light *sun)
{
    if (!prt_method_sharp_environment(m) || prt_scene_light_count(scene)) return 0;
    prt_environment_desc env;
    const int named = prt_scene_environment(scene, &env);
    if (named && (env.none || env.path[0] || env.rotate_deg[0] || env.rotate_deg[1] || env.rotate_deg[2])) return 0;
    float d[3] = {0.4f, 0.8f, 0.3f};   /* prt_sky_desc's default */
    if (named && (env.sun_dir[0] || env.sun_dir[1] || env.sun_dir[2])) memcpy(d, env.sun_dir, sizeof d);
    memset(sun, 0, sizeof *sun);
    sun->type = PRT_LIGHT_DIRECTIONAL;
    memcpy(sun->direction, d, sizeof d);
    sun->irradiance[0] = sun->irradiance[1] = sun->irradiance[2] = 1;
    return prt_light_validate(sun) ? 0 : 1;
}

/* Per-vertex transfer cannot show a shadow that falls between vertices (sawtooth contact
 * shadows): when a quick sample finds enough such triangles, split just those, within a budget
 * that at most doubles a small mesh and adds 100,000 vertices to a big one (per-texel bakes
 * sample texels, not vertices). */
static prt_status auto_refine(cli *c, const prt_method *m, prt_scene *scene, const prt_options *o, bool coarse_check)
{
    if (prt_options_light_map(o)) return PRT_OK;   /* its light map is the resolution, not the mesh */
    if (coarse_check && !c->quiet) coarse_mesh_warning(m, scene);
    prt_refine_desc rd = {0};
    prt_light sun;
    rd.extra_light_count = sky_sun(m, scene, &sun);
    rd.extra_lights = rd.extra_light_count ? &sun : NULL;
    prt_refine_stats rs;
    prt_status st = prt_scene_refine_estimate(c->ctx, scene, &rd, &rs);
    if (st == PRT_ERR_CANCELLED) return st;
    if (st) return PRT_OK;   /* only an estimate: the bake goes on with the mesh as it is */
    const size_t nt = prt_scene_triangle_count(scene), nv = prt_scene_vertex_count(scene);
    if (rs.marked_triangles * 100 < nt || rs.marked_triangles < 20) return PRT_OK;
    if (!c->quiet)
        fprintf(stderr, "prt %s: about %zu triangles (%.0f%%) span contact or shadow edges that their vertices cannot resolve: refining them "
                "(--no-refine keeps the mesh)\n", c->cmd, rs.marked_triangles, 100.0 * (double)rs.marked_triangles / (double)nt);
    rd.max_new_vertices = nv < 10000 ? 10000 : nv > 100000 ? 100000 : nv;
    st = refine_scene(c, scene, &rd);
    if (st && st != PRT_ERR_CANCELLED) {   /* a convenience: the bake goes on with the mesh as it is */
        if (!c->quiet) fprintf(stderr, "prt %s: warning: refinement failed (%s): baking the mesh as it is\n", c->cmd, prt_last_error());
        return PRT_OK;
    }
    return st;
}

/* The bake as JSON for scripts and CI: what went in, what came out, where the time went. */
static prt_status write_summary(cli *c, const char *path, const char *input, const char *output, const prt_transfer *t)
{
    cJSON *j = cJSON_CreateObject(), *stages = j ? cJSON_AddArrayToObject(j, "stages") : NULL;
    if (!j || !stages) { cJSON_Delete(j); return PRT_ERR_NO_MEMORY; }
    cJSON_AddStringToObject(j, "input", input);
    cJSON_AddStringToObject(j, "output", output);
    cJSON_AddStringToObject(j, "method", prt_method_name(prt_transfer_method(t)));
    cJSON_AddNumberToObject(j, "vertices", (double)prt_transfer_vertex_count(t));
    cJSON_AddNumberToObject(j, "triangles", (double)prt_transfer_triangle_count(t));
    cJSON_AddNumberToObject(j, "transfer_bytes", (double)prt_transfer_bytes(t));
    const char *const *names;
    const double *secs;
    const int ns = cli_stage_times(&names, &secs);
    for (int i = 0; i < ns; ++i) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", names[i]);
        cJSON_AddNumberToObject(o, "seconds", secs[i]);
        cJSON_AddItemToArray(stages, o);
    }
    cJSON_AddNumberToObject(j, "bake_seconds", prt_transfer_bake_seconds(t));
    cJSON_AddNumberToObject(j, "peak_resident_bytes", (double)prt_transfer_peak_bytes(t));
    char *text = cJSON_Print(j);
    cJSON_Delete(j);
    if (!text) return PRT_ERR_NO_MEMORY;
    const prt_status st = cli_write_text(path, text);
    cJSON_free(text);
    if (st) { cli_error(c, "cannot write the summary '%s'", path); c->reported = true; }
    return st;
}

/* SCENE (or one key frame) with the command line's lights and BRDF sets. */
static prt_status load_scene(cli *c, const char *path, const prt_scene_desc *sd, const cli_light *lights, const char *const *sets, int nsets,
                             prt_scene **out)
{
    prt_scene *scene = NULL;
    prt_status st = prt_scene_load(c->ctx, path, sd, &scene);
    if (!st && lights->set_lights && (st = prt_scene_set_lights(scene, lights->lights, lights->light_count))) {
        cli_error(c, "--light: %s", prt_last_error());
        c->reported = true;
    }
    for (int i = 0; !st && i < nsets; ++i) {
        /* NAME=SPEC,SPEC: a BRDF spec holds no comma. */
        char name[128], list[1024];
        const char *eq = strchr(sets[i], '=');
        snprintf(name, sizeof name, "%.*s", (int)(eq - sets[i]), sets[i]);
        snprintf(list, sizeof list, "%s", eq + 1);
        for (char *save = NULL, *spec = strtok_r(list, ",", &save); spec && !st; spec = strtok_r(NULL, ",", &save)) {
            prt_brdf b;
            if ((st = prt_brdf_parse(spec, &b)) || (st = prt_scene_add_brdf_choice(scene, name, &b))) {
                cli_error(c, "--brdf-set %s: %s", sets[i], prt_last_error());
                c->reported = true;
            }
        }
    }
    if (st) prt_scene_release(scene);
    else *out = scene;
    return st;
}

/* Key frames share their topology; the first that does not is named. */
static bool same_topology(cli *c, prt_scene *const *scenes, int count, char **paths)
{
    const size_t nv = prt_scene_vertex_count(scenes[0]), nt = prt_scene_triangle_count(scenes[0]);
    for (int f = 1; f < count; ++f) {
        const size_t v = prt_scene_vertex_count(scenes[f]), t = prt_scene_triangle_count(scenes[f]);
        if (v != nv || t != nt)
            cli_error(c, "--frames: '%s' differs in topology from '%s': %zu vertices and %zu triangles, not %zu and %zu", paths[f], paths[0], v, t, nv, nt);
        else if (memcmp(prt_scene_indices(scenes[f]), prt_scene_indices(scenes[0]), nt * 3 * sizeof(uint32_t))) {
            /* The same triangles wound the other way: the importer turned one frame over. */
            const uint32_t *a = prt_scene_indices(scenes[0]), *b = prt_scene_indices(scenes[f]);
            size_t turned = 0;
            for (size_t i = 0; i < nt; ++i) turned += a[i * 3] == b[i * 3] && a[i * 3 + 1] == b[i * 3 + 2] && a[i * 3 + 2] == b[i * 3 + 1];
            if (turned) cli_error(c, "--frames: '%s' differs in topology from '%s': %zu of its triangles are wound the other way (--winding keep or flip "
                                  "reads every frame alike)", paths[f], paths[0], turned);
            else cli_error(c, "--frames: '%s' differs in topology from '%s': its triangles join other vertices", paths[f], paths[0]);
        } else continue;
        return false;
    }
    return true;
}

/* --stage's list, line by line as the bake reaches each stage. */
static void print_stage(void *user, int index, const char *name, uint64_t units, int spreadable, uint64_t recorded)
{
    (void)user;
    if (!units) printf("%-3d %-28s whole step (runs wherever the bake goes on)\n", index, name);
    else if (!spreadable) printf("%-3d %-28s %llu units, no records (run wherever the bake goes on)\n", index, name, (unsigned long long)units);
    else printf("%-3d %-28s %llu units, can be spread%s\n", index, name, (unsigned long long)units, recorded == units ? " (done in --from)" :
                recorded ? " (partly in --from)" : "");
    fflush(stdout);
}

int cli_bake_main(int argc, char **argv, const cli_bake_extra *extra)
{
    cli c = {.cmd = extra && extra->merged ? "merge" : "bake"};
    const char *merged = extra ? extra->merged : NULL;
    int shard_i = 0, shard_n = 0, stage = -1;
    bool list_stages = false;
    const char *from = NULL;
    prt_scene_desc sd = {0};
    const char *output = NULL;
    const char *summary = NULL;
    uint64_t memory_limit = 0;   /* 0: the library's default */
    bool resume = false, checkpoint = true, refine = false, no_refine = false, key_frames = false;
    prt_refine_desc rd = {0};
    cli_light lights = {.intensity = 1.0f};   /* --light only */
    const char *sets[16];   /* --brdf-set */
    int nsets = 0;
    const prt_method *method = cli_method_from_argv(&c, argc, argv);
    if (!method) return EXIT_USAGE;
    bool method_named = false, winding_named = false;
    for (int i = 1; i < argc; ++i) method_named |= !strcmp(argv[i], "--method") || !strncmp(argv[i], "--method=", 9);
    for (int i = 1; i < argc; ++i) winding_named |= !strncmp(argv[i], "--winding", 9);
    struct option opts[256];
    const char *names[200];
    collect_options(method, opts, 256, names, 200);
    prt_options *o = NULL;
    if (prt_options_create(method, &o)) return cli_fail(&c, PRT_ERR_NO_MEMORY);
    int opt, rc = EXIT_OK;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while (!rc && (opt = getopt_long(argc, argv, ":o:j:qh", opts, NULL)) != -1) {
        int r = cli_scene_option(&c, &sd, opt, optarg);
        if (r < 0) { rc = EXIT_USAGE; break; }
        if (r) continue;
        if (opt >= OPT_METHOD_OPTION) {
            if (prt_options_set(o, names[opt - OPT_METHOD_OPTION], optarg)) rc = cli_usage(&c, "%s", prt_last_error());
            continue;
        }
        switch (opt) {
        case 'o': output = optarg; break;
        case OPT_RESUME: resume = true; break;
        case OPT_KEY_FRAMES: key_frames = true; break;
        case OPT_NO_CHECKPOINT: checkpoint = false; break;
        case OPT_MEMORY_LIMIT:
            if (prt_memory_size_parse(optarg, &memory_limit)) rc = cli_usage(&c, "--memory-limit: %s", prt_last_error());
            break;
        case OPT_SUMMARY: summary = optarg; break;
        case OPT_SHARD: {
            char tail;
            if (sscanf(optarg, "%d/%d%c", &shard_i, &shard_n, &tail) != 2 || shard_n < 1 || shard_n > 1000000 || shard_i < 1 || shard_i > shard_n)
                rc = cli_usage(&c, "--shard takes I/N with 1 <= I <= N (1/3, 2/3, 3/3), not '%s'", optarg);
            break;
        }
        case OPT_STAGE:
            if (!optarg) list_stages = true;
            else if (!cli_parse_int(optarg, 0, 4095, &stage)) rc = cli_usage(&c, "--stage takes a stage number 0..4095 (--stage alone lists them)");
            break;
        case OPT_FROM: from = optarg; break;
        case OPT_BRDF_SET:
            if (nsets == 16 || !strchr(optarg, '=') || strchr(optarg, '=') == optarg) rc = cli_usage(&c, "--brdf-set takes NAME=SPEC[,SPEC...], at most 16 times");
            else sets[nsets++] = optarg;
            break;
        case OPT_BAKE_LIGHT: if (cli_light_option(&c, &lights, OPT_LIGHT, optarg) < 0) rc = EXIT_USAGE; break;
        case OPT_REFINE: refine = true; break;
        case OPT_NO_REFINE: no_refine = true; break;
        case OPT_REFINE_VERTICES: {
            int n;
            if (!cli_parse_int(optarg, 1, 50000000, &n)) rc = cli_usage(&c, "--refine-vertices must be 1..50000000");
            rd.max_new_vertices = (size_t)n;
            refine = true;
            break;
        }
        case OPT_REFINE_THRESHOLD:
            if (!cli_parse_float(optarg, &rd.threshold) || !(rd.threshold > 0 && rd.threshold < 1)) rc = cli_usage(&c, "--refine-threshold must lie in (0, 1)");
            refine = true;
            break;
        case OPT_METHOD:
            /* Read before parsing; getopt also accepts abbreviations such as --meth, which that
             * scan does not see. */
            if (prt_method_find(optarg) != method) rc = cli_usage(&c, "give the method as --method %s (or --method=%s)", optarg, optarg);
            break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) rc = cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': help(method_named ? method : NULL); prt_options_release(o); return EXIT_OK;
        default: rc = cli_bad_option(&c, opt, argv, opts); break;
        }
    }
    if (!rc && !key_frames && optind != argc - 1) rc = cli_usage(&c, "expected exactly one SCENE argument");
    if (!rc && key_frames && (argc - optind < 2 || argc - optind > 1024)) rc = cli_usage(&c, "--frames takes 2 to 1024 key frames");
    if (!rc && key_frames && (resume || refine))
        rc = cli_usage(&c, "--frames bakes the key frames as they are, without %s", resume ? "a checkpoint to resume" : "refinement (it would split each frame differently)");
    if (key_frames) {
        checkpoint = false;
        no_refine = true;
        /* --winding auto decides per file from its shape: a frame curled up could be turned over
         * and its neighbours not. Key frames are read as they are wound unless told. */
        if (!winding_named) sd.winding = PRT_WINDING_KEEP;
    }
    if (!rc && list_stages && (shard_n || stage >= 0)) rc = cli_usage(&c, "--stage alone lists the stages; --stage K goes with --shard I/N");
    if (!rc && stage >= 0 && !shard_n) rc = cli_usage(&c, "--stage K needs --shard I/N (--stage alone lists the stages)");
    if (!rc && from && !shard_n && !list_stages) rc = cli_usage(&c, "--from goes with --shard I/N or --stage (prt merge finishes a bake)");
    if (!rc && (shard_n || list_stages || merged) && (resume || summary))
        rc = cli_usage(&c, "--resume and --summary do not go with --shard or --stage");
    if (!rc && !output && !list_stages) rc = cli_usage(&c, "an output file is required (-o %s)", shard_n ? "SHARD" : "OUT.prt");
    char from_abs[4096] = "";
    if (!rc && from && !realpath(from, from_abs)) rc = cli_usage(&c, "--from %s: no such file", from);
    if (shard_n || list_stages || merged) checkpoint = false;   /* they read --from, and write no checkpoint of their own */
    const int rank = extra ? extra->rank : 0, ranks = extra && extra->ranks > 1 ? extra->ranks : 1;
    if (!rc && ranks > 1 && (shard_n || list_stages)) rc = cli_usage(&c, "--shard and --stage are for bakes outside mpirun (under it, the processes share the stages)");
    if (rank) {   /* only rank 0 speaks and writes */
        c.quiet = true;
        checkpoint = false;
    }
    if (!rc && key_frames && (shard_n || list_stages || merged || ranks > 1))
        rc = cli_usage(&c, "--frames bakes on one machine: not with --shard, --stage, prt merge or mpirun");
    if (!rc && resume && !checkpoint) rc = cli_usage(&c, "--resume needs the checkpoint that --no-checkpoint turns off");
    if (!rc && refine && no_refine) rc = cli_usage(&c, "--no-refine contradicts --refine, --refine-vertices and --refine-threshold");
    char checkpoint_path[4096] = "";
    if (!rc && checkpoint && snprintf(checkpoint_path, sizeof checkpoint_path, "%s.checkpoint", output) >= (int)sizeof checkpoint_path)
        rc = cli_usage(&c, "the output path is too long");
    /* Never throw finished work away unasked: a bake rerun after an interruption must say which it wants. */
    struct stat cps;
    if (!rc && checkpoint && !resume && stat(checkpoint_path, &cps) == 0 && cps.st_size > 36)   /* 36: its header alone */
        rc = cli_usage(&c, "%s holds the finished work of an interrupted bake: add --resume to continue it, or delete it to start over",
                       checkpoint_path);
    if (!rc && resume && access(checkpoint_path, F_OK) != 0 && !c.quiet)
        fprintf(stderr, "prt %s: no checkpoint %s to resume from: baking from the start\n", c.cmd, checkpoint_path);
    if (!rc) rc = cli_make_context(&c);
    if (rc) { prt_options_release(o); return rc; }
    prt_scene *scene = NULL;
    prt_transfer *t = NULL;
    float inside[CLI_MAX_INSIDE_POINTS * 3];
    sd.inside_point_count = cli_inside_points(&lights, NULL, inside);
    sd.inside_points = inside;
    const int nframes = key_frames ? argc - optind : 1;
    prt_scene **frames = calloc((size_t)nframes, sizeof *frames);
    prt_status st = frames ? PRT_OK : PRT_ERR_NO_MEMORY;
    for (int f = 0; !st && f < nframes; ++f) st = load_scene(&c, argv[optind + f], &sd, &lights, sets, nsets, &frames[f]);
    if (!st && key_frames && !same_topology(&c, frames, nframes, argv + optind)) {
        st = PRT_ERR_INVALID_ARG;
        c.reported = true;
    }
    if (!st) scene = frames[0];
    if (!st && !c.quiet)
        fprintf(stderr, "prt %s: %s%s: %zu vertices, %zu triangles\n", c.cmd, argv[optind], key_frames ? " and the other key frames" : "", prt_scene_vertex_count(scene),
                prt_scene_triangle_count(scene));
    prt_light sun;
    if (!st && refine && (rd.extra_light_count = sky_sun(method, scene, &sun))) rd.extra_lights = &sun;
    if (!st && refine) st = refine_scene(&c, scene, &rd);
    else if (!st && !no_refine) st = auto_refine(&c, method, scene, o, sd.max_edge == 0);
    if (!st) {
        uint64_t recovered = 0, total = 0;
        int stopped = -1;
        prt_bake_run_desc run = {.progress = cli_progress, .progress_user = &c, .checkpoint = checkpoint ? checkpoint_path : NULL,
                                 .resume = resume, .recovered_units = &recovered, .total_units = &total, .stopped_stage = &stopped,
                                 .memory_limit = memory_limit};
        if (shard_n) {
            run.checkpoint = from ? from_abs : NULL;
            run.shard_index = shard_i;
            run.shard_count = shard_n;
            run.shard = output;
            run.shard_note = extra ? extra->note : NULL;
            run.stage_given = stage >= 0;
            run.stage = stage;
        } else if (ranks > 1) {
            run.spread = cli_cluster_spread;
        } else if (list_stages || merged) {
            run.checkpoint = list_stages ? (from ? from_abs : NULL) : merged;
            run.stop_at_missing = 1;
            if (list_stages) run.stage_seen = print_stage;
        }
        if (key_frames) st = prt_bake_frames(c.ctx, (const prt_scene *const *)frames, nframes, method, o, &run, &t);
        else st = prt_bake(c.ctx, scene, method, o, &run, &t);
        if (!st && (!t || list_stages)) {   /* a shard written, the stages listed, or stages remain */
            rc = EXIT_OK;
            if (shard_n && !c.quiet) {
                prt_bake_shard info;
                if (!prt_bake_shard_info(c.ctx, output, &info)) {
                    if (info.stage < 0)
                        fprintf(stderr, "prt %s: warning: no stage of this bake can be spread (all its work is whole steps): %s holds "
                                "nothing, and prt merge bakes it all\n", c.cmd, output);
                    else
                        fprintf(stderr, "prt %s: wrote shard %d/%d of stage %d (%s): %llu of its %llu units, to %s\n", c.cmd, shard_i, shard_n,
                                info.stage, info.stage_name, (unsigned long long)info.records, (unsigned long long)info.units, output);
                    free(info.note);
                }
            } else if (list_stages) {
                if (stopped >= 0) printf("(the stages after %d are known once its shards are merged)\n", stopped);
                else printf("(the end of the bake)\n");
                prt_transfer_release(t);
            } else if (merged) {
                if (rename(merged, output) != 0) { cli_error(&c, "cannot write %s", output); rc = EXIT_FAILURE_INPUT; }
                else {
                    printf("next %d\n", stopped);
                    if (!c.quiet)
                        fprintf(stderr, "prt merge: stages remain: wrote the finished ones to %s; next, stage %d: prt bake ... --from %s --shard I/N\n",
                                output, stopped, output);
                }
            }
            prt_scene_release(scene);   /* one scene: --frames goes with none of these */
            free(frames);
            prt_options_release(o);
            prt_context_release(c.ctx);
            return rc;
        }
        if (!st && resume && !c.quiet && total)
            fprintf(stderr, "prt %s: resumed: %llu of %llu work units (%.0f%%) came from %s\n", c.cmd, (unsigned long long)recovered,
                    (unsigned long long)total, 100.0 * (double)recovered / (double)total, checkpoint_path);
    }
    if (!st && rank) {   /* rank 0 writes the file */
        prt_transfer_release(t);
        prt_scene_release(scene);   /* one scene: --frames is not spread */
        free(frames);
        prt_options_release(o);
        prt_context_release(c.ctx);
        return EXIT_OK;
    }
    if (!st && !c.quiet) {
        char *report = NULL;
        if (!prt_transfer_bake_report(t, &report)) {
            char prefix[32];
            snprintf(prefix, sizeof prefix, "prt %s: ", c.cmd);
            cli_print_lines(stderr, prefix, report);
        }
        free(report);
        /* Where the time went, stage by stage (compression is its own stage). */
        const char *const *names;
        const double *secs;
        const int ns = cli_stage_times(&names, &secs);
        char line[2048];
        size_t at = 0;
        for (int i = 0; i < ns && at < sizeof line; ++i)
            at += (size_t)snprintf(line + at, sizeof line - at, "%s%s %.2f s", i ? ", " : "", names[i], secs[i]);
        if (ns) fprintf(stderr, "prt %s: stage times: %s\n", c.cmd, line);
        char peak[32], limit[32];
        if (prt_transfer_peak_bytes(t))
            fprintf(stderr, "prt %s: peak resident memory %s (limit %s)\n", c.cmd, prt_memory_size_format(prt_transfer_peak_bytes(t), peak, sizeof peak),
                    prt_memory_size_format(prt_transfer_memory_limit(t), limit, sizeof limit));
    }
    if (!st) st = cli_check_interrupt(&c);
    /* The summary first: if it cannot be written, the bake fails before its file appears. */
    if (!st && summary) st = write_summary(&c, summary, argv[optind], output, t);
    /* A big file should not come as a surprise: say its size before writing it. */
    if (!st && !c.quiet && prt_transfer_bytes(t) >= (size_t)64 << 20)
        fprintf(stderr, "prt %s: writing %.0f MB to %s (prt bake --method %s --help lists what stores less)\n", c.cmd, (double)prt_transfer_bytes(t) / 1e6,
                output, prt_method_name(method));
    if (!st) {
        st = prt_transfer_save(t, output);
        if (st && summary) remove(summary);
    }
    if (!st && checkpoint) remove(checkpoint_path);   /* the result is safe: nothing to resume */
    if (!st && merged) {
        remove(merged);
        printf("done\n");
    }
    if (!st && !c.quiet) {
        char *text = NULL;
        if (!prt_transfer_describe(t, output, 0, &text)) {
            fprintf(stderr, "prt %s: wrote %s:\n", c.cmd, output);
            cli_print_lines(stderr, "  ", text);
        }
        free(text);
    }
    if (st == PRT_ERR_CANCELLED && checkpoint && access(checkpoint_path, F_OK) == 0) {
        cli_error(&c, "interrupted: nothing written; finished work is kept in %s (the same command with --resume continues)", checkpoint_path);
        rc = EXIT_INTERRUPTED;
    } else {
        rc = st ? cli_fail(&c, st) : EXIT_OK;
    }
    prt_transfer_release(t);
    for (int f = 0; frames && f < nframes; ++f) prt_scene_release(frames[f]);
    free(frames);
    prt_options_release(o);
    prt_context_release(c.ctx);
    return rc;
}

/* The arguments a shard keeps for prt merge: the bake's own, without where this run writes or
 * reads (-o, --shard, --stage, --from) nor how it runs (-j, -q, --progress, --summary). */
static char *shard_note(int argc, char **argv)
{
    static const char *const skip_arg[] = {"-o", "--output", "--shard", "--from", "-j", "--threads", "--progress", "--summary"};
    static const char *const skip[] = {"-q", "--quiet", "--resume", "--no-checkpoint"};
    cJSON *j = cJSON_CreateObject(), *args = j ? cJSON_AddArrayToObject(j, "args") : NULL;
    char cwd[4096];
    if (!args || !getcwd(cwd, sizeof cwd)) { cJSON_Delete(j); return NULL; }
    cJSON_AddStringToObject(j, "cwd", cwd);
    for (int i = 1; i < argc; ++i) {
        bool drop = false;
        for (size_t k = 0; k < sizeof skip_arg / sizeof *skip_arg && !drop; ++k) {
            const size_t n = strlen(skip_arg[k]);
            if (!strcmp(argv[i], skip_arg[k])) { drop = true; i++; }
            else if (!strncmp(argv[i], skip_arg[k], n) && (argv[i][n] == '=' || (n == 2 && argv[i][n]))) drop = true;
        }
        for (size_t k = 0; k < sizeof skip / sizeof *skip && !drop; ++k) drop = !strcmp(argv[i], skip[k]);
        if (!strcmp(argv[i], "--stage") || !strncmp(argv[i], "--stage=", 8)) drop = true;
        if (!drop) cJSON_AddItemToArray(args, cJSON_CreateString(argv[i]));
    }
    char *text = cJSON_PrintUnformatted(j);
    cJSON_Delete(j);
    return text;
}

int cmd_bake(int argc, char **argv)
{
    /* --stage K as two words (getopt takes an optional value only as --stage=K), --stage alone lists. */
    char **args = calloc((size_t)argc + 1, sizeof *args), *joined[8];
    int n = 0, nj = 0;
    if (!args) { fprintf(stderr, "prt bake: out of memory\n"); return EXIT_NO_MEMORY; }
    for (int i = 0; i < argc; ++i) {
        if (!strcmp(argv[i], "--stage") && i + 1 < argc && argv[i + 1][0] >= '0' && argv[i + 1][0] <= '9' && nj < 8) {
            const size_t len = strlen(argv[i + 1]) + 9;
            if ((joined[nj] = malloc(len))) {
                snprintf(joined[nj], len, "--stage=%s", argv[i + 1]);
                args[n++] = joined[nj++];
                i++;
                continue;
            }
        }
        args[n++] = argv[i];
    }
    cli_bake_extra extra = {.note = shard_note(n, args)};
    if (cli_cluster_start(&argc, &argv)) {
        extra.rank = cli_cluster_rank();
        extra.ranks = cli_cluster_size();
    }
    const int rc = cli_bake_main(n, args, &extra);
    cli_cluster_end(rc);
    cJSON_free(extra.note);
    for (int i = 0; i < nj; ++i) free(joined[i]);
    free(args);
    return rc;
}
