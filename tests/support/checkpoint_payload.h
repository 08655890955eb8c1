// The film payload of a checkpoint file (render/checkpoint.h: everything after the JSON header),
// to compare two checkpoints' films byte for byte whatever their timings. Empty if unreadable.
#pragma once
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace tpb::test {

inline std::string checkpointPayload(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream ss;
    ss << f.rdbuf();
    const std::string b = ss.str();
    if (b.size() < 16) return {};
    uint64_t n = 0;
    std::memcpy(&n, b.data() + 8, 8);
    return 16 + n <= b.size() ? b.substr(16 + n) : std::string();
}

}  // namespace tpb::test
