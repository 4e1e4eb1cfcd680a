# Script mode helper for burnish_embed: writes the bytes of IN as a char array into OUT.
file(READ "${IN}" hex HEX)
string(LENGTH "${hex}" hexlen)
math(EXPR bytes "${hexlen} / 2")
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," body "${hex}")
file(WRITE "${OUT}" "// Generated from ${IN}; do not edit.\n#include <string_view>\nnamespace burnish::resources {\nnamespace { const char data_[] = {${body} '\\0'}; }\nextern const std::string_view ${SYMBOL};\nconst std::string_view ${SYMBOL}(data_, ${bytes});\n}\n")
