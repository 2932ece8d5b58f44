/* The transfer object: what a bake produced and a .prt file holds. Method-independent parts
 * (the baked mesh with materials, UVs and emission; the scene's lighting; bake bookkeeping) plus
 * one method's state, which only that method's files look inside. */
#ifndef PRT_TRANSFER_TRANSFER_H
#define PRT_TRANSFER_TRANSFER_H

#include "geom/mesh.h"
#include "prt/method.h"
#include "prt/transfer.h"

struct prt_method;

struct prt_transfer {
    prt__mesh mesh;
    int brdf_count;
    prt_brdf brdfs[PRT__MAX_BRDFS];   /* materials named by mesh.material */
    /* The lighting the scene named. */
    bool has_env;
    prt_environment_desc env;
    int light_count;
    prt_light *lights;
    /* Bookkeeping: informational, except that timing fields never take part in comparisons. */
    char source[512];
    double bake_seconds;
    int threads;
    uint64_t peak_bytes, memory_limit;   /* the process's peak resident memory after the bake, the limit (0: unknown) */
    const struct prt_method *method;
    void *state;                      /* the method's own, freed by method->free_state */
    uint64_t serial;                  /* unique in the process: what GPU caches key on (never reused, unlike an address) */
};
/* The next transfer serial (thread-safe). */
uint64_t prt__transfer_serial(void);

/* A new transfer of method m with a copy of scene's mesh, materials and lighting. */
prt_status prt__transfer_from_scene(prt_context *ctx, const struct prt_method *m, const prt_scene *scene, prt_transfer **out);
/* A new transfer of the same method sharing nothing with src: mesh, materials, lighting and
 * bookkeeping copied; state left NULL for the caller. */
prt_status prt__transfer_copy_frame(prt_context *ctx, const prt_transfer *src, prt_transfer **out);
/* Copies a mesh including materials, UVs and emission. */
prt_status prt__mesh_copy(prt__mesh *dst, const prt__mesh *src);
/* The state of t when t was baked with method m, else NULL. */
static inline void *prt__state_of(const prt_transfer *t, const struct prt_method *m)
{
    return t && t->method == m ? t->state : NULL;
}

#endif
