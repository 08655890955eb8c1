// Plain description of a scene, as read from a scene file (parse -> describe -> build).
// No Embree, no render state: the loader (scene_loader.h) fills it, Scene (scene.h) builds from it.
// Every value read from the file has its location recorded in `locs` under its key path
// (e.g. "lights[0].power"), so the build step can report "scene.json:12: lights[0].power: ...".
#pragma once
#include "base/math.h"
#include "film/time_axis.h"
#include <map>
#include <string>
#include <vector>

namespace tpb {

// Largest coordinate (m) a scene may use: positions, corners, edges, sizes and radii in the scene
// file, and mesh vertices after their transform, must lie within +-kMaxSceneCoordinateM. Far beyond
// any scene tpb is meant for (a million km), and small enough that no length, squared length or
// optical path length between two points of the scene can overflow (1e308 would: a camera there
// used to be reported as "up parallel to the viewing direction").
inline constexpr double kMaxSceneCoordinateM = 1e9;

// Kernel radii against the scene's bounding diagonal. The cost of a pass grows with the radius
// (every camera ray gathers the beams within it: at a radius of the order of the diagonal every ray
// meets every beam, rays x beams, and the automatic-range pilot alone took minutes); typical radii
// are 0.1% - 2% of the diagonal. Larger than kMaxRadiusFraction is refused, larger than
// kSlowRadiusFraction warned about (render.radius(_relative), surface_radius(_relative), --radius),
// and smaller than kTinyRadiusFraction warned about too: such a kernel almost never meets a photon.
inline constexpr double kMaxRadiusFraction = 0.25;
inline constexpr double kSlowRadiusFraction = 0.05;
inline constexpr double kTinyRadiusFraction = 1e-6;

struct SourceLoc {
    std::string file;
    int line = 0;
};

// A pinhole camera, or a relay-wall sensor for non-line-of-sight captures ("type": "relay_wall"):
// its pixels are a width x height grid on a quad shape (the relay wall), pixel (i, j) covering
// corner + [i, i + 1) / width edge_u + [j, j + 1) / height edge_v, and each measures the radiance
// leaving its patch of the wall towards `position`, the sensor's origin (a focused SPAD).
enum class CameraType { Pinhole, RelayWall };
// Where a relay wall's time starts: Sensor counts the wall -> sensor leg (the real time axis as
// for a camera), Wall leaves it out (the NLOS toolkit's t_accounts_first_and_last_bounces false,
// on the sensor side): time is measured at the wall point.
enum class WallTimeOrigin { Sensor, Wall };
// How a relay wall's laser scans it ("scan" in the camera block): not at all (the scene's lights
// as they are), one wall point, the sensor's own point for every pixel (confocal), or every point of
// an Lx x Ly grid for every pixel (exhaustive: the film stacks one Sx x Sy image per laser point).
enum class ScanMode { None, Single, Confocal, Exhaustive };

struct CameraDesc {
    CameraType type = CameraType::Pinhole;
    Vec3 position{0.0, 0.0, 3.0};
    Vec3 lookAt{0.0, 0.0, 0.0};
    Vec3 up{0.0, 1.0, 0.0};
    double fovYDeg = 40.0;  // vertical field of view, degrees
    int width = 256;
    int height = 256;
    // Relay wall: the quad shape holding the grid (index into SceneDesc::shapes), and the time origin.
    int wallShape = -1;
    WallTimeOrigin timeOrigin = WallTimeOrigin::Sensor;
    // The scan: the laser light that scans (index into SceneDesc::lights; its direction is replaced
    // by the aim at each laser point), the single point as wall fractions (u along edge_u, v along
    // edge_v, in [0, 1]), the exhaustive grid (points at the cell centres, as the sensor's).
    ScanMode scan = ScanMode::None;
    int scanLaser = -1;
    double scanPointU = 0.5, scanPointV = 0.5;
    int laserGridX = 1, laserGridY = 1;
    // Laser points rendered one after the other per pass (1 unless a scan), and the film's height:
    // an exhaustive scan stacks one sensor image per laser point.
    int64_t laserPoints() const {
        return scan == ScanMode::Confocal     ? static_cast<int64_t>(width) * height
               : scan == ScanMode::Exhaustive ? static_cast<int64_t>(laserGridX) * laserGridY
                                              : 1;
    }
    int64_t filmHeight() const {
        return scan == ScanMode::Exhaustive ? static_cast<int64_t>(height) * laserGridX * laserGridY : height;
    }
};

// Time axis of the transient film, always optical path length in meters internally.
struct FilmDesc {
    bool autoRange = true;      // fit [start, start + bins*binWidth] to the scene's bounds
    double startOpl = 0.0;      // m of OPL
    double binWidthOpl = 0.01;  // m of OPL (ignored when autoRange; derived from bins)
    int bins = 256;
    // The phasor film's frequencies as written ("" = none): film/phasor.h parsePhasorFrequencies,
    // read once the time axis is known (render/prepare.cpp).
    std::string phasor;
};

struct MediumDesc {
    std::string name;
    Color sigma_s{0.0};  // scattering coefficient, 1/m
    Color sigma_a{0.0};  // absorption coefficient, 1/m
    double ior = 1.0;    // index of refraction (slows light: OPL = ior * distance)
    double g = 0.0;      // Henyey-Greenstein asymmetry, (-1, 1)
};

enum class MaterialType { Diffuse, Mirror, Dielectric, Null };

struct MaterialDesc {
    std::string name;
    MaterialType type = MaterialType::Diffuse;
    Color albedo{0.8};    // diffuse: Lambertian albedo
    Color specular{1.0};  // mirror: reflectance; dielectric: transmission/reflection tint
    double ior = 1.5;     // dielectric: index of refraction of the interior
};

enum class ShapeType { Mesh, Sphere, Quad, Box };

struct ShapeDesc {
    std::string name;
    ShapeType type = ShapeType::Mesh;
    int material = -1;        // index into SceneDesc::materials
    int interiorMedium = -1;  // index into SceneDesc::media, -1 = none (vacuum / glass interior)
    // Mesh
    std::string meshPath;  // resolved path of the mesh file (OBJ, or PLY by its extension)
    Mat4 transform{1.0};   // object to world
    // A mesh given by its triangles instead of a file (meshPath empty): the Mitsuba importer's
    // tessellated disks. Object space, then `transform`.
    std::vector<Vec3> inlinePositions;
    std::vector<glm::uvec3> inlineTriangles;
    // Sphere
    Vec3 center{0.0};
    double radius = 1.0;
    // Quad: corner + s*edgeU + t*edgeV, s,t in [0,1]; normal = normalize(cross(edgeU, edgeV))
    Vec3 corner{0.0}, edgeU{1.0, 0.0, 0.0}, edgeV{0.0, 1.0, 0.0};
    // Box: axis-aligned in object space, then `transform`
    Vec3 boxMin{-0.5}, boxMax{0.5};
    bool flipNormals = false;
    int areaLight = -1;  // index into lights when this quad is the visible surface of an area light
};

enum class LightType { Point, Spot, AreaQuad, Laser };

struct LightDesc {
    std::string name;
    LightType type = LightType::Point;
    Color power{1.0};                                              // radiant flux, W (RGB)
    double emitOpl = 0.0;                                          // pulse instant as OPL, m
    Vec3 position{0.0};                                            // point, spot, laser origin
    Vec3 direction{0.0, -1.0, 0.0};                                // spot axis, laser direction (unit)
    double spotCutoffDeg = 30.0;                                   // spot: half-angle of the cone
    double spotFalloffDeg = 25.0;                                  // spot: half-angle where the smooth falloff starts
    Vec3 corner{0.0}, edgeU{1.0, 0.0, 0.0}, edgeV{0.0, 0.0, 1.0};  // area quad; emits along cross(edgeU, edgeV)
    double laserRadius = 0.0;                                      // laser: beam radius, m (0 = infinitely thin)
};

enum class BeamLength { Short, Long };

struct RenderDesc {
    int64_t photonsPerPass = 20000;
    int warmup = 0;              // warm-up passes with fewer photons (RenderSettings::warmupPasses)
    double radius = 0.01;        // initial kernel radius
    bool radiusRelative = true;  // radius is a fraction of the scene's bounding diagonal
    // "radius": "auto", also the default when no volume radius is written: chosen by prepareRender
    // from a pilot pass (render/auto_radius.h); `radius` is then the fallback without a medium.
    bool radiusAuto = true;
    double surfaceRadius = 0.02;  // initial surface-photon kernel radius (same convention)
    double alpha = 0.7;           // progressive shrink parameter, (0, 1]
    int passes = 16;              // 0 = until the time budget
    double timeBudgetSec = 0.0;   // 0 = no budget
    int maxDepth = 16;
    int bounceMin = 0, bounceMax = INT_MAX;  // "bounces": the bounce filter (RenderSettings::bounceMin)
    uint64_t seed = 1;
    int threads = 0;  // 0 = all cores
    EmissionMode emission = EmissionMode::Delta;
    bool unwarp = false;
    TimeProfile timeProfile = TimeProfile::Exact;
    BeamLength beamLength = BeamLength::Short;
    // The density estimators by name (estimators/estimator_names.h) and the time kernel.
    std::string volumeEstimator = "beam2d";
    std::string surfaceEstimator = "ppm";
    TimeKernelSettings timeKernel;
};

// The kinds' names as the scene file writes them ("mesh", "diffuse", "area"...).
const char* shapeTypeName(ShapeType t);
const char* materialTypeName(MaterialType t);
const char* lightTypeName(LightType t);
const char* scanModeName(ScanMode m);

struct SceneDesc {
    int version = 1;
    std::string path;  // the scene file
    std::string dir;   // its folder (relative mesh paths are resolved against it)
    CameraDesc camera;
    FilmDesc film;
    int globalMedium = -1;  // index into media, -1 = vacuum
    std::vector<MediumDesc> media;
    std::vector<MaterialDesc> materials;
    std::vector<ShapeDesc> shapes;
    std::vector<LightDesc> lights;
    RenderDesc render;
    std::map<std::string, SourceLoc> locs;  // key path -> where it was written
    std::vector<std::string> warnings;      // unused keys and other non-fatal remarks, "file:line: ..."

    // "file:line: " for a key path, or "file: " when the key was not written in the file.
    std::string where(const std::string& keyPath) const;
};

}  // namespace tpb
