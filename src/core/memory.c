/* Memory sizes, the machine's physical memory and the process's peak resident memory: what bakes
 * bounded by prt_bake_run_desc.memory_limit are held to and report (prt/base.h). */
#include "core/internal.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <unistd.h>

prt_status prt_memory_size_parse(const char *text, uint64_t *bytes)
{
    if (!text || !bytes) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a memory size is required");
    if (!strcasecmp(text, "none") || !strcasecmp(text, "unlimited")) { *bytes = UINT64_MAX; return PRT_OK; }
    const char *p = text;
    if (!isdigit((unsigned char)*p) && *p != '.')
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "memory size '%s' is not a size: a number with K, M, G or T (4G, 512M) or 'none'", text);
    errno = 0;
    char *end;
    const double x = strtod(p, &end);
    if (end == p || errno || !isfinite(x))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "memory size '%s' is not a size: a number with K, M, G or T (4G, 512M) or 'none'", text);
    double scale = 1;
    switch (toupper((unsigned char)*end)) {
    case 'K': scale = 1024.0; end++; break;
    case 'M': scale = 1024.0 * 1024; end++; break;
    case 'G': scale = 1024.0 * 1024 * 1024; end++; break;
    case 'T': scale = 1024.0 * 1024 * 1024 * 1024; end++; break;
    default: break;
    }
    if (scale > 1 && (end[0] == 'i' || end[0] == 'I') && (end[1] == 'B' || end[1] == 'b')) end += 2;
    else if (*end == 'B' || *end == 'b') end++;
    if (*end)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "memory size '%s' ends in '%s': the units are K, M, G and T (4G, 512M)", text, end);
    const double b = floor(x * scale);
    if (!(b >= 1)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "memory size '%s' is zero: give at least 1 byte, or 'none' for no limit", text);
    if (b >= 9223372036854775808.0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "memory size '%s' is past 8 EiB: give 'none' for no limit", text);
    *bytes = (uint64_t)b;
    return PRT_OK;
}

const char *prt_memory_size_format(uint64_t bytes, char *buf, size_t n)
{
    if (!buf || !n) return buf;
    if (bytes == UINT64_MAX) { snprintf(buf, n, "none"); return buf; }
    static const char *const unit[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB"};
    double x = (double)bytes;
    int u = 0;
    while (x >= 1024 && u < 5) { x /= 1024; u++; }
    if (!u) snprintf(buf, n, "%llu bytes", (unsigned long long)bytes);
    else snprintf(buf, n, "%.*f %s", x < 10 ? 2 : x < 100 ? 1 : 0, x, unit[u]);
    return buf;
}

uint64_t prt_memory_physical(void)
{
    const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    return pages > 0 && size > 0 ? (uint64_t)pages * (uint64_t)size : 0;
}

uint64_t prt_memory_default_limit(void)
{
    /* Half: the rest is the page cache a streamed bake reads its scratch file through, and the
     * other work of the machine. */
    const uint64_t phys = prt_memory_physical();
    return phys ? phys / 2 : (uint64_t)4 << 30;
}

uint64_t prt_memory_peak_resident(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0 || ru.ru_maxrss <= 0) return 0;
    return (uint64_t)ru.ru_maxrss * 1024;   /* Linux counts kilobytes */
}
