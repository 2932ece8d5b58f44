# Turns one text file into a C source defining `const char NAME[]` (the file's bytes and a NUL):
# the web page's scripts (src/*/*.js, src/methods/*/*.js) stay plain JavaScript in the tree and
# reach prt export --web compiled in. cmake -DIN=FILE -DOUT=FILE.c -DNAME=SYMBOL -P embed.cmake
file(READ "${IN}" hex HEX)
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REGEX REPLACE "(0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,)" "\\1\n" bytes "${bytes}")
if(bytes MATCHES "0x[89a-f]")
  message(FATAL_ERROR "${IN}: keep the page's scripts ASCII (they are compiled in as char arrays)")
endif()
file(WRITE "${OUT}.tmp" "/* Generated from ${IN} by cmake/embed.cmake: do not edit. */\nconst char ${NAME}[] = {\n${bytes}0};\n")
file(RENAME "${OUT}.tmp" "${OUT}")
