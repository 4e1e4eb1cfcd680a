#include <burnish/core/util/memory.h>

#include <fmt/format.h>

#include <cctype>
#include <cstdlib>
#include <fstream>
#include <limits>

namespace burnish {

std::optional<std::uint64_t> availableMemoryBytes() {
    std::ifstream meminfo("/proc/meminfo");
    if (!meminfo) return std::nullopt;
    std::uint64_t available = 0;
    bool found = false;
    std::string key;
    std::uint64_t kb = 0;
    std::string unit;
    while (meminfo >> key >> kb) {
        std::getline(meminfo, unit);
        if (key == "MemAvailable:" || key == "SwapFree:") {
            available += kb * 1024;
            found = found || key == "MemAvailable:";
        }
    }
    if (!found) return std::nullopt;
    return available;
}

Result<std::optional<std::uint64_t>> memoryLimitFromEnvironment() {
    const char* value = std::getenv("BURNISH_MEMORY_LIMIT");
    if (!value) return std::optional<std::uint64_t>{};
    const std::string text(value);
    const Error bad{"BURNISH_MEMORY_LIMIT '" + text +
                    "' is not a size (bytes, or a whole number with K, M or G, e.g. 6G)"};
    size_t digits = 0;
    while (digits < text.size() && std::isdigit(static_cast<unsigned char>(text[digits])))
        ++digits;
    if (digits == 0 || digits > 15) return bad;
    std::uint64_t number = std::stoull(text.substr(0, digits));
    const std::string suffix = text.substr(digits);
    std::uint64_t scale = 1;
    if (suffix == "K" || suffix == "k")
        scale = std::uint64_t(1) << 10;
    else if (suffix == "M" || suffix == "m")
        scale = std::uint64_t(1) << 20;
    else if (suffix == "G" || suffix == "g")
        scale = std::uint64_t(1) << 30;
    else if (!suffix.empty())
        return bad;
    if (number > std::numeric_limits<std::uint64_t>::max() / scale) return bad;
    return std::optional<std::uint64_t>(number * scale);
}

Result<std::optional<std::uint64_t>> usableMemoryBytes() {
    auto limit = memoryLimitFromEnvironment();
    if (!limit) return Error{limit.error()};
    std::optional<std::uint64_t> available = availableMemoryBytes();
    if (*limit) available = available ? std::min(*available, **limit) : **limit;
    return available;
}

std::string formatBytes(std::uint64_t bytes) {
    const double b = double(bytes);
    if (b >= 1e9) return fmt::format("{:.1f} GB", b / 1e9);
    return fmt::format("{:.0f} MB", b / 1e6);
}

Status checkMemory(std::uint64_t need, std::optional<std::uint64_t> available, std::string_view what,
                   std::string_view advice) {
    if (!available || need <= *available) return {};
    return Error{fmt::format("{} needs about {} of memory, and {} {} available ({})", what, formatBytes(need),
                             formatBytes(*available), *available == 1 ? "is" : "are", advice)};
}

Status checkMemory(std::uint64_t need, std::string_view what, std::string_view advice) {
    auto available = usableMemoryBytes();
    if (!available) return Error{available.error()};
    return checkMemory(need, *available, what, advice);
}

bool decodedByCore(std::string_view formatName, std::string_view channelType) {
    return formatName == "png" && (channelType == "uint8" || channelType == "uint16");
}

} // namespace burnish
