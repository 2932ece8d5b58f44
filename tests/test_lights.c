/* Local lights: the command-line form, validation, irradiance against closed forms and numerical
 * integration, the lighting object, and lights and emission in scene files. */
#include "common.h"

static void test_parse_format_round_trip(void **state)
{
    (void)state;
    static const char *specs[] = {
        "point:1,2.5,-3:100",
        "point:0,1e-3,0:1,0.5,0.25",
        "spot:0,4,0:0,-1,0:30:50,40,30",
        "spot:1,2,3:1,-2,0.5:45,20:7",
        "spot:0,1,0:0,-1,0:90:1",
        "directional:0.4,0.8,0.3:3,2,1",
        "directional:0,1,0:0",
        "sphere:0,3,0:0.25:10",
        "sphere:-1,2,-3:1e-3:1,2,3",
    };
    for (size_t i = 0; i < sizeof specs / sizeof *specs; ++i) {
        prt_light a, b;
        if (prt_light_parse(specs[i], &a) != PRT_OK) fail_msg("'%s': %s", specs[i], prt_last_error());
        char buf[256];
        prt_light_format(&a, buf, sizeof buf);
        if (prt_light_parse(buf, &b) != PRT_OK) fail_msg("'%s' formatted as '%s': %s", specs[i], buf, prt_last_error());
        assert_memory_equal(&a, &b, sizeof a);
        /* Formatting the re-read light gives the same text. */
        char buf2[256];
        prt_light_format(&b, buf2, sizeof buf2);
        assert_string_equal(buf, buf2);
    }
    prt_light l;
    assert_int_equal(prt_light_parse("spot:0,4,0:0,-2,0:30:5", &l), PRT_OK);
    assert_int_equal(l.type, PRT_LIGHT_SPOT);
    assert_true(l.direction[1] == -1.0f);          /* normalised */
    assert_true(l.angle_deg == 30.0f && l.falloff_deg == 30.0f);   /* no falloff = a hard edge */
    assert_true(l.intensity[0] == 5.0f && l.intensity[2] == 5.0f);
    assert_int_equal(prt_light_parse("sphere:1,2,3:0.5:1,2,3", &l), PRT_OK);
    assert_true(l.radius == 0.5f && l.radiance[1] == 2.0f && l.position[2] == 3.0f);
    assert_int_equal(prt_light_parse("directional:0,3,4:2", &l), PRT_OK);
    assert_true(fabsf(l.direction[1] - 0.6f) < 1e-7f && fabsf(l.direction[2] - 0.8f) < 1e-7f && l.irradiance[1] == 2.0f);
    assert_string_equal(prt_light_type_name(PRT_LIGHT_DIRECTIONAL), "directional");
    assert_int_equal(prt_light_type_bit(PRT_LIGHT_SPHERE), PRT_LIGHTS_SPHERE);
    assert_string_equal(prt_lights_bit_name(PRT_LIGHTS_EMISSIVE), "emissive surfaces");
    assert_string_equal(prt_lights_bit_name(PRT_LIGHTS_POINT), "point lights");
}

static void test_parse_errors(void **state)
{
    (void)state;
    static const struct { const char *spec, *msg; } bad[] = {
        {"point:1,2:1", "light 'point:1,2:1': position needs X,Y,Z"},
        {"point:1,2,3,4:1", "position needs X,Y,Z"},
        {"point:1,,3:1", "position needs X,Y,Z"},
        {"point:1,2,x:1", "position needs X,Y,Z"},
        {"point:1,2,nan:1", "position needs X,Y,Z"},
        {"point: 1,2,3:1", "position needs X,Y,Z"},
        {"point:1,2,3", "expected point:X,Y,Z:R,G,B"},
        {"point:1,2,3:1:1", "expected point:X,Y,Z:R,G,B"},
        {"point:1,2,3:1,2", "intensity needs R,G,B or one number"},
        {"point:1,2,3:inf", "intensity needs R,G,B or one number"},
        {"point:1,2,3:1e400", "intensity needs R,G,B or one number"},
        {"point:1,2,3:-1", "intensity must be finite, >= 0 and at most 1e30"},
        {"point:1,2,3:2e30", "at most 1e30"},
        {"spot:0,1,0:0,0,0:30:1", "direction must be finite and non-zero"},
        {"spot:0,1,0:0,-1:30:1", "direction needs DX,DY,DZ"},
        {"spot:0,1,0:0,-1,0:95:1", "angle 95 outside (0, 90]"},
        {"spot:0,1,0:0,-1,0:0:1", "angle must be > 0"},
        {"spot:0,1,0:0,-1,0:30,40:1", "falloff 40 outside [0, angle 30]"},
        {"spot:0,1,0:0,-1,0:30,-1:1", "falloff >= 0"},
        {"spot:0,1,0:0,-1,0:30,10,5:1", "angle needs ANGLE or ANGLE,FALLOFF"},
        {"spot:0,1,0:0,-1,0:1", "expected spot:X,Y,Z:DX,DY,DZ:ANGLE[,FALLOFF]:R,G,B"},
        {"directional:0,0,0:1", "direction must be finite and non-zero"},
        {"directional:0,1,0:1,1,1,1", "irradiance needs R,G,B or one number"},
        {"sphere:0,1,0:0:1", "radius must be finite and > 0"},
        {"sphere:0,1,0:-2:1", "radius must be finite and > 0"},
        {"sphere:0,1,0:1,2:1", "radius needs one number"},
        {"sphere:0,1,0:1:", "radiance needs R,G,B or one number"},
        {"laser:0,0,0:1", "unknown type"},
        {"", "unknown type"},
        {"point:0,0,0:1:2:3:4:5:6", "too many"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        prt_light l;
        memset(&l, 0x5a, sizeof l);
        prt_light before = l;
        if (prt_light_parse(bad[i].spec, &l) != PRT_ERR_INVALID_ARG) fail_msg("'%s' was accepted", bad[i].spec);
        if (!strstr(prt_last_error(), bad[i].msg)) fail_msg("'%s': message '%s' lacks '%s'", bad[i].spec, prt_last_error(), bad[i].msg);
        assert_null(strchr(prt_last_error(), '\n'));
        assert_memory_equal(&l, &before, sizeof l);   /* untouched on failure */
    }
    prt_light l = {0};
    assert_int_equal(prt_light_validate(&l), PRT_ERR_INVALID_ARG);
    l.type = PRT_LIGHT_SPOT;
    l.direction[1] = -1;
    assert_int_equal(prt_light_validate(&l), PRT_OK);
    assert_true(l.angle_deg == 30.0f && l.falloff_deg == 30.0f);
}

/* Irradiance from a uniform unit-radiance sphere cap by brute-force quadrature over the cap. The
 * azimuths' sines and cosines are computed once, not per point: the same sums, bit for bit, in a
 * fraction of the time (this test runs under valgrind in every make test). */
static double cap_irradiance_numeric(double theta, double sigma)
{
    enum { nt = 1500, np = 1500 };
    static double cp[np], sp[np];
    for (int k = 0; k < np; ++k) {
        double p = 2 * M_PI * (k + 0.5) / np;
        cp[k] = cos(p);
        sp[k] = sin(p);
    }
    double n[3] = {sin(theta), cos(theta), 0}, e = 0;   /* the cap is centred on +y */
    for (int i = 0; i < nt; ++i) {
        double t = sigma * (i + 0.5) / nt, st = sin(t), ct = cos(t);
        for (int k = 0; k < np; ++k) {
            double w[3] = {st * cp[k], ct, st * sp[k]};
            double c = w[0] * n[0] + w[1] * n[1] + w[2] * n[2];
            if (c > 0) e += c * st;
        }
    }
    return e * (sigma / nt) * (2 * M_PI / np);
}

static void test_irradiance_closed_forms(void **state)
{
    (void)state;
    const float p[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    float e[3];
    prt_light l;
    /* Point: I cos / r^2. */
    assert_int_equal(prt_light_parse("point:3,4,0:50,25,10", &l), PRT_OK);
    prt_light_irradiance(&l, p, up, e);
    assert_true(fabsf(e[0] - 50 * 0.8f / 25) < 1e-5f && fabsf(e[2] - 10 * 0.8f / 25) < 1e-5f);
    const float down[3] = {0, -1, 0};
    prt_light_irradiance(&l, p, down, e);
    assert_true(e[0] == 0 && e[1] == 0 && e[2] == 0);
    /* Spot: full inside the falloff, none outside the angle, smoothstep in cos between. */
    assert_int_equal(prt_light_parse("spot:0,1,0:0,-1,0:40,20:10", &l), PRT_OK);
    float q[3] = {(float)tan(10 * M_PI / 180), 0, 0};   /* 10 degrees off the axis */
    prt_light_irradiance(&l, q, up, e);
    double r2 = 1 + q[0] * q[0], c = 1 / sqrt(r2);
    assert_true(fabs(e[0] - 10 * c / r2) < 1e-5);
    q[0] = (float)tan(45 * M_PI / 180);
    prt_light_irradiance(&l, q, up, e);
    assert_true(e[0] == 0);
    q[0] = (float)tan(30 * M_PI / 180);
    prt_light_irradiance(&l, q, up, e);
    r2 = 1 + q[0] * q[0]; c = 1 / sqrt(r2);
    double t = (c - cos(40 * M_PI / 180)) / (cos(20 * M_PI / 180) - cos(40 * M_PI / 180)), s = t * t * (3 - 2 * t);
    assert_true(fabs(e[0] - 10 * c / r2 * s) < 1e-5);
    /* Directional: E cos. */
    assert_int_equal(prt_light_parse("directional:0,1,1:2", &l), PRT_OK);
    prt_light_irradiance(&l, p, up, e);
    assert_true(fabsf(e[1] - 2 * (float)sqrt(0.5)) < 1e-6f);
    /* Sphere facing the point: pi L R^2 / d^2. */
    assert_int_equal(prt_light_parse("sphere:0,4,0:0.5:3", &l), PRT_OK);
    prt_light_irradiance(&l, p, up, e);
    assert_true(fabs(e[0] - M_PI * 3 * 0.25 / 16) < 1e-5);
    /* Tilted, above the horizon, straddling it and below it, against quadrature over the cap. */
    const double sigma = asin(0.5 / 1.5);
    assert_int_equal(prt_light_parse("sphere:0,1.5,0:0.5:1", &l), PRT_OK);
    double worst = 0;
    for (double deg = 0; deg <= 120; deg += 7.5) {
        double th = deg * M_PI / 180;
        float n[3] = {(float)sin(th), (float)cos(th), 0};
        prt_light_irradiance(&l, p, n, e);
        double ref = cap_irradiance_numeric(th, sigma);
        worst = fmax(worst, fabs(e[0] - ref));
        if (fabs(e[0] - ref) > 1e-4 + 1e-4 * ref) fail_msg("sphere at %g degrees: %g, quadrature %g", deg, e[0], ref);
    }
    print_message("sphere cap irradiance vs quadrature, 0..120 degrees tilt: worst absolute error %.2e (of pi sin^2 = %.4f)\n", worst,
                  M_PI * 0.25 / 2.25);
    /* Inside the sphere: L from the whole hemisphere. */
    float inside[3] = {0, 1.4f, 0};
    prt_light_irradiance(&l, inside, up, e);
    assert_true(fabs(e[0] - M_PI) < 1e-6);
}

static void test_lighting_object(void **state)
{
    (void)state;
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_null(prt_lighting_envmap(l));
    assert_int_equal(prt_lighting_count(l), 0);
    assert_true(prt_lighting_emission(l) == 1.0f && prt_lighting_intensity(l) == 1.0f);
    assert_int_equal(prt_lighting_content(l), PRT_LIGHTS_EMISSIVE);
    prt_light a, b;
    assert_int_equal(prt_light_parse("point:0,1,0:5", &a), PRT_OK);
    assert_int_equal(prt_light_parse("sphere:0,1,0:0.1:5", &b), PRT_OK);
    int idx = -1;
    assert_int_equal(prt_lighting_add(l, &a, &idx), PRT_OK);
    assert_int_equal(idx, 0);
    assert_int_equal(prt_lighting_add(l, &b, &idx), PRT_OK);
    assert_int_equal(idx, 1);
    for (int i = 0; i < 20; ++i) assert_int_equal(prt_lighting_add(l, &a, NULL), PRT_OK);   /* grows */
    assert_int_equal(prt_lighting_count(l), 22);
    assert_int_equal(prt_lighting_content(l), PRT_LIGHTS_POINT | PRT_LIGHTS_SPHERE | PRT_LIGHTS_EMISSIVE);
    prt_light bad = a;
    bad.intensity[0] = -1;
    assert_int_equal(prt_lighting_add(l, &bad, NULL), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_lighting_set(l, 0, &bad), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_lighting_set(l, 22, &a), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_lighting_remove(l, 22), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_lighting_remove(l, 0), PRT_OK);
    assert_int_equal(prt_lighting_light(l, 0)->type, PRT_LIGHT_SPHERE);
    assert_null(prt_lighting_light(l, 21));
    assert_null(prt_lighting_light(l, -1));
    prt_lighting_set_emission(l, 0);
    assert_false(prt_lighting_content(l) & PRT_LIGHTS_EMISSIVE);
    prt_lighting_set_emission(l, -3);
    assert_true(prt_lighting_emission(l) == 0.0f);
    /* An environment, copied deeply. */
    prt_envmap *env = constant_env(2.0f);
    double rot[9];
    prt_rotation_from_euler_deg(30, 0, 0, rot);
    assert_int_equal(prt_lighting_set_envmap(l, env, rot, 0), PRT_OK);
    assert_true(prt_lighting_envmap(l) == env && prt_lighting_intensity(l) == 1.0f);
    assert_int_equal(prt_lighting_environment_desc(l)->path[0], 0);
    prt_lighting *c = NULL;
    assert_int_equal(prt_lighting_copy(l, &c), PRT_OK);
    assert_int_equal(prt_lighting_count(c), 21);
    assert_true(prt_lighting_envmap(c) != env);
    assert_true(prt_envmap_image(prt_lighting_envmap(c))->rgb[5] == 2.0f);
    double r2[9];
    prt_lighting_rotation(c, r2);
    assert_memory_equal(r2, rot, sizeof rot);
    prt_lighting_clear_lights(l);
    assert_int_equal(prt_lighting_count(l), 0);
    assert_int_equal(prt_lighting_count(c), 21);
    prt_lighting_release(l);   /* releases env; the copy keeps its own */
    assert_true(prt_envmap_image(prt_lighting_envmap(c))->rgb[0] == 2.0f);
    /* Environment descs: none, the sky, a missing probe. */
    prt_environment_desc d = {0};
    d.none = 1;
    assert_int_equal(prt_lighting_set_environment(c, &d), PRT_OK);
    assert_null(prt_lighting_envmap(c));
    assert_true(prt_lighting_environment_desc(c)->none);
    memset(&d, 0, sizeof d);
    d.rotate_deg[0] = 90;
    d.intensity = 2;
    d.sun_dir[1] = 1;
    assert_int_equal(prt_lighting_set_environment(c, &d), PRT_OK);
    assert_non_null(prt_lighting_envmap(c));
    assert_true(prt_lighting_intensity(c) == 2.0f);
    prt_lighting_rotation(c, r2);
    prt_rotation_from_euler_deg(90, 0, 0, rot);
    assert_memory_equal(r2, rot, sizeof rot);
    assert_true(prt_lighting_content(c) & PRT_LIGHTS_ENVIRONMENT);
    snprintf(d.path, sizeof d.path, "%s/missing.hdr", test_dir);
    assert_int_not_equal(prt_lighting_set_environment(c, &d), PRT_OK);
    assert_non_null(prt_lighting_envmap(c));   /* a failed load keeps what was there */
    prt_lighting_set_intensity(c, 0);   /* an explicit 0 turns the environment off */
    assert_true(prt_lighting_intensity(c) == 0.0f);
    prt_lighting_set_intensity(c, -1);  /* refused: unchanged */
    prt_lighting_set_intensity(c, NAN);
    assert_true(prt_lighting_intensity(c) == 0.0f);
    prt_lighting_release(c);
    prt_lighting_release(NULL);
}

static const char *QUAD_OBJ = "v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nf 1 2 3 4\n";

static void test_scene_json_lights(void **state)
{
    (void)state;
    char obj[512], path[512];
    write_text("quad.obj", QUAD_OBJ, obj, sizeof obj);
    write_text("lit.json",
               "{\"materials\": {\"lamp\": {\"emission\": [1, 2, 3]}},\n"
               " \"meshes\": [{\"file\": \"quad.obj\"}, {\"file\": \"quad.obj\", \"translate\": [0, 2, 0], \"material\": \"lamp\"},\n"
               "            {\"file\": \"quad.obj\", \"translate\": [0, 4, 0], \"emission\": 0.5}],\n"
               " \"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": [1, 2, 3]},\n"
               "            {\"type\": \"spot\", \"position\": [0, 3, 0], \"direction\": [0, -2, 0], \"angle\": 40, \"falloff\": 30, \"intensity\": 7},\n"
               "            {\"type\": \"directional\", \"direction\": [0, 1, 0], \"irradiance\": 2},\n"
               "            {\"type\": \"sphere\", \"position\": [0, 1, 1], \"radius\": 0.25, \"radiance\": [4, 5, 6]}]}\n",
               path, sizeof path);
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    if (prt_scene_load(ctx, path, NULL, &s) != PRT_OK) fail_msg("%s", prt_last_error());
    assert_int_equal(prt_scene_light_count(s), 4);
    assert_int_equal(prt_scene_light(s, 0)->type, PRT_LIGHT_POINT);
    assert_true(prt_scene_light(s, 0)->intensity[2] == 3.0f);
    const prt_light *sp = prt_scene_light(s, 1);
    assert_true(sp->type == PRT_LIGHT_SPOT && sp->direction[1] == -1.0f && sp->angle_deg == 40.0f && sp->falloff_deg == 30.0f);
    assert_true(prt_scene_light(s, 2)->irradiance[1] == 2.0f);
    assert_true(prt_scene_light(s, 3)->radius == 0.25f && prt_scene_light(s, 3)->radiance[2] == 6.0f);
    assert_null(prt_scene_light(s, 4));
    const float *e = prt_scene_emission(s), *pos = prt_scene_positions(s);
    assert_non_null(e);
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) {
        float y = pos[v * 3 + 1], want[3] = {0, 0, 0};
        if (y == 2) { want[0] = 1; want[1] = 2; want[2] = 3; }
        if (y == 4) want[0] = want[1] = want[2] = 0.5f;
        assert_memory_equal(e + v * 3, want, sizeof want);
    }
    /* Lights and no environment: the scene's lighting has none. */
    prt_lighting *l = NULL;
    assert_int_equal(prt_scene_lighting(ctx, s, &l), PRT_OK);
    assert_null(prt_lighting_envmap(l));
    assert_int_equal(prt_lighting_count(l), 4);
    assert_int_equal(prt_lighting_content(l),
                     PRT_LIGHTS_POINT | PRT_LIGHTS_SPOT | PRT_LIGHTS_DIRECTIONAL | PRT_LIGHTS_SPHERE | PRT_LIGHTS_EMISSIVE);
    prt_lighting_release(l);
    prt_scene_release(s);

    /* Subdivision carries emission along (interpolated like albedo). */
    prt_scene_desc sd = {0};
    sd.max_edge = 0.5f;
    assert_int_equal(prt_scene_load(ctx, path, &sd, &s), PRT_OK);
    e = prt_scene_emission(s);
    pos = prt_scene_positions(s);
    assert_true(prt_scene_vertex_count(s) > 12);
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v)
        if (pos[v * 3 + 1] == 2) assert_true(e[v * 3] == 1 && e[v * 3 + 2] == 3);
        else if (pos[v * 3 + 1] == 0) assert_true(e[v * 3] == 0);
    prt_scene_release(s);

    /* "environment": "none" with nothing else; no lights and no emission: the sky. */
    write_text("dark.json", "{\"environment\": \"none\", \"meshes\": [{\"file\": \"quad.obj\"}]}", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    prt_environment_desc env;
    assert_true(prt_scene_environment(s, &env) && env.none);
    assert_null(prt_scene_emission(s));
    assert_int_equal(prt_scene_lighting(ctx, s, &l), PRT_OK);
    assert_null(prt_lighting_envmap(l));
    prt_lighting_release(l);
    prt_scene_release(s);
    write_text("dark2.json", "{\"environment\": {\"none\": true}, \"meshes\": [{\"file\": \"quad.obj\"}]}", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_true(prt_scene_environment(s, &env) && env.none);
    prt_scene_release(s);
    write_text("sky.json", "{\"meshes\": [{\"file\": \"quad.obj\"}]}", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_light_count(s), 0);
    assert_int_equal(prt_scene_lighting(ctx, s, &l), PRT_OK);
    assert_non_null(prt_lighting_envmap(l));
    assert_int_equal(prt_lighting_count(l), 0);
    prt_lighting_release(l);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_scene_json_light_errors(void **state)
{
    (void)state;
    char obj[512], path[512];
    write_text("quad.obj", QUAD_OBJ, obj, sizeof obj);
    static const struct { const char *lights, *msg; } bad[] = {
        {"{\"type\": \"laser\", \"position\": [0, 1, 0]}", "lights[1]: unknown type 'laser'"},
        {"{\"position\": [0, 1, 0]}", "lights[1] needs a \"type\""},
        {"{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": 1, \"colour\": 2}", "lights[1]: a point light has no \"colour\""},
        {"{\"type\": \"point\", \"position\": [0, 1, 0], \"radius\": 1, \"intensity\": 1}", "lights[1]: a point light has no \"radius\""},
        {"{\"type\": \"point\", \"intensity\": 1}", "lights[1]: a point light needs \"position\""},
        {"{\"type\": \"point\", \"position\": [0, 1], \"intensity\": 1}", "lights[1]: 'position' must be a number or an array of 3"},
        {"{\"type\": \"point\", \"position\": 3, \"intensity\": 1}", "lights[1]: \"position\" must be [x, y, z]"},
        {"{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": -1}", "lights[1]: 'intensity' must be finite and >= 0"},
        {"{\"type\": \"point\", \"position\": [0, \"a\", 0], \"intensity\": 1}", "lights[1]: 'position' element 1 is not a finite number"},
        {"{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, 0, 0], \"intensity\": 1}", "lights[1]: spot light: direction"},
        {"{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], \"angle\": 120, \"intensity\": 1}", "lights[1]: spot light: angle 120"},
        {"{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], \"angle\": \"wide\", \"intensity\": 1}", "lights[1]: \"angle\" must be a number"},
        {"{\"type\": \"directional\", \"direction\": [0, 1, 0], \"intensity\": 1}", "lights[1]: a directional light has no \"intensity\""},
        {"{\"type\": \"sphere\", \"position\": [0, 1, 0], \"radius\": 0, \"radiance\": 1}", "lights[1]: sphere light: radius"},
        {"{\"type\": \"sphere\", \"position\": [0, 1, 0], \"radiance\": 1}", "lights[1]: a sphere light needs \"radius\""},
        {"7", "lights[1] must be an object"},
    };
    prt_context *ctx = test_context(1);
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        char json[1024];
        snprintf(json, sizeof json,
                 "{\"meshes\": [{\"file\": \"quad.obj\"}], \"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": 1}, %s]}",
                 bad[i].lights);
        write_text("bad.json", json, path, sizeof path);
        prt_scene *s = NULL;
        if (prt_scene_load(ctx, path, NULL, &s) == PRT_OK) fail_msg("accepted %s", bad[i].lights);
        if (!strstr(prt_last_error(), bad[i].msg)) fail_msg("%s: message '%s' lacks '%s'", bad[i].lights, prt_last_error(), bad[i].msg);
        assert_null(s);
    }
    write_text("bad.json", "{\"meshes\": [{\"file\": \"quad.obj\"}], \"lights\": {}}", path, sizeof path);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "\"lights\" must be an array"));
    write_text("bad.json", "{\"meshes\": [{\"file\": \"quad.obj\", \"emission\": [1, -1, 0]}]}", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "meshes[0]: \"emission\""));
    write_text("bad.json", "{\"meshes\": [{\"file\": \"quad.obj\"}], \"environment\": \"nothing\"}", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_ERR_FORMAT);
    prt_context_release(ctx);
}

/* Emission from mesh files: MTL Ke and glTF emissiveFactor. */
static void test_imported_emission(void **state)
{
    (void)state;
    char path[512];
    write_text("lamp.mtl", "newmtl lamp\nKd 0.5 0.5 0.5\nKe 17 12 4\nnewmtl wall\nKd 0.7 0.7 0.7\nKe 0 0 0\n", path, sizeof path);
    write_text("lamp.obj", "mtllib lamp.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nv 3 0 0\nv 4 0 0\nv 4 1 0\n"
                           "usemtl lamp\nf 1 2 3 4\nusemtl wall\nf 5 6 7\n", path, sizeof path);
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    const float *e = prt_scene_emission(s), *pos = prt_scene_positions(s);
    assert_non_null(e);
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) {
        if (pos[v * 3] < 2) assert_true(e[v * 3] == 17 && e[v * 3 + 1] == 12 && e[v * 3 + 2] == 4);
        else assert_true(e[v * 3] == 0 && e[v * 3 + 1] == 0 && e[v * 3 + 2] == 0);
    }
    prt_scene_release(s);
    write_text("plain.mtl", "newmtl wall\nKd 0.7 0.7 0.7\nKe 0 0 0\n", path, sizeof path);
    write_text("plain.obj", "mtllib plain.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nusemtl wall\nf 1 2 3\n", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_null(prt_scene_emission(s));
    prt_scene_release(s);
    write_text("glow.gltf",
               "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}], \"nodes\": [{\"mesh\": 0}],\n"
               " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, \"material\": 0}]}],\n"
               " \"materials\": [{\"emissiveFactor\": [0.5, 0.25, 1.0]}],\n"
               " \"buffers\": [{\"byteLength\": 44, \"uri\": \"data:application/octet-stream;base64,"
               "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAIC/AAABAAIAAAA=\"}],\n"
               " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36}, {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 6}],\n"
               " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\", \"min\": [0, 0, -1], \"max\": [1, 0, 0]},\n"
               "               {\"bufferView\": 1, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\"}]}\n",
               path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    e = prt_scene_emission(s);
    assert_non_null(e);
    assert_true(fabsf(e[0] - 0.5f) < 1e-6f && fabsf(e[1] - 0.25f) < 1e-6f && fabsf(e[2] - 1.0f) < 1e-6f);
    prt_scene_release(s);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_format_round_trip),
        cmocka_unit_test(test_parse_errors),
        cmocka_unit_test(test_irradiance_closed_forms),
        cmocka_unit_test(test_lighting_object),
        cmocka_unit_test(test_scene_json_lights),
        cmocka_unit_test(test_scene_json_light_errors),
        cmocka_unit_test(test_imported_emission),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
