// Shared by the libFuzzer targets: the input bytes as a file (for loaders that read files by name),
// written to a private folder of this process, with the extension the loader should see.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace burnish::fuzz {

inline std::filesystem::path inputFile(const std::string& extension, const std::uint8_t* data,
                                       std::size_t size) {
    static const std::filesystem::path folder = [] {
        auto dir = std::filesystem::temp_directory_path() / ("burnish-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir);
        return dir;
    }();
    const auto path = folder / ("input." + extension);
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return path;
}

} // namespace burnish::fuzz
