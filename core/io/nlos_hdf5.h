// NLOS captures written as HDF5 files in the layout of the NLOS toolkit y-tal ("HDF5_TAL"), so that
// `tal.io.read_capture(path)` reads them as they are (docs/user/nlos_hdf5.md lists every key, shape,
// type and unit, with the line of y-tal each rule comes from).
//
// tal refuses a file with any key it does not know, so the file holds exactly its keys: H, H_format,
// sensor_xyz, sensor_grid_xyz, sensor_grid_normals, sensor_grid_format, laser_xyz, laser_grid_xyz,
// laser_grid_normals, laser_grid_format, delta_t, t_start, t_accounts_first_and_last_bounces and
// scene_info (the deprecated volume_format is left out), and no attributes. The types are those
// h5py gives the values tal's own renderer writes: float32 arrays, float64 scalars, enums as HDF5
// enums of int32 (shape (1,)), the bool as h5py's bool (an enum of int8 FALSE/TRUE), scene_info a
// variable-length UTF-8 string of YAML.
//
// The file is written by HDF5 under "<path>.tmp-<pid>" (atomicTmpName, atomic_file.h) in the same
// folder and renamed over `path` only when HDF5 closed it without an error; on any failure the
// temporary file is removed and an existing file at `path` is left as it was. (HDF5 writes the file
// itself, by name: streaming its bytes through AtomicFile would need the whole file image in memory,
// a second copy of H.)
#pragma once
#include "base/math.h"

#include <string>
#include <vector>

namespace tpb {

// One NLOS capture in the NLOS toolkit's layout (y-tal), as tpb writes it. Three scans:
//  - single:     confocal == exhaustive == false; one laser point (laserX = laserY = 1), H (T, Sx, Sy);
//  - confocal:   the laser point of each sensor point is that point; H (T, Sx, Sy); laserGrid and
//                laserNormals stay empty (the sensor grid is written as tal's laser grid, which is
//                how tal tells confocal data: laser_grid_xyz == sensor_grid_xyz); laserX x laserY is
//                1 x 1 or Sx x Sy;
//  - exhaustive: every laser point with every sensor point; H (T, Lx, Ly, Sx, Sy).
struct NlosCapture {
    int bins = 0;                  // T
    int sensorX = 0, sensorY = 0;  // Sx, Sy: the sensor grid on the relay wall
    int laserX = 1, laserY = 1;    // Lx, Ly: laser points (1 x 1 for single / confocal)
    bool confocal = false;         // H is (T, Sx, Sy) with laser point == sensor point
    bool exhaustive = false;       // H is (T, Lx, Ly, Sx, Sy)
    // H, time-first, C order: (T, Sx, Sy), or (T, Lx, Ly, Sx, Sy) when exhaustive. One channel
    // (tpb passes luminance or one colour channel). Bin k holds the response integrated over
    // [tStart + k deltaT, tStart + (k + 1) deltaT).
    std::vector<float> H;
    // Sx*Sy points on the wall, index sx*Sy + sy (tal's (Sx, Sy, 3)); normals of unit length.
    std::vector<Vec3> sensorGrid, sensorNormals;
    // Lx*Ly points, index lx*Ly + ly (tal's (Lx, Ly, 3)); empty when confocal.
    std::vector<Vec3> laserGrid, laserNormals;
    Vec3 sensorOrigin{0.0}, laserOrigin{0.0};  // m: the SPAD's and the laser's positions (tal's sensor_xyz, laser_xyz)
    double deltaT = 0.0;                       // bin width, m of optical path length (tal's delta_t; > 0)
    double tStart = 0.0;                       // start of bin 0, m of optical path length (tal's t_start)
    // true: times count the laser -> wall and wall -> sensor legs (a real clock at the devices);
    // false: times start at the laser's wall point and stop at the sensor's wall point.
    bool tAccountsFirstAndLastBounces = true;
    // tal's scene_info: YAML text of a mapping (tal needs a dict there); empty writes "{}". A key
    // "config" must hold a mapping with "mitsuba_variant" (tal's is_polarized reads it).
    std::string sceneInfoYaml;
};

// Writes `c` to `path` atomically; throws UserError naming the path on failure or on
// inconsistent sizes (H.size() != product of the shape, etc.), before anything is created.
// One call at a time in the process: Debian's HDF5 is built without thread safety.
void writeNlosHdf5(const std::string& path, const NlosCapture& c);

}  // namespace tpb
