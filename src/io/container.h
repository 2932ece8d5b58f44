/* The .prt container's framing (docs/FORMAT.md): magic, version, a chunk table with a CRC-32 per
 * chunk and one over the table, 8-byte aligned chunks. It knows nothing of what chunks mean:
 * transfer/file.c and each method's entry fill and read them. */
#ifndef PRT_IO_CONTAINER_H
#define PRT_IO_CONTAINER_H

#include "core/internal.h"

#define PRT__FOURCC(a, b, c, d) ((uint32_t)(a) | (uint32_t)(b) << 8 | (uint32_t)(c) << 16 | (uint32_t)(d) << 24)
#define PRT__CHUNK_PARTS 8

/* A chunk to write: up to PRT__CHUNK_PARTS byte ranges written one after another (no copy). */
typedef struct prt__chunk_out {
    uint32_t id;
    const void *parts[PRT__CHUNK_PARTS];
    size_t sizes[PRT__CHUNK_PARTS];
} prt__chunk_out;

typedef struct prt__chunk_list {
    prt__chunk_out *chunks;
    int count, capacity;
    void **owned;             /* buffers freed with the list */
    int owned_count, owned_capacity;
    bool failed;              /* an allocation failed: writing reports it */
    /* The format version the file needs (0 = 1): raised by writers of chunks that older readers
     * would misread by skipping them (version 2: half-float maps and texel sets; 3: spectral rows
     * with a scale each), so that those readers refuse the file as newer instead. */
    uint32_t version;
} prt__chunk_list;

/* Appends a chunk of up to PRT__CHUNK_PARTS parts (pairs of pointer and size, NULL-terminated). */
void prt__chunks_add(prt__chunk_list *l, uint32_t id, ...);
/* A zeroed buffer that lives as long as the list. */
void *prt__chunks_alloc(prt__chunk_list *l, size_t bytes);
void prt__chunks_free(prt__chunk_list *l);
/* Writes the chunks atomically (temporary file + rename). */
prt_status prt__container_write(const char *path, const prt__chunk_list *l);

/* A chunk read back: its bytes (inside the caller's buffer) after the CRC was checked. */
typedef struct prt__chunk_in {
    uint32_t id;
    const unsigned char *data;
    uint64_t size;
    bool used;                /* set by whoever consumed it */
} prt__chunk_in;

/* Validates the framing of a whole file in memory (magic, version, table checksum, every chunk
 * inside the file and matching its CRC) and lists the chunks in file order; *chunks is malloc'd. */
prt_status prt__container_read(prt_context *ctx, const void *data, size_t size, prt__chunk_in **chunks, int *count);
/* The first unused chunk with this id, marked used; NULL if none. */
prt__chunk_in *prt__chunk_take(prt__chunk_in *chunks, int count, uint32_t id);
/* "MESH" for a chunk id. */
void prt__chunk_name(uint32_t id, char out[5]);

static inline void prt__put32(unsigned char *p, uint32_t v) { memcpy(p, &v, 4); }
static inline void prt__put64(unsigned char *p, uint64_t v) { memcpy(p, &v, 8); }
static inline uint32_t prt__get32(const unsigned char *p) { uint32_t v; memcpy(&v, p, 4); return v; }
static inline uint64_t prt__get64(const unsigned char *p) { uint64_t v; memcpy(&v, p, 8); return v; }
bool prt__all_finite(const float *p, size_t n);

#endif
