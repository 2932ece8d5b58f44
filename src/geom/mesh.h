/* The scene's triangle mesh and the growable builder that importers fill. */
#ifndef PRT_GEOM_MESH_H
#define PRT_GEOM_MESH_H

#include "core/internal.h"
#include "prt/brdf.h"
#include "prt/scene.h"
#include "geom/volume.h"

/* Struct-of-arrays mesh; every array has 3 entries per vertex or per triangle. */
typedef struct prt__mesh {
    size_t vertex_count, triangle_count;
    float *positions, *normals, *albedo;
    uint8_t *material;    /* per vertex: 0 = Lambert with `albedo`, k = the owner's brdfs[k - 1] */
    float *uv;            /* 2 per vertex; NaN where the input had no texture coordinates */
    float *emission;      /* 3 per vertex, emitted radiance; NULL when nothing emits */
    uint32_t *indices;
    /* Named surfaces (the materials of mesh files, the materials of scene JSON): per vertex 0 =
     * unnamed, k = surface_names[k - 1]. What --albedo-of NAME recolours at run time. */
    uint16_t *surface;
    int surface_count;
    char (*surface_names)[64];
} prt__mesh;

#define PRT__MAX_BRDFS 255
#define PRT__MAX_SURFACES 65535
#define PRT__SURFACE_NAME 64   /* bytes per name, the terminating NUL included */

void prt__mesh_free(prt__mesh *m);
/* Appends vertices/triangles; indices are relative to the appended vertices. normals may be
 * NULL (then zero, meaning "compute"); albedo may be NULL (then rgb_default). */
prt_status prt__mesh_append(prt__mesh *m, const float *pos, const float *nrm, const float *albedo,
                            const float rgb_default[3], size_t nv, const uint32_t *idx, size_t nt);
/* The id (1-based) of the surface called name, added if new: control characters become '_',
 * names are cut to 63 bytes; "" is 0 (unnamed). -1 when the table is full or memory ran out. */
int prt__mesh_surface_id(prt__mesh *m, const char *name);
/* Sets albedo (3 per vertex) of the vertices of every surface called name; fails listing the
 * names when none is. */
prt_status prt__mesh_paint(const prt__mesh *m, const char *name, const float rgb[3], float *albedo);
/* Drops surface names no vertex uses, renumbering the rest in order. */
void prt__mesh_compact_surfaces(prt__mesh *m);
/* Gives vertices [first, first + count) surface id. */
void prt__mesh_set_surface(prt__mesh *m, size_t first, size_t count, int id);
/* The per-vertex emission array, allocated as zeros on first use (emission stays NULL while
 * nothing emits); NULL when out of memory. */
float *prt__mesh_emission(prt__mesh *m);
/* Sets texture coordinates of vertices [first, first + count). */
void prt__mesh_set_uv(prt__mesh *m, size_t first, size_t count, const float *uv);
/* True when every vertex has texture coordinates. */
bool prt__mesh_has_uv(const prt__mesh *m);
/* Validates and cleans in place: rejects non-finite positions and out-of-range indices, drops
 * zero-area triangles and unreferenced vertices, repairs missing or bad normals. */
prt_status prt__mesh_clean(const prt_context *ctx, prt__mesh *m, const char *what);
/* Splits edges until none is longer than max_edge, keeping the mesh conforming. */
prt_status prt__mesh_subdivide(const prt_context *ctx, prt__mesh *m, float max_edge);
#define PRT__MAX_REFINE_VERTICES 50000000u
/* Adaptive refinement (see prt_scene_refine) with the scene's lights. */
prt_status prt__mesh_refine(const prt_context *ctx, prt__mesh *m, const prt_light *lights, int light_count,
                            const prt_refine_desc *desc, prt_refine_stats *stats);
prt_status prt__mesh_refine_estimate(const prt_context *ctx, const prt__mesh *m, const prt_light *lights, int light_count,
                                     const prt_refine_desc *desc, prt_refine_stats *stats);
/* Grows every per-vertex array to hold max_v vertices; false when out of memory (or past 2^32). */
bool prt__mesh_reserve(prt__mesh *m, size_t max_v);
/* Appends the midpoint of edge (a, b), every attribute interpolated, and returns its id; the
 * arrays must have room (prt__mesh_reserve). */
uint32_t prt__mesh_midpoint(prt__mesh *m, uint32_t a, uint32_t b);

/* One candidate BRDF of a named surface, for methods that switch BRDFs at run time. */
#define PRT__MAX_BRDF_SET 64
typedef struct prt__brdf_choice {
    uint16_t surface;                 /* 1-based surface id */
    prt_brdf brdf;
} prt__brdf_choice;

struct prt_scene {
    prt__mesh mesh;
    int brdf_count;
    prt_brdf brdfs[PRT__MAX_BRDFS];
    char source[512];
    bool has_env;
    prt_environment_desc env;
    int light_count;
    prt_light *lights;
    bool has_camera;                  /* a JSON scene's "camera" */
    float camera_eye[3], camera_target[3], camera_fov;
    int brdf_set_count;               /* candidate BRDFs of named surfaces (a material's "brdfs") */
    prt__brdf_choice *brdf_set;
    int medium_count;                 /* translucent surfaces, by name */
    struct prt__named_medium { char name[PRT__SURFACE_NAME]; prt_medium m; } *media;
    int specular_count;               /* specular surfaces, by name */
    struct prt__named_specular { char name[PRT__SURFACE_NAME]; prt_specular s; } *speculars;
    int volume_count;                 /* participating media ("volumes") */
    prt__volume *volumes;
};

/* Adds brdf to the candidates of surface (1-based) unless it is there; PRT_ERR_INVALID_ARG when
 * PRT__MAX_BRDF_SET are taken (no message: callers say where). */
prt_status prt__scene_brdf_choice(prt_scene *scene, int surface, const prt_brdf *brdf);
/* The material id (1-based) of brdf in the scene's table, adding it if new; 0 when the table is full. */
int prt__scene_brdf_id(prt_scene *scene, const prt_brdf *brdf);

/* Adds the mesh file at path (anything assimp reads), with optional transform (row-major 4x4,
 * NULL = identity) and albedo override (NULL = from materials, else desc default). `inside`
 * holds inside_count world points (the scene's lights, its camera's eye, desc->inside_points) that
 * a room around them must keep facing: a closed piece around one is never flipped. */
prt_status prt__import_mesh(const prt_context *ctx, const char *path, const float *xform, const float *albedo_override,
                            const float *inside, size_t inside_count, const prt_scene_desc *desc, prt__mesh *m);
/* Adds every mesh a .json scene names. */
prt_status prt__import_scene_json(const prt_context *ctx, const char *path, const prt_scene_desc *desc,
                                  prt_scene *scene);

#endif
