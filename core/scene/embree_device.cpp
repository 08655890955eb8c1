// The process-wide Embree device and Embree's errors as exceptions (scene/embree_device.h).
#include "scene/embree_device.h"

#include <embree3/rtcore.h>

#include <string>

namespace tpb {
namespace {

const char* errorName(RTCError code) {
    switch (code) {
        case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
        case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
        case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
        case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
        case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
        case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
        case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
    }
    return "unrecognised Embree error";
}

// What the user can do about it.
const char* fixHint(RTCError code) {
    switch (code) {
        case RTC_ERROR_OUT_OF_MEMORY:
            return "reduce the scene's triangles, the photon count or the film size, or free memory";
        case RTC_ERROR_UNSUPPORTED_CPU: return "Embree 3 needs an x86-64 CPU with SSE2 or newer";
        case RTC_ERROR_CANCELLED: return "the build was cancelled; run again";
        default: return "this is a bug in tpb: please report it with the scene file";
    }
}

std::string describe(RTCError code, const std::string& detail) {
    std::string s = errorName(code);
    if (!detail.empty()) s += " (" + detail + ")";
    return s + "; " + fixHint(code);
}

// Message of the last Embree error raised on this thread (Embree calls the error function on the
// thread that made the failing call).
thread_local std::string tlsEmbreeMessage;

void onEmbreeError(void*, RTCError, const char* str) { tlsEmbreeMessage = str ? str : ""; }

struct SharedDevice {
    RTCDevice device = nullptr;
    RTCError failureCode = RTC_ERROR_NONE;  // why rtcNewDevice failed
    SharedDevice() {
        device = rtcNewDevice("verbose=0");
        if (!device) {
            failureCode = rtcGetDeviceError(nullptr);
            return;
        }
        rtcSetDeviceErrorFunction(device, onEmbreeError, nullptr);
    }
    ~SharedDevice() {
        // Scenes hold their own reference, so this is safe even if one outlives us.
        if (device) rtcReleaseDevice(device);
    }
    SharedDevice(const SharedDevice&) = delete;
    SharedDevice& operator=(const SharedDevice&) = delete;
};

SharedDevice& shared() {
    static SharedDevice device;  // created on first use; C++ makes the initialisation thread-safe
    return device;
}

}  // namespace

EmbreeDeviceHandle embreeDevice() {
    SharedDevice& s = shared();
    if (!s.device)
        throw EmbreeError(static_cast<int>(s.failureCode),
                          "cannot create the Embree device: " + describe(s.failureCode, ""));
    return s.device;
}

void checkEmbree(const char* during) {
    const RTCError code = rtcGetDeviceError(embreeDevice());  // also clears this thread's code
    if (code == RTC_ERROR_NONE) return;
    const std::string detail = tlsEmbreeMessage;
    tlsEmbreeMessage.clear();
    throw EmbreeError(static_cast<int>(code),
                      std::string("Embree error while ") + during + ": " + describe(code, detail));
}

}  // namespace tpb
