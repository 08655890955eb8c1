#include "scene/scene_desc.h"

namespace tpb {

std::string SceneDesc::where(const std::string& keyPath) const {
    auto it = locs.find(keyPath);
    if (it != locs.end() && it->second.line > 0) return it->second.file + ":" + std::to_string(it->second.line) + ": ";
    return path.empty() ? std::string() : path + ": ";
}

const char* shapeTypeName(ShapeType t) {
    switch (t) {
        case ShapeType::Mesh: return "mesh";
        case ShapeType::Sphere: return "sphere";
        case ShapeType::Quad: return "quad";
        case ShapeType::Box: return "box";
    }
    return "?";
}

const char* materialTypeName(MaterialType t) {
    switch (t) {
        case MaterialType::Diffuse: return "diffuse";
        case MaterialType::Mirror: return "mirror";
        case MaterialType::Dielectric: return "dielectric";
        case MaterialType::Null: return "null";
    }
    return "?";
}

const char* lightTypeName(LightType t) {
    switch (t) {
        case LightType::Point: return "point";
        case LightType::Spot: return "spot";
        case LightType::AreaQuad: return "area";
        case LightType::Laser: return "laser";
    }
    return "?";
}

const char* scanModeName(ScanMode m) {
    switch (m) {
        case ScanMode::None: return "none";
        case ScanMode::Single: return "single";
        case ScanMode::Confocal: return "confocal";
        case ScanMode::Exhaustive: return "exhaustive";
    }
    return "?";
}

}  // namespace tpb
