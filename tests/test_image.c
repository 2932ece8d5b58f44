/* Images and environment maps: file round trips, layouts, SH projection, bad pixels. */
#include "common.h"

#include <unistd.h>


/* A known band-limited radiance: positive everywhere, with structure in every band < 3. */

static float known_eval(const double d[3])
{
    double y[9];
    prt_sh_eval(3, d, y);
    double s = 0;
    for (int i = 0; i < 9; ++i) s += test_known_sh[i] * y[i];
    return (float)s;
}

/* Direction of a pixel centre, per the layout conventions documented in prt/lighting.h. */
static bool layout_dir(prt_env_layout layout, int w, int h, int x, int y, double d[3])
{
    if (layout == PRT_ENV_LATLONG) {
        double th = M_PI * (y + 0.5) / h, ph = 2 * M_PI * ((x + 0.5) / w - 0.5);
        d[0] = sin(th) * sin(ph); d[1] = cos(th); d[2] = -sin(th) * cos(ph);
        return true;
    }
    if (layout == PRT_ENV_ANGULAR) {
        double a = 2.0 * (x + 0.5) / w - 1, b = 1 - 2.0 * (y + 0.5) / h, r = sqrt(a * a + b * b);
        if (r >= 1) return false;
        double th = M_PI * r;
        d[0] = a / r * sin(th); d[1] = b / r * sin(th); d[2] = -cos(th);
        return true;
    }
    int s = w / 3, col = x / s, row = y / s;
    double fu = 2.0 * (x - col * s + 0.5) / s - 1, fv = 2.0 * (y - row * s + 0.5) / s - 1;
    double v[3];
    if (col == 1 && row == 0) { v[0] = fu; v[1] = 1; v[2] = -fv; }
    else if (col == 0 && row == 1) { v[0] = -1; v[1] = -fv; v[2] = -fu; }
    else if (col == 1 && row == 1) { v[0] = fu; v[1] = -fv; v[2] = -1; }
    else if (col == 2 && row == 1) { v[0] = 1; v[1] = -fv; v[2] = fu; }
    else if (col == 1 && row == 2) { v[0] = fu; v[1] = -1; v[2] = fv; }
    else if (col == 1 && row == 3) { v[0] = fu; v[1] = fv; v[2] = 1; }
    else return false;
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int i = 0; i < 3; ++i) d[i] = v[i] / l;
    return true;
}

static void make_env_image(prt_env_layout layout, int w, int h, prt_image *img)
{
    img->width = w;
    img->height = h;
    img->rgb = calloc((size_t)w * h * 3, sizeof(float));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double d[3];
            if (!layout_dir(layout, w, h, x, y, d)) continue;
            float v = known_eval(d);
            for (int c = 0; c < 3; ++c) img->rgb[((size_t)y * w + x) * 3 + c] = v * (c == 0 ? 1.0f : c == 1 ? 0.5f : 0.25f);
        }
}

static void test_layouts_project_known_function(void **state)
{
    (void)state;
    const prt_env_layout layouts[3] = {PRT_ENV_LATLONG, PRT_ENV_ANGULAR, PRT_ENV_VCROSS};
    const int dims[3][2] = {{512, 256}, {512, 512}, {384, 512}};
    const char *names[3] = {"latlong.pfm", "angular.exr", "cross.hdr"};
    for (int k = 0; k < 3; ++k) {
        prt_image img;
        make_env_image(layouts[k], dims[k][0], dims[k][1], &img);
        char path[512];
        snprintf(path, sizeof path, "%s/%s", test_dir, names[k]);
        assert_int_equal(prt_image_save(path, &img, NULL), PRT_OK);
        prt_image_free(&img);
        prt_envmap *env = NULL;
        /* Layout detection from the aspect ratio. */
        assert_int_equal(prt_envmap_load(path, PRT_ENV_AUTO, &env), PRT_OK);
        assert_int_equal(prt_envmap_layout(env), layouts[k]);
        prt_sh_light L;
        assert_int_equal(prt_envmap_project_sh(env, 4, &L), PRT_OK);
        /* HDR (RGBE) keeps ~1% precision, EXR half ~0.1%; discretization adds a little. */
        double tol = k == 2 ? 0.03 : 0.01, worst = 0;
        for (int i = 0; i < 16; ++i) {
            double expect = i < 9 ? test_known_sh[i] : 0.0;
            worst = fmax(worst, fabs(L.coeffs[0][i] - expect));
            worst = fmax(worst, fabs(L.coeffs[2][i] - 0.25 * expect));
        }
        if (worst > tol * 3.0) fail_msg("%s: SH projection off by %g", names[k], worst);
        /* Lookup inverts the pixel mapping. */
        for (int j = 0; j < 50; ++j) {
            double z = 1 - 2 * (j + 0.5) / 50, r = sqrt(1 - z * z), ph = j * 2.39996;
            double d[3] = {r * cos(ph), z, r * sin(ph)};
            float df[3] = {(float)d[0], (float)d[1], (float)d[2]}, rgb[3];
            prt_envmap_lookup(env, df, rgb);
            if (fabsf(rgb[0] - known_eval(d)) > 0.05f) fail_msg("%s: lookup at (%g %g %g) = %g, expected %g", names[k], d[0], d[1], d[2], rgb[0], known_eval(d));
        }
        prt_envmap_release(env);
    }
}

static void test_latlong_orientation(void **state)
{
    (void)state;
    /* A lat-long map bright only in its top rows lights from +y; bright at its centre column
     * lights from -z: band 1 coefficients are (y, z, x). */
    prt_image img = {64, 32, calloc(64 * 32 * 3, sizeof(float))};
    for (int x = 0; x < 64; ++x) img.rgb[x * 3] = img.rgb[x * 3 + 1] = img.rgb[x * 3 + 2] = 1;
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_AUTO, &env), PRT_OK);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 2, &L), PRT_OK);
    assert_true(L.coeffs[0][1] > 0 && fabsf(L.coeffs[0][2]) < 1e-6f && fabsf(L.coeffs[0][3]) < 1e-6f);
    prt_envmap_release(env);
    prt_image img2 = {64, 32, calloc(64 * 32 * 3, sizeof(float))};
    for (int y = 12; y < 20; ++y)
        for (int x = 31; x <= 32; ++x) img2.rgb[(y * 64 + x) * 3] = 1;
    assert_int_equal(prt_envmap_from_image(&img2, PRT_ENV_LATLONG, &env), PRT_OK);
    assert_int_equal(prt_envmap_project_sh(env, 2, &L), PRT_OK);
    assert_true(L.coeffs[0][2] < 0);                            /* -z */
    assert_true(fabsf(L.coeffs[0][3]) < 1e-3f * fabsf(L.coeffs[0][2]));   /* no x */
    prt_envmap_release(env);
}

static void test_constant_env_and_irradiance_map(void **state)
{
    (void)state;
    prt_image img = {128, 64, malloc(128 * 64 * 3 * sizeof(float))};
    for (int i = 0; i < 128 * 64 * 3; ++i) img.rgb[i] = 2.0f;
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 5, &L), PRT_OK);
    assert_true(fabsf(L.coeffs[1][0] - 2.0f * sqrtf(4 * (float)M_PI)) < 1e-4f);
    for (int i = 1; i < 25; ++i)
        if (fabsf(L.coeffs[1][i]) > 1e-4f) fail_msg("coefficient %d = %g", i, L.coeffs[1][i]);
    prt_image irr;
    assert_int_equal(prt_sh_light_to_image(&L, 64, 1, &irr), PRT_OK);
    /* A white Lambertian surface under constant radiance 2 reflects radiance 2. */
    for (int i = 0; i < 64 * 32 * 3; ++i) assert_true(fabsf(irr.rgb[i] - 2.0f) < 1e-3f);
    prt_image_free(&irr);
    prt_envmap_release(env);
}

static void test_bad_pixels_rejected(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/nan.pfm", test_dir);
    FILE *f = fopen(path, "wb");
    fprintf(f, "PF\n4 2\n-1.0\n");
    for (int i = 0; i < 24; ++i) {
        float v = i == 13 ? NAN : 1.0f;
        fwrite(&v, 4, 1, f);
    }
    fclose(f);
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_load(path, PRT_ENV_AUTO, &env), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "not finite"));
    assert_non_null(strstr(prt_last_error(), "nan.pfm"));
    snprintf(path, sizeof path, "%s/inf.pfm", test_dir);
    f = fopen(path, "wb");
    fprintf(f, "PF\n4 2\n-1.0\n");
    for (int i = 0; i < 24; ++i) {
        float v = i == 2 ? INFINITY : 1.0f;
        fwrite(&v, 4, 1, f);
    }
    fclose(f);
    assert_int_equal(prt_envmap_load(path, PRT_ENV_AUTO, &env), PRT_ERR_FORMAT);
    /* Truncated pixels, garbage, wrong aspect. */
    snprintf(path, sizeof path, "%s/short.pfm", test_dir);
    f = fopen(path, "wb");
    fprintf(f, "PF\n4 2\n-1.0\n");
    fclose(f);
    assert_int_equal(prt_envmap_load(path, PRT_ENV_AUTO, &env), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "truncated"));
    snprintf(path, sizeof path, "%s/garbage.hdr", test_dir);
    f = fopen(path, "wb");
    fprintf(f, "this is not an image");
    fclose(f);
    assert_int_equal(prt_envmap_load(path, PRT_ENV_AUTO, &env), PRT_ERR_FORMAT);
    prt_image odd = {30, 7, calloc(30 * 7 * 3, sizeof(float))};
    assert_int_equal(prt_envmap_from_image(&odd, PRT_ENV_AUTO, &env), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "layout"));
    prt_image_free(&odd);
    assert_int_equal(prt_envmap_load("/nonexistent/probe.hdr", PRT_ENV_AUTO, &env), PRT_ERR_IO);
    assert_null(env);
}

static void test_image_round_trips(void **state)
{
    (void)state;
    prt_image img = {7, 5, malloc(7 * 5 * 3 * sizeof(float))};
    for (int i = 0; i < 105; ++i) img.rgb[i] = 0.01f * (float)i + 0.001f;
    const char *ext[4] = {"pfm", "exr", "hdr", "png"};
    const double tol[4] = {0, 2e-3, 1e-2, 2e-2};
    for (int k = 0; k < 4; ++k) {
        char path[512];
        snprintf(path, sizeof path, "%s/rt.%s", test_dir, ext[k]);
        prt_image_save_desc sd = {0};
        sd.tonemap = 2;   /* clamp: PNG keeps values < 1 */
        assert_int_equal(prt_image_save(path, &img, &sd), PRT_OK);
        prt_image back;
        assert_int_equal(prt_image_load(path, &back), PRT_OK);
        assert_int_equal(back.width, 7);
        assert_int_equal(back.height, 5);
        for (int i = 0; i < 105; ++i) {
            double ref = k == 3 ? fmin(img.rgb[i], 1.0) : img.rgb[i], err = fabs(back.rgb[i] - ref);
            if (err > tol[k] * fmax(ref, 0.05)) fail_msg("%s pixel %d: %g vs %g", ext[k], i, back.rgb[i], ref);
        }
        prt_image_free(&back);
    }
    assert_int_equal(prt_image_save("/tmp/x.bmpx", &img, NULL), PRT_ERR_INVALID_ARG);
    prt_image_free(&img);
    /* A piece of an exported offset map (halves) whose ZIP chunk compresses to exactly its packed
     * size: OpenEXRCore up to 3.4.7 stored the zlib bytes, which read back as raw pixels (a NaN
     * at pixel (2, 3)); it must round-trip exactly. */
    static const float piece[72] = {
        0.0389404297f, 0.0374450684f, 0.0359802246f, 0.0985717773f, 0.0931396484f, 0.0878295898f, 0.0617675781f, 0.0594482422f, 0.0570983887f,
        0.0169219971f, 0.0162811279f, 0.0156402588f, 0.0152359009f, 0.0146560669f, 0.0140762329f, 0.0110015869f, 0.0105819702f, 0.0101699829f,
        0.00423049927f, 0.00407028198f, 0.0039100647f, 0.0194702148f, 0.0187225342f, 0.0179901123f, 0.0194702148f, 0.0187225342f, 0.0179901123f,
        0, 0, 0, 0.00761795044f, 0.00732803345f, 0.00703811646f, 0.0262298584f, 0.0252380371f, 0.0242462158f,
        0.0938720703f, 0.0869140625f, 0.0802001953f, 0.000846385956f, 0.000814437866f, 0.000782012939f, 0.0613098145f, 0.0572814941f, 0.0534057617f,
        0.0938720703f, 0.0869140625f, 0.0802001953f, 0.0477905273f, 0.0442810059f, 0.0408935547f, 0.00846099854f, 0.00814056396f, 0.00782012939f,
        0.0469360352f, 0.0434570312f, 0.0401000977f, 0, 0, 0, 0.0469360352f, 0.0434570312f, 0.0401000977f,
        0.0938720703f, 0.0869140625f, 0.0802001953f, 0.0469360352f, 0.0434570312f, 0.0401000977f, 0, 0, 0};
    prt_image small = {3, 8, (float *)piece}, back;
    char path[512];
    snprintf(path, sizeof path, "%s/piece.exr", test_dir);
    assert_int_equal(prt_image_save(path, &small, NULL), PRT_OK);
    assert_int_equal(prt_image_load(path, &back), PRT_OK);
    assert_memory_equal(back.rgb, piece, sizeof piece);
    prt_image_free(&back);
}

/* An animated PNG: a valid PNG whose first frame is what viewers without APNG show, then one
 * fcTL per frame and the rest of the frames in fdAT chunks, numbered in one sequence; every
 * chunk's CRC holds. */
static void test_animation(void **state)
{
    (void)state;
    prt_image frames[3];
    for (int f = 0; f < 3; ++f) {
        frames[f] = (prt_image){6, 4, malloc(6 * 4 * 3 * sizeof(float))};
        for (int i = 0; i < 72; ++i) frames[f].rgb[i] = 0.1f + 0.25f * (float)f + 0.001f * (float)i;
    }
    char path[512];
    snprintf(path, sizeof path, "%s/anim.png", test_dir);
    prt_image_save_desc sd = {.tonemap = 2};
    assert_int_equal(prt_image_save_animation(path, frames, 3, 10, &sd), PRT_OK);
    prt_image back;
    assert_int_equal(prt_image_load(path, &back), PRT_OK);
    assert_int_equal(back.width, 6);
    assert_int_equal(back.height, 4);
    for (int i = 0; i < 72; ++i) assert_true(fabsf(back.rgb[i] - frames[0].rgb[i]) < 0.02f * frames[0].rgb[i] + 1e-3f);
    prt_image_free(&back);
    size_t n = 0;
    unsigned char *d = test_slurp(path, &n);
    uint32_t expect_seq = 0;
    int fctl = 0, fdat = 0, actl_frames = -1;
    size_t at = 8;
    while (at + 12 <= n) {
        const uint32_t len = (uint32_t)d[at] << 24 | (uint32_t)d[at + 1] << 16 | (uint32_t)d[at + 2] << 8 | d[at + 3];
        assert_true(len <= n - at - 12);
        const unsigned char *type = d + at + 4, *data = d + at + 8;
        const uint32_t crc = (uint32_t)d[at + 8 + len] << 24 | (uint32_t)d[at + 9 + len] << 16 | (uint32_t)d[at + 10 + len] << 8 | d[at + 11 + len];
        assert_int_equal(crc, (uint32_t)crc32(0L, type, len + 4));
        if (!memcmp(type, "acTL", 4)) actl_frames = data[3];
        if (!memcmp(type, "fcTL", 4) || !memcmp(type, "fdAT", 4)) {
            const uint32_t seq = (uint32_t)data[0] << 24 | (uint32_t)data[1] << 16 | (uint32_t)data[2] << 8 | data[3];
            assert_int_equal(seq, expect_seq++);
            fctl += !memcmp(type, "fcTL", 4);
            fdat += !memcmp(type, "fdAT", 4);
        }
        at += 12 + len;
    }
    assert_int_equal(at, n);
    assert_int_equal(actl_frames, 3);
    assert_int_equal(fctl, 3);
    assert_true(fdat >= 2);
    free(d);
    /* Frames of another size, no frames, another format: refused. */
    frames[2].width = 4;
    frames[2].height = 6;
    assert_int_equal(prt_image_save_animation(path, frames, 3, 10, NULL), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_image_save_animation(path, frames, 0, 10, NULL), PRT_ERR_INVALID_ARG);
    snprintf(path, sizeof path, "%s/anim.exr", test_dir);
    assert_int_equal(prt_image_save_animation(path, frames, 2, 10, NULL), PRT_ERR_INVALID_ARG);
    for (int f = 0; f < 3; ++f) free(frames[f].rgb);
}

static void test_sky(void **state)
{
    (void)state;
    prt_sky_desc d = {0};
    d.sun_dir[0] = 1; d.sun_dir[1] = 1; d.sun_dir[2] = 0;
    prt_envmap *env = NULL;
    assert_int_equal(prt_sky_create(&d, &env), PRT_OK);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 3, &L), PRT_OK);
    /* The sun at +x+y dominates band 1: x and y components positive, z about zero. */
    assert_true(L.coeffs[0][3] > 0.5f && L.coeffs[0][1] > 0.5f && fabsf(L.coeffs[0][2]) < 0.05f * L.coeffs[0][3]);
    prt_envmap_release(env);
    d.sun_angle_deg = 120;
    assert_int_equal(prt_sky_create(&d, &env), PRT_ERR_INVALID_ARG);
}

/* A Radiance file written the way Radiance writes it: header, resolution, new-style runs. */
static size_t rgbe_file(unsigned char *buf, int w, int h, bool flip)
{
    size_t n = (size_t)sprintf((char *)buf, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1\n\n%cY %d +X %d\n", flip ? '+' : '-', h, w);
    for (int y = 0; y < h; ++y) {
        buf[n++] = 2; buf[n++] = 2; buf[n++] = (unsigned char)(w >> 8); buf[n++] = (unsigned char)(w & 255);
        for (int c = 0; c < 4; ++c) {
            /* Half the row as one run, the rest as literals. */
            buf[n++] = (unsigned char)(128 + w / 2);
            buf[n++] = (unsigned char)(c == 3 ? 129 + y % 3 : 64 + 16 * c + y);
            buf[n++] = (unsigned char)(w - w / 2);
            for (int x = w / 2; x < w; ++x) buf[n++] = (unsigned char)(c == 3 ? 130 : 10 * c + x);
        }
    }
    return n;
}

/* prt's own Radiance reader: exact values, both orientations, the old run convention; a 100-byte
 * file with truncated runs (which hung stb), 16-bit PGM (which overread in stb) and the other
 * formats stb would take are refused; thousands of mutated files end in OK or a clear error. */
static void test_hdr_reader_and_signatures(void **state)
{
    (void)state;
    unsigned char buf[8192];
    prt_image img;
    const int w = 16, h = 5;
    size_t n = rgbe_file(buf, w, h, false);
    assert_int_equal(prt_image_load_memory(buf, n, &img), PRT_OK);
    assert_int_equal(img.width, w);
    assert_int_equal(img.height, h);
    for (int y = 0; y < h; ++y) {
        /* Exponent 129 + y % 3 for the run half: m * 2^(e - 136). */
        const float f = ldexpf(1.0f, 129 + y % 3 - 136), g = ldexpf(1.0f, 130 - 136);
        assert_float_equal(img.rgb[((size_t)y * w) * 3 + 1], (float)(64 + 16 + y) * f, 1e-6f);
        assert_float_equal(img.rgb[((size_t)y * w + w - 1) * 3 + 2], (float)(20 + w - 1) * g, 1e-6f);
    }
    prt_image flipped;
    n = rgbe_file(buf, w, h, true);
    assert_int_equal(prt_image_load_memory(buf, n, &flipped), PRT_OK);
    assert_memory_equal(flipped.rgb, img.rgb + (size_t)(h - 1) * w * 3, (size_t)w * 3 * sizeof(float));   /* +Y: bottom row first */
    prt_image_free(&flipped);
    /* Old runs: width 4 (too narrow for new runs), a pixel then "repeat it 3 times". */
    n = (size_t)sprintf((char *)buf, "#?RGBE\n\n-Y 1 +X 4\n");
    const unsigned char old[8] = {100, 50, 25, 128, 1, 1, 1, 3};
    memcpy(buf + n, old, 8);
    assert_int_equal(prt_image_load_memory(buf, n + 8, &flipped), PRT_OK);
    for (int x = 0; x < 4; ++x) assert_float_equal(flipped.rgb[x * 3], 100.0f / 256.0f, 1e-7f);
    prt_image_free(&flipped);
    /* Truncated runs: an error at once, not a hang. */
    n = rgbe_file(buf, w, h, false);
    assert_int_equal(prt_image_load_memory(buf, 100, &flipped), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), ".hdr"));
    /* A size the bytes cannot hold is refused before anything is allocated. */
    n = (size_t)sprintf((char *)buf, "#?RADIANCE\n\n-Y 30000 +X 30000\n\2\2");
    assert_int_equal(prt_image_load_memory(buf, n, &flipped), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "shorter"));
    /* Formats prt does not document never reach stb. */
#define BYTES(s) {s, sizeof s - 1}
    const struct { const char *data; size_t n; } others[] = {
        BYTES("P5\n2 2\n65535\n\0\1\0\2\0\3\0\4"), BYTES("BM\0\0\0\0\0\0\0\0"), BYTES("GIF89a\1\0\1\0"), BYTES("8BPS\0\1")};
#undef BYTES
    for (size_t i = 0; i < sizeof others / sizeof others[0]; ++i) {
        assert_int_equal(prt_image_load_memory(others[i].data, others[i].n, &flipped), PRT_ERR_FORMAT);
        assert_non_null(strstr(prt_last_error(), "not an image prt can read"));
    }
    /* Mutations of a valid file: bytes flipped, cut, repeated; every one loads or fails cleanly
     * (under the sanitizer build this is a small fuzz run of the reader). */
    n = rgbe_file(buf, w, h, false);
    uint64_t r = 0x9e3779b97f4a7c15ULL;
    unsigned char m[8192];
    int loaded = 0;
    for (int it = 0; it < 20000; ++it) {
        memcpy(m, buf, n);
        size_t len = n;
        for (int k = 0; k < 1 + it % 4; ++k) {
            r ^= r << 13; r ^= r >> 7; r ^= r << 17;
            const size_t at = (size_t)(r >> 16) % len;
            switch ((r >> 8) % 4) {
            case 0: m[at] ^= (unsigned char)(1u << (r % 8)); break;
            case 1: m[at] = (unsigned char)(r >> 40); break;
            case 2: len = at + 1; break;
            default: if (len + 4 < sizeof m) { memmove(m + at + 4, m + at, len - at); memcpy(m + at, &r, 4); len += 4; } break;
            }
        }
        prt_image out;
        if (prt_image_load_memory(m, len, &out) == PRT_OK) { loaded++; prt_image_free(&out); }
    }
    print_message("mutated .hdr files: %d of 20000 still load\n", loaded);
    prt_image_free(&img);
}

static char *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    *n = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    char *d = malloc(*n + 1);
    assert_int_equal(fread(d, 1, *n, f), *n);
    d[*n] = 0;
    fclose(f);
    return d;
}

static uint32_t le32(const char *p) { const unsigned char *u = (const unsigned char *)p; return u[0] | u[1] << 8 | (uint32_t)u[2] << 16 | (uint32_t)u[3] << 24; }

/* Custom vertex attributes in glTF (how prt export hands SH transfer to other renderers): named as
 * asked, a valid GLB container around them, refused where the format has none or a name is bad. */
static void test_mesh_export_attributes(void **state)
{
    (void)state;
    const float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, rgb[12] = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f, 0.9f, 1, 1, 1};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    float attr[4 * 2 * 4];
    for (int i = 0; i < 32; ++i) attr[i] = 1000.0f + i;   /* beyond [0, 1]: not colours, kept as they are */
    const char *const names[2] = {"_SH0", "_ALBEDO"};
    prt_mesh_export_desc d = {pos, NULL, 4, idx, 2, rgb, PRT_COLOURS_LINEAR, 0, 2, attr, names};
    char gltf[600], glb[600], bin[600];
    snprintf(gltf, sizeof gltf, "%s/attr.gltf", test_dir);
    snprintf(glb, sizeof glb, "%s/attr.glb", test_dir);
    snprintf(bin, sizeof bin, "%s/attr.bin", test_dir);
    assert_int_equal(prt_mesh_export(gltf, &d), PRT_OK);
    size_t n;
    char *text = slurp(gltf, &n);
    assert_non_null(strstr(text, "\"_SH0\""));
    assert_non_null(strstr(text, "\"_ALBEDO\""));
    assert_non_null(strstr(text, "\"COLOR_0\""));
    assert_null(strstr(text, "COLOR_1"));
    /* What the glTF-Validator would report of assimp's JSON is gone: extensions declared but
     * unused (FB_ngon_encoding, KHR_materials_volume); the one declared is the one used (the
     * colours are light: the material is unlit); the generator names prt. */
    assert_null(strstr(text, "FB_ngon_encoding"));
    assert_null(strstr(text, "KHR_materials_volume"));
    assert_non_null(strstr(text, "\"extensionsUsed\":[\"KHR_materials_unlit\"]"));
    assert_non_null(strstr(text, "\"extensions\":{\"KHR_materials_unlit\":{}}"));
    assert_non_null(strstr(text, "\"generator\":\"prt "));
    free(text);
    /* The values travel unclamped: 1000 + i is in the buffer as a float. */
    char *data = slurp(bin, &n);
    int found = 0;
    for (size_t at = 0; at + 4 <= n; at += 4) {
        float f;
        memcpy(&f, data + at, 4);
        found += f == 1031.0f || f == 1000.0f;
    }
    assert_int_equal(found, 2);
    free(data);

    assert_int_equal(prt_mesh_export(glb, &d), PRT_OK);
    data = slurp(glb, &n);
    assert_memory_equal(data, "glTF", 4);
    assert_int_equal(le32(data + 4), 2);
    assert_int_equal(le32(data + 8), n);               /* the header's length after the rewrite */
    const uint32_t json_len = le32(data + 12);
    assert_int_equal(json_len % 4, 0);                 /* chunks stay 4-byte aligned */
    assert_memory_equal(data + 16, "JSON", 4);
    assert_true(20 + json_len + 8 <= n);
    assert_memory_equal(data + 20 + json_len + 4, "BIN", 3);
    assert_int_equal(20 + json_len + 8 + le32(data + 20 + json_len), n);
    data[20 + json_len - 1] = 0;
    assert_non_null(strstr(data + 20, "\"_ALBEDO\""));
    free(data);

    /* Refused: formats without custom attributes, names glTF does not allow, too many. */
    char ply[600];
    snprintf(ply, sizeof ply, "%s/attr.ply", test_dir);
    assert_int_equal(prt_mesh_export(ply, &d), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "glTF"));
    const char *const bad[4][2] = {{"SH0", "_A"}, {"_sh0", "_A"}, {"_A", "_A"}, {"_A", "_THIS_NAME_IS_LONGER_THAN_31_BYTES"}};
    for (int k = 0; k < 4; ++k) {
        d.attribute_names = bad[k];
        assert_int_equal(prt_mesh_export(gltf, &d), PRT_ERR_INVALID_ARG);
    }
    d.attribute_names = names;
    d.attribute_count = 8;
    assert_int_equal(prt_mesh_export(gltf, &d), PRT_ERR_INVALID_ARG);
    d.attribute_count = 2;

    /* What glTF cannot hold is refused, not written: NaN or infinity in any accessor, a NORMAL
     * that is no direction. Normals of other lengths are written as unit vectors. */
    float bad_pos[12], bad_attr[32], nrm[12] = {0, 0, 2, 0, 0, 1, 0, 0, 1, 0, 0, 0.5f};
    memcpy(bad_pos, pos, sizeof pos);
    bad_pos[4] = NAN;
    d.positions = bad_pos;
    assert_int_equal(prt_mesh_export(glb, &d), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "position"));
    d.positions = pos;
    memcpy(bad_attr, attr, sizeof attr);
    bad_attr[31] = INFINITY;
    d.attributes = bad_attr;
    assert_int_equal(prt_mesh_export(glb, &d), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "attribute"));
    d.attributes = attr;
    d.normals = nrm;
    assert_int_equal(prt_mesh_export(gltf, &d), PRT_OK);
    text = slurp(gltf, &n);   /* the NORMAL accessor's bounds: every normal (0, 0, 1) */
    assert_non_null(strstr(text, "\"max\":[0,0,1],\"min\":[0,0,1]"));
    free(text);
    nrm[4] = NAN;
    assert_int_equal(prt_mesh_export(gltf, &d), PRT_ERR_INVALID_ARG);
    nrm[4] = 0;
    nrm[5] = 0;
    assert_int_equal(prt_mesh_export(gltf, &d), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "normal of vertex 1"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layouts_project_known_function),
        cmocka_unit_test(test_latlong_orientation),
        cmocka_unit_test(test_constant_env_and_irradiance_map),
        cmocka_unit_test(test_bad_pixels_rejected),
        cmocka_unit_test(test_image_round_trips),
        cmocka_unit_test(test_animation),
        cmocka_unit_test(test_sky),
        cmocka_unit_test(test_hdr_reader_and_signatures),
        cmocka_unit_test(test_mesh_export_attributes),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
