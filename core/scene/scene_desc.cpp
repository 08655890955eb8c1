#include "scene/scene_desc.h"

namespace tpb {

std::string SceneDesc::where(const std::string& keyPath) const {
    auto it = locs.find(keyPath);
    if (it != locs.end() && it->second.line > 0)
        return it->second.file + ":" + std::to_string(it->second.line) + ": ";
    return path.empty() ? std::string() : path + ": ";
}

}  // namespace tpb
