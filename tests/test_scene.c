/* Scene import, cleaning, subdivision, and bad inputs. */
#include "common.h"

#include <unistd.h>


static void test_obj_with_materials(void **state)
{
    (void)state;
    char path[512];
    write_text("two.mtl", "newmtl red\r\nKd 0.8 0.1 0.05\r\nnewmtl blue\nKd 0.1 0.2 0.7\n", path, sizeof path);
    write_text("two.obj",
               "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nv 3 0 0\nv 4 0 0\nv 4 1 0\n"
               "usemtl red\nf 1 2 3 4\nusemtl blue\nf 5 6 7\n",
               path, sizeof path);
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_triangle_count(s), 3);
    const float *alb = prt_scene_albedo(s), *pos = prt_scene_positions(s), *n = prt_scene_normals(s);
    int red = 0, blue = 0;
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) {
        if (pos[v * 3] < 2) { red++; assert_true(fabsf(alb[v * 3] - 0.8f) < 1e-6f && fabsf(n[v * 3 + 1] - 1) < 1e-5f); }
        else { blue++; assert_true(fabsf(alb[v * 3 + 2] - 0.7f) < 1e-6f && fabsf(n[v * 3 + 2] - 1) < 1e-5f); }
    }
    assert_int_equal(red, 4);
    assert_int_equal(blue, 3);
    prt_scene_release(s);
    /* Albedo override. */
    prt_scene_desc d = {0};
    d.override_albedo = 1;
    d.default_albedo[0] = d.default_albedo[1] = d.default_albedo[2] = 0.25f;
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    for (size_t v = 0; v < prt_scene_vertex_count(s) * 3; ++v) assert_true(prt_scene_albedo(s)[v] == 0.25f);
    prt_scene_release(s);
    /* It overrides a JSON scene's colours too: a mesh's own albedo, a material's albedo, a
     * material named like the file's, and a BRDF's kd (whose glossy lobe stays). */
    write_text("two.json",
               "{ \"materials\": { \"red\": { \"albedo\": 0.9 }, \"shiny\": { \"brdf\": \"phong:20:0.5:0.4\" } },\n"
               "  \"meshes\": [ { \"file\": \"two.obj\" }, { \"file\": \"two.obj\", \"albedo\": [0.1, 0.2, 0.3], \"translate\": [0, 2, 0] },\n"
               "              { \"file\": \"two.obj\", \"material\": \"shiny\", \"translate\": [0, 4, 0] } ] }\n",
               path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    assert_int_equal(prt_scene_vertex_count(s), 21);
    for (size_t v = 0; v < prt_scene_vertex_count(s) * 3; ++v) assert_true(prt_scene_albedo(s)[v] == 0.25f);
    assert_int_equal(prt_scene_brdf_count(s), 1);
    /* The BRDF record itself, which the path tracer and the wavelet bake read (through a file's
     * copy of the scene's materials). */
    prt_transfer *ao = NULL;
    assert_int_equal(prt_bake(ctx, s, prt_method_find("ao"), NULL, NULL, &ao), PRT_OK);
    const prt_brdf *shiny = prt_transfer_brdf(ao, 1);
    assert_non_null(shiny);
    assert_true(shiny->diffuse[0] == 0.25f && shiny->diffuse[2] == 0.25f && shiny->specular[0] == 0.5f);
    prt_transfer_release(ao);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* --albedo 0 is black, not "unset": default_albedo_given keeps an all-zero default as given. */
static void test_black_default_albedo(void **state)
{
    (void)state;
    static const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const uint32_t tri[] = {0, 1, 2};
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    prt_scene_desc d = {0};
    assert_int_equal(prt_scene_create_copy(ctx, pos, NULL, NULL, 3, tri, 1, &d, &s), PRT_OK);
    assert_true(prt_scene_albedo(s)[0] == 0.7f);   /* zero-initialised: the old default */
    prt_scene_release(s);
    d.default_albedo_given = 1;
    assert_int_equal(prt_scene_create_copy(ctx, pos, NULL, NULL, 3, tri, 1, &d, &s), PRT_OK);
    for (size_t v = 0; v < prt_scene_vertex_count(s) * 3; ++v)
        assert_true(prt_scene_albedo(s)[v] == 0.0f);
    prt_scene_release(s);
    /* The same through a mesh file without materials (imported in a child process). */
    char path[512];
    write_text("black.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    for (size_t v = 0; v < prt_scene_vertex_count(s) * 3; ++v)
        assert_true(prt_scene_albedo(s)[v] == 0.0f);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* A unit cube without normals, wound clockwise seen from outside (inside out). */
static const char *CW_CUBE =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 2 3\nf 1 3 4\nf 5 7 6\nf 5 8 7\nf 1 6 2\nf 1 5 6\nf 4 3 7\nf 4 7 8\nf 1 8 5\nf 1 4 8\nf 2 7 3\nf 2 6 7\n";

static float mean_outwardness(const prt_scene *s)
{
    const float *p = prt_scene_positions(s), *n = prt_scene_normals(s);
    double acc = 0;
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v)
        acc += (p[v * 3] - 0.5f) * n[v * 3] + (p[v * 3 + 1] - 0.5f) * n[v * 3 + 1] + (p[v * 3 + 2] - 0.5f) * n[v * 3 + 2];
    return (float)(acc / (double)prt_scene_vertex_count(s));
}

static void test_winding(void **state)
{
    (void)state;
    char path[512];
    write_text("cw_cube.obj", CW_CUBE, path, sizeof path);
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    prt_scene_desc d = {0};
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);   /* auto: flipped outwards */
    assert_true(mean_outwardness(s) > 0.4f);
    prt_scene_release(s);
    d.winding = PRT_WINDING_KEEP;
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    assert_true(mean_outwardness(s) < -0.4f);
    prt_scene_release(s);
    d.winding = PRT_WINDING_FLIP;
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    assert_true(mean_outwardness(s) > 0.4f);
    prt_scene_release(s);
    /* An open surface (a room's floor and walls facing in) is never flipped in auto mode. */
    write_text("room.obj", "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 1 1 0\nf 1 4 3\nf 1 3 2\nf 1 2 6\nf 1 6 5\n", path, sizeof path);
    d.winding = PRT_WINDING_AUTO;
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    const float *n = prt_scene_normals(s);
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) assert_true(n[v * 3 + 1] > 0.5f || n[v * 3 + 2] > 0.5f);
    prt_scene_release(s);
    /* A closed room wound inwards around a closed box wound inside out, both without normals: the
     * box is an object seen from outside and is flipped; the room holds other geometry and is kept
     * facing in, so that its inside can receive light. */
    char text[2048];
    size_t len = 0;
    for (int c = 0; c < 8; ++c)
        len += (size_t)snprintf(text + len, sizeof text - len, "v %d %d %d\n", 4 * (c == 1 || c == 2 || c == 5 || c == 6) - 2,
                                4 * (c == 2 || c == 3 || c == 6 || c == 7) - 2, 4 * (c >= 4) - 2);
    for (int c = 0; c < 8; ++c)
        len += (size_t)snprintf(text + len, sizeof text - len, "v %d %d %d\n", c == 1 || c == 2 || c == 5 || c == 6, c == 2 || c == 3 || c == 6 || c == 7, c >= 4);
    const int faces[12][3] = {{1, 2, 3}, {1, 3, 4}, {5, 7, 6}, {5, 8, 7}, {1, 6, 2}, {1, 5, 6}, {4, 3, 7}, {4, 7, 8}, {1, 8, 5}, {1, 4, 8}, {2, 7, 3}, {2, 6, 7}};
    for (int k = 0; k < 2; ++k)   /* the same clockwise winding for both */
        for (int f = 0; f < 12; ++f)
            len += (size_t)snprintf(text + len, sizeof text - len, "f %d %d %d\n", faces[f][0] + 8 * k, faces[f][1] + 8 * k, faces[f][2] + 8 * k);
    write_text("room_and_box.obj", text, path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    const float *pos = prt_scene_positions(s);
    n = prt_scene_normals(s);
    size_t room = 0, box = 0;
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) {
        const float *p = pos + v * 3, *q = n + v * 3;
        const bool in_room = fabsf(p[0]) > 1.5f;
        const float out = in_room ? p[0] * q[0] + p[1] * q[1] + p[2] * q[2] : (p[0] - 0.5f) * q[0] + (p[1] - 0.5f) * q[1] + (p[2] - 0.5f) * q[2];
        if (in_room) { assert_true(out < 0); room++; }   /* the room's walls face in */
        else { assert_true(out > 0); box++; }            /* the box faces out */
    }
    assert_true(room >= 8 && box >= 8);
    prt_scene_release(s);

    /* The room alone looks like an object wound inside out and is flipped; around a light of a
     * JSON scene (moved and scaled with the room, so the check runs in the file's frame) it is a
     * room and keeps facing in; a light outside it changes nothing. */
    text[0] = 0;
    len = 0;
    for (int c = 0; c < 8; ++c)
        len += (size_t)snprintf(text + len, sizeof text - len, "v %d %d %d\n", 4 * (c == 1 || c == 2 || c == 5 || c == 6) - 2,
                                4 * (c == 2 || c == 3 || c == 6 || c == 7) - 2, 4 * (c >= 4) - 2);
    for (int f = 0; f < 12; ++f) len += (size_t)snprintf(text + len, sizeof text - len, "f %d %d %d\n", faces[f][0], faces[f][1], faces[f][2]);
    write_text("lone_room.obj", text, path, sizeof path);
    const char *scenes[3] = {
        "{\"meshes\": [{\"file\": \"lone_room.obj\"}]}",
        /* A long room turned a quarter about +y: the light 6 along z is inside only if the check
         * undoes the turn (the room is 1 wide along z before it). */
        "{\"meshes\": [{\"file\": \"lone_room.obj\", \"translate\": [10, 0, 0], \"scale\": [4, 0.5, 0.5], \"rotate\": [90, 0, 0]}],"
        " \"lights\": [{\"type\": \"point\", \"position\": [10, 0, 6], \"intensity\": 1}]}",
        "{\"meshes\": [{\"file\": \"lone_room.obj\", \"translate\": [10, 0, 0], \"scale\": [2, 2, 2], \"rotate\": [30, 0, 0]}],"
        " \"lights\": [{\"type\": \"point\", \"position\": [30, 0, 0], \"intensity\": 1}]}"};
    const float centre[3][3] = {{0, 0, 0}, {10, 0, 0}, {10, 0, 0}};
    for (int k = 0; k < 3; ++k) {
        write_text("lit_room.json", scenes[k], path, sizeof path);
        assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
        pos = prt_scene_positions(s);
        n = prt_scene_normals(s);
        for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) {
            const float *p = pos + v * 3, *q = n + v * 3;
            const float out = (p[0] - centre[k][0]) * q[0] + (p[1] - centre[k][1]) * q[1] + (p[2] - centre[k][2]) * q[2];
            if (k == 1) assert_true(out < 0);   /* a room around its light faces in */
            else assert_true(out > 0);          /* alone, or with the light outside: flipped to face out */
        }
        prt_scene_release(s);
    }
    /* Whatever marks the inside: a spot or sphere light, the JSON scene's camera, or a point the
     * caller names (the command line's --light and --eye) for a JSON scene or a bare mesh file. A
     * directional light has no position and a camera outside looks at an object: both flipped. */
    const char *more[] = {
        "{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"lights\": [{\"type\": \"spot\", \"position\": [0, 1.5, 0], \"direction\": [0, -1, 0], \"intensity\": 1}]}",
        "{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"lights\": [{\"type\": \"sphere\", \"position\": [0.5, 1, 0], \"radius\": 0.2, \"radiance\": 1}]}",
        "{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"camera\": {\"eye\": [0, 0.5, 1.5], \"target\": [0, 0, 0], \"fov\": 60}}",
        "{\"meshes\": [{\"file\": \"lone_room.obj\"}]}",   /* with desc.inside_points */
        "lone_room.obj",                                        /* the mesh file, with desc.inside_points */
        "{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"lights\": [{\"type\": \"directional\", \"direction\": [0, 1, 0], \"irradiance\": 1}]}",
        "{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"camera\": {\"eye\": [0, 0.5, 8], \"target\": [0, 0, 0]}}"};
    const float light_at[3] = {0.3f, -1.0f, 0.2f};
    for (int k = 0; k < 7; ++k) {
        if (k == 4) snprintf(path, sizeof path, "%s/lone_room.obj", test_dir);
        else write_text("lit_room.json", more[k], path, sizeof path);
        d.inside_points = k == 3 || k == 4 ? light_at : NULL;
        d.inside_point_count = d.inside_points ? 1 : 0;
        assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
        pos = prt_scene_positions(s);
        n = prt_scene_normals(s);
        for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) {
            const float *p = pos + v * 3, *q = n + v * 3;
            const float out = p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
            if (k < 5) assert_true(out < 0);   /* kept facing in */
            else assert_true(out > 0);         /* flipped to face out */
        }
        float eye[3], target[3], fov;
        assert_int_equal(prt_scene_camera(s, eye, target, &fov), k == 2 || k == 6);
        if (k == 2) assert_true(eye[2] == 1.5f && target[1] == 0 && fov == 60);
        prt_scene_release(s);
    }
    d.inside_points = NULL;
    d.inside_point_count = 0;
    /* A camera needs an eye and a target, nothing else, and they must differ. */
    const char *bad[] = {"{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"camera\": {\"eye\": [0, 0, 1]}}",
                         "{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"camera\": {\"eye\": [0, 0, 1], \"target\": [0, 0, 0], \"up\": [0, 1, 0]}}",
                         "{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"camera\": {\"eye\": [0, 0, 1], \"target\": [0, 0, 1]}}",
                         "{\"meshes\": [{\"file\": \"lone_room.obj\"}], \"camera\": {\"eye\": [0, 0, 1], \"target\": [0, 0, 0], \"fov\": 200}}"};
    for (int k = 0; k < 4; ++k) {
        write_text("lit_room.json", bad[k], path, sizeof path);
        assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_ERR_FORMAT);
        assert_non_null(strstr(prt_last_error(), "camera"));
    }
    /* prt_scene_set_lights replaces the scene's lights (validated copies). */
    write_text("lit_room.json", scenes[1], path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    assert_int_equal(prt_scene_light_count(s), 1);
    prt_light two[2] = {{.type = PRT_LIGHT_POINT, .position = {1, 2, 3}, .intensity = {1, 1, 1}},
                        {.type = PRT_LIGHT_DIRECTIONAL, .direction = {0, 2, 0}, .irradiance = {1, 1, 1}}};
    assert_int_equal(prt_scene_set_lights(s, two, 2), PRT_OK);
    assert_int_equal(prt_scene_light_count(s), 2);
    assert_true(prt_scene_light(s, 1)->direction[1] == 1.0f);   /* normalised in the copy */
    assert_true(two[1].direction[1] == 2.0f);
    two[0].intensity[0] = -1;
    assert_int_not_equal(prt_scene_set_lights(s, two, 2), PRT_OK);
    assert_int_equal(prt_scene_light_count(s), 2);
    assert_int_equal(prt_scene_set_lights(s, NULL, 0), PRT_OK);
    assert_int_equal(prt_scene_light_count(s), 0);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* glTF 2.0 (embedded buffer, base colour) and ASCII PLY with extra vertex properties. */
static void test_gltf_and_ply(void **state)
{
    (void)state;
    char path[512];
    write_text("tri.gltf",
               "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}], \"nodes\": [{\"mesh\": 0}],\n"
               " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, \"material\": 0}]}],\n"
               " \"materials\": [{\"pbrMetallicRoughness\": {\"baseColorFactor\": [0.2, 0.4, 0.6, 1.0]}}],\n"
               " \"buffers\": [{\"byteLength\": 44, \"uri\": \"data:application/octet-stream;base64,"
               "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAIC/AAABAAIAAAA=\"}],\n"
               " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36}, {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 6}],\n"
               " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\", \"min\": [0, 0, -1], \"max\": [1, 0, 0]},\n"
               "               {\"bufferView\": 1, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\"}]}\n",
               path, sizeof path);
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_triangle_count(s), 1);
    const float *alb = prt_scene_albedo(s), *n = prt_scene_normals(s);
    assert_true(fabsf(alb[0] - 0.2f) < 1e-5f && fabsf(alb[1] - 0.4f) < 1e-5f && fabsf(alb[2] - 0.6f) < 1e-5f);
    assert_true(fabsf(n[1] - 1.0f) < 1e-5f);   /* counter-clockwise seen from +y */
    prt_scene_release(s);
    write_text("quad.ply",
               "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
               "property float confidence\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
               "0 0 0 1\n1 0 0 1\n1 0 -1 1\n0 0 -1 1\n5 5 5 0\n3 0 1 2\n3 0 2 3\n",
               path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_triangle_count(s), 2);
    assert_int_equal(prt_scene_vertex_count(s), 4);   /* the unreferenced fifth vertex is gone */
    assert_true(fabsf(prt_scene_albedo(s)[0] - 0.7f) < 1e-6f);   /* no material: the default */
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_json_scene(void **state)
{
    (void)state;
    char path[512];
    write_text("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", path, sizeof path);
    write_text("scene.json",
               "{\"materials\": {\"gold\": {\"albedo\": [0.9, 0.7, 0.2]}},\n"
               " \"environment\": {\"file\": \"probe.hdr\", \"layout\": \"angular\", \"rotate\": [30, 0, 0], \"intensity\": 2},\n"
               " \"meshes\": [{\"file\": \"tri.obj\", \"material\": \"gold\"},\n"
               "            {\"file\": \"tri.obj\", \"translate\": [10, 0, 0], \"scale\": 2, \"albedo\": 0.5}]}",
               path, sizeof path);
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_triangle_count(s), 2);
    float lo[3], hi[3];
    prt_scene_bounds(s, lo, hi);
    assert_true(fabsf(hi[0] - 12.0f) < 1e-5f && fabsf(hi[1] - 2.0f) < 1e-5f);
    const float *alb = prt_scene_albedo(s), *pos = prt_scene_positions(s);
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v)
        assert_true(pos[v * 3] >= 10 ? alb[v * 3] == 0.5f : fabsf(alb[v * 3 + 2] - 0.2f) < 1e-6f);
    /* The named lighting, resolved beside the scene file, travels through a bake and a file. */
    prt_environment_desc env;
    assert_int_equal(prt_scene_environment(s, &env), 1);
    char expect[600];
    snprintf(expect, sizeof expect, "%s/probe.hdr", test_dir);
    assert_string_equal(env.path, expect);
    assert_int_equal(env.layout, PRT_ENV_ANGULAR);
    prt_bake_desc bd = {0};
    bd.samples = 16;
    prt_transfer *t = NULL, *u = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &bd, &t), PRT_OK);
    char prt_path[600];
    snprintf(prt_path, sizeof prt_path, "%s/env.prt", test_dir);
    assert_int_equal(prt_transfer_save(t, prt_path), PRT_OK);
    assert_int_equal(prt_transfer_load(ctx, prt_path, &u), PRT_OK);
    memset(&env, 0, sizeof env);
    assert_int_equal(prt_transfer_environment(u, &env), 1);
    assert_string_equal(env.path, expect);
    assert_int_equal(env.layout, PRT_ENV_ANGULAR);
    assert_true(env.rotate_deg[0] == 30.0f && env.intensity == 2.0f);
    prt_transfer_release(t);
    prt_transfer_release(u);
    prt_scene_release(s);
    /* A JSON material named like a material of the mesh file replaces it there, and only there. */
    write_text("two.mtl", "newmtl red\nKd 0.8 0.1 0.05\nnewmtl blue\nKd 0.1 0.2 0.7\n", path, sizeof path);
    write_text("two.obj", "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 3 0 0\nv 4 0 0\nv 4 1 0\nusemtl red\nf 1 2 3\nusemtl blue\nf 4 5 6\n",
               path, sizeof path);
    write_text("by_name.json", "{\"materials\": {\"blue\": {\"brdf\": \"phong:40:0.5:0.3\"}}, \"meshes\": [{\"file\": \"two.obj\"}]}", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_brdf_count(s), 1);
    alb = prt_scene_albedo(s);
    pos = prt_scene_positions(s);
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v)
        if (pos[v * 3] < 2) assert_true(fabsf(alb[v * 3] - 0.8f) < 1e-6f);   /* red: the file's */
        else assert_true(fabsf(alb[v * 3] - 0.3f) < 1e-6f && fabsf(alb[v * 3 + 2] - 0.3f) < 1e-6f);   /* blue: the BRDF's kd */
    prt_scene_release(s);
    write_text("by_name.json", "{\"materials\": {\"blue\": {\"brdf\": \"phong:nope\"}}, \"meshes\": [{\"file\": \"two.obj\"}]}", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "blue"));
    /* Bad scene files: a clear error. */
    const char *bad[] = {"{\"meshes\": []}", "{\"meshes\": [{\"file\": 3}]}", "{nope",
                         "{\"meshes\": [{\"file\": \"tri.obj\", \"material\": \"none\"}]}",
                         "{\"meshes\": [{\"file\": \"absent.obj\"}]}", "{\"meshes\": [{\"file\": \"tri.obj\", \"albedo\": [1, 2]}]}"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        write_text("bad.json", bad[i], path, sizeof path);
        prt_status st = prt_scene_load(ctx, path, NULL, &s);
        if (st == PRT_OK) fail_msg("bad scene %zu accepted", i);
        assert_null(s);
        assert_true(strlen(prt_last_error()) > 10);
    }
    prt_context_release(ctx);
}

static void test_bad_mesh_inputs(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    char path[512];
    /* Missing file. */
    snprintf(path, sizeof path, "%s/missing.obj", test_dir);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_ERR_IO);
    assert_non_null(strstr(prt_last_error(), "missing.obj"));
    /* Not a mesh. */
    write_text("notamesh.ply", "this is plainly not a mesh file\n", path, sizeof path);
    assert_int_not_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    assert_non_null(strstr(prt_last_error(), "notamesh.ply"));
    write_text("random.bin", "\x01\x02\x03\x04garbage", path, sizeof path);
    assert_int_not_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    /* Empty mesh: vertices, no faces. */
    write_text("empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", path, sizeof path);
    prt_status st = prt_scene_load(ctx, path, NULL, &s);
    assert_true(st == PRT_ERR_EMPTY || st == PRT_ERR_FORMAT);
    assert_null(s);
    /* All triangles zero-area. */
    write_text("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\nf 1 1 2\n", path, sizeof path);
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_ERR_EMPTY);
    assert_non_null(strstr(prt_last_error(), "zero area"));
    prt_context_release(ctx);
}

static void test_cleaning_in_memory(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    /* One good triangle, one degenerate, NaN and zero normals, an unreferenced vertex. */
    float pos[] = {0, 0, 0, 1, 0, 0, 0, 0, -1, 2, 0, 0, 9, 9, 9};
    float nrm[] = {NAN, 0, 0, 0, 0, 0, 0, 3, 0, 0, 1, 0, 0, 1, 0};
    uint32_t idx[] = {0, 1, 2, 0, 1, 3};
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_create_copy(ctx, pos, nrm, NULL, 5, idx, 2, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_triangle_count(s), 1);
    assert_int_equal(prt_scene_vertex_count(s), 3);
    const float *n = prt_scene_normals(s);
    for (int v = 0; v < 3; ++v) {
        assert_true(isfinite(n[v * 3]) && isfinite(n[v * 3 + 1]) && isfinite(n[v * 3 + 2]));
        assert_true(fabsf(n[v * 3 + 1] - 1.0f) < 1e-6f);   /* repaired to the face normal, or normalized */
    }
    assert_true(fabsf(prt_scene_albedo(s)[0] - 0.7f) < 1e-6f);
    prt_scene_release(s);
    /* Non-finite positions, out-of-range indices, bad albedo: rejected. */
    float bad_pos[] = {0, 0, 0, INFINITY, 0, 0, 0, 0, -1};
    uint32_t tri[] = {0, 1, 2}, bad_tri[] = {0, 1, 7};
    assert_int_equal(prt_scene_create_copy(ctx, bad_pos, NULL, NULL, 3, tri, 1, NULL, &s), PRT_ERR_FORMAT);
    assert_int_equal(prt_scene_create_copy(ctx, pos, NULL, NULL, 3, bad_tri, 1, NULL, &s), PRT_ERR_FORMAT);
    float bad_alb[] = {0.5f, 0.5f, 0.5f, 1.5f, 0, 0, 0.5f, 0.5f, 0.5f};
    assert_int_equal(prt_scene_create_copy(ctx, pos, NULL, bad_alb, 3, tri, 1, NULL, &s), PRT_ERR_FORMAT);
    assert_int_equal(prt_scene_create_copy(ctx, pos, NULL, NULL, 0, tri, 0, NULL, &s), PRT_ERR_EMPTY);
    assert_null(s);
    prt_context_release(ctx);
}

/* A face pasted over another with its own vertices and corners in another order (as the Cornell
 * box's OBJ does) is dropped; a face back to back with it (a two-sided sheet) stays. */
static void test_duplicate_faces(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    float pos[] = {0, 0, 0, 1, 0, 0, 0, 0, -1,        /* the face */
                   1, 0, 0, 0, 0, -1, 0, 0, 0,        /* the same corners, turned: a duplicate */
                   0, 0, 0, 0, 0, -1, 1, 0, 0,        /* the same corners, the other winding */
                   -0.0f, 0, 0, 1, 0, 0, 0, 0, -1};   /* -0 is 0: a duplicate */
    uint32_t idx[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_create_copy(ctx, pos, NULL, NULL, 12, idx, 4, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_triangle_count(s), 2);
    assert_int_equal(prt_scene_vertex_count(s), 6);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static double tri_area(const float *p, const uint32_t *t)
{
    float e1[3], e2[3];
    for (int c = 0; c < 3; ++c) { e1[c] = p[t[1] * 3 + c] - p[t[0] * 3 + c]; e2[c] = p[t[2] * 3 + c] - p[t[0] * 3 + c]; }
    double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
    return 0.5 * sqrt(x * x + y * y + z * z);
}

static void test_subdivision(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    /* A cube with split normals per face (24 vertices): creases must survive subdivision. */
    test_mesh m = {0};
    const float o[6][3] = {{0, 0, 1}, {1, 0, 0}, {1, 0, 1}, {0, 0, 0}, {0, 1, 1}, {0, 0, 0}};
    const float u[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 0, -1}, {0, 0, 1}, {1, 0, 0}, {0, 0, 1}};
    const float v[6][3] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 0, -1}, {1, 0, 0}};
    for (int f = 0; f < 6; ++f) tm_quad(&m, o[f], u[f], v[f], 1);
    prt_scene_desc d = {0};
    d.max_edge = 0.1f;
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_create_copy(ctx, m.pos, m.nrm, NULL, m.nv, m.idx, m.nt, &d, &s), PRT_OK);
    const float *p = prt_scene_positions(s), *n = prt_scene_normals(s);
    const uint32_t *t = prt_scene_indices(s);
    size_t nt = prt_scene_triangle_count(s), nv = prt_scene_vertex_count(s);
    assert_true(nt > 12 * 50);
    double area = 0;
    for (size_t i = 0; i < nt; ++i) {
        area += tri_area(p, t + i * 3);
        for (int k = 0; k < 3; ++k) {
            uint32_t a = t[i * 3 + k], b = t[i * 3 + (k + 1) % 3];
            float dx = p[a * 3] - p[b * 3], dy = p[a * 3 + 1] - p[b * 3 + 1], dz = p[a * 3 + 2] - p[b * 3 + 2];
            assert_true(sqrtf(dx * dx + dy * dy + dz * dz) <= 0.1f + 1e-6f);
        }
    }
    assert_true(fabs(area - 6.0) < 1e-4);
    /* Normals stay axis-aligned: nothing was averaged across a crease. */
    for (size_t i = 0; i < nv; ++i) {
        float mx = fmaxf(fabsf(n[i * 3]), fmaxf(fabsf(n[i * 3 + 1]), fabsf(n[i * 3 + 2])));
        assert_true(fabsf(mx - 1.0f) < 1e-6f);
    }
    /* Conforming: every edge inside a face is shared by exactly two triangles, so counting
     * directed edges, each has its reverse, except along the 12 cube edges (split vertices). */
    size_t unmatched = 0;
    for (size_t i = 0; i < nt; ++i)
        for (int k = 0; k < 3; ++k) {
            uint32_t a = t[i * 3 + k], b = t[i * 3 + (k + 1) % 3];
            bool found = false;
            for (size_t j = 0; j < nt && !found; ++j)
                for (int q = 0; q < 3; ++q)
                    if (t[j * 3 + q] == b && t[j * 3 + (q + 1) % 3] == a) { found = true; break; }
            unmatched += !found;
        }
    /* 12 cube edges of length 1, split into 16 segments (<= 0.1), seen from two faces. */
    assert_int_equal(unmatched, 12 * 16 * 2);
    prt_scene_release(s);
    d.max_edge = -1;
    assert_int_equal(prt_scene_create_copy(ctx, m.pos, m.nrm, NULL, m.nv, m.idx, m.nt, &d, &s), PRT_ERR_INVALID_ARG);
    tm_free(&m);
    prt_context_release(ctx);
}

static void test_demo_scene(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_scene *s = load_demo_scene(ctx);
    assert_true(prt_scene_vertex_count(s) > 5000);
    /* Its five materials arrive through the MTL file: look for the red wall's albedo. */
    const float *alb = prt_scene_albedo(s);
    bool red = false;
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) red |= alb[v * 3] > 0.7f && alb[v * 3 + 1] < 0.2f;
    assert_true(red);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_shared_meshes(void **state)
{
    (void)state;
    const char *data = shared_data_dir();
    char path[1024];
    if (data) snprintf(path, sizeof path, "%s/meshes/bunny/bun_zipper.ply", data);
    if (!data || access(path, R_OK) != 0) {
        print_message("skipping: ../shared/data is absent (bunny and Cornell box tests need it)\n");
        skip();
    }
    prt_context *ctx = test_context(0);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    /* 35947 vertices in the file, 34834 referenced; assimp may split none (smooth normals). */
    assert_true(prt_scene_vertex_count(s) >= 34834 && prt_scene_vertex_count(s) <= 35947);
    assert_int_equal(prt_scene_triangle_count(s), 69451);
    prt_scene_release(s);
    /* The Cornell box is too coarse for per-vertex transfer: --max-edge subdivides it. */
    snprintf(path, sizeof path, "%s/meshes/cornell_box/CornellBox-Original.obj", data);
    prt_scene_desc d = {0};
    d.max_edge = 0.1f;
    assert_int_equal(prt_scene_load(ctx, path, &d, &s), PRT_OK);
    assert_true(prt_scene_triangle_count(s) > 2000);
    const float *alb = prt_scene_albedo(s);
    bool red = false, green = false;
    for (size_t v = 0; v < prt_scene_vertex_count(s); ++v) {
        red |= fabsf(alb[v * 3] - 0.63f) < 1e-3f && fabsf(alb[v * 3 + 1] - 0.065f) < 1e-3f;
        green |= fabsf(alb[v * 3] - 0.14f) < 1e-3f && fabsf(alb[v * 3 + 1] - 0.45f) < 1e-3f;
    }
    assert_true(red && green);
    prt_bake_desc bd = {0};
    bd.order = 3;
    bd.samples = 128;
    bd.bounces = 2;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &bd, &t), PRT_OK);
    /* Every transfer value is finite. */
    const float *c = prt_transfer_coeffs(t, PRT_TRANSFER_INTERREFLECTED);
    for (size_t i = 0; i < prt_transfer_vertex_count(t) * 27; ++i) assert_true(isfinite(c[i]));
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Auto framing: from outside for an object, from inside for a closed room (also one with a box in
 * its middle, and one with its front open, as the Cornell box). */
static void test_camera_framing(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    for (int scene = 0; scene < 4; ++scene) {
        test_mesh m = {0};
        if (scene == 0) tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 12, 24);
        else {
            /* A 4 x 3 x 5 room, walls facing in; scene 2 adds a box at the centre, scene 3 has no front wall. */
            tm_quad(&m, (float[3]){-2, 0, 2.5f}, (float[3]){4, 0, 0}, (float[3]){0, 0, -5}, 4);     /* floor, up */
            tm_quad(&m, (float[3]){-2, 3, -2.5f}, (float[3]){4, 0, 0}, (float[3]){0, 0, 5}, 4);     /* ceiling, down */
            tm_quad(&m, (float[3]){-2, 0, 2.5f}, (float[3]){0, 0, -5}, (float[3]){0, 3, 0}, 4);     /* x = -2, +x */
            tm_quad(&m, (float[3]){2, 0, -2.5f}, (float[3]){0, 0, 5}, (float[3]){0, 3, 0}, 4);      /* x = 2, -x */
            tm_quad(&m, (float[3]){-2, 0, -2.5f}, (float[3]){4, 0, 0}, (float[3]){0, 3, 0}, 4);     /* back, +z */
            if (scene != 3) tm_quad(&m, (float[3]){2, 0, 2.5f}, (float[3]){-4, 0, 0}, (float[3]){0, 3, 0}, 4);   /* front, -z */
            if (scene == 2) tm_sphere(&m, (float[3]){0, 1.5f, 0}, 0.6f, 8, 16);
        }
        prt_camera cam;
        const int inside = prt_camera_frame_mesh(ctx, m.pos, m.nv, m.idx, m.nt, NULL, 0, 4.0f / 3.0f, &cam);
        print_message("scene %d: framed from %s, eye %.2f %.2f %.2f, fov %.0f\n", scene, inside ? "inside" : "outside", cam.eye[0], cam.eye[1], cam.eye[2],
                      cam.fov_y_deg);
        if (scene == 0) {
            assert_int_equal(inside, 0);
            assert_true(sqrtf(cam.eye[0] * cam.eye[0] + cam.eye[1] * cam.eye[1] + cam.eye[2] * cam.eye[2]) > 1.5f);
        } else {
            assert_int_equal(inside, 1);
            assert_true(fabsf(cam.eye[0]) < 2 && cam.eye[1] > 0 && cam.eye[1] < 3 && fabsf(cam.eye[2]) < 2.5f);
            assert_true(cam.fov_y_deg == 70.0f);
        }
        tm_free(&m);
    }
    prt_context_release(ctx);
}

/* Objects without materials keep their own names as surfaces, in the file's order (assimp joined
 * meshes sharing its default material into one, named after the last). */
static void test_objects_without_materials(void **state)
{
    (void)state;
    char path[512];
    write_text("objects.obj", "o plane\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nf 1 2 3\nf 1 3 4\no blocker\nv 0.2 0.5 -0.2\nv 0.8 0.5 -0.2\nv 0.8 0.5 -0.8\nf 5 7 6\n",
               path, sizeof path);
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("sh"), &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "order", "1"), PRT_OK);
    assert_int_equal(prt_options_set(o, "samples", "16"), PRT_OK);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, s, prt_method_find("sh"), o, NULL, &t), PRT_OK);
    assert_int_equal(prt_transfer_surface_count(t), 2);
    assert_string_equal(prt_transfer_surface_name(t, 1), "plane");
    assert_string_equal(prt_transfer_surface_name(t, 2), "blocker");
    prt_transfer_release(t);
    prt_options_release(o);
    prt_scene_release(s);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_obj_with_materials),
        cmocka_unit_test(test_black_default_albedo),
        cmocka_unit_test(test_winding),
        cmocka_unit_test(test_camera_framing),
        cmocka_unit_test(test_gltf_and_ply),
        cmocka_unit_test(test_json_scene),
        cmocka_unit_test(test_bad_mesh_inputs),
        cmocka_unit_test(test_cleaning_in_memory),
        cmocka_unit_test(test_duplicate_faces),
        cmocka_unit_test(test_subdivision),
        cmocka_unit_test(test_demo_scene),
        cmocka_unit_test(test_shared_meshes),
        cmocka_unit_test(test_objects_without_materials),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
