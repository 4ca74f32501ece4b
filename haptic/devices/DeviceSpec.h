// SPDX-License-Identifier: Apache-2.0
/// @file DeviceSpec.h
/// @brief Devices by name (architecture.md "Devices"): "hand", "sim",
/// "replay:FILE", and the kinds other libraries register, such as
/// voxhap::igtl's "igtl[:PORT]". `voxhap serve --device`, Python's
/// `voxhap.make_device` and embedding programs all make their device here.
///
/// The names are checked, and what they point at read, by parseDeviceSpec(),
/// before anything else is loaded: a typo is said at once, not after a scene's
/// volume was built. makeDevice() then builds the device for one force model.
///
/// A kind is registered by an explicit call at start-up (igtl's
/// `registerIgtlDevice()`, haptic/igtl/IgtlDevice.h), never by a static
/// initialiser: the libraries are static, and a linker drops an object file
/// nothing references, registrar and all.
#pragma once

#include "haptic/DeviceLimits.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/servo/Device.h"

#include <any>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace voxhap::haptic {

/// @brief A device as named: "KIND" or "KIND:ARGUMENT".
struct DeviceSpec {
    std::string text;     ///< as given, for messages
    std::string kind;     ///< "hand", "sim", "replay", "igtl", ...
    std::string argument; ///< after the first colon; empty without one
    /// What the kind's check prepared from the argument (a replay's poses), for
    /// makeDevice; empty for kinds that need nothing.
    std::any prepared;
};

/// @brief What a device is made for: the needle's path and the device's
/// limits (from the force model), and the insertion a simulated hand or
/// script performs (from the scene, or the caller).
struct DeviceContext {
    NeedlePath path;
    DeviceLimits limits;
    double speedMmPerS = 10.0; ///< the hand's set point and the script's constant speed
    double startMm = -5.0;     ///< depth where they start: minus the scene's approach
    double depthMm = 60.0;     ///< the script's end depth past the entry
    bool careful = true;       ///< the hand stops after it feels the loss of resistance
    /// One line for the person at the terminal (the server's address); may be empty.
    std::function<void(const std::string&)> announce;
};

/// @brief The context of @p model with the scene's insertion (speed, approach,
/// depth: Scene.h's defaults when the caller has none).
DeviceContext deviceContext(
    const NeedleForceModel& model, double speedMmPerS, double approachMm, std::optional<double> depthMm);

/// @brief One kind of device.
struct DeviceKind {
    std::string name;  ///< "igtl"
    std::string usage; ///< how it is written, e.g. "igtl[:PORT]"
    /// Checks the argument and prepares what makeDevice needs (may read a
    /// file). @throw ValueError naming DeviceSpec::text and what is wrong with
    /// it; IoError for a file it names that cannot be read or is malformed
    std::function<void(DeviceSpec&)> check;
    /// Builds the device. @throw ValueError, IoError
    std::function<std::unique_ptr<Device>(const DeviceSpec&, const DeviceContext&)> make;
};

/// @brief Add a kind, or replace the one of the same name. Call at start-up,
/// before parseDeviceSpec() or makeDevice() runs on another thread.
void registerDeviceKind(DeviceKind kind);

/// @brief The kinds known in this program, built-in first, as their usage
/// strings: "hand", "sim", "replay:FILE", then the registered ones.
std::vector<std::string> deviceKindUsages();

/// @brief Parse and check @p text (see the file comment).
/// @throw ValueError, one line starting "device 'TEXT'": an unknown kind
///        (naming the kinds known) or a bad argument; IoError naming the file
///        when a file the kind reads cannot be read or is malformed
DeviceSpec parseDeviceSpec(const std::string& text);

/// @brief The device @p spec names, for @p context.
/// @throw ValueError, IoError when it cannot be made (a port in use)
std::unique_ptr<Device> makeDevice(const DeviceSpec& spec, const DeviceContext& context);

} // namespace voxhap::haptic
