// Mitsuba 3 XML import: the subset transient scenes use (mitransient's transient_hdr_film
// included) -> the same SceneDesc the JSON loader makes (docs/user/scenes.md "Mitsuba 3 XML":
// the supported plugins, how each maps and the unit conversions). The only user of pugixml.
// Everything the importer cannot represent is an error or a warning (SceneDesc::warnings) naming
// "file:line: <element>: ..."; nothing is dropped silently. SceneDesc::locs gets the XML lines
// under the JSON key paths ("shapes[2].file", "lights[0].power", "render.max_depth", ...), so the
// errors of later stages point into the XML too.
#pragma once
#include "scene/scene_desc.h"

#include <map>
#include <string>

namespace tpb {

struct MitsubaOptions {
    // `$name` parameters, as Mitsuba's `-D name=value`: they win over the file's <default> values.
    std::map<std::string, std::string> params;
};

// Reads `path` (and the files it <include>s, relative to the including file).
SceneDesc loadMitsubaScene(const std::string& path, const MitsubaOptions& options = {});
// Same, from text; `virtualPath` names it in messages and sets the folder for relative files.
SceneDesc loadMitsubaSceneFromString(const std::string& text, const std::string& virtualPath,
                                     const MitsubaOptions& options = {});

// Named indices of refraction Mitsuba accepts for int_ior/ext_ior ("bk7", "water", ...); false
// when unknown.
bool mitsubaNamedIor(const std::string& name, double& ior);

}  // namespace tpb
