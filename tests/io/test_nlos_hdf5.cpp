// The NLOS capture writer (core/io/nlos_hdf5.h) read back with HDF5's C API: for a confocal, a
// single and an exhaustive capture, every key of the file, each data set's type class, size, sign,
// shape and values, the enums' members, the bool's and the string's HDF5 types, and no attribute
// anywhere. Bad input is refused before anything is created (no file, no temporary file, an
// existing file left as it was); a failure after HDF5 wrote the file (the rename) leaves no
// temporary file either. Then tools/check_nlos_hdf5 (y-tal's read rules) passes the three files and
// refuses a file with an unknown key, a scene_info that is no mapping and an H_format that does not
// match H; skipped (with the reason) when /usr/bin/python3 lacks h5py, numpy or yaml.
#include "base/error.h"
#include "io/atomic_file.h"
#include "io/nlos_hdf5.h"
#include "support/temp_dir.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace tpb;
namespace fs = std::filesystem;

namespace {

const char* kPython = "/usr/bin/python3";

enum class Scan { Single, Confocal, Exhaustive };

// T = 4 bins, a 3 x 2 sensor grid, 2 x 3 laser points (exhaustive); every value different, so that
// a wrong index order or axis shows.
NlosCapture capture(Scan scan) {
    NlosCapture c;
    c.bins = 4;
    c.sensorX = 3;
    c.sensorY = 2;
    c.confocal = scan == Scan::Confocal;
    c.exhaustive = scan == Scan::Exhaustive;
    if (scan == Scan::Exhaustive) {
        c.laserX = 2;
        c.laserY = 3;
    }
    for (int sx = 0; sx < c.sensorX; ++sx)
        for (int sy = 0; sy < c.sensorY; ++sy) {
            c.sensorGrid.push_back(Vec3(0.25 * sx - 0.5, 0.125 * sy + 0.0625, 0.0));
            c.sensorNormals.push_back(glm::normalize(Vec3(0.1 * sx, 0.05 * sy, 1.0)));
        }
    if (scan != Scan::Confocal)
        for (int lx = 0; lx < c.laserX; ++lx)
            for (int ly = 0; ly < c.laserY; ++ly) {
                c.laserGrid.push_back(Vec3(0.5 * lx - 0.25, -0.375 + 0.25 * ly, 0.0));
                c.laserNormals.push_back(glm::normalize(Vec3(-0.05 * lx, 0.1 * ly, 1.0)));
            }
    const size_t n = size_t(c.bins) * (c.exhaustive ? size_t(c.laserX * c.laserY) : 1) * size_t(c.sensorX * c.sensorY);
    for (size_t i = 0; i < n; ++i) c.H.push_back(0.5f * static_cast<float>(i) - 7.25f);
    c.sensorOrigin = Vec3(-0.5, 0.0, 0.25);
    c.laserOrigin = Vec3(0.75, -0.125, 0.5);
    c.deltaT = 0.003;
    c.tStart = 1.2345678901234;
    c.tAccountsFirstAndLastBounces = scan != Scan::Single;
    c.sceneInfoYaml = scan == Scan::Exhaustive ? "" : "renderer: tpb\nscan: {kind: x}\n";
    return c;
}

// ---- reading back with the C API -----------------------------------------------------------------

struct H5 {
    hid_t id;
    herr_t (*close)(hid_t);
    ~H5() {
        if (id >= 0) close(id);
    }
};

std::vector<std::string> rootKeys(hid_t file) {
    H5G_info_t info;
    EXPECT_GE(H5Gget_info(file, &info), 0);
    std::vector<std::string> keys;
    for (hsize_t i = 0; i < info.nlinks; ++i) {
        char name[256] = {};
        H5Lget_name_by_idx(file, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
        keys.push_back(name);
    }
    std::sort(keys.begin(), keys.end());
    return keys;
}

herr_t countAttr(hid_t, const char*, const H5A_info_t*, void* n) {
    ++*static_cast<int*>(n);
    return 0;
}
int attributes(hid_t obj) {
    int n = 0;
    EXPECT_GE(H5Aiterate2(obj, H5_INDEX_NAME, H5_ITER_NATIVE, nullptr, countAttr, &n), 0);
    return n;
}

struct Dataset {
    H5T_class_t cls = H5T_NO_CLASS;
    size_t bytes = 0;                 // size of one value in the file
    H5T_sign_t sign = H5T_SGN_ERROR;  // integers (and an enum's base)
    H5T_order_t order = H5T_ORDER_ERROR;
    bool scalar = false;
    std::vector<hsize_t> dims;
};

Dataset describe(hid_t file, const char* name) {
    Dataset d;
    H5 ds{H5Dopen2(file, name, H5P_DEFAULT), H5Dclose};
    EXPECT_GE(ds.id, 0) << name;
    if (ds.id < 0) return d;
    EXPECT_EQ(attributes(ds.id), 0) << name << ": tpb writes no attributes";
    H5 type{H5Dget_type(ds.id), H5Tclose};
    d.cls = H5Tget_class(type.id);
    d.bytes = H5Tget_size(type.id);
    H5 base{d.cls == H5T_ENUM ? H5Tget_super(type.id) : H5Tcopy(type.id), H5Tclose};
    if (d.cls == H5T_ENUM || d.cls == H5T_INTEGER) d.sign = H5Tget_sign(base.id);
    if (d.cls != H5T_STRING) d.order = H5Tget_order(base.id);
    H5 space{H5Dget_space(ds.id), H5Sclose};
    d.scalar = H5Sget_simple_extent_type(space.id) == H5S_SCALAR;
    d.dims.resize(static_cast<size_t>(H5Sget_simple_extent_ndims(space.id)));
    H5Sget_simple_extent_dims(space.id, d.dims.data(), nullptr);
    return d;
}

std::vector<float> floats(hid_t file, const char* name) {
    H5 ds{H5Dopen2(file, name, H5P_DEFAULT), H5Dclose};
    H5 space{H5Dget_space(ds.id), H5Sclose};
    std::vector<float> v(static_cast<size_t>(H5Sget_simple_extent_npoints(space.id)));
    EXPECT_GE(H5Dread(ds.id, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0) << name;
    return v;
}

double float64(hid_t file, const char* name) {
    H5 ds{H5Dopen2(file, name, H5P_DEFAULT), H5Dclose};
    double v = -1.0;
    EXPECT_GE(H5Dread(ds.id, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), 0) << name;
    return v;
}

// An enum's members (name -> value, read as the base type's integer) and its stored value.
struct Enum {
    std::map<std::string, long> members;
    long value = -99;
};
Enum enumeration(hid_t file, const char* name) {
    Enum e;
    H5 ds{H5Dopen2(file, name, H5P_DEFAULT), H5Dclose};
    H5 type{H5Dget_type(ds.id), H5Tclose};
    const int n = H5Tget_nmembers(type.id);
    const bool wide = H5Tget_size(type.id) == 4;
    for (int i = 0; i < n; ++i) {
        char* m = H5Tget_member_name(type.id, static_cast<unsigned>(i));
        int32_t v32 = 0;
        int8_t v8 = 0;
        H5Tget_member_value(type.id, static_cast<unsigned>(i), wide ? static_cast<void*>(&v32) : &v8);
        e.members[m] = wide ? v32 : v8;
        H5free_memory(m);
    }
    // Read as the base integer type, not through the enum conversion.
    H5 base{H5Tget_super(type.id), H5Tclose};
    H5 native{H5Tget_native_type(base.id, H5T_DIR_ASCEND), H5Tclose};
    int32_t v32 = 0;
    int8_t v8 = 0;
    EXPECT_GE(H5Dread(ds.id, native.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, wide ? static_cast<void*>(&v32) : &v8), 0);
    e.value = wide ? v32 : v8;
    return e;
}

// A variable-length string data set: checks its type and returns the text.
std::string text(hid_t file, const char* name) {
    H5 ds{H5Dopen2(file, name, H5P_DEFAULT), H5Dclose};
    H5 type{H5Dget_type(ds.id), H5Tclose};
    EXPECT_EQ(H5Tget_class(type.id), H5T_STRING);
    EXPECT_GT(H5Tis_variable_str(type.id), 0) << "h5py stores a Python str as a variable-length string";
    EXPECT_EQ(H5Tget_cset(type.id), H5T_CSET_UTF8);
    char* s = nullptr;
    EXPECT_GE(H5Dread(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, &s), 0);
    std::string out = s ? s : "";
    H5free_memory(s);
    return out;
}

std::vector<float> asFloats(const std::vector<Vec3>& v) {
    std::vector<float> f;
    for (const Vec3& p : v)
        for (int k = 0; k < 3; ++k) f.push_back(static_cast<float>(p[k]));
    return f;
}

void expectFloat32(hid_t f, const char* name, const std::vector<hsize_t>& dims, const std::vector<float>& values) {
    SCOPED_TRACE(name);
    const Dataset d = describe(f, name);
    EXPECT_EQ(d.cls, H5T_FLOAT);
    EXPECT_EQ(d.bytes, 4u);
    EXPECT_EQ(d.order, H5T_ORDER_LE);
    EXPECT_EQ(d.dims, dims);
    EXPECT_EQ(floats(f, name), values);
}

void expectScalarFloat64(hid_t f, const char* name, double value) {
    SCOPED_TRACE(name);
    const Dataset d = describe(f, name);
    EXPECT_EQ(d.cls, H5T_FLOAT);
    EXPECT_EQ(d.bytes, 8u);
    EXPECT_TRUE(d.scalar);
    EXPECT_EQ(float64(f, name), value);
}

void expectEnum(hid_t f, const char* name, const std::map<std::string, long>& members, long value, size_t bytes,
                bool scalar) {
    SCOPED_TRACE(name);
    const Dataset d = describe(f, name);
    EXPECT_EQ(d.cls, H5T_ENUM);
    EXPECT_EQ(d.bytes, bytes);
    EXPECT_EQ(d.sign, H5T_SGN_2);
    EXPECT_EQ(d.scalar, scalar);
    if (!scalar) {
        EXPECT_EQ(d.dims, std::vector<hsize_t>{1});
    }
    const Enum e = enumeration(f, name);
    EXPECT_EQ(e.members, members);
    EXPECT_EQ(e.value, value);
}

const std::map<std::string, long> kHFormat = {{"UNKNOWN", 0},        {"T_Sx_Sy", 1}, {"T_Lx_Ly_Sx_Sy", 2},
                                              {"T_Si", 3},           {"T_Li_Si", 4}, {"F_Sx_Sy", 10},
                                              {"F_Lx_Ly_Sx_Sy", 11}, {"F_Si", 12},   {"F_Li_Si", 13}};
const std::map<std::string, long> kGridFormat = {{"UNKNOWN", 0}, {"N_3", 1}, {"X_Y_3", 2}};

// Writes `c` and checks every key of the file against it.
void writeAndReadBack(Scan scan) {
    const NlosCapture c = capture(scan);
    test::TempDir dir("nlos_hdf5");
    const std::string path = (dir / "capture.hdf5").string();
    writeNlosHdf5(path, c);
    EXPECT_FALSE(fs::exists(atomicTmpName(path))) << "the temporary file is renamed";

    H5 file{H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
    ASSERT_GE(file.id, 0);
    const hid_t f = file.id;
    EXPECT_EQ(rootKeys(f), (std::vector<std::string>{"H", "H_format", "delta_t", "laser_grid_format",
                                                     "laser_grid_normals", "laser_grid_xyz", "laser_xyz", "scene_info",
                                                     "sensor_grid_format", "sensor_grid_normals", "sensor_grid_xyz",
                                                     "sensor_xyz", "t_accounts_first_and_last_bounces", "t_start"}))
        << "exactly tal's keys (it refuses any other)";
    EXPECT_EQ(attributes(f), 0);

    const hsize_t T = 4, Sx = 3, Sy = 2;
    expectFloat32(f, "H", c.exhaustive ? std::vector<hsize_t>{T, 2, 3, Sx, Sy} : std::vector<hsize_t>{T, Sx, Sy}, c.H);
    expectEnum(f, "H_format", kHFormat, c.exhaustive ? 2 : 1, 4, false);
    expectFloat32(f, "sensor_xyz", {3}, {-0.5f, 0.0f, 0.25f});
    expectFloat32(f, "laser_xyz", {3}, {0.75f, -0.125f, 0.5f});
    expectFloat32(f, "sensor_grid_xyz", {Sx, Sy, 3}, asFloats(c.sensorGrid));
    expectFloat32(f, "sensor_grid_normals", {Sx, Sy, 3}, asFloats(c.sensorNormals));
    // sensor point (sx, sy) = (2, 1) is the last one: x = 0.25 * 2 - 0.5, y = 0.125 + 0.0625.
    EXPECT_EQ(floats(f, "sensor_grid_xyz")[3 * (2 * 2 + 1) + 1], 0.1875f);
    expectEnum(f, "sensor_grid_format", kGridFormat, 2, 4, false);
    expectEnum(f, "laser_grid_format", kGridFormat, 2, 4, false);
    switch (scan) {
        case Scan::Confocal:  // the laser grid is the sensor grid: how tal tells confocal data
            expectFloat32(f, "laser_grid_xyz", {Sx, Sy, 3}, asFloats(c.sensorGrid));
            expectFloat32(f, "laser_grid_normals", {Sx, Sy, 3}, asFloats(c.sensorNormals));
            break;
        case Scan::Single:
            expectFloat32(f, "laser_grid_xyz", {1, 1, 3}, asFloats(c.laserGrid));
            expectFloat32(f, "laser_grid_normals", {1, 1, 3}, asFloats(c.laserNormals));
            break;
        case Scan::Exhaustive:
            expectFloat32(f, "laser_grid_xyz", {2, 3, 3}, asFloats(c.laserGrid));
            expectFloat32(f, "laser_grid_normals", {2, 3, 3}, asFloats(c.laserNormals));
            EXPECT_EQ(floats(f, "laser_grid_xyz")[3 * (1 * 3 + 2) + 1], 0.125f) << "laser point (1, 2): y";
            break;
    }
    expectScalarFloat64(f, "delta_t", 0.003);
    expectScalarFloat64(f, "t_start", 1.2345678901234);
    expectEnum(f, "t_accounts_first_and_last_bounces", {{"FALSE", 0}, {"TRUE", 1}}, scan != Scan::Single, 1, true);
    {
        SCOPED_TRACE("scene_info");
        const Dataset d = describe(f, "scene_info");
        EXPECT_TRUE(d.scalar);
        EXPECT_EQ(text(f, "scene_info"), c.sceneInfoYaml.empty() ? "{}\n" : c.sceneInfoYaml);
    }
}

}  // namespace

TEST(NlosHdf5, ConfocalCaptureReadsBackKeyByKey) { writeAndReadBack(Scan::Confocal); }
TEST(NlosHdf5, SingleCaptureReadsBackKeyByKey) { writeAndReadBack(Scan::Single); }
TEST(NlosHdf5, ExhaustiveCaptureReadsBackKeyByKey) { writeAndReadBack(Scan::Exhaustive); }

TEST(NlosHdf5, OverwritesAnExistingFile) {
    test::TempDir dir("nlos_hdf5");
    const std::string path = (dir / "capture.hdf5").string();
    dir.write("capture.hdf5", "old");
    writeNlosHdf5(path, capture(Scan::Single));
    EXPECT_GT(H5Fis_hdf5(path.c_str()), 0);
}

// Each bad capture is refused with the path and the field in the message, before anything exists.
TEST(NlosHdf5, RefusesInconsistentCapturesAndWritesNothing) {
    struct Case {
        const char* what;
        void (*spoil)(NlosCapture&);
        const char* key;
        Scan scan = Scan::Single;
    };
    const Case cases[] = {
        {"one value short", [](NlosCapture& c) { c.H.pop_back(); },
         "H: has 23 values, the shape (T, Sx, Sy) = (4, 3, 2) needs 24"},
        {"exhaustive H sized as single", [](NlosCapture& c) { c.H.resize(24); }, "H: has 24 values", Scan::Exhaustive},
        {"no bins", [](NlosCapture& c) { c.bins = 0; }, "bins:"},
        {"sensor grid short", [](NlosCapture& c) { c.sensorGrid.pop_back(); }, "sensorGrid: has 5 points"},
        {"normals short", [](NlosCapture& c) { c.sensorNormals.clear(); }, "sensorNormals:"},
        {"normal not unit", [](NlosCapture& c) { c.laserNormals[0] *= 2.0; }, "laserNormals: normal 0 has length 2"},
        {"laser grid short", [](NlosCapture& c) { c.laserGrid.pop_back(); }, "laserGrid: has 5 points",
         Scan::Exhaustive},
        {"single with a laser grid", [](NlosCapture& c) { c.laserX = 2; }, "laserX, laserY:"},
        {"both scans", [](NlosCapture& c) { c.exhaustive = true; }, "confocal, exhaustive:", Scan::Confocal},
        {"confocal with a laser grid", [](NlosCapture& c) { c.laserGrid = c.sensorGrid; },
         "laserGrid, laserNormals:", Scan::Confocal},
        {"zero bin width", [](NlosCapture& c) { c.deltaT = 0.0; }, "deltaT:"},
        {"NaN start", [](NlosCapture& c) { c.tStart = std::nan(""); }, "tStart:"},
        {"infinite origin", [](NlosCapture& c) { c.laserOrigin.y = kInf; }, "laserOrigin:"},
        {"NUL in the YAML", [](NlosCapture& c) { c.sceneInfoYaml = std::string("a: 1\0b", 6); }, "sceneInfoYaml:"},
    };
    test::TempDir dir("nlos_hdf5");
    for (const Case& k : cases) {
        SCOPED_TRACE(k.what);
        for (const bool existing : {false, true}) {
            const std::string path = (dir / "capture.hdf5").string();
            fs::remove(path);
            if (existing) dir.write("capture.hdf5", "the previous capture");
            NlosCapture c = capture(k.scan);
            k.spoil(c);
            try {
                writeNlosHdf5(path, c);
                ADD_FAILURE() << "not refused";
            } catch (const UserError& e) {
                const std::string msg = e.what();
                EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;
                EXPECT_NE(msg.find(k.key), std::string::npos) << msg;
                EXPECT_NE(msg.find("nothing was written"), std::string::npos) << msg;
            }
            EXPECT_FALSE(fs::exists(atomicTmpName(path)));
            if (existing) {
                std::ifstream in(path);
                std::stringstream s;
                s << in.rdbuf();
                EXPECT_EQ(s.str(), "the previous capture") << "an existing file is left as it was";
            } else {
                EXPECT_FALSE(fs::exists(path));
            }
        }
    }
    for (const auto& e : fs::directory_iterator(dir.path()))
        EXPECT_EQ(e.path().filename(), "capture.hdf5") << "a file left behind";
}

// The failure after HDF5 finished (the rename, here onto a folder) removes the temporary file too.
TEST(NlosHdf5, FailedRenameLeavesNoTemporaryFile) {
    test::TempDir dir("nlos_hdf5");
    const std::string path = (dir / "capture.hdf5").string();
    fs::create_directory(path);
    try {
        writeNlosHdf5(path, capture(Scan::Exhaustive));
        ADD_FAILURE() << "not refused";
    } catch (const UserError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(path + ": cannot move the finished file into place: Is a directory", 0), 0u) << msg;
    }
    EXPECT_FALSE(fs::exists(atomicTmpName(path)));
    EXPECT_TRUE(fs::is_directory(path));
}

TEST(NlosHdf5, MissingFolderIsAUserErrorNamingThePath) {
    test::TempDir dir("nlos_hdf5");
    const std::string path = (dir / "no" / "such" / "capture.hdf5").string();
    try {
        writeNlosHdf5(path, capture(Scan::Confocal));
        ADD_FAILURE() << "not refused";
    } catch (const UserError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(path + ": cannot create the file: No such file or directory; the folder does not exist", 0),
                  0u)
            << msg;
    }
    EXPECT_TRUE(fs::is_empty(dir.path()));
}

// ---- y-tal's read rules: tools/check_nlos_hdf5 ----------------------------------------------------

namespace {

int run(const std::string& cmd, std::string& out) {
    out.clear();
    FILE* p = ::popen((cmd + " 2>&1").c_str(), "r");
    if (!p) return -1;
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    const int st = ::pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string checkerMissing() {
    std::string out;
    if (!fs::exists(kPython))
        return std::string(kPython) + " is missing (apt-get install python3 python3-h5py python3-yaml)";
    if (run(std::string(kPython) + " -c 'import h5py, numpy, yaml'", out) != 0)
        return std::string(kPython) +
               " cannot import h5py, numpy and yaml (apt-get install python3-h5py python3-yaml): " + out;
    return "";
}

int check(const std::string& path, std::string& out) {
    return run(std::string(kPython) + " " + TPB_SOURCE_DIR + "/tools/check_nlos_hdf5 '" + path + "'", out);
}

}  // namespace

TEST(NlosHdf5Checker, PassesEveryScanTpbWrites) {
    const std::string missing = checkerMissing();
    if (!missing.empty()) GTEST_SKIP() << missing;
    test::TempDir dir("nlos_hdf5");
    for (const Scan scan : {Scan::Single, Scan::Confocal, Scan::Exhaustive}) {
        const std::string path = (dir / ("scan" + std::to_string(int(scan)) + ".hdf5")).string();
        writeNlosHdf5(path, capture(scan));
        std::string out;
        EXPECT_EQ(check(path, out), 0) << out;
    }
}

TEST(NlosHdf5Checker, RefusesWhatTalRefuses) {
    const std::string missing = checkerMissing();
    if (!missing.empty()) GTEST_SKIP() << missing;
    test::TempDir dir("nlos_hdf5");
    std::string out;

    // A key tal does not know, added with the C API.
    const std::string extra = (dir / "extra.hdf5").string();
    writeNlosHdf5(extra, capture(Scan::Confocal));
    {
        H5 file{H5Fopen(extra.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose};
        ASSERT_GE(file.id, 0);
        H5 space{H5Screate(H5S_SCALAR), H5Sclose};
        H5 ds{H5Dcreate2(file.id, "tpb_version", H5T_STD_I32LE, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
              H5Dclose};
        const int32_t v = 1;
        ASSERT_GE(H5Dwrite(ds.id, H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), 0);
    }
    EXPECT_EQ(check(extra, out), 1) << out;
    EXPECT_NE(out.find(extra + ": tpb_version: is not a key of tal's NLOSCaptureData"), std::string::npos) << out;

    // scene_info that is YAML, but of a list: tal looks keys up in it.
    const std::string list = (dir / "list.hdf5").string();
    NlosCapture c = capture(Scan::Single);
    c.sceneInfoYaml = "- a\n- b\n";
    writeNlosHdf5(list, c);
    EXPECT_EQ(check(list, out), 1) << out;
    EXPECT_NE(out.find(list + ": scene_info: is YAML of a list"), std::string::npos) << out;

    // An exhaustive H labelled (T, Sx, Sy).
    const std::string format = (dir / "format.hdf5").string();
    writeNlosHdf5(format, capture(Scan::Exhaustive));
    {
        H5 file{H5Fopen(format.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose};
        H5 ds{H5Dopen2(file.id, "H_format", H5P_DEFAULT), H5Dclose};
        H5 type{H5Dget_type(ds.id), H5Tclose};
        const int32_t tSxSy = 1;
        ASSERT_GE(H5Dwrite(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, &tSxSy), 0);
    }
    EXPECT_EQ(check(format, out), 1) << out;
    EXPECT_NE(out.find(format + ": H: has shape (4, 2, 3, 3, 2); H_format T_Sx_Sy needs (T, Sx, Sy)"),
              std::string::npos)
        << out;
}
