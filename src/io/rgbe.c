/* Radiance RGBE (.hdr) decoding (Ward, "Real Pixels", Graphics Gems II; the format of Radiance's
 * color.c): a text header ending in an empty line, a resolution line, then per scanline either
 * flat 4-byte pixels (with the old run convention: 1,1,1,n repeats the previous pixel) or, for
 * widths 8..32767, the new run-length form: 2, 2, width (big endian), then each of R, G, B, E as
 * runs (count > 128: one byte repeated count - 128 times) and literals (count <= 128 bytes).
 * Values are m * 2^(e - 136), as stb_image reads them, so results do not change with the reader. */
#include "io/rgbe.h"

#include <string.h>

bool prt__is_rgbe(const unsigned char *data, size_t size)
{
    return (size >= 10 && !memcmp(data, "#?RADIANCE", 10)) || (size >= 6 && !memcmp(data, "#?RGBE", 6));
}

static prt_status bad(const char *msg) { return prt__fail(NULL, PRT_ERR_FORMAT, "corrupt .hdr image: %s", msg); }

/* The next line of the header (without its newline) into line; false at the end of the data. */
static bool next_line(const unsigned char *data, size_t size, size_t *at, char *line, size_t cap)
{
    size_t n = 0;
    while (*at < size && data[*at] != '\n') {
        if (n + 1 < cap) line[n++] = (char)data[*at];
        ++*at;
    }
    line[n] = 0;
    if (*at >= size) return false;
    ++*at;   /* the newline */
    return true;
}

static void to_float(const unsigned char rgbe[4], float *rgb)
{
    if (!rgbe[3]) { rgb[0] = rgb[1] = rgb[2] = 0.0f; return; }
    const float f = ldexpf(1.0f, (int)rgbe[3] - (128 + 8));
    for (int c = 0; c < 3; ++c) rgb[c] = (float)rgbe[c] * f;
}

/* One scanline of w pixels from data[*at...] into rgbe (4 bytes per pixel). */
static prt_status scanline(const unsigned char *data, size_t size, size_t *at, int w, unsigned char *rgbe)
{
    const unsigned char *p = data + *at;
    const size_t left = size - *at;
    const bool rle = w >= 8 && w <= 0x7fff && left >= 4 && p[0] == 2 && p[1] == 2 && !(p[2] & 0x80);
    if (!rle) {
        /* Flat pixels; 1,1,1,n repeats the previous pixel n << shift times (shift grows by 8 for
         * consecutive repeat codes). */
        int x = 0, shift = 0;
        while (x < w) {
            if (size - *at < 4) return bad("a scanline is cut off");
            const unsigned char *q = data + *at;
            *at += 4;
            if (q[0] == 1 && q[1] == 1 && q[2] == 1) {
                if (x == 0) return bad("a run repeats a pixel before the first");
                if (shift > 16) return bad("a run is too long");
                const size_t n = (size_t)q[3] << shift;
                if (n > (size_t)(w - x)) return bad("a run overruns its scanline");
                for (size_t k = 0; k < n; ++k, ++x) memcpy(rgbe + (size_t)x * 4, rgbe + (size_t)(x - 1) * 4, 4);
                shift += 8;
            } else {
                memcpy(rgbe + (size_t)x * 4, q, 4);
                ++x;
                shift = 0;
            }
        }
        return PRT_OK;
    }
    if (((int)p[2] << 8 | p[3]) != w) return bad("a scanline's length does not match the image width");
    *at += 4;
    for (int c = 0; c < 4; ++c) {
        int x = 0;
        while (x < w) {
            if (*at >= size) return bad("a scanline is cut off");
            int count = data[(*at)++];
            if (count > 128) {
                count -= 128;
                if (count > w - x) return bad("a run overruns its scanline");
                if (*at >= size) return bad("a scanline is cut off");
                const unsigned char v = data[(*at)++];
                for (int k = 0; k < count; ++k, ++x) rgbe[(size_t)x * 4 + c] = v;
            } else {
                if (count == 0) return bad("a zero-length run");
                if (count > w - x) return bad("a run overruns its scanline");
                if ((size_t)count > size - *at) return bad("a scanline is cut off");
                for (int k = 0; k < count; ++k, ++x) rgbe[(size_t)x * 4 + c] = data[(*at)++];
            }
        }
    }
    return PRT_OK;
}

prt_status prt__load_rgbe(const unsigned char *data, size_t size, int max_dim, prt_image *out)
{
    memset(out, 0, sizeof *out);
    if (!prt__is_rgbe(data, size)) return bad("no #?RADIANCE signature");
    size_t at = 0;
    char line[256];
    bool format_ok = true;
    for (int lines = 0;; ++lines) {
        if (lines > 1000 || !next_line(data, size, &at, line, sizeof line)) return bad("the header never ends");
        if (!line[0]) break;
        if (!strncmp(line, "FORMAT=", 7)) format_ok = !strcmp(line + 7, "32-bit_rle_rgbe");
    }
    if (!format_ok) return prt__fail(NULL, PRT_ERR_FORMAT, ".hdr image: only FORMAT=32-bit_rle_rgbe is supported (not XYZE)");
    if (!next_line(data, size, &at, line, sizeof line)) return bad("no resolution line");
    char ys, xs;
    long h, w;
    int used = 0;
    if (sscanf(line, "%cY %ld %cX %ld%n", &ys, &h, &xs, &w, &used) != 4 || line[used] || (ys != '-' && ys != '+') || xs != '+')
        return prt__fail(NULL, PRT_ERR_FORMAT, ".hdr image: unsupported resolution line '%.64s' (prt reads -Y H +X W and +Y H +X W)", line);
    if (w < 1 || h < 1 || w > max_dim || h > max_dim) return prt__fail(NULL, PRT_ERR_FORMAT, ".hdr image size %ldx%ld is out of range (1..%d)", w, h, max_dim);
    /* Before the size sizes an allocation: even fully run-length coded, each scanline needs 4
     * bytes plus two per 127 values of each channel. */
    const size_t min_line = w >= 8 && w <= 0x7fff ? 4 + 8 * (((size_t)w + 126) / 127) : 4;
    if ((size_t)h > (size - at) / min_line) return bad("the file is shorter than its size says");
    unsigned char *rgbe = malloc((size_t)w * 4);
    out->rgb = prt__calloc((size_t)w * (size_t)h * 3, sizeof(float));
    if (!rgbe || !out->rgb) { free(rgbe); prt_image_free(out); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for a %ldx%ld image", w, h); }
    out->width = (int)w;
    out->height = (int)h;
    prt_status st = PRT_OK;
    for (long y = 0; y < h && !st; ++y) {
        if ((st = scanline(data, size, &at, (int)w, rgbe))) break;
        const long row = ys == '-' ? y : h - 1 - y;   /* +Y stores the bottom row first */
        for (long x = 0; x < w; ++x) to_float(rgbe + x * 4, out->rgb + ((size_t)row * w + x) * 3);
    }
    free(rgbe);
    if (st) prt_image_free(out);
    return st;
}
