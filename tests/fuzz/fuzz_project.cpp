// libFuzzer target: a studio project file (.burnish, JSON) through the studio's own parser, which
// checks every field before anything is used.
#include "project.h"

#include <QString>

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view json(reinterpret_cast<const char*>(data), size);
    (void)burnish::studio::parseProject(json, QStringLiteral("/tmp/fuzz/project.burnish"));
    return 0;
}
