// The .npy writer (core/io/npy.h) byte for byte: the magic, version, header length, the dict
// NumPy expects and its padding to 64 bytes; the values after it; nothing under the name until
// commit. (tests/film/test_volume_export.cpp reads the files back with numpy.)
#include "io/npy.h"
#include "support/temp_dir.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace tpb;

namespace {
std::string slurp(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}
}  // namespace

TEST(NpyHeader, MagicVersionLengthAndDictPaddedTo64Bytes) {
    for (const std::vector<int64_t>& shape :
         std::vector<std::vector<int64_t>>{{4, 5, 7, 3}, {2, 3, 3}, {10}, {1024, 2048, 4096, 3}}) {
        const std::string h = npyHeader(shape);
        ASSERT_GE(h.size(), 10u);
        EXPECT_EQ(h.substr(0, 6), std::string("\x93NUMPY"));
        EXPECT_EQ(h[6], '\x01');
        EXPECT_EQ(h[7], '\x00');
        const size_t len = static_cast<unsigned char>(h[8]) | (static_cast<unsigned char>(h[9]) << 8);
        EXPECT_EQ(len + 10, h.size());
        EXPECT_EQ(h.size() % 64, 0u) << "the data must start at a multiple of 64 bytes";
        EXPECT_EQ(h.back(), '\n');
        const std::string dict = h.substr(10);
        std::string dims;
        for (size_t i = 0; i < shape.size(); ++i) dims += (i ? ", " : "") + std::to_string(shape[i]);
        if (shape.size() == 1) dims += ",";
        const std::string want = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + dims + "), }";
        EXPECT_EQ(dict.substr(0, want.size()), want);
        EXPECT_EQ(dict.find_first_not_of(' ', want.size()), dict.size() - 1) << "only spaces, then the newline";
    }
    EXPECT_EQ(npyHeader({4, 5, 7, 3}), std::string("\x93NUMPY\x01\x00\x76\x00", 10) +
                                           "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 5, 7, 3), }" +
                                           std::string(52, ' ') + "\n");
    EXPECT_EQ(npyCount({4, 5, 7, 3}), 420u);
}

TEST(NpyHeader, StreamedValuesFollowTheHeaderAndAppearOnlyOnCommit) {
    test::TempDir dir("npy");
    const std::string path = (dir / "a.npy").string();
    std::vector<float> v(2 * 3 * 3);
    for (size_t i = 0; i < v.size(); ++i) v[i] = 0.5f * static_cast<float>(i) - 3.0f;
    {
        NpyWriter w(path, {2, 3, 3});
        w.write(v.data(), 9);
        EXPECT_FALSE(std::filesystem::exists(path));
        w.write(v.data() + 9, 9);
        w.commit();
    }
    const std::string bytes = slurp(path);
    const std::string h = npyHeader({2, 3, 3});
    ASSERT_EQ(bytes.size(), h.size() + v.size() * 4);
    EXPECT_EQ(bytes.substr(0, h.size()), h);
    std::vector<float> back(v.size());
    std::memcpy(back.data(), bytes.data() + h.size(), v.size() * 4);
    EXPECT_EQ(back, v);

    // Abandoned before commit: nothing, not even the temporary file.
    {
        NpyWriter w((dir / "b.npy").string(), {4});
        w.write(v.data(), 2);
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()) || !std::filesystem::exists(dir / "b.npy"));
    size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.path().filename() != "a.npy";
    EXPECT_EQ(files, 0u);
}
