// The render an export came from (film/volume_export.h VolumeProvenance), read from a Driver: the
// settings it runs with and the radii of its last finished pass. Used by `tpb render --npy` and
// the viewer's volume export, so both side files say the same things.
#pragma once
#include "film/volume_export.h"
#include "render/driver.h"

namespace tpb {

inline VolumeProvenance provenanceOf(const Driver& drv, const std::string& scenePath) {
    const RenderSettings& s = drv.settings();
    VolumeProvenance v;
    v.scene = scenePath;
    v.settings = settingsRecord(s);
    if (drv.completedPasses() > 0) {
        const PassStats last = drv.lastPass();
        v.beamRadius = last.beamRadius;
        v.surfaceRadius = last.surfaceRadius;
    }
    return v;
}

}  // namespace tpb
