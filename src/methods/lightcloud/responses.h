/* Kept cloud-light solutions (responses.c, `--responses FILE`): a bake takes the solutions a file
 * holds for its cloud lights' positions instead of solving them again, and writes the file back
 * with its own added. */
#ifndef PRT_METHODS_LIGHTCLOUD_RESPONSES_H
#define PRT_METHODS_LIGHTCLOUD_RESPONSES_H

#include "methods/lightcloud/lightcloud.h"
#include "transfer/checkpoint.h"

typedef struct prt__lightcloud_responses prt__lightcloud_responses;

/* What a solution depends on besides its position: the library version, the scene and the solve's
 * settings (not the cloud, zones, merging or compression). */
void prt__lightcloud_responses_fingerprint(const prt_transfer *t, const prt_options *o, const prt__lightcloud_set *s, prt__fingerprint *fp);
/* Opens path (missing: none kept yet) and finds the n cloud lights it holds. A file of another
 * fingerprint or of another number of emission lobes per light (1, 4 or 9) is refused, a damaged
 * one too. */
prt_status prt__lightcloud_responses_open(prt_context *ctx, const char *path, const prt__fingerprint *fp, uint64_t nv, uint64_t glossy, int lobes,
                                          const float *cloud, uint32_t n, prt__lightcloud_responses **out);
bool prt__lightcloud_responses_has(const prt__lightcloud_responses *r, uint32_t light);
/* Light `light`'s kept solution to emission lobe `lobe`: diffuse [vertex][3], glossy
 * [glossy vertex][48], whether the light lights anything. Thread-safe. */
prt_status prt__lightcloud_responses_read(prt_context *ctx, prt__lightcloud_responses *r, uint32_t light, int lobe, float *diffuse, float *glossy,
                                          bool *lit);
uint32_t prt__lightcloud_responses_reused(const prt__lightcloud_responses *r);
/* Writes path: the n cloud lights' solutions (asked of get lobe by lobe, in the layout above; lobe
 * 0's lit counts), then the kept ones of positions not in the cloud. */
prt_status prt__lightcloud_responses_write(prt_context *ctx, prt__lightcloud_responses *r, const char *path, const prt__fingerprint *fp,
                                           const float *cloud, uint32_t n,
                                           prt_status (*get)(void *user, uint32_t light, int lobe, float *diffuse, float *glossy, bool *lit),
                                           void *user);
void prt__lightcloud_responses_close(prt__lightcloud_responses *r);

#endif
