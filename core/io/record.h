// A flat, ordered list of (key, value): how a set of settings is written once for every file that
// records it (summary.json, `tpb info`, transient.json, the reference header, the checkpoint's
// fingerprint). The producer decides the keys (integrators/render_settings.h settingsRecord: the
// scene file's render keys); recordJson (record_json.h) and recordText turn it into output.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace tpb {

using RecordValue = std::variant<bool, int64_t, uint64_t, double, std::string>;
struct RecordEntry {
    std::string key;
    RecordValue value;
};
using Record = std::vector<RecordEntry>;

// The value as text: doubles as %.17g (reads back bit for bit), integers in full, strings as they
// are, booleans as true/false. The fingerprint compares these texts.
std::string recordText(const RecordValue& v);

// The entry of `key`, or null.
const RecordValue* recordFind(const Record& r, const std::string& key);

}  // namespace tpb
