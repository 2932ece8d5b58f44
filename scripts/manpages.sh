#!/bin/sh
# Man pages from the --help texts, so that the two never disagree: prt.1 lists the commands,
# prt-CMD.1 holds `prt CMD --help` verbatim. Usage: manpages.sh PRT OUTDIR VERSION
set -eu
PRT=$1
OUT=$2
VERSION=${3:-}
mkdir -p "$OUT"
# troff: a leading dot or quote would start a request; backslashes are escapes.
quote() { sed -e 's/\\/\\e/g' -e "s/^\\([.']\\)/\\\\\\&\\1/"; }
{
    echo ".TH PRT 1 \"\" \"prt $VERSION\" \"User Commands\""
    echo ".SH NAME"
    echo "prt \\- precomputed radiance transfer: bake, relight, render, view"
    echo ".SH SYNOPSIS"
    echo ".B prt"
    echo "\\fICOMMAND\\fR [\\fIoptions\\fR]"
    echo ".SH DESCRIPTION"
    echo ".nf"
    "$PRT" --help 2>&1 | quote
    echo ".fi"
    echo ".SH SEE ALSO"
    for cmd in bake merge relight export render view env info demo-scene reference compare sweep; do echo ".BR prt-$cmd (1)"; done
} >"$OUT/prt.1"
for cmd in bake merge relight export render view env info demo-scene reference compare sweep; do
    {
        echo ".TH PRT-$(echo "$cmd" | tr a-z A-Z) 1 \"\" \"prt $VERSION\" \"User Commands\""
        echo ".SH NAME"
        echo "prt-$cmd \\- prt $cmd"
        echo ".SH DESCRIPTION"
        echo ".nf"
        "$PRT" "$cmd" --help 2>&1 | quote
        echo ".fi"
        echo ".SH SEE ALSO"
        echo ".BR prt (1)"
    } >"$OUT/prt-$cmd.1"
done
