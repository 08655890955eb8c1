// Replays files through the fuzz target without libFuzzer: `fuzz_replay FILE...` feeds each file to
// LLVMFuzzerTestOneInput. Built by CMake from tests/fuzz/sources.txt alone, so the fuzz target's
// source list cannot go stale (a missing source is a link error in the normal build), and run by
// CTest over scenes/*.json (every shipped scene must pass the loader's invariants).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        std::ifstream in(argv[i], std::ios::binary);
        if (!in) {
            std::fprintf(stderr, "fuzz_replay: cannot read %s\n", argv[i]);
            return 1;
        }
        const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    }
    std::printf("fuzz_replay: %d inputs replayed\n", argc - 1);
    return 0;
}
