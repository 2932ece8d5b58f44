/* Source compatibility with prt 0.1: a program that included prt/transfer.h (not the umbrella)
 * and used the SH method's names of then - prt_bake_desc, prt_bake_desc_defaults, prt_bake_sh,
 * prt_transfer_kind, prt_transfer_compress - still builds and links. */
#include <prt/compress.h>
#include <prt/transfer.h>

int main(void)
{
    prt_bake_desc d = prt_bake_desc_defaults();
    const prt_transfer_kind kind = PRT_TRANSFER_SHADOWED;
    prt_status (*bake)(prt_context *, const prt_scene *, const prt_bake_desc *, prt_transfer **) = prt_bake_sh;
    prt_status (*compress)(prt_context *, const prt_transfer *, const prt_compress_desc *, prt_transfer **) = prt_transfer_compress;
    return d.order == 5 && kind == 2 && bake && compress ? 0 : 1;
}
