// The process-wide Embree device, shared by the scene's surfaces (scene/geometry.cpp) and the
// photon-beam accelerator (accel/beam_accel.cpp): one place creates it, configures it and turns
// Embree's errors into exceptions. Embree itself is included only by the .cpp files; this header
// names the device by a forward declaration of Embree's opaque type, so including it pulls in no
// Embree header.
//
// Errors: Embree reports a failing call through the device's error function (on the thread that
// made the call). The function only records the code and message (an exception must not cross
// Embree's C frames); checkEmbree() then throws them as an EmbreeError naming the operation, the
// Embree error code and what to do about it.
#pragma once
#include <stdexcept>
#include <string>

struct RTCDeviceTy;  // Embree 3's device (embree3/rtcore_device.h: typedef struct RTCDeviceTy* RTCDevice)

namespace tpb {

using EmbreeDeviceHandle = RTCDeviceTy*;

// An Embree call failed. code() is the RTCError value (RTC_ERROR_OUT_OF_MEMORY, ...).
class EmbreeError : public std::runtime_error {
public:
    EmbreeError(int code, const std::string& message) : std::runtime_error(message), code_(code) {}
    int code() const { return code_; }

private:
    int code_;
};

// The device, created on the first call (thread-safe) and released at exit. Throws EmbreeError if
// Embree cannot create it (then again on every call).
EmbreeDeviceHandle embreeDevice();

// Throws EmbreeError if an Embree call on this thread failed since the last check; `during` says
// what was being done ("building the photon-beam BVH").
void checkEmbree(const char* during);

}  // namespace tpb
