#include "cli.h"

#include <cjson/cJSON.h>
#include <getopt.h>
#include <stdio.h>

static const char *HELP =
    "usage: prt info FILE.prt [--json]\n"
    "Describes a .prt file: method, SH order, transfer kinds, mesh size, storage, bake settings.\n"
    "The file is fully validated (sizes and checksums) on the way.\n\n"
    "      --json             machine-readable output\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

int cmd_info(int argc, char **argv)
{
    cli c = {.cmd = "info", .quiet = true};
    int json = 0, opt;
    static const struct option opts[] = {{"json", no_argument, 0, 'J'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    optind = 1;
    while ((opt = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        if (opt == 'J') json = 1;
        else if (opt == 'h') { fputs(HELP, stdout); return EXIT_OK; }
        else return cli_usage(&c, "unknown option");
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    c.threads = 1;
    int rc = cli_make_context(&c);
    if (rc) return rc;
    prt_transfer *t = NULL;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (st) { rc = cli_fail(&c, st); prt_context_release(c.ctx); return rc; }
    prt_transfer_info info;
    prt_transfer_get_info(t, &info);
    const prt_transfer_kind all[5] = {PRT_TRANSFER_UNSHADOWED, PRT_TRANSFER_SHADOWED, PRT_TRANSFER_INTERREFLECTED,
                                      PRT_TRANSFER_GLOSSY_SHADOWED, PRT_TRANSFER_GLOSSY_INTERREFLECTED};
    const bool glossy = info.kinds & (PRT_TRANSFER_GLOSSY_SHADOWED | PRT_TRANSFER_GLOSSY_INTERREFLECTED);
    prt_wavelet_info wi;
    const bool wavelet = prt_transfer_wavelet_info(t, &wi);
    if (wavelet) {
        static const char *params[2] = {"grid", "polar"};
        if (json) {
            cJSON *root = cJSON_CreateObject();
            cJSON_AddStringToObject(root, "file", argv[optind]);
            cJSON_AddStringToObject(root, "method", "wavelet");
            cJSON_AddNumberToObject(root, "terms", wi.terms);
            cJSON_AddNumberToObject(root, "coefficients", wi.coefficients);
            cJSON_AddNumberToObject(root, "bits", wi.bits);
            cJSON_AddNumberToObject(root, "supersample", wi.supersample);
            cJSON_AddNumberToObject(root, "bounces", wi.bounces);
            cJSON_AddNumberToObject(root, "gather_resolution", wi.gather_resolution);
            cJSON_AddNumberToObject(root, "brdf_resolution", wi.brdf_resolution);
            cJSON_AddStringToObject(root, "brdf_parameterization", params[wi.param]);
            cJSON_AddNumberToObject(root, "vectors", (double)wi.vectors);
            cJSON_AddNumberToObject(root, "vertices", (double)info.vertex_count);
            cJSON_AddNumberToObject(root, "triangles", (double)info.triangle_count);
            cJSON_AddNumberToObject(root, "transfer_bytes", (double)wi.bytes);
            cJSON_AddNumberToObject(root, "bytes_per_vertex", (double)wi.bytes / (double)info.vertex_count);
            cJSON_AddNumberToObject(root, "bake_seconds", info.bake_seconds);
            cJSON_AddNumberToObject(root, "bake_threads", info.threads);
            cJSON_AddStringToObject(root, "source", info.source);
            cJSON *mats = cJSON_AddArrayToObject(root, "materials");
            for (int k = 1; k <= prt_transfer_brdf_count(t); ++k) {
                char spec[128];
                prt_brdf_format(prt_transfer_brdf(t, k), spec, sizeof spec);
                cJSON *o = cJSON_CreateObject();
                cJSON_AddStringToObject(o, "brdf", spec);
                cJSON_AddNumberToObject(o, "terms", prt_brdf_factors_terms(prt_transfer_wavelet_factors(t, k)));
                cJSON_AddItemToArray(mats, o);
            }
            char *text = cJSON_Print(root);
            puts(text);
            cJSON_free(text);
            cJSON_Delete(root);
        } else {
            printf("file:        %s\nmethod:      all-frequency wavelet PRT (separable BRDFs, Haar cube maps)\n", argv[optind]);
            printf("transport:   6x64x64 Haar, %d coefficients per vector, %d-bit, up to %d terms per vertex\n", wi.coefficients, wi.bits, wi.terms);
            printf("bake:        %d x %d rays per texel, %d interreflection pass%s (%dx%d gather), %.2f s on %d threads\n", wi.supersample,
                   wi.supersample, wi.bounces, wi.bounces == 1 ? "" : "es", wi.gather_resolution, wi.gather_resolution, info.bake_seconds, info.threads);
            for (int k = 1; k <= prt_transfer_brdf_count(t); ++k) {
                char spec[128];
                prt_brdf_format(prt_transfer_brdf(t, k), spec, sizeof spec);
                const prt_brdf_factors *f = prt_transfer_wavelet_factors(t, k);
                if (f) printf("material %d:  %s: %d separable terms, %dx%d %s maps\n", k, spec, prt_brdf_factors_terms(f), wi.brdf_resolution,
                              wi.brdf_resolution, params[wi.param]);
                else printf("material %d:  %s: Lambertian (one term)\n", k, spec);
            }
            printf("mesh:        %zu vertices, %zu triangles\n", info.vertex_count, info.triangle_count);
            printf("storage:     %.2f MiB transfer, %zu vectors, %.0f bytes per vertex\n", wi.bytes / 1048576.0, wi.vectors,
                   (double)wi.bytes / (double)info.vertex_count);
            printf("source:      %s\n", info.source);
        }
        prt_transfer_release(t);
        prt_context_release(c.ctx);
        return EXIT_OK;
    }
    if (json) {
        cJSON *root = cJSON_CreateObject();
        cJSON_AddStringToObject(root, "file", argv[optind]);
        cJSON_AddStringToObject(root, "method", "sh");
        cJSON_AddNumberToObject(root, "order", info.order);
        cJSON_AddNumberToObject(root, "coefficients", info.order * info.order);
        cJSON *kinds = cJSON_AddArrayToObject(root, "kinds");
        for (int k = 0; k < 5; ++k)
            if (info.kinds & all[k]) {
                cJSON *o = cJSON_CreateObject();
                cJSON_AddStringToObject(o, "kind", prt_transfer_kind_name(all[k]));
                cJSON_AddNumberToObject(o, "channels", prt_transfer_channels(t, all[k]));
                cJSON_AddNumberToObject(o, "floats_per_vertex", (double)prt_transfer_set_floats(t, all[k]));
                prt_compress_info ci;
                prt_transfer_compress_info(t, all[k], &ci);
                cJSON_AddNumberToObject(o, "bytes", (double)ci.bytes);
                if (ci.quantize_bits) cJSON_AddNumberToObject(o, "quantize_bits", ci.quantize_bits);
                if (ci.compressed) {
                    static const char *names[3] = {"cpca", "pca", "vq"};
                    cJSON_AddStringToObject(o, "compression", names[ci.method]);
                    cJSON_AddNumberToObject(o, "clusters", ci.clusters);
                    cJSON_AddNumberToObject(o, "pca_vectors", ci.vectors_total);
                    cJSON_AddNumberToObject(o, "relative_error", ci.relative_error);
                    cJSON_AddNumberToObject(o, "compression_ratio",
                                            (double)info.vertex_count * (double)prt_transfer_set_floats(t, all[k]) * 4.0 / (double)ci.bytes);
                }
                cJSON_AddItemToArray(kinds, o);
            }
        if (info.texel_width) {
            cJSON *tx = cJSON_AddObjectToObject(root, "texels");
            cJSON_AddNumberToObject(tx, "width", info.texel_width);
            cJSON_AddNumberToObject(tx, "height", info.texel_height);
            cJSON_AddNumberToObject(tx, "bytes", (double)info.texel_bytes);
            cJSON *tk = cJSON_AddArrayToObject(tx, "kinds");
            for (int k = 0; k < 3; ++k)
                if (prt_transfer_texel_coeffs(t, all[k], NULL)) cJSON_AddItemToArray(tk, cJSON_CreateString(prt_transfer_kind_name(all[k])));
        }
        cJSON_AddNumberToObject(root, "vertices", (double)info.vertex_count);
        cJSON_AddNumberToObject(root, "triangles", (double)info.triangle_count);
        cJSON_AddNumberToObject(root, "transfer_bytes", (double)info.transfer_bytes);
        cJSON_AddNumberToObject(root, "bytes_per_vertex", (double)(info.transfer_bytes - info.texel_bytes) / (double)info.vertex_count);
        cJSON_AddNumberToObject(root, "samples", info.samples);
        cJSON_AddNumberToObject(root, "bounces", info.bounces);
        cJSON_AddNumberToObject(root, "seed", info.seed);
        cJSON_AddNumberToObject(root, "bake_seconds", info.bake_seconds);
        cJSON_AddNumberToObject(root, "bake_threads", info.threads);
        cJSON_AddStringToObject(root, "source", info.source);
        if (glossy) cJSON_AddStringToObject(root, "glossy", prt_transfer_glossy_mirror(t) ? "incident radiance (lobe at render time)" : "exit radiance (BRDF baked in)");
        cJSON *mats = cJSON_AddArrayToObject(root, "materials");
        for (int k = 1; k <= prt_transfer_brdf_count(t); ++k) {
            char spec[128];
            prt_brdf_format(prt_transfer_brdf(t, k), spec, sizeof spec);
            cJSON_AddItemToArray(mats, cJSON_CreateString(spec));
        }
        char *text = cJSON_Print(root);
        puts(text);
        cJSON_free(text);
        cJSON_Delete(root);
    } else {
        printf("file:        %s\nmethod:      spherical-harmonic PRT (%s)\n", argv[optind], glossy ? "diffuse and glossy" : "diffuse");
        printf("order:       %d (%d coefficients)\n", info.order, info.order * info.order);
        printf("kinds:      ");
        for (int k = 0; k < 5; ++k)
            if (info.kinds & all[k]) printf(" %s (%d ch)", prt_transfer_kind_name(all[k]), prt_transfer_channels(t, all[k]));
        printf("\n");
        if (glossy)
            printf("glossy:      %s\n", prt_transfer_glossy_mirror(t) ? "transfer matrices to incident radiance; the lobe is applied when rendering"
                                                                      : "transfer matrices to exit radiance (BRDF baked in)");
        for (int k = 1; k <= prt_transfer_brdf_count(t); ++k) {
            char spec[128];
            prt_brdf_format(prt_transfer_brdf(t, k), spec, sizeof spec);
            printf("material %d:  %s\n", k, spec);
        }
        for (int k = 0; k < 5; ++k) {
            prt_compress_info ci;
            if (!(info.kinds & all[k]) || prt_transfer_compress_info(t, all[k], &ci)) continue;
            if (ci.quantize_bits) printf("quantized:   %s %d-bit\n", prt_transfer_kind_name(all[k]), ci.quantize_bits);
            if (!ci.compressed) continue;
            static const char *names[3] = {"clustered PCA", "PCA", "VQ"};
            double raw = (double)info.vertex_count * (double)prt_transfer_set_floats(t, all[k]) * 4.0;
            printf("compressed:  %s %s, %d clusters, %d PCA vectors, %.1f bytes/vertex (%.1fx smaller), relative error %.4f\n",
                   prt_transfer_kind_name(all[k]), names[ci.method], ci.clusters, ci.vectors_total, (double)ci.bytes / (double)info.vertex_count,
                   raw / (double)ci.bytes, ci.relative_error);
        }
        if (info.texel_width) {
            printf("texels:      %d x %d (", info.texel_width, info.texel_height);
            for (int k = 0, first = 1; k < 3; ++k)
                if (prt_transfer_texel_coeffs(t, all[k], NULL)) { printf("%s%s", first ? "" : ", ", prt_transfer_kind_name(all[k])); first = 0; }
            printf("), %.2f MiB\n", info.texel_bytes / 1048576.0);
        }
        printf("mesh:        %zu vertices, %zu triangles%s\n", info.vertex_count, info.triangle_count, prt_transfer_uvs(t) ? ", with UVs" : "");
        printf("storage:     %.2f MiB transfer, %.0f bytes per vertex (vertex sets)\n", info.transfer_bytes / 1048576.0,
               (double)(info.transfer_bytes - info.texel_bytes) / (double)info.vertex_count);
        printf("bake:        %d samples, %d bounces, seed %u, %.2f s on %d threads\n", info.samples, info.bounces, info.seed,
               info.bake_seconds, info.threads);
        printf("source:      %s\n", info.source);
    }
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return EXIT_OK;
}
