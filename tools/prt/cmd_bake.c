#include "cli.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

static const char *HELP =
    "usage: prt bake SCENE -o OUT.prt [options]\n"
    "Precomputes radiance transfer for every vertex of SCENE (a mesh file assimp reads,\n"
    "or a .json scene, see docs/SCENE.md) and writes it to OUT.prt.\n\n"
    "  -o, --output FILE      the .prt file to write (required; written atomically)\n"
    "      --method M         sh (default): spherical-harmonic PRT; wavelet: all-frequency\n"
    "                         glossy PRT (Haar cube maps, separable BRDFs; options below)\n"
    "      --order N          SH order, 1..10 bands (default 5 = 25 coefficients)\n"
    "      --samples N        directions per vertex over the sphere (default 1024)\n"
    "      --kinds LIST       comma list of unshadowed, shadowed, interreflected (or 'all':\n"
    "                         these three, the default) and glossy-shadowed,\n"
    "                         glossy-interreflected: per-vertex transfer matrices (order^4\n"
    "                         floats each; use --order 4 or 5) for view-dependent surfaces\n"
    "      --brdf SPEC        bake this BRDF into the glossy sets for every vertex (any isotropic\n"
    "                         model: lambert, phong, blinn, ashikhmin:N:N, lafortune:clay|skin)\n"
    "      --bake-materials   bake each vertex's scene material BRDF into the glossy sets\n"
    "                         (without either, glossy sets hold incident radiance and the lobe\n"
    "                         is chosen when rendering)\n"
    "      --bounces N        interreflection bounces (sh: 1..64, default 3; wavelet: 0..8,\n"
    "                         default 0 = direct light only)\n"
    "      --texels N         also bake per-texel transfer (the diffuse kinds) over the mesh's\n"
    "                         UV layout into an N x N map; needs unique UVs inside [0, 1]\n"
    "      --normal-map FILE  tangent-space normal map perturbing the per-texel normals\n"
    "                         (.png/.jpg values as stored; .exr/.hdr/.pfm values in [0, 1])\n"
    "      --seed N           rotates the low-discrepancy directions (default 0)\n"
    CLI_SCENE_OPTIONS_HELP
    "      --ray-offset E     shadow-ray origin offset (default 1e-4 x scene diagonal)\n"
    "      --compress M       cpca | pca | vq: store the sets compressed (clustered PCA, one\n"
    "                         cluster, or clusters only); relighting reads them directly\n"
    "      --clusters K       clusters for cpca (default 64) and vq (default 256)\n"
    "      --vectors N        average PCA vectors per cluster for cpca and pca (default 8)\n"
    "      --quantize B       store uncompressed sets as 8- or 16-bit integers (scale and bias\n"
    "                         per coefficient)\n"
    "Wavelet method (--method wavelet):\n"
    "      --terms K          separable BRDF terms per glossy material, 1..16 (default 4); the\n"
    "                         cosine-weighted RMS error per K is printed\n"
    "      --coefficients N   Haar coefficients kept per transport vector (default 128)\n"
    "      --bits B           8 (default) or 16-bit quantization per colour channel\n"
    "      --supersample S    visibility rays per cube texel side, 1..4 (default 2: 6x128x128)\n"
    "      --gather-res R     hit-point cube map per side for bounces, 4..64 (default 32)\n"
    "      --brdf-res R       BRDF light/view map size, 4..96 (default 48)\n"
    "      --param P          grid (default, eq. 10) or polar (eq. 11) BRDF parameterization\n"
    "      --brdf SPEC        this BRDF for every vertex instead of the scene's materials\n"
    "  -j, --threads N        worker threads (default: all cores; results do not change)\n"
    "  -q, --quiet            no progress or warnings\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

int cmd_bake(int argc, char **argv)
{
    cli c = {.cmd = "bake"};
    prt_bake_desc bd = {0};
    prt_scene_desc sd = {0};
    const char *output = NULL;
    prt_compress_desc cd = {0};
    bool compress = false;
    int quantize = 0;
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"order", required_argument, 0, 'O'}, {"samples", required_argument, 0, 'n'},
        {"kinds", required_argument, 0, 'k'}, {"bounces", required_argument, 0, 'b'}, {"seed", required_argument, 0, 's'},
        CLI_SCENE_LONG_OPTIONS, {"ray-offset", required_argument, 0, 'r'}, {"compress", required_argument, 0, 'C'},
        {"clusters", required_argument, 0, 'K'}, {"vectors", required_argument, 0, 'V'}, {"quantize", required_argument, 0, 'Q'},
        {"brdf", required_argument, 0, 'B'}, {"bake-materials", no_argument, 0, 'M'},
        {"texels", required_argument, 0, 'T'}, {"normal-map", required_argument, 0, 'N'},
        {"method", required_argument, 0, 1500}, {"terms", required_argument, 0, 1501}, {"coefficients", required_argument, 0, 1502},
        {"bits", required_argument, 0, 1503}, {"supersample", required_argument, 0, 1504}, {"gather-res", required_argument, 0, 1505},
        {"brdf-res", required_argument, 0, 1506}, {"param", required_argument, 0, 1507},
        {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt, seed;
    bool wavelet = false, sh_only = false, wavelet_only = false, have_bounces = false;
    prt_wavelet_bake_desc wd = {0};
    prt_brdf bake_brdf;
    const char *normal_map_path = NULL;
    prt_image normal_map = {0};
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:j:qh", opts, NULL)) != -1) {
        int r = cli_scene_option(&c, &sd, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case 'O': if (!cli_parse_int(optarg, 1, PRT_SH_MAX_ORDER, &bd.order)) return cli_usage(&c, "--order must be 1..%d", PRT_SH_MAX_ORDER); break;
        case 'n': if (!cli_parse_int(optarg, 16, 1 << 20, &bd.samples)) return cli_usage(&c, "--samples must be 16..1048576"); break;
        case 'b': if (!cli_parse_int(optarg, 0, 64, &bd.bounces)) return cli_usage(&c, "--bounces must be 0..64"); have_bounces = true; break;
        case 1500:
            if (!strcasecmp(optarg, "wavelet")) wavelet = true;
            else if (strcasecmp(optarg, "sh")) return cli_usage(&c, "--method must be sh or wavelet");
            break;
        case 1501: if (!cli_parse_int(optarg, 1, PRT_BRDF_MAX_TERMS, &wd.terms)) return cli_usage(&c, "--terms must be 1..%d", PRT_BRDF_MAX_TERMS); wavelet_only = true; break;
        case 1502: if (!cli_parse_int(optarg, 1, PRT_WAVELET_DIM, &wd.coefficients)) return cli_usage(&c, "--coefficients must be 1..%d", PRT_WAVELET_DIM); wavelet_only = true; break;
        case 1503: if (!cli_parse_int(optarg, 8, 16, &wd.bits) || (wd.bits != 8 && wd.bits != 16)) return cli_usage(&c, "--bits must be 8 or 16"); wavelet_only = true; break;
        case 1504: if (!cli_parse_int(optarg, 1, 4, &wd.supersample)) return cli_usage(&c, "--supersample must be 1..4"); wavelet_only = true; break;
        case 1505: if (!cli_parse_int(optarg, 4, 64, &wd.gather_resolution)) return cli_usage(&c, "--gather-res must be 4..64"); wavelet_only = true; break;
        case 1506: if (!cli_parse_int(optarg, 4, 96, &wd.brdf_resolution)) return cli_usage(&c, "--brdf-res must be 4..96"); wavelet_only = true; break;
        case 1507:
            if (!strcasecmp(optarg, "grid")) wd.param = PRT_BRDF_PARAM_GRID;
            else if (!strcasecmp(optarg, "polar")) wd.param = PRT_BRDF_PARAM_POLAR;
            else return cli_usage(&c, "--param must be grid or polar");
            wavelet_only = true;
            break;
        case 's': if (!cli_parse_int(optarg, 0, 2147483647, &seed)) return cli_usage(&c, "--seed must be a non-negative integer"); bd.seed = (uint32_t)seed; break;
        case 'k': {
            char buf[256], *save = NULL;
            snprintf(buf, sizeof buf, "%s", optarg);
            bd.kinds = 0;
            for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
                prt_transfer_kind k;
                if (!strcasecmp(tok, "all")) { bd.kinds = 7; continue; }
                if (prt_transfer_kind_parse(tok, &k)) return cli_usage(&c, "%s", prt_last_error());
                bd.kinds |= (unsigned)k;
            }
            if (!bd.kinds) return cli_usage(&c, "--kinds is empty");
            break;
        }
        case 'B':
            if (prt_brdf_parse(optarg, &bake_brdf)) return cli_usage(&c, "--brdf: %s", prt_last_error());
            bd.glossy_brdf = &bake_brdf;
            bd.glossy_exit = 1;
            break;
        case 'M': bd.glossy_exit = 1; break;
        case 'T': if (!cli_parse_int(optarg, 1, 8192, &bd.texels)) return cli_usage(&c, "--texels must be 1..8192"); break;
        case 'N': normal_map_path = optarg; break;
        case 'C':
            if (!strcasecmp(optarg, "cpca")) cd.method = PRT_COMPRESS_CPCA;
            else if (!strcasecmp(optarg, "pca")) cd.method = PRT_COMPRESS_PCA;
            else if (!strcasecmp(optarg, "vq")) cd.method = PRT_COMPRESS_VQ;
            else return cli_usage(&c, "--compress must be cpca, pca or vq");
            compress = true;
            break;
        case 'K': if (!cli_parse_int(optarg, 1, 65536, &cd.clusters)) return cli_usage(&c, "--clusters must be 1..65536"); break;
        case 'Q':
            if (!cli_parse_int(optarg, 8, 16, &quantize) || (quantize != 8 && quantize != 16)) return cli_usage(&c, "--quantize must be 8 or 16");
            break;
        case 'V': if (!cli_parse_int(optarg, 1, 300, &cd.vectors)) return cli_usage(&c, "--vectors must be 1..300"); break;
        case 'r': if (!cli_parse_float(optarg, &bd.ray_offset) || bd.ray_offset <= 0) return cli_usage(&c, "--ray-offset must be > 0"); break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_usage(&c, "unknown option");
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one SCENE argument");
    sh_only = bd.order || bd.samples || bd.kinds || bd.seed || (bd.glossy_exit && !bd.glossy_brdf) || bd.texels || normal_map_path || compress || quantize;
    if (wavelet && sh_only)
        return cli_usage(&c, "--order, --samples, --kinds, --seed, --bake-materials, --texels, --normal-map, --compress and --quantize are SH options, not for --method wavelet");
    if (!wavelet && wavelet_only) return cli_usage(&c, "--terms, --coefficients, --bits, --supersample, --gather-res, --brdf-res and --param need --method wavelet");
    if (wavelet) {
        if (bd.bounces > 8) return cli_usage(&c, "--bounces must be 0..8 for the wavelet method");
        wd.bounces = bd.bounces;
        wd.brdf = bd.glossy_brdf;
        wd.ray_offset = bd.ray_offset;
    } else if (have_bounces && bd.bounces < 1) {
        return cli_usage(&c, "--bounces must be 1..64 for the SH method");
    }
    if (!compress && (cd.clusters || cd.vectors)) return cli_usage(&c, "--clusters and --vectors need --compress");
    if (compress && quantize) return cli_usage(&c, "--quantize applies to uncompressed sets; drop --compress or --quantize");
    if (!output) return cli_usage(&c, "an output file is required (-o OUT.prt)");
    if (normal_map_path && !bd.texels) return cli_usage(&c, "--normal-map needs --texels N");
    int rc = cli_make_context(&c);
    if (rc) return rc;
    cli_catch_interrupt();
    prt_scene *scene = NULL;
    prt_transfer *t = NULL;
    prt_status st = PRT_OK;
    if (normal_map_path) {
        st = prt_image_load(normal_map_path, &normal_map);
        if (st) {
            cli_error(&c, "normal map: %s", prt_last_error());
            prt_context_release(c.ctx);
            return cli_exit_code(st);
        }
        /* 8-bit images come back sRGB-decoded; a normal map stores plain numbers, so undo it. */
        const char *ext = strrchr(normal_map_path, '.');
        if (ext && (!strcasecmp(ext, ".png") || !strcasecmp(ext, ".jpg") || !strcasecmp(ext, ".jpeg")))
            for (size_t i = 0; i < (size_t)normal_map.width * normal_map.height * 3; ++i) {
                float x = normal_map.rgb[i];
                normal_map.rgb[i] = x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
            }
        bd.normal_map = &normal_map;
    }
    st = prt_scene_load(c.ctx, argv[optind], &sd, &scene);
    if (!st) {
        if (!c.quiet) {
            fprintf(stderr, "prt bake: %s: %zu vertices, %zu triangles\n", argv[optind], prt_scene_vertex_count(scene), prt_scene_triangle_count(scene));
            /* Transfer lives at vertices: a handful of big triangles gives blocky shading. */
            if (sd.max_edge == 0 && prt_scene_triangle_count(scene) < 1000) {
                float lo[3], hi[3];
                prt_scene_bounds(scene, lo, hi);
                float diag = sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
                fprintf(stderr, "prt bake: warning: only %zu triangles; per-vertex transfer will look blocky (try --max-edge %.3g)\n",
                        prt_scene_triangle_count(scene), diag / 100.0f);
            }
        }
        bd.progress = wd.progress = cli_progress;
        bd.progress_user = wd.progress_user = &c;
        st = wavelet ? prt_bake_wavelet(c.ctx, scene, &wd, &t) : prt_bake_sh(c.ctx, scene, &bd, &t);
    }
    if (!st && wavelet && !c.quiet) cli_report_factors(t);
    if (!st && compress) {
        prt_transfer *z = NULL;
        cd.progress = cli_progress;
        cd.progress_user = &c;
        st = prt_transfer_compress(c.ctx, t, &cd, &z);
        if (!st) { prt_transfer_release(t); t = z; }
    }
    if (!st && quantize) {
        prt_transfer *q = NULL;
        st = prt_transfer_quantize(c.ctx, t, quantize, &q);
        if (!st) { prt_transfer_release(t); t = q; }
    }
    if (!st) st = prt_transfer_save(t, output);
    if (!st && !c.quiet) {
        prt_transfer_info info;
        prt_transfer_get_info(t, &info);
        if (wavelet) {
            prt_wavelet_info wi;
            prt_transfer_wavelet_info(t, &wi);
            fprintf(stderr, "prt bake: wrote %s (wavelet: %zu vectors of %d coefficients at %d bits, %.1f bytes/vertex, %.2f s on %d threads)\n",
                    output, wi.vectors, wi.coefficients, wi.bits, (double)wi.bytes / (double)info.vertex_count, info.bake_seconds, info.threads);
        } else {
            fprintf(stderr, "prt bake: wrote %s (order %d, %d samples, %.2f s on %d threads)\n", output, info.order, info.samples,
                    info.bake_seconds, info.threads);
        }
    }
    rc = st ? cli_fail(&c, st) : EXIT_OK;
    prt_transfer_release(t);
    prt_scene_release(scene);
    prt_image_free(&normal_map);
    prt_context_release(c.ctx);
    return rc;
}
