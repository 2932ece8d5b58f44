/* The transfer object shared by bake, file I/O and relighting. */
#ifndef PRT_CORE_TRANSFER_SET_H
#define PRT_CORE_TRANSFER_SET_H

#include "geom/mesh.h"

#define PRT__KIND_COUNT 3

typedef struct prt__sh_set {
    int channels;       /* 0 = absent, 1 = albedo applied at relight, 3 = RGB with albedo */
    float *coeffs;      /* [vertex][channel][order^2] */
} prt__sh_set;

struct prt_transfer {
    prt__mesh mesh;
    int order;
    prt__sh_set sets[PRT__KIND_COUNT];   /* indexed by prt__kind_index */
    int samples, bounces, threads;
    uint32_t seed;
    double bake_seconds;
    char source[512];
    bool has_env;
    prt_environment_desc env;
};

/* 0, 1, 2 for UNSHADOWED, SHADOWED, INTERREFLECTED; -1 for anything else. */
int prt__kind_index(prt_transfer_kind kind);
prt_transfer_kind prt__kind_from_index(int index);

#endif
