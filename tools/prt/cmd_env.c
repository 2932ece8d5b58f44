#include "cli.h"

#include <cjson/cJSON.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *HELP =
    "usage: prt env [PROBE] [options]\n"
    "Projects an environment probe (or, without PROBE, the procedural sky) onto real orthonormal\n"
    "spherical harmonics and prints the coefficients as JSON: \"coefficients\"[i] = [r, g, b] for\n"
    "index i = l*(l+1)+m. With --image, also writes the band-limited lighting as a lat-long\n"
    "image; --irradiance makes that image E(n)/pi, the exit radiance of a white Lambertian\n"
    "surface facing n (the irradiance map game engines use).\n\n"
    "  -o, --output FILE      write the JSON there instead of standard output\n"
    "      --order N          SH order, 1..10 (default 3: the 9 irradiance coefficients)\n"
    "      --image FILE       band-limited reconstruction (.png .exr .hdr .pfm)\n"
    "      --irradiance       make --image the irradiance map\n"
    "      --width N          --image width (default 512; height is half)\n"
    "      --layout L         latlong | angular | cross | auto (default auto)\n"
    "      --rotate Y[,P[,R]] rotate before projecting, degrees\n"
    "      --intensity S      scale (default 1)\n"
    "      --sun X,Y,Z        sun direction of the procedural sky (without PROBE)\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

enum { OPT_ORDER = 2100, OPT_IMAGE, OPT_IRRADIANCE, OPT_IMAGE_WIDTH };

static const char *layout_name(prt_env_layout l)
{
    return l == PRT_ENV_LATLONG ? "latlong" : l == PRT_ENV_ANGULAR ? "angular" : l == PRT_ENV_VCROSS ? "cross" : "auto";
}

int cmd_env(int argc, char **argv)
{
    cli c = {.cmd = "env"};
    cli_light light = {.intensity = 1.0f};
    const char *output = NULL, *image = NULL;
    int order = 3, width = 512, irradiance = 0;
    bool sun = false;
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"order", required_argument, 0, OPT_ORDER}, {"image", required_argument, 0, OPT_IMAGE},
        {"irradiance", no_argument, 0, OPT_IRRADIANCE}, {"width", required_argument, 0, OPT_IMAGE_WIDTH}, CLI_LIGHT_LONG_OPTIONS,
        {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:qh", opts, NULL)) != -1) {
        if (opt == OPT_ENV) return cli_usage(&c, "give the probe as the argument: prt env PROBE");
        if (opt == OPT_SUN) sun = true;
        int r = cli_light_option(&c, &light, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case OPT_ORDER: if (!cli_parse_int(optarg, 1, PRT_SH_MAX_ORDER, &order)) return cli_usage(&c, "--order must be 1..%d", PRT_SH_MAX_ORDER); break;
        case OPT_IMAGE: image = optarg; break;
        case OPT_IRRADIANCE: irradiance = 1; break;
        case OPT_IMAGE_WIDTH: if (!cli_parse_int(optarg, 2, 16384, &width) || width % 2) return cli_usage(&c, "--width must be even, 2..16384"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind < argc - 1) return cli_usage(&c, "expected at most one PROBE argument");
    if (optind == argc - 1) { light.env_path = argv[optind]; light.set_source = true; }
    if (irradiance && !image) return cli_usage(&c, "--irradiance needs --image FILE");
    if (light.set_lights || light.set_emission || light.have_brdf || light.paint_count || light.brdf_of_count ||
        light.control_count)
        return cli_usage(&c, "--light, --emission, --brdf(-all), --albedo-of, --brdf-of and --control do not apply: "
                             "prt env projects an environment");
    if (sun && light.env_path)
        return cli_usage(&c, "--sun places the procedural sky's sun: not with a PROBE");
    if (light.env_none) return cli_usage(&c, "--env none leaves nothing to project");
    int rc = cli_make_context(&c);
    if (rc) return rc;
    prt_sh_light sh;
    prt_env_layout layout = PRT_ENV_AUTO;
    prt_image img = {0};
    prt_status st = cli_light_project(&c, &light, order, &sh, &layout);
    if (!st && image) st = prt_sh_light_to_image(&sh, width, irradiance, &img);
    if (!st) st = cli_check_interrupt(&c);
    if (!st && image) st = prt_image_save(image, &img, NULL);
    if (st) {
        rc = cli_fail(&c, st);
    } else {
        cJSON *root = cJSON_CreateObject();
        cJSON_AddStringToObject(root, "source", light.env_path ? light.env_path : "procedural sky");
        cJSON_AddStringToObject(root, "layout", layout_name(layout));
        cJSON_AddNumberToObject(root, "order", order);
        cJSON_AddStringToObject(root, "basis", "real orthonormal SH, index l*(l+1)+m; y(1,-1), y(1,0), y(1,1) ~ y, z, x; +y is up");
        cJSON *arr = cJSON_AddArrayToObject(root, "coefficients");
        for (int i = 0; i < order * order; ++i) {
            float v[3] = {sh.coeffs[0][i], sh.coeffs[1][i], sh.coeffs[2][i]};
            cJSON_AddItemToArray(arr, cJSON_CreateFloatArray(v, 3));
        }
        char *text = cJSON_Print(root);
        cJSON_Delete(root);
        /* A file is written beside its final name and renamed, so it is never seen half-written. */
        char tmp[1100];
        if (output) snprintf(tmp, sizeof tmp, "%s.tmp", output);
        FILE *f = output ? fopen(tmp, "w") : stdout;
        bool ok = f && fputs(text, f) >= 0 && fputc('\n', f) >= 0;
        if (output && f) ok = (fclose(f) == 0) && ok && rename(tmp, output) == 0;
        if (!ok) {
            if (output) remove(tmp);
            cli_error(&c, "cannot write '%s'", output ? output : "(stdout)");
            rc = EXIT_FAILURE_INPUT;
        }
        cJSON_free(text);
        if (!rc && image && !c.quiet) fprintf(stderr, "prt env: wrote %s\n", image);
    }
    prt_image_free(&img);
    prt_context_release(c.ctx);
    return rc;
}
