#include "io/nlos_hdf5.h"

#include "base/error.h"
#include "io/atomic_file.h"

#include <hdf5.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <utility>

namespace tpb {

namespace {

// tal.enums.HFormat and tal.enums.GridFormat, every member (h5py.enum_dtype of the whole class is
// what tal's writer stores).
struct EnumMember {
    const char* name;
    int32_t value;
};
constexpr EnumMember kHFormat[] = {{"UNKNOWN", 0},        {"T_Sx_Sy", 1}, {"T_Lx_Ly_Sx_Sy", 2},
                                   {"T_Si", 3},           {"T_Li_Si", 4}, {"F_Sx_Sy", 10},
                                   {"F_Lx_Ly_Sx_Sy", 11}, {"F_Si", 12},   {"F_Li_Si", 13}};
constexpr EnumMember kGridFormat[] = {{"UNKNOWN", 0}, {"N_3", 1}, {"X_Y_3", 2}};
constexpr int32_t kHFormatTSxSy = 1, kHFormatTLxLySxSy = 2, kGridFormatXY3 = 2;

// ---- validation: everything is checked before the file is created ------------------------------

[[noreturn]] void refuse(const std::string& path, const std::string& key, const std::string& what) {
    throw UserError(path, 0, key, what + " (nothing was written)");
}

// a * b, refused when it passes 2^62 (no file of that size can be written anyway).
uint64_t mul(const std::string& path, uint64_t a, uint64_t b) {
    if (b != 0 && a > (uint64_t(1) << 62) / b) refuse(path, "H", "the capture's shape holds more than 2^62 values");
    return a * b;
}

void checkPoints(const std::string& path, const std::string& key, const std::vector<Vec3>& v, size_t want,
                 const std::string& shape, bool unit) {
    if (v.size() != want)
        refuse(path, key,
               "has " + std::to_string(v.size()) + " points, the grid " + shape + " needs " + std::to_string(want));
    for (size_t i = 0; i < v.size(); ++i) {
        const Vec3& p = v[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            refuse(path, key, "point " + std::to_string(i) + " is not finite");
        if (unit && std::abs(glm::length(p) - 1.0) > 1e-4)
            refuse(path, key,
                   "normal " + std::to_string(i) + " has length " + shortNumber(glm::length(p)) +
                       "; normals must be unit vectors");
    }
}

void validate(const std::string& path, const NlosCapture& c) {
    if (c.bins < 1) refuse(path, "bins", "is " + std::to_string(c.bins) + "; a capture needs at least one bin");
    if (c.sensorX < 1 || c.sensorY < 1)
        refuse(path, "sensorX, sensorY",
               "are " + std::to_string(c.sensorX) + " x " + std::to_string(c.sensorY) + "; both must be at least 1");
    if (c.confocal && c.exhaustive)
        refuse(path, "confocal, exhaustive", "are both set; a capture is single, confocal or exhaustive");
    const uint64_t sensors = mul(path, uint64_t(c.sensorX), uint64_t(c.sensorY));
    const std::string sensorShape = "Sx x Sy = " + std::to_string(c.sensorX) + " x " + std::to_string(c.sensorY);
    checkPoints(path, "sensorGrid", c.sensorGrid, sensors, sensorShape, false);
    checkPoints(path, "sensorNormals", c.sensorNormals, sensors, sensorShape, true);

    uint64_t lasers = 1;
    const std::string laserShape = "Lx x Ly = " + std::to_string(c.laserX) + " x " + std::to_string(c.laserY);
    if (c.confocal) {
        const bool oneByOne = c.laserX == 1 && c.laserY == 1;
        const bool sameAsSensor = c.laserX == c.sensorX && c.laserY == c.sensorY;
        if (!oneByOne && !sameAsSensor)
            refuse(path, "laserX, laserY",
                   "are " + std::to_string(c.laserX) + " x " + std::to_string(c.laserY) +
                       " in a confocal capture; leave them 1 x 1 (or Sx x Sy): the laser points are the sensor points");
        if (!c.laserGrid.empty() || !c.laserNormals.empty())
            refuse(path, "laserGrid, laserNormals",
                   "are given in a confocal capture; leave them empty: the sensor grid is written as the laser grid");
    } else {
        if (c.laserX < 1 || c.laserY < 1)
            refuse(path, "laserX, laserY",
                   "are " + std::to_string(c.laserX) + " x " + std::to_string(c.laserY) + "; both must be at least 1");
        if (!c.exhaustive && (c.laserX != 1 || c.laserY != 1))
            refuse(path, "laserX, laserY",
                   "are " + std::to_string(c.laserX) + " x " + std::to_string(c.laserY) +
                       " in a single capture (one laser point); set exhaustive for a grid of laser points");
        lasers = mul(path, uint64_t(c.laserX), uint64_t(c.laserY));
        checkPoints(path, "laserGrid", c.laserGrid, lasers, laserShape, false);
        checkPoints(path, "laserNormals", c.laserNormals, lasers, laserShape, true);
    }

    const uint64_t values = mul(path, mul(path, uint64_t(c.bins), c.exhaustive ? lasers : 1), sensors);
    if (c.H.size() != values) {
        const std::string shape = c.exhaustive ? "(T, Lx, Ly, Sx, Sy) = (" + std::to_string(c.bins) + ", " +
                                                     std::to_string(c.laserX) + ", " + std::to_string(c.laserY) + ", " +
                                                     std::to_string(c.sensorX) + ", " + std::to_string(c.sensorY) + ")"
                                               : "(T, Sx, Sy) = (" + std::to_string(c.bins) + ", " +
                                                     std::to_string(c.sensorX) + ", " + std::to_string(c.sensorY) + ")";
        refuse(
            path, "H",
            "has " + std::to_string(c.H.size()) + " values, the shape " + shape + " needs " + std::to_string(values));
    }
    for (const auto& [key, v] : {std::pair<const char*, const Vec3*>{"sensorOrigin", &c.sensorOrigin},
                                 std::pair<const char*, const Vec3*>{"laserOrigin", &c.laserOrigin}})
        if (!std::isfinite(v->x) || !std::isfinite(v->y) || !std::isfinite(v->z)) refuse(path, key, "is not finite");
    if (!(std::isfinite(c.deltaT) && c.deltaT > 0.0))
        refuse(path, "deltaT", "is " + shortNumber(c.deltaT) + "; the bin width must be a finite positive length (m)");
    if (!std::isfinite(c.tStart)) refuse(path, "tStart", "is not finite");
    if (c.sceneInfoYaml.find('\0') != std::string::npos)
        refuse(path, "sceneInfoYaml", "holds a NUL character; HDF5 stores it as a C string");
}

// ---- HDF5 ---------------------------------------------------------------------------------------

// An HDF5 identifier closed by its own close function when it goes out of scope.
class Handle {
public:
    Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
    ~Handle() {
        if (id_ >= 0) close_(id_);
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    hid_t get() const { return id_; }
    // Closes now; false when HDF5 reports an error (a data set's or the file's last write failed).
    bool close() {
        const hid_t id = std::exchange(id_, -1);
        return id < 0 || close_(id) >= 0;
    }

private:
    hid_t id_;
    herr_t (*close_)(hid_t);
};

// HDF5's own printing of its error stack to stderr is turned off while the writer runs (the error
// goes into the UserError instead) and turned back on after.
class QuietHdf5Errors {
public:
    QuietHdf5Errors() {
        H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    }
    ~QuietHdf5Errors() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
    QuietHdf5Errors(const QuietHdf5Errors&) = delete;
    QuietHdf5Errors& operator=(const QuietHdf5Errors&) = delete;

private:
    H5E_auto2_t func_ = nullptr;
    void* data_ = nullptr;
};

// The innermost message of HDF5's current error stack and the system errno it names, if any
// ("... errno = 28, error message = 'No space left on device' ...").
struct Hdf5Failure {
    std::string innermost;
    int err = 0;
};

herr_t collectError(unsigned n, const H5E_error2_t* e, void* out) {
    auto* f = static_cast<Hdf5Failure*>(out);
    const char* desc = e->desc ? e->desc : "";
    if (n == 0) f->innermost = desc;
    if (f->err == 0)
        if (const char* p = std::strstr(desc, "errno = ")) f->err = std::atoi(p + 8);
    return 0;
}

Hdf5Failure currentFailure() {
    Hdf5Failure f;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, collectError, &f);
    return f;
}

// Writes the file with HDF5; every step throws UserError on failure. `removeTmp` cleans up.
class Writer {
public:
    Writer(std::string path, std::string tmp) : path_(std::move(path)), tmp_(std::move(tmp)) {}

    [[noreturn]] void fail(const std::string& what) const {
        const Hdf5Failure f = currentFailure();
        std::string reason;
        if (f.err != 0)
            reason = std::string(": ") + std::strerror(f.err) + atomicFailureFix(f.err);
        else if (!f.innermost.empty())
            reason = ": HDF5: " + f.innermost;
        throw UserError(path_, 0, "", what + reason + " (nothing was written under this name)");
    }
    // An identifier or a status: negative is HDF5's failure.
    template <class R>
    R check(R r, const std::string& what) const {
        if (r < 0) fail(what);
        return r;
    }

    Handle create() {
        return Handle(check(H5Fcreate(tmp_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "cannot create the file"),
                      H5Fclose);
    }

    // A data set `name` of file type `fileType` and shape `dims` (empty: a scalar), from `data` in
    // memory type `memType`.
    void dataset(hid_t file, const char* name, hid_t fileType, hid_t memType, const std::vector<hsize_t>& dims,
                 const void* data) const {
        const std::string what = std::string("cannot write ") + name;
        Handle space(check(dims.empty() ? H5Screate(H5S_SCALAR)
                                        : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                           what),
                     H5Sclose);
        Handle ds(check(H5Dcreate2(file, name, fileType, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), what),
                  H5Dclose);
        check(H5Dwrite(ds.get(), memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), what);
        if (!ds.close()) fail(what);
    }

    void points(hid_t file, const char* name, const std::vector<Vec3>& v, hsize_t x, hsize_t y) const {
        std::vector<float> f(v.size() * 3);
        for (size_t i = 0; i < v.size(); ++i)
            for (int k = 0; k < 3; ++k) f[3 * i + k] = static_cast<float>(v[i][k]);
        dataset(file, name, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {x, y, 3}, f.data());
    }

    void vec3(hid_t file, const char* name, const Vec3& v) const {
        const float f[3] = {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
        dataset(file, name, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {3}, f);
    }

    void scalar(hid_t file, const char* name, double v) const {
        dataset(file, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {}, &v);
    }

    template <size_t N>
    void enumeration(hid_t file, const char* name, const EnumMember (&members)[N], int32_t value) const {
        const std::string what = std::string("cannot write ") + name;
        Handle type(check(H5Tenum_create(H5T_NATIVE_INT32), what), H5Tclose);
        for (const EnumMember& m : members) check(H5Tenum_insert(type.get(), m.name, &m.value), what);
        dataset(file, name, type.get(), type.get(), {1}, &value);
    }

    // h5py's bool: an enum of int8 with the members FALSE = 0 and TRUE = 1 (read back as numpy.bool_).
    void boolean(hid_t file, const char* name, bool v) const {
        const std::string what = std::string("cannot write ") + name;
        Handle type(check(H5Tenum_create(H5T_NATIVE_INT8), what), H5Tclose);
        const int8_t no = 0, yes = 1, value = v ? 1 : 0;
        check(H5Tenum_insert(type.get(), "FALSE", &no), what);
        check(H5Tenum_insert(type.get(), "TRUE", &yes), what);
        dataset(file, name, type.get(), type.get(), {}, &value);
    }

    // A Python str as h5py stores it: a scalar variable-length UTF-8 string.
    void text(hid_t file, const char* name, const std::string& s) const {
        const std::string what = std::string("cannot write ") + name;
        Handle type(check(H5Tcopy(H5T_C_S1), what), H5Tclose);
        check(H5Tset_size(type.get(), H5T_VARIABLE), what);
        check(H5Tset_cset(type.get(), H5T_CSET_UTF8), what);
        const char* p = s.c_str();
        dataset(file, name, type.get(), type.get(), {}, &p);
    }

private:
    std::string path_, tmp_;
};

// Removes the temporary file unless disarmed (after the rename).
class TmpGuard {
public:
    explicit TmpGuard(std::string tmp) : tmp_(std::move(tmp)) {}
    ~TmpGuard() {
        if (!tmp_.empty()) std::remove(tmp_.c_str());
    }
    TmpGuard(const TmpGuard&) = delete;
    TmpGuard& operator=(const TmpGuard&) = delete;
    void disarm() { tmp_.clear(); }

private:
    std::string tmp_;
};

}  // namespace

void writeNlosHdf5(const std::string& path, const NlosCapture& c) {
    validate(path, c);
    const hsize_t T = hsize_t(c.bins), Sx = hsize_t(c.sensorX), Sy = hsize_t(c.sensorY);
    const hsize_t Lx = hsize_t(c.laserX), Ly = hsize_t(c.laserY);

    const std::string tmp = atomicTmpName(path);
    QuietHdf5Errors quiet;
    TmpGuard guard(tmp);
    Writer w(path, tmp);
    {
        Handle file = w.create();
        const hid_t f = file.get();
        const std::vector<hsize_t> hShape =
            c.exhaustive ? std::vector<hsize_t>{T, Lx, Ly, Sx, Sy} : std::vector<hsize_t>{T, Sx, Sy};
        w.dataset(f, "H", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, hShape, c.H.data());
        w.enumeration(f, "H_format", kHFormat, c.exhaustive ? kHFormatTLxLySxSy : kHFormatTSxSy);
        w.vec3(f, "sensor_xyz", c.sensorOrigin);
        w.points(f, "sensor_grid_xyz", c.sensorGrid, Sx, Sy);
        w.points(f, "sensor_grid_normals", c.sensorNormals, Sx, Sy);
        w.enumeration(f, "sensor_grid_format", kGridFormat, kGridFormatXY3);
        w.vec3(f, "laser_xyz", c.laserOrigin);
        // Confocal: tal knows it by laser_grid_xyz equal to sensor_grid_xyz (same shape and values).
        if (c.confocal) {
            w.points(f, "laser_grid_xyz", c.sensorGrid, Sx, Sy);
            w.points(f, "laser_grid_normals", c.sensorNormals, Sx, Sy);
        } else {
            w.points(f, "laser_grid_xyz", c.laserGrid, Lx, Ly);
            w.points(f, "laser_grid_normals", c.laserNormals, Lx, Ly);
        }
        w.enumeration(f, "laser_grid_format", kGridFormat, kGridFormatXY3);
        w.scalar(f, "delta_t", c.deltaT);
        w.scalar(f, "t_start", c.tStart);
        w.boolean(f, "t_accounts_first_and_last_bounces", c.tAccountsFirstAndLastBounces);
        w.text(f, "scene_info", c.sceneInfoYaml.empty() ? std::string("{}\n") : c.sceneInfoYaml);
        // Closing flushes the metadata: where a full disk shows up last.
        if (!file.close()) w.fail("cannot finish writing the file");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        const int err = errno;
        throw UserError(path, 0, "",
                        std::string("cannot move the finished file into place: ") + std::strerror(err) +
                            atomicFailureFix(err) + " (nothing was written under this name)");
    }
    guard.disarm();
}

}  // namespace tpb
