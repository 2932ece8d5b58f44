# Prints the prt_* and PRT_* names a C header declares at file scope: macros, typedef names, the
# tags of structs, unions and enums it defines, enum constants, functions and extern variables.
# Input: the header with its comments removed (scripts/check-architecture.sh runs it through
# gcc -fpreprocessed). Used to know a method's identifiers from its own headers.
function emit(name) { if (name ~ /^(prt_|PRT_)/) print name }
function reset() { typedef_stmt = 0; extern_stmt = 0; paren_seen = 0; last = ""; tagword = 0; enum_stmt = 0 }
BEGIN { depth = 0; paren = 0; reset(); cont = 0; n = 0 }
{
    line = $0
    if (cont) { cont = line ~ /\\$/; next }            # continuation of a directive
    if (line ~ /^[ \t]*#[ \t]*ifdef[ \t]+__cplusplus/) { cpp = 1; next }   # extern "C" { ... }
    if (cpp) { if (line ~ /^[ \t]*#[ \t]*endif/) cpp = 0; next }
    if (line ~ /^[ \t]*#/) {
        if (match(line, /^[ \t]*#[ \t]*define[ \t]+[A-Za-z_][A-Za-z0-9_]*/)) {
            name = substr(line, 1, RLENGTH); sub(/^[ \t]*#[ \t]*define[ \t]+/, "", name); emit(name)
        }
        cont = line ~ /\\$/
        next
    }
    while (length(line) > 0) {
        if (match(line, /^[ \t\r]+/)) { line = substr(line, RLENGTH + 1); continue }
        if (match(line, /^[A-Za-z_][A-Za-z0-9_]*/)) { tok[++n] = substr(line, 1, RLENGTH); line = substr(line, RLENGTH + 1); continue }
        if (match(line, /^"([^"\\]|\\.)*"/) || match(line, /^'([^'\\]|\\.)*'/) || match(line, /^[0-9][0-9A-Za-z_.]*/)) {
            tok[++n] = "0"; line = substr(line, RLENGTH + 1); continue
        }
        tok[++n] = substr(line, 1, 1); line = substr(line, 2)
    }
}
END {
    for (i = 1; i <= n; ++i) {
        t = tok[i]; next_tok = (i < n) ? tok[i + 1] : ""
        if (t == "{") { if (depth == 0 && enum_stmt) in_enum = 1; depth++; continue }
        if (t == "}") {
            depth--
            if (depth == 0) { in_enum = 0; if (paren_seen && !typedef_stmt) reset() }
            continue
        }
        if (t == "(") {
            if (depth == 0 && paren == 0 && !paren_seen && !typedef_stmt && prev ~ /^[A-Za-z_]/) emit(prev)
            if (depth == 0 && paren == 0) paren_seen = 1
            paren++; prev = t; continue
        }
        if (t == ")") { paren--; prev = t; continue }
        if (t == ";" && depth == 0 && paren == 0) { if ((typedef_stmt || extern_stmt) && last != "") emit(last); reset(); prev = t; continue }
        if (t ~ /^[A-Za-z_]/) {
            if (depth == 0 && paren == 0) {
                if (t == "typedef") typedef_stmt = 1
                else if (t == "extern") extern_stmt = 1
                else if (t == "enum") enum_stmt = 1
                if (tagword && next_tok == "{") emit(t)    # a struct, union or enum defined here
                tagword = (t == "struct" || t == "union" || t == "enum")
                last = t
            }
            if (depth == 0 && paren == 1 && prev == "*" && pprev == "(" && typedef_stmt) emit(t)   # typedef R (*name)(...)
            if (in_enum && depth == 1 && (next_tok == "=" || next_tok == "," || next_tok == "}")) emit(t)
        }
        pprev = prev; prev = t
    }
}
