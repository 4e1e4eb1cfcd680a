// A PNG of a few hundred bytes whose header claims side × side RGB8 texels (its one IDAT holds
// nothing): what reads the header sees a huge image, what decodes it finds it cut short. For the memory
// checks that must refuse such a file before decoding it.
#pragma once

#include <zlib.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace burnish::test {

inline void writeClaimingPng(const std::filesystem::path& path, std::uint32_t side) {
    auto u32 = [](std::uint32_t v) {
        return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    };
    auto chunk = [&](const std::string& type, const std::string& data) {
        const std::string body = type + data;
        return u32(std::uint32_t(data.size())) + body +
               u32(std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()))));
    };
    const std::string ihdr = u32(side) + u32(side) + std::string{8, 2, 0, 0, 0}; // RGB8
    std::ofstream(path, std::ios::binary)
        << std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) +
               chunk("IDAT", std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8)) + chunk("IEND", "");
}

} // namespace burnish::test
