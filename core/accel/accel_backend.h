// Which beam query backend a render uses (accel/beam_accel.h). All return exactly the same hits:
// our own BVH over the beam pieces (accel/piece_bvh.h), Embree's, or testing every piece (the
// oracle of the tests).
#pragma once

#include <optional>
#include <string>

namespace tpb {

enum class AccelBackend { Embree, BruteForce, Bvh };

// The names the CLI, the checkpoints and the fingerprints use: "bvh", "embree", "brute-force".
inline const char* accelBackendName(AccelBackend a) {
    return a == AccelBackend::Bvh ? "bvh" : a == AccelBackend::Embree ? "embree" : "brute-force";
}
// A name back (also "brute", the CLI's short form); nullopt for anything else.
inline std::optional<AccelBackend> parseAccelBackend(const std::string& name) {
    if (name == "bvh") return AccelBackend::Bvh;
    if (name == "embree") return AccelBackend::Embree;
    if (name == "brute" || name == "brute-force") return AccelBackend::BruteForce;
    return std::nullopt;
}

}  // namespace tpb
