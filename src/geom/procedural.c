/* The procedural demo scene: shapes chosen so that every transfer kind looks different.
 * A torus lying on the ground (its hole is a concavity that shadows itself), a sphere casting a
 * contact shadow, and a red and a green wall that bleed colour onto a white floor. */
#include "geom/mesh.h"

#include <stdio.h>
#include <string.h>

typedef struct shape {
    const char *material;
    float rgb[3];
    float chart[4];       /* u0, v0, u1, v1: the shape's rectangle in the scene's UV atlas */
    size_t nv, nt;
    float *pos, *nrm, *uv;
    uint32_t *idx;
} shape;

static bool shape_alloc(shape *s, size_t nv, size_t nt)
{
    s->nv = nv; s->nt = nt;
    s->pos = prt__calloc(nv * 3, sizeof(float));
    s->nrm = prt__calloc(nv * 3, sizeof(float));
    s->idx = prt__calloc(nt * 3, sizeof(uint32_t));
    s->uv = prt__calloc(nv * 2, sizeof(float));
    return s->pos && s->nrm && s->idx && s->uv;
}

/* (u+1) x (v+1) grid of vertices with param(u, v) -> position, normal; wraps nothing. */
typedef void (*param_fn)(const float *args, float u, float v, float *p, float *n);

static bool shape_grid(shape *s, int nu, int nv, param_fn f, const float *args)
{
    if (!shape_alloc(s, (size_t)(nu + 1) * (nv + 1), (size_t)nu * nv * 2)) return false;
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) {
            size_t k = (size_t)j * (nu + 1) + i;
            f(args, (float)i / nu, (float)j / nv, s->pos + k * 3, s->nrm + k * 3);
            /* A unique UV layout (one chart per shape), so per-texel transfer works on the demo. */
            s->uv[k * 2] = s->chart[0] + (s->chart[2] - s->chart[0]) * (float)i / nu;
            s->uv[k * 2 + 1] = s->chart[1] + (s->chart[3] - s->chart[1]) * (float)j / nv;
        }
    size_t t = 0;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            uint32_t a = (uint32_t)(j * (nu + 1) + i), b = a + 1, c = a + (uint32_t)(nu + 1), d = c + 1;
            uint32_t tri[6] = {a, b, c, b, d, c};
            for (int k = 0; k < 2; ++k) {
                float e1[3], e2[3], n[3];   /* rows collapsed at a pole give zero-area triangles */
                prt__v3_sub(s->pos + tri[k * 3 + 1] * 3, s->pos + tri[k * 3] * 3, e1);
                prt__v3_sub(s->pos + tri[k * 3 + 2] * 3, s->pos + tri[k * 3] * 3, e2);
                prt__v3_cross(e1, e2, n);
                if (prt__v3_len(n) < 1e-6f) continue;
                memcpy(s->idx + t * 3, tri + k * 3, 3 * sizeof(uint32_t));
                t++;
            }
        }
    s->nt = t;
    return true;
}

/* args: origin[3], edge_u[3], edge_v[3]; the normal is edge_u x edge_v, the side from which the
 * grid's winding is counter-clockwise. */
static void plane_param(const float *a, float u, float v, float *p, float *n)
{
    for (int c = 0; c < 3; ++c) p[c] = a[c] + u * a[3 + c] + v * a[6 + c];
    prt__v3_cross(a + 3, a + 6, n);
    prt__v3_normalize(n);
}

/* args: centre[3], major radius, minor radius. Torus around +y. */
static void torus_param(const float *a, float u, float v, float *p, float *n)
{
    float phi = (float)(2 * PRT_PI) * u, th = (float)(2 * PRT_PI) * v;
    float dir[3] = {cosf(phi), 0, -sinf(phi)};
    n[0] = dir[0] * cosf(th); n[1] = sinf(th); n[2] = dir[2] * cosf(th);
    for (int c = 0; c < 3; ++c) p[c] = a[c] + dir[c] * a[3] + n[c] * a[4];
}

/* args: centre[3], radius. */
static void sphere_param(const float *a, float u, float v, float *p, float *n)
{
    float phi = (float)(2 * PRT_PI) * u, th = (float)PRT_PI * (1.0f - v);
    n[0] = sinf(th) * cosf(phi); n[1] = cosf(th); n[2] = -sinf(th) * sinf(phi);
    for (int c = 0; c < 3; ++c) p[c] = a[c] + n[c] * a[3];
}

static prt_status write_obj(const char *obj_path, const shape *shapes, int count)
{
    char mtl_path[1024], mtl_name[1024];
    snprintf(mtl_path, sizeof mtl_path, "%s", obj_path);
    char *dot = strrchr(mtl_path, '.');
    if (dot && !strchr(dot, '/')) *dot = 0;
    strncat(mtl_path, ".mtl", sizeof mtl_path - strlen(mtl_path) - 1);
    const char *base = strrchr(mtl_path, '/');
    snprintf(mtl_name, sizeof mtl_name, "%s", base ? base + 1 : mtl_path);

    prt__atomic_file f;
    prt_status st = prt__atomic_open(&f, mtl_path);
    if (st) return st;
    char line[256];
    for (int i = 0; i < count && !st; ++i) {
        bool seen = false;   /* several shapes may share a material: one entry each */
        for (int j = 0; j < i && !seen; ++j) seen = !strcmp(shapes[j].material, shapes[i].material);
        if (seen) continue;
        int n = snprintf(line, sizeof line, "newmtl %s\nKd %.4f %.4f %.4f\n\n", shapes[i].material,
                         shapes[i].rgb[0], shapes[i].rgb[1], shapes[i].rgb[2]);
        st = prt__atomic_write(&f, line, (size_t)n);
    }
    if (st) { prt__atomic_abort(&f); return st; }
    if ((st = prt__atomic_commit(&f))) return st;

    if ((st = prt__atomic_open(&f, obj_path))) return st;
    int n = snprintf(line, sizeof line, "# prt procedural demo scene\nmtllib %s\n", mtl_name);
    st = prt__atomic_write(&f, line, (size_t)n);
    size_t base_v = 1;
    for (int i = 0; i < count && !st; ++i) {
        const shape *s = &shapes[i];
        n = snprintf(line, sizeof line, "o %s\nusemtl %s\n", s->material, s->material);
        st = prt__atomic_write(&f, line, (size_t)n);
        for (size_t v = 0; v < s->nv && !st; ++v) {
            n = snprintf(line, sizeof line, "v %.6f %.6f %.6f\nvn %.6f %.6f %.6f\nvt %.6f %.6f\n", s->pos[v * 3], s->pos[v * 3 + 1],
                         s->pos[v * 3 + 2], s->nrm[v * 3], s->nrm[v * 3 + 1], s->nrm[v * 3 + 2], s->uv[v * 2], s->uv[v * 2 + 1]);
            st = prt__atomic_write(&f, line, (size_t)n);
        }
        for (size_t t = 0; t < s->nt && !st; ++t) {
            size_t a = s->idx[t * 3] + base_v, b = s->idx[t * 3 + 1] + base_v, c = s->idx[t * 3 + 2] + base_v;
            n = snprintf(line, sizeof line, "f %zu/%zu/%zu %zu/%zu/%zu %zu/%zu/%zu\n", a, a, a, b, b, b, c, c, c);
            st = prt__atomic_write(&f, line, (size_t)n);
        }
        base_v += s->nv;
    }
    if (st) { prt__atomic_abort(&f); return st; }
    return prt__atomic_commit(&f);
}

prt_status prt_demo_scene_write(const char *obj_path)
{
    /* Charts sized roughly by area, 0.01 apart. */
    shape s[5] = {{.material = "floor", .rgb = {0.75f, 0.75f, 0.72f}, .chart = {0.01f, 0.01f, 0.49f, 0.49f}},
                  {.material = "red_wall", .rgb = {0.75f, 0.12f, 0.08f}, .chart = {0.51f, 0.01f, 0.99f, 0.245f}},
                  {.material = "green_wall", .rgb = {0.12f, 0.6f, 0.12f}, .chart = {0.51f, 0.255f, 0.99f, 0.49f}},
                  {.material = "torus", .rgb = {0.8f, 0.8f, 0.78f}, .chart = {0.01f, 0.51f, 0.99f, 0.74f}},
                  {.material = "sphere", .rgb = {0.85f, 0.7f, 0.45f}, .chart = {0.01f, 0.75f, 0.6f, 0.99f}}};
    const float floor_args[9] = {-1.5f, 0, 1.5f, 3, 0, 0, 0, 0, -3};
    const float red_args[9] = {-1.5f, 0, 1.5f, 0, 0, -3, 0, 1.5f, 0};
    const float green_args[9] = {-1.5f, 0, -1.5f, 3, 0, 0, 0, 1.5f, 0};
    const float torus_args[5] = {0.35f, 0.16f, 0.35f, 0.5f, 0.16f};
    const float sphere_args[4] = {-0.55f, 0.4f, -0.55f, 0.4f};
    bool ok = shape_grid(&s[0], 48, 48, plane_param, floor_args) && shape_grid(&s[1], 48, 24, plane_param, red_args) &&
              shape_grid(&s[2], 48, 24, plane_param, green_args) && shape_grid(&s[3], 96, 32, torus_param, torus_args) &&
              shape_grid(&s[4], 64, 32, sphere_param, sphere_args);
    prt_status st = ok ? write_obj(obj_path, s, 5) : prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    for (int i = 0; i < 5; ++i) { free(s[i].pos); free(s[i].nrm); free(s[i].idx); free(s[i].uv); }
    return st;
}

static int cells(float length, float cell) { int n = (int)ceilf(length / cell); return n < 1 ? 1 : n; }

prt_status prt_demo_room_write(const char *obj_path, float cell)
{
    if (!(cell >= 0.005f && cell <= 1.0f)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "room cell size %g out of range 0.005..1", cell);
    /* A 6 x 3 x 4 m room, inward normals, a 1.2 x 1 m window in the front wall (z = 2), and two
     * boxes; every surface a grid of about cell-sized squares (the paper's Fig. 6 scene). */
    enum { N = 15 };
    shape s[N] = {{.material = "floor", .rgb = {0.6f, 0.45f, 0.3f}}, {.material = "ceiling", .rgb = {0.8f, 0.8f, 0.8f}},
                  {.material = "back_wall", .rgb = {0.75f, 0.72f, 0.65f}}, {.material = "front_wall", .rgb = {0.75f, 0.72f, 0.65f}},
                  {.material = "front_wall", .rgb = {0.75f, 0.72f, 0.65f}}, {.material = "front_wall", .rgb = {0.75f, 0.72f, 0.65f}},
                  {.material = "front_wall", .rgb = {0.75f, 0.72f, 0.65f}},
                  {.material = "left_wall", .rgb = {0.7f, 0.25f, 0.2f}}, {.material = "right_wall", .rgb = {0.75f, 0.72f, 0.65f}},
                  {.material = "box", .rgb = {0.2f, 0.3f, 0.65f}}, {.material = "box", .rgb = {0.2f, 0.3f, 0.65f}},
                  {.material = "box", .rgb = {0.2f, 0.3f, 0.65f}}, {.material = "box", .rgb = {0.2f, 0.3f, 0.65f}},
                  {.material = "box", .rgb = {0.2f, 0.3f, 0.65f}}, {.material = "shelf", .rgb = {0.8f, 0.75f, 0.6f}}};
    for (int i = 0; i < N; ++i) { s[i].chart[2] = 1; s[i].chart[3] = 1; }
    const float W = 6, H = 3, D = 4, x0 = -3, z0 = -2;
    /* origin, edge u, edge v (normal u x v points into the room) */
    const float args[N][9] = {
        {x0, 0, -z0, W, 0, 0, 0, 0, -D},            /* floor, up */
        {x0, H, z0, W, 0, 0, 0, 0, D},              /* ceiling, down */
        {x0, 0, z0, W, 0, 0, 0, H, 0},              /* back wall z = -2, facing +z */
        /* front wall z = +2, facing -z, in four pieces around the window x in [-0.6, 0.6], y in [1, 2] */
        {-x0, 0, -z0, -W, 0, 0, 0, 1, 0},
        {-x0, 2, -z0, -W, 0, 0, 0, 1, 0},
        {-0.6f, 1, -z0, x0 + 0.6f, 0, 0, 0, 1, 0},
        {-x0, 1, -z0, 0.6f + x0, 0, 0, 0, 1, 0},
        {x0, 0, -z0, 0, 0, -D, 0, H, 0},            /* left wall x = -3, facing +x */
        {-x0, 0, z0, 0, 0, D, 0, H, 0},             /* right wall x = +3, facing -x */
        /* a 1.2 x 0.9 x 1.0 box at x in [-2, -0.8], z in [-1.2, -0.2]: top and four sides */
        {-2.0f, 0.9f, -0.2f, 1.2f, 0, 0, 0, 0, -1.0f},
        {-2.0f, 0, -0.2f, 1.2f, 0, 0, 0, 0.9f, 0},
        {-0.8f, 0, -1.2f, -1.2f, 0, 0, 0, 0.9f, 0},
        {-2.0f, 0, -1.2f, 0, 0, 1.0f, 0, 0.9f, 0},
        {-0.8f, 0, -0.2f, 0, 0, -1.0f, 0, 0.9f, 0},
        /* a shelf board 1.5 m up on the right wall, facing up */
        {1.8f, 1.5f, 0.5f, 1.2f, 0, 0, 0, 0, -1.5f},
    };
    bool ok = true;
    for (int i = 0; i < N && ok; ++i) {
        const float lu = prt__v3_len(args[i] + 3), lv = prt__v3_len(args[i] + 6);
        ok = shape_grid(&s[i], cells(lu, cell), cells(lv, cell), plane_param, args[i]);
    }
    prt_status st = ok ? write_obj(obj_path, s, N) : prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    for (int i = 0; i < N; ++i) { free(s[i].pos); free(s[i].nrm); free(s[i].idx); free(s[i].uv); }
    return st;
}
