// Which beam query backend a render uses (accel/beam_accel.h). Both return exactly the same hits:
// Embree's BVH over beam pieces, or testing every piece (the oracle of the tests).
#pragma once

namespace tpb {

enum class AccelBackend { Embree, BruteForce };

}  // namespace tpb
