#include "io/record.h"

#include <cinttypes>
#include <cstdio>

namespace tpb {

std::string recordText(const RecordValue& v) {
    char b[64];
    if (const bool* x = std::get_if<bool>(&v)) return *x ? "true" : "false";
    if (const int64_t* x = std::get_if<int64_t>(&v)) {
        std::snprintf(b, sizeof b, "%" PRId64, *x);
        return b;
    }
    if (const uint64_t* x = std::get_if<uint64_t>(&v)) {
        std::snprintf(b, sizeof b, "%" PRIu64, *x);
        return b;
    }
    if (const double* x = std::get_if<double>(&v)) {
        std::snprintf(b, sizeof b, "%.17g", *x);
        return b;
    }
    return std::get<std::string>(v);
}

const RecordValue* recordFind(const Record& r, const std::string& key) {
    for (const RecordEntry& e : r)
        if (e.key == key) return &e.value;
    return nullptr;
}

}  // namespace tpb
