// SPDX-License-Identifier: Apache-2.0
/// @file DeviceSpec.cpp
/// @brief The built-in device kinds and the table of registered ones.

#include "haptic/devices/DeviceSpec.h"

#include "core/Errors.h"
#include "haptic/devices/ReplayDevice.h"
#include "haptic/devices/SimulatedDevices.h"
#include "haptic/servo/Session.h"

#include <mutex>

namespace voxhap::haptic {

namespace {

void noArgument(DeviceSpec& s)
{
    if (!s.argument.empty()) throw ValueError("device '" + s.text + "': " + s.kind + " takes no argument");
}

/// The built-in kinds, then the registered ones; guarded, since a program may
/// register while another thread lists (the registration itself is set-up).
struct Registry {
    std::mutex mutex;
    std::vector<DeviceKind> kinds;

    Registry()
    {
        kinds.push_back({"hand", "hand", noArgument, [](const DeviceSpec&, const DeviceContext& c) {
                             HandParams p;
                             p.speedMmPerS = c.speedMmPerS;
                             p.startMm = c.startMm;
                             p.stopOnLor = c.careful;
                             return std::unique_ptr<Device>(std::make_unique<HandDevice>(c.path, p, c.limits));
                         }});
        kinds.push_back({"sim", "sim", noArgument, [](const DeviceSpec&, const DeviceContext& c) {
                             return std::unique_ptr<Device>(std::make_unique<ScriptedDevice>(c.path,
                                 InsertionScript::constantSpeed(c.startMm, c.depthMm, c.speedMmPerS), c.limits));
                         }});
        kinds.push_back({"replay", "replay:FILE",
            [](DeviceSpec& s) {
                if (s.argument.empty()) throw ValueError("device '" + s.text + "': replay needs a session.csv");
                try {
                    s.prepared = readSessionPoses(s.argument);
                } catch (const ValueError& e) {
                    throw IoError(e.what()); // the name was right; the file it names is not
                }
            },
            [](const DeviceSpec& s, const DeviceContext& c) {
                return std::unique_ptr<Device>(std::make_unique<ReplayDevice>(
                    std::any_cast<const std::vector<ServoRecord>&>(s.prepared), c.limits));
            }});
    }
};

Registry& registry()
{
    static Registry r;
    return r;
}

/// A copy of the kind @p s names, so that it runs without the lock.
/// @throw ValueError naming the kinds known
DeviceKind kindOf(const DeviceSpec& s)
{
    Registry& r = registry();
    const std::lock_guard lock(r.mutex);
    for (const auto& k : r.kinds) {
        if (k.name == s.kind) return k;
    }
    std::string known;
    for (std::size_t i = 0; i < r.kinds.size(); ++i)
        known += (i == 0 ? "" : i + 1 == r.kinds.size() ? " or " : ", ") + r.kinds[i].usage;
    throw ValueError("device '" + s.text + "' is not " + known);
}

} // namespace

DeviceContext deviceContext(
    const NeedleForceModel& model, double speedMmPerS, double approachMm, std::optional<double> depthMm)
{
    DeviceContext c;
    c.path = model.path();
    c.limits = model.device();
    c.speedMmPerS = speedMmPerS;
    c.startMm = -approachMm;
    if (depthMm) c.depthMm = *depthMm;
    return c;
}

void registerDeviceKind(DeviceKind kind)
{
    Registry& r = registry();
    const std::lock_guard lock(r.mutex);
    for (auto& k : r.kinds) {
        if (k.name == kind.name) {
            k = std::move(kind);
            return;
        }
    }
    r.kinds.push_back(std::move(kind));
}

std::vector<std::string> deviceKindUsages()
{
    Registry& r = registry();
    const std::lock_guard lock(r.mutex);
    std::vector<std::string> out;
    for (const auto& k : r.kinds) out.push_back(k.usage);
    return out;
}

DeviceSpec parseDeviceSpec(const std::string& text)
{
    DeviceSpec s;
    s.text = text;
    const std::size_t colon = text.find(':');
    s.kind = text.substr(0, colon);
    if (colon != std::string::npos) s.argument = text.substr(colon + 1);
    const DeviceKind kind = kindOf(s);
    if (kind.check) kind.check(s);
    return s;
}

std::unique_ptr<Device> makeDevice(const DeviceSpec& spec, const DeviceContext& context)
{
    return kindOf(spec).make(spec, context);
}

} // namespace voxhap::haptic
