/* prt export: the method's own files (its export options) beside a relit mesh. The dispatch and
 * the result's bookkeeping here; what each method writes in its folder (methods/NAME/export.c). */
#include "transfer/method.h"

#include <stdarg.h>

void prt__export_report(prt_export_result *r, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    const size_t have = r->report ? strlen(r->report) : 0, add = strlen(line);
    char *grown = realloc(r->report, have + add + 2);
    if (!grown) return;   /* the report is a courtesy: the files are written */
    memcpy(grown + have, line, add);
    grown[have + add] = '\n';
    grown[have + add + 1] = 0;
    r->report = grown;
}

bool prt__export_file(prt_export_result *r, const char *path)
{
    char **grown = realloc(r->files, (size_t)(r->file_count + 1) * sizeof *grown);
    if (!grown) return false;
    r->files = grown;
    if (!(r->files[r->file_count] = strdup(path))) return false;
    r->file_count++;
    return true;
}

void prt_export_result_free(prt_export_result *r)
{
    if (!r) return;
    free(r->attributes);
    free(r->radiance);
    for (int i = 0; i < r->file_count; ++i) free(r->files[i]);
    free(r->files);
    free(r->report);
    memset(r, 0, sizeof *r);
}

prt_status prt_transfer_export(prt_context *ctx, const prt_transfer *t, const prt_export_desc *desc, prt_export_result *out)
{
    if (!t || !desc || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_export: transfer, desc and out are required");
    memset(out, 0, sizeof *out);
    prt_export_desc d = *desc;
    if (d.options && !prt__options_exporting(d.options))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_export takes export options (prt_export_options_create), not bake options");
    if (d.options && prt_options_method(d.options) != t->method)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "export options made for method %s, and this is a %s file", prt_method_name(prt_options_method(d.options)),
                         t->method->name);
    if (d.variant < 0) d.variant = prt_transfer_default_variant(t, 0);
    if (d.variant >= prt_transfer_variant_count(t)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "variant %d out of range", d.variant);
    if (d.mesh != PRT_EXPORT_NO_MESH && !d.lighting) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_export: a mesh export needs its lighting");
    if (!t->method->export_files) return PRT_OK;   /* no export options: none can have been given */
    prt_status st = t->method->export_files(ctx, t, &d, out);
    if (st) {
        for (int i = 0; i < out->file_count; ++i) remove(out->files[i]);
        prt_export_result_free(out);
    }
    return st;
}
