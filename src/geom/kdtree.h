/* A static kd-tree over 3D points for k-nearest-neighbour queries (after Bentley 1975; as
 * Kristensen et al. 2005, section 6.1, find the precomputed lights nearest a user's light). */
#ifndef PRT_GEOM_KDTREE_H
#define PRT_GEOM_KDTREE_H

#include "core/internal.h"

#define PRT__KDTREE_MAX_K 64

typedef struct prt__kdtree {
    uint32_t count;
    const float *points;     /* [count][3], borrowed */
    uint32_t *order;         /* the points in tree order: node i of range [lo, hi) splits at its middle */
    uint8_t *axis;           /* [count] split axis of the node whose middle element is at that position */
} prt__kdtree;

/* Builds over points (borrowed: they must outlive the tree); false when out of memory. */
bool prt__kdtree_build(prt__kdtree *t, const float *points, uint32_t count);
void prt__kdtree_free(prt__kdtree *t);
/* The k (at most PRT__KDTREE_MAX_K and count) points nearest q, nearest first (ties by index);
 * returns how many were found. dist may be NULL. */
int prt__kdtree_nearest(const prt__kdtree *t, const float q[3], int k, uint32_t *index, float *dist);

#endif
