/* Images: prt's own Radiance .hdr and PFM readers, stb for .png/.jpg only, OpenEXR's C API for
 * .exr. The format is chosen by the file's signature before anything decodes it, so stb never
 * sees the formats prt does not document (PNM, BMP, TGA, PSD, GIF: stb's weakest readers).
 * Everything decodes from memory; the file variants are thin wrappers. */
#include "core/internal.h"
#include "prt/image.h"
#include "io/rgbe.h"

#include <OpenEXR/openexr.h>
#include <ctype.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#define MAX_DIM 32768   /* hostile-input bound before any allocation */

void prt_image_free(prt_image *img)
{
    if (!img) return;
    free(img->rgb);
    memset(img, 0, sizeof *img);
}

static prt_status alloc_image(prt_image *img, long w, long h)
{
    if (w <= 0 || h <= 0 || w > MAX_DIM || h > MAX_DIM)
        return prt__fail(NULL, PRT_ERR_FORMAT, "image size %ldx%ld is out of range (1..%d)", w, h, MAX_DIM);
    img->width = (int)w;
    img->height = (int)h;
    img->rgb = prt__calloc((size_t)w * (size_t)h * 3, sizeof(float));
    return img->rgb ? PRT_OK : prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for a %ldx%ld image", w, h);
}

static prt_status check_finite(prt_image *img)
{
    size_t n = (size_t)img->width * img->height * 3;
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(img->rgb[i])) {
            size_t px = i / 3;
            prt_status s = prt__fail(NULL, PRT_ERR_FORMAT, "pixel (%zu, %zu) is not finite (NaN or Inf)", px % (size_t)img->width,
                                     px / (size_t)img->width);
            prt_image_free(img);
            return s;
        }
    return PRT_OK;
}

/* ---- PFM: "PF" (RGB) or "Pf" (grey), width height, scale (negative = little endian), rows bottom-up. */
static prt_status load_pfm(const unsigned char *data, size_t size, prt_image *out)
{
    char head[128];
    size_t n = size < sizeof head - 1 ? size : sizeof head - 1;
    memcpy(head, data, n);
    head[n] = 0;
    char kind;
    long w, h;
    double scale;
    int used = 0;
    if (sscanf(head, "P%c %ld %ld %lf%n", &kind, &w, &h, &scale, &used) != 4 || (kind != 'F' && kind != 'f') || scale == 0.0 ||
        (size_t)used >= n || !isspace((unsigned char)head[used]))
        return prt__fail(NULL, PRT_ERR_FORMAT, "malformed PFM header");
    size_t offset = (size_t)used + 1;   /* exactly one whitespace byte ends the header */
    int ch = kind == 'F' ? 3 : 1;
    /* The pixels must be in the file before the header may size an allocation. */
    if (w < 1 || h < 1 || (size_t)w > (size - offset) / 4 || (size_t)h > (size - offset) / ((size_t)w * 4 * (size_t)ch))
        return prt__fail(NULL, PRT_ERR_FORMAT, "PFM file is truncated (its header promises %ld x %ld pixels)", w, h);
    prt_status st = alloc_image(out, w, h);
    if (st) return st;
    bool swap = scale > 0;   /* big endian data on a little-endian host */
    const unsigned char *p = data + offset;
    for (long y = 0; y < h; ++y)
        for (long x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                size_t src = (((size_t)y * (size_t)w + (size_t)x) * (size_t)ch + (size_t)(ch == 3 ? c : 0)) * 4;
                unsigned char b[4];
                memcpy(b, p + src, 4);
                if (swap) { unsigned char t = b[0]; b[0] = b[3]; b[3] = t; t = b[1]; b[1] = b[2]; b[2] = t; }
                float v;
                memcpy(&v, b, 4);
                out->rgb[(((size_t)(h - 1 - y)) * (size_t)w + (size_t)x) * 3 + (size_t)c] = v * (float)fabs(scale);
            }
    return PRT_OK;
}

/* ---- EXR through OpenEXRCore, reading from memory. */
typedef struct mem_stream { const unsigned char *data; size_t size; } mem_stream;

static int64_t exr_mem_read(exr_const_context_t c, void *user, void *buf, uint64_t sz, uint64_t off, exr_stream_error_func_ptr_t err)
{
    (void)c; (void)err;
    const mem_stream *m = user;
    if (off >= m->size) return 0;
    uint64_t n = m->size - off < sz ? m->size - off : sz;
    memcpy(buf, m->data + off, n);
    return (int64_t)n;
}

static int64_t exr_mem_size(exr_const_context_t c, void *user) { (void)c; return (int64_t)((const mem_stream *)user)->size; }

static _Thread_local char exr_message[256];
static void exr_quiet_error(exr_const_context_t c, exr_result_t code, const char *msg)
{
    (void)c;
    snprintf(exr_message, sizeof exr_message, "%s", msg ? msg : exr_get_default_error_message(code));
}

static prt_status load_exr(const unsigned char *data, size_t size, prt_image *out)
{
    mem_stream ms = {data, size};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_quiet_error;
    init.user_data = &ms;
    init.read_fn = exr_mem_read;
    init.size_fn = exr_mem_size;
    exr_context_t ctx = NULL;
    exr_message[0] = 0;
    if (exr_start_read(&ctx, "(memory)", &init) != EXR_ERR_SUCCESS)
        return prt__fail(NULL, PRT_ERR_FORMAT, "not a readable OpenEXR file: %s", exr_message);
    prt_status st = PRT_OK;
    exr_storage_t storage;
    exr_attr_box2i_t dw;
    int32_t lines = 0;
    if (exr_get_storage(ctx, 0, &storage) || exr_get_data_window(ctx, 0, &dw) || exr_get_scanlines_per_chunk(ctx, 0, &lines)) {
        st = prt__fail(NULL, PRT_ERR_FORMAT, "OpenEXR header unreadable: %s", exr_message);
    } else if (storage != EXR_STORAGE_SCANLINE) {
        st = prt__fail(NULL, PRT_ERR_FORMAT, "only scanline OpenEXR images are supported (this one is tiled or deep)");
    } else {
        long w = (long)dw.max.x - dw.min.x + 1, h = (long)dw.max.y - dw.min.y + 1;
        st = lines < 1 || lines > 256 ? prt__fail(NULL, PRT_ERR_FORMAT, "OpenEXR chunks of %d scanlines are not a valid layout", lines)
                                      : alloc_image(out, w, h);
        /* Channels prt does not use are decoded into scratch: OpenEXRCore 3.1's fast unpackers
         * write through a NULL decode_to_ptr (found by fuzzing: fuzz/regress/image/exr_unused_channel). */
        float *scratch = st == PRT_OK ? prt__calloc((size_t)w * (size_t)lines, sizeof(float)) : NULL;
        if (st == PRT_OK && !scratch) st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory decoding OpenEXR");
        exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
        bool have_rgb[3] = {false, false, false}, initialised = false;
        for (int32_t y = dw.min.y; st == PRT_OK && y <= dw.max.y; y += lines) {
            exr_chunk_info_t ci;
            if (exr_read_scanline_chunk_info(ctx, 0, y, &ci) ||
                (initialised ? exr_decoding_update(ctx, 0, &ci, &dec) : exr_decoding_initialize(ctx, 0, &ci, &dec))) {
                st = prt__fail(NULL, PRT_ERR_FORMAT, "OpenEXR chunk at line %d unreadable: %s", y, exr_message);
                break;
            }
            initialised = true;
            for (int c = 0; c < dec.channel_count; ++c) {
                exr_coding_channel_info_t *chan = &dec.channels[c];
                const char *name = chan->channel_name;
                const char *dot = strrchr(name, '.');   /* layer prefixes such as "diffuse.R" */
                if (dot) name = dot + 1;
                int k = !strcasecmp(name, "R") ? 0 : !strcasecmp(name, "G") ? 1 : !strcasecmp(name, "B") ? 2 :
                        !strcasecmp(name, "Y") ? 0 : -1;
                const bool used = k >= 0 && chan->x_samples == 1 && chan->y_samples == 1;
                if (used) have_rgb[k] = true;
                chan->decode_to_ptr = used ? (uint8_t *)(out->rgb + ((size_t)(ci.start_y - dw.min.y) * (size_t)w) * 3 + k) : (uint8_t *)scratch;
                chan->user_pixel_stride = used ? 3 * sizeof(float) : sizeof(float);
                chan->user_line_stride = (int32_t)(w * (used ? 3 : 1) * (long)sizeof(float));
                chan->user_data_type = EXR_PIXEL_FLOAT;
                chan->user_bytes_per_element = sizeof(float);
            }
            if (exr_decoding_choose_default_routines(ctx, 0, &dec) || exr_decoding_run(ctx, 0, &dec))
                st = prt__fail(NULL, PRT_ERR_FORMAT, "OpenEXR data at line %d is corrupt: %s", y, exr_message);
        }
        if (initialised) exr_decoding_destroy(ctx, &dec);
        free(scratch);
        if (st == PRT_OK && !have_rgb[0])
            st = prt__fail(NULL, PRT_ERR_FORMAT, "OpenEXR image has no R, G, B or Y channel");
        if (st == PRT_OK)   /* single-channel images become grey */
            for (size_t i = 0; i < (size_t)w * (size_t)h; ++i)
                for (int k = 1; k < 3; ++k)
                    if (!have_rgb[k]) out->rgb[i * 3 + k] = out->rgb[i * 3];
        if (st) prt_image_free(out);
    }
    exr_finish(&ctx);
    return st;
}

static float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f); }

prt_status prt_image_load_memory(const void *data, size_t size, prt_image *out)
{
    if (!out || !data) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_image_load_memory: data and out are required");
    memset(out, 0, sizeof *out);
    const unsigned char *b = data;
    prt_status st;
    if (size >= 4 && b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01) {
        st = load_exr(b, size, out);
    } else if (size >= 3 && b[0] == 'P' && (b[1] == 'F' || b[1] == 'f') && isspace(b[2])) {
        st = load_pfm(b, size, out);
    } else if (prt__is_rgbe(b, size)) {
        st = prt__load_rgbe(b, size, MAX_DIM, out);
    } else if ((size >= 8 && !memcmp(b, "\x89PNG\r\n\x1a\n", 8)) || (size >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff)) {
        if (size > INT32_MAX) return prt__fail(NULL, PRT_ERR_FORMAT, "image too large");
        int w, h, n;
        if (!stbi_info_from_memory(b, (int)size, &w, &h, &n))
            return prt__fail(NULL, PRT_ERR_FORMAT, "corrupt image: %s", stbi_failure_reason());
        if ((st = alloc_image(out, w, h))) return st;
        if (stbi_is_16_bit_from_memory(b, (int)size)) {
            /* 16-bit PNGs decode at 16 bits: no conversion inside stb. */
            stbi_us *px = stbi_load_16_from_memory(b, (int)size, &w, &h, &n, 3);
            if (!px) { prt_image_free(out); return prt__fail(NULL, PRT_ERR_FORMAT, "corrupt image: %s", stbi_failure_reason()); }
            for (size_t i = 0; i < (size_t)w * h * 3; ++i) out->rgb[i] = srgb_to_linear(px[i] / 65535.0f);
            stbi_image_free(px);
        } else {
            unsigned char *px = stbi_load_from_memory(b, (int)size, &w, &h, &n, 3);
            if (!px) { prt_image_free(out); return prt__fail(NULL, PRT_ERR_FORMAT, "corrupt image: %s", stbi_failure_reason()); }
            for (size_t i = 0; i < (size_t)w * h * 3; ++i) out->rgb[i] = srgb_to_linear(px[i] / 255.0f);
            stbi_image_free(px);
        }
        st = PRT_OK;
    } else {
        return prt__fail(NULL, PRT_ERR_FORMAT, "not an image prt can read (.hdr, .pfm, .exr, .png, .jpg: none of their signatures)");
    }
    return st ? st : check_finite(out);
}

static prt_status load_bytes(void *user, const void *data, size_t size) { return prt_image_load_memory(data, size, user); }

prt_status prt_image_load(const char *path, prt_image *out)
{
    if (out) memset(out, 0, sizeof *out);
    return prt__load_path(NULL, path, load_bytes, out);
}

/* ---- Saving. */
typedef struct buf { unsigned char *p; size_t n, cap; bool failed; } buf;
static void buf_put(void *user, void *data, int size)
{
    buf *b = user;
    if (b->failed || size <= 0) return;
    if (b->n + (size_t)size > b->cap) {
        size_t cap = (b->cap ? b->cap * 2 : 65536) + (size_t)size;
        unsigned char *q = realloc(b->p, cap);
        if (!q) { b->failed = true; return; }
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->n, data, (size_t)size);
    b->n += (size_t)size;
}

static float linear_to_srgb(float c) { return c <= 0.0031308f ? 12.92f * c : 1.055f * powf(c, 1.0f / 2.4f) - 0.055f; }

static prt_status write_bytes(const char *path, const void *data, size_t size)
{
    prt__atomic_file f;
    prt_status st = prt__atomic_open(&f, path);
    if (st) return st;
    if ((st = prt__atomic_write(&f, data, size))) { prt__atomic_abort(&f); return st; }
    return prt__atomic_commit(&f);
}

/* OpenEXRCore (3.1 here; fixed after 3.4.7, openexr issue 2306) keeps a ZIP chunk's zlib output when it is
 * exactly as long as the packed pixels, and every reader takes a chunk of that length for the
 * packed pixels themselves: the image reads back as noise (an exported 3 x 8 offset map piece had
 * a NaN). The library's compressor, then the packed pixels in its place in that case, as the
 * fixed library stores them. */
typedef struct exr_zip_guard { exr_result_t (*compress)(exr_encode_pipeline_t *); } exr_zip_guard;
static exr_result_t exr_zip_guarded(exr_encode_pipeline_t *enc)
{
    const exr_zip_guard *g = enc->encoding_user_data;
    const exr_result_t rv = g->compress(enc);
    if (rv == EXR_ERR_SUCCESS && enc->compressed_buffer && enc->packed_buffer && enc->compressed_bytes == enc->packed_bytes &&
        enc->compressed_buffer != enc->packed_buffer)
        memcpy(enc->compressed_buffer, enc->packed_buffer, enc->packed_bytes);
    return rv;
}

static prt_status save_exr(const char *path, const prt_image *img)
{
    char tmp[1100];
    snprintf(tmp, sizeof tmp, "%s.tmp.%ld.exr", path, (long)getpid());
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_quiet_error;
    exr_context_t ctx = NULL;
    int part = 0;
    exr_message[0] = 0;
    if (exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init))
        return prt__fail(NULL, PRT_ERR_IO, "cannot create '%s': %s", tmp, exr_message);
    prt_status st = PRT_OK;
    const char *names[3] = {"B", "G", "R"};   /* EXR stores channels sorted by name */
    if (exr_add_part(ctx, "rgb", EXR_STORAGE_SCANLINE, &part) ||
        exr_initialize_required_attr_simple(ctx, part, img->width, img->height, EXR_COMPRESSION_ZIP) ||
        exr_add_channel(ctx, part, names[0], EXR_PIXEL_HALF, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1) ||
        exr_add_channel(ctx, part, names[1], EXR_PIXEL_HALF, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1) ||
        exr_add_channel(ctx, part, names[2], EXR_PIXEL_HALF, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1) || exr_write_header(ctx))
        st = prt__fail(NULL, PRT_ERR_IO, "cannot write OpenEXR header: %s", exr_message);
    int32_t lines = 1;
    if (!st && exr_get_scanlines_per_chunk(ctx, part, &lines)) st = prt__fail(NULL, PRT_ERR_IO, "OpenEXR: %s", exr_message);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    exr_zip_guard guard = {NULL};
    bool initialised = false;
    for (int32_t y = 0; !st && y < img->height; y += lines) {
        exr_chunk_info_t ci;
        if (exr_write_scanline_chunk_info(ctx, part, y, &ci) ||
            (initialised ? exr_encoding_update(ctx, part, &ci, &enc) : exr_encoding_initialize(ctx, part, &ci, &enc))) {
            st = prt__fail(NULL, PRT_ERR_IO, "OpenEXR chunk %d: %s", y, exr_message);
            break;
        }
        initialised = true;
        for (int c = 0; c < enc.channel_count; ++c) {
            int k = enc.channels[c].channel_name[0] == 'R' ? 0 : enc.channels[c].channel_name[0] == 'G' ? 1 : 2;
            enc.channels[c].encode_from_ptr = (const uint8_t *)(img->rgb + (size_t)y * img->width * 3 + k);
            enc.channels[c].user_pixel_stride = 3 * sizeof(float);
            enc.channels[c].user_line_stride = img->width * 3 * (int32_t)sizeof(float);
            enc.channels[c].user_data_type = EXR_PIXEL_FLOAT;
            enc.channels[c].user_bytes_per_element = sizeof(float);
        }
        if (exr_encoding_choose_default_routines(ctx, part, &enc)) {
            st = prt__fail(NULL, PRT_ERR_IO, "OpenEXR encoding failed: %s", exr_message);
            break;
        }
        if (enc.compress_fn != exr_zip_guarded) guard.compress = enc.compress_fn;   /* never wraps itself */
        if (enc.compress_fn) {
            enc.encoding_user_data = &guard;
            enc.compress_fn = exr_zip_guarded;
        }
        if (exr_encoding_run(ctx, part, &enc)) st = prt__fail(NULL, PRT_ERR_IO, "OpenEXR encoding failed: %s", exr_message);
        enc.encoding_user_data = NULL;
    }
    if (initialised) exr_encoding_destroy(ctx, &enc);
    if (exr_finish(&ctx) && !st) st = prt__fail(NULL, PRT_ERR_IO, "OpenEXR: could not finish '%s'", tmp);
    if (!st && rename(tmp, path) != 0) st = prt__fail(NULL, PRT_ERR_IO, "cannot rename '%s' to '%s'", tmp, path);
    if (st) remove(tmp);
    return st;
}

/* Tone-mapped sRGB 8-bit PNG bytes of img, appended to out. */
static prt_status encode_png(const prt_image *img, const prt_image_save_desc *d, buf *out)
{
    const size_t n = (size_t)img->width * img->height;
    unsigned char *px = malloc(n * 3);
    if (!px) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    float scale = exp2f(d->exposure_stops);
    for (size_t i = 0; i < n; ++i) {
        float c[3] = {img->rgb[i * 3] * scale, img->rgb[i * 3 + 1] * scale, img->rgb[i * 3 + 2] * scale};
        if (d->tonemap != 2) {   /* Reinhard on luminance keeps hue while compressing highlights */
            float lum = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
            float k = lum > 0 ? 1.0f / (1.0f + lum) : 1.0f;
            for (int j = 0; j < 3; ++j) c[j] *= k;
        }
        for (int j = 0; j < 3; ++j) {
            float v = linear_to_srgb(fminf(fmaxf(c[j], 0.0f), 1.0f));
            px[i * 3 + j] = (unsigned char)lrintf(v * 255.0f);
        }
    }
    int ok = stbi_write_png_to_func(buf_put, out, img->width, img->height, 3, px, img->width * 3);
    free(px);
    if (!ok || out->failed) { free(out->p); out->p = NULL; return prt__fail(NULL, PRT_ERR_NO_MEMORY, "PNG encoding failed"); }
    return PRT_OK;
}

prt_status prt_image_save(const char *path, const prt_image *img, const prt_image_save_desc *desc)
{
    if (!path || !img || !img->rgb || img->width <= 0 || img->height <= 0)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_image_save: an image with pixels is required");
    prt_image_save_desc d = desc ? *desc : (prt_image_save_desc){0};
    const char *ext = strrchr(path, '.');
    ext = ext ? ext + 1 : "";
    if (!strcasecmp(ext, "exr")) return save_exr(path, img);
    buf out = {0};
    if (!strcasecmp(ext, "png")) {
        prt_status st = encode_png(img, &d, &out);
        if (st) return st;
    } else if (!strcasecmp(ext, "hdr")) {
        if (!stbi_write_hdr_to_func(buf_put, &out, img->width, img->height, 3, img->rgb) || out.failed) {
            free(out.p);
            return prt__fail(NULL, PRT_ERR_NO_MEMORY, "HDR encoding failed");
        }
    } else if (!strcasecmp(ext, "pfm")) {
        char head[64];
        int hn = snprintf(head, sizeof head, "PF\n%d %d\n-1.0\n", img->width, img->height);
        buf_put(&out, head, hn);
        for (int y = img->height - 1; y >= 0; --y) buf_put(&out, img->rgb + (size_t)y * img->width * 3, img->width * 3 * 4);
        if (out.failed) { free(out.p); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    } else {
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "'%s': unknown image type (use .png, .exr, .hdr or .pfm)", path);
    }
    prt_status st = write_bytes(path, out.p, out.n);
    free(out.p);
    return st;
}

/* Offset of the first IDAT chunk of an encoded PNG (0 when it has none). */
static size_t png_first_data(const buf *png)
{
    for (size_t at = 8; at + 12 <= png->n;) {
        const unsigned char *c = png->p + at;
        const uint32_t len = (uint32_t)c[0] << 24 | (uint32_t)c[1] << 16 | (uint32_t)c[2] << 8 | c[3];
        if (!memcmp(c + 4, "IDAT", 4)) return at;
        if (len > png->n - at - 12) break;
        at += 12 + (size_t)len;
    }
    return 0;
}

/* One PNG chunk: length, type, data, CRC over type and data. */
static void put_chunk(buf *out, const char type[4], const unsigned char *data, uint32_t size)
{
    unsigned char be[4] = {(unsigned char)(size >> 24), (unsigned char)(size >> 16), (unsigned char)(size >> 8), (unsigned char)size};
    buf_put(out, be, 4);
    unsigned char *tmp = malloc((size_t)size + 4);
    if (!tmp) { out->failed = true; return; }
    memcpy(tmp, type, 4);
    if (size) memcpy(tmp + 4, data, size);
    buf_put(out, tmp, (int)size + 4);
    const uint32_t crc = prt__crc32(tmp, (size_t)size + 4);
    free(tmp);
    unsigned char c[4] = {(unsigned char)(crc >> 24), (unsigned char)(crc >> 16), (unsigned char)(crc >> 8), (unsigned char)crc};
    buf_put(out, c, 4);
}

static void put_be32(unsigned char *p, uint32_t v) { p[0] = (unsigned char)(v >> 24); p[1] = (unsigned char)(v >> 16); p[2] = (unsigned char)(v >> 8); p[3] = (unsigned char)v; }

/* An animated PNG (APNG): each frame encoded as a PNG by stb, its image data moved into the
 * frame chunks (fcTL + IDAT for the first frame, which viewers without APNG show, fdAT for the
 * rest). */
prt_status prt_image_save_animation(const char *path, const prt_image *frames, int count, int fps, const prt_image_save_desc *desc)
{
    if (!path || !frames || count < 1 || fps < 1 || fps > 100)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_image_save_animation: a path, 1 or more frames and 1..100 frames per second are required");
    for (int i = 0; i < count; ++i)
        if (!frames[i].rgb || frames[i].width != frames[0].width || frames[i].height != frames[0].height || frames[i].width <= 0 || frames[i].height <= 0)
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_image_save_animation: frame %d has no pixels or another size than the first", i);
    const char *ext = strrchr(path, '.');
    if (!ext || strcasecmp(ext, ".png")) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "'%s': an animation is written as an animated PNG (.png)", path);
    const prt_image_save_desc d = desc ? *desc : (prt_image_save_desc){0};
    buf out = {0};
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    buf_put(&out, (void *)sig, 8);
    uint32_t seq = 0;
    prt_status st = PRT_OK;
    for (int i = 0; i < count && !st && !out.failed; ++i) {
        buf png = {0};
        if ((st = encode_png(&frames[i], &d, &png))) break;
        /* Walk stb's chunks: IHDR once (then acTL), image data into this frame's chunks. */
        size_t at = 8;
        while (at + 12 <= png.n && !out.failed) {
            const unsigned char *c = png.p + at;
            const uint32_t len = (uint32_t)c[0] << 24 | (uint32_t)c[1] << 16 | (uint32_t)c[2] << 8 | c[3];
            if (len > png.n - at - 12) break;
            if (!memcmp(c + 4, "IHDR", 4) && i == 0) {
                put_chunk(&out, "IHDR", c + 8, len);
                unsigned char actl[8];
                put_be32(actl, (uint32_t)count);
                put_be32(actl + 4, 0);   /* loop forever */
                put_chunk(&out, "acTL", actl, 8);
            } else if (!memcmp(c + 4, "IDAT", 4)) {
                if (at == png_first_data(&png)) {
                    unsigned char fctl[26] = {0};
                    put_be32(fctl, seq++);
                    put_be32(fctl + 4, (uint32_t)frames[i].width);
                    put_be32(fctl + 8, (uint32_t)frames[i].height);
                    fctl[20] = 0; fctl[21] = 1;                    /* delay 1/fps s */
                    fctl[22] = (unsigned char)(fps >> 8); fctl[23] = (unsigned char)fps;
                    put_chunk(&out, "fcTL", fctl, 26);
                }
                if (i == 0) {
                    put_chunk(&out, "IDAT", c + 8, len);
                } else {
                    unsigned char *fd = malloc((size_t)len + 4);
                    if (!fd) { out.failed = true; break; }
                    put_be32(fd, seq++);
                    memcpy(fd + 4, c + 8, len);
                    put_chunk(&out, "fdAT", fd, len + 4);
                    free(fd);
                }
            }
            at += 12 + (size_t)len;
        }
        free(png.p);
    }
    if (!st) put_chunk(&out, "IEND", NULL, 0);
    if (!st && out.failed) st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = write_bytes(path, out.p, out.n);
    free(out.p);
    return st;
}
