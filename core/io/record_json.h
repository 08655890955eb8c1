// A Record (record.h) as a JSON object, keys in the record's order (nlohmann's ordered_json keeps
// it; a plain json object sorts them). Output only: tpb writes JSON with nlohmann and reads the
// files people write (scenes) with its own parser (json.h), which knows lines.
#pragma once
#include "io/record.h"

#include <nlohmann/json.hpp>

namespace tpb {

template <class Json = nlohmann::json>
Json recordJson(const Record& r) {
    Json j = Json::object();
    for (const RecordEntry& e : r) std::visit([&](const auto& v) { j[e.key] = v; }, e.value);
    return j;
}

// The inverse, for files tpb reads back (a reference header): booleans, integers (unsigned when
// JSON says so), doubles and strings; other values are skipped.
template <class Json>
Record recordFromJson(const Json& j) {
    Record r;
    if (!j.is_object()) return r;
    for (auto it = j.begin(); it != j.end(); ++it) {
        const Json& v = it.value();
        if (v.is_boolean())
            r.push_back({it.key(), v.template get<bool>()});
        else if (v.is_number_unsigned())
            r.push_back({it.key(), v.template get<uint64_t>()});
        else if (v.is_number_integer())
            r.push_back({it.key(), v.template get<int64_t>()});
        else if (v.is_number_float())
            r.push_back({it.key(), v.template get<double>()});
        else if (v.is_string())
            r.push_back({it.key(), v.template get<std::string>()});
    }
    return r;
}

}  // namespace tpb
