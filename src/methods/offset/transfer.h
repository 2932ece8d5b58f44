/* Offset transfer maps (Sunshine-Hill & Faloutsos 2006): texel patches, the transfer between
 * them - diffuse inter-reflection (form factors with visibility) and subsurface scattering
 * (Jensen's dipole) - the maps TR(t, t + dt) TVA(t, dt) of eq. 10, and the two ways of applying
 * transfer to a first-order light map: the offset form of eq. 9 (modulate, shift, accumulate) and
 * the direct gather of eq. 3 it approximates. */
#ifndef PRT_METHODS_OFFSET_TRANSFER_H
#define PRT_METHODS_OFFSET_TRANSFER_H

#include "geom/raycast.h"
#include "brdf/dipole.h"

/* The surface behind each texel of a W x H map over the mesh's UVs: the point and normal at the
 * texel centre (of the triangle that owns it), albedo, world area TA(t) (0 off the charts). */
typedef struct prt__texel_patches {
    int width, height;
    float *pos, *nrm, *albedo, *area;   /* 3, 3, 3, 1 per texel */
    uint32_t *owner;                    /* triangle + 1; 0 = no surface */
} prt__texel_patches;

prt_status prt__texel_patches_build(const prt_context *ctx, const prt__mesh *m, int width, int height, prt__texel_patches *out);
void prt__texel_patches_free(prt__texel_patches *p);

/* Transfer from source texel s to receiver t per unit area of s, per colour channel. */
typedef enum prt__offset_kind {
    PRT__OFFSET_RADIOSITY = 1,   /* one diffuse bounce: albedo(t) cos cos' V / (pi r^2 + TA(s)) */
    PRT__OFFSET_DIPOLE           /* subsurface: R_d at |x_t - x_s| widened by the source's radius,
                                  * no visibility (not yet limited to one object: R_d is negligible
                                  * a few mean free paths away) */
} prt__offset_kind;

typedef struct prt__offset_transfer {
    prt__offset_kind kind;
    const prt__texel_patches *patches;
    const prt__raycaster *rc;          /* radiosity: visibility */
    float ray_offset;
    prt__dipole dipole[3];             /* dipole: per channel, when medium is NULL */
    /* Dipole with translucent materials: per texel (width x height) 0 = opaque, else a medium of
     * media[medium - 1]; light scatters only between texels of one medium. */
    const uint8_t *medium;
    const prt__dipole (*media)[3];
} prt__offset_transfer;

void prt__offset_tr(const prt__offset_transfer *x, size_t t, size_t s, float out[3]);

/* The transfer maps of eq. 10: maps[(k * texels + t) * 3 + c] = TR(t, t + offset k) TVA(t, k). */
prt_status prt__offset_maps(const prt_context *ctx, const prt__offset_transfer *x, const int *offsets, int count, float **maps);

/* Eq. 9: out(t) = sum_k first(t + offset k) maps_k(t), 3 channels, texels off the map giving 0. */
void prt__offset_apply(const prt_context *ctx, int width, int height, const int *offsets, int count, const float *maps, const float *first,
                       float *out);

/* Eq. 3, the direct gather the offset form approximates: out(t) = sum_s first(s) TR(t, s) TA(s). */
void prt__offset_gather(const prt_context *ctx, const prt__offset_transfer *x, const float *first, float *out);

#endif
