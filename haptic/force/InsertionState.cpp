// SPDX-License-Identifier: Apache-2.0
/// @file InsertionState.cpp
/// @brief The layer state machine (physics.md §2.1 tenting and pop, §3.1 Conci
/// stages, §4 [LP] per-layer tip force, §2.3 loss of resistance, §1.3 bone).

#include "haptic/force/InsertionState.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

namespace {
/// Depths are sums of layer thicknesses and tick steps: a puncture depth reached to
/// within this counts as reached, so that round-off never defers a pop by a tick.
constexpr double kDepthToleranceMm = 1e-9;
} // namespace

const char* layerStateName(LayerState s)
{
    switch (s) {
    case LayerState::Intact:
        return "intact";
    case LayerState::Tenting:
        return "tenting";
    case LayerState::Punctured:
        return "punctured";
    case LayerState::Contact:
        return "contact";
    }
    return "?";
}

InsertionState::InsertionState(std::vector<Layer> layers)
    : mLayers(std::move(layers)), mState(mLayers.size(), LayerState::Intact), mOrigin(mLayers.size(), 0.0),
      mPopPush(mLayers.size(), 0.0)
{
    for (const Layer& l : mLayers) {
        if (l.role != LayerRole::Air) {
            mSurfaceMm = l.startMm;
            break;
        }
    }
    reset();
}

void InsertionState::reset() noexcept
{
    std::fill(mState.begin(), mState.end(), LayerState::Intact);
    std::fill(mOrigin.begin(), mOrigin.end(), 0.0);
    std::fill(mPopPush.begin(), mPopPush.end(), 0.0);
    mTip = TipState{};
    mLastPopMm = -kNoLimit;
    mSkinEntered = false;
    mTouched = false;
}

void InsertionState::reach(int i, double d, double t, EventBuffer& ev) noexcept
{
    const Layer& l = mLayers[std::size_t(i)];
    if (l.role == LayerRole::Air) return;
    if (!mTouched) ev.push({EventType::SkinContact, t, d, i}), mTouched = true;
    if (l.role == LayerRole::Epidural) ev.push({EventType::LossOfResistance, t, d, i});
    if (l.role == LayerRole::Bone) ev.push({EventType::BoneContact, t, d, i});
}

void InsertionState::enter(int i, double d, double t, EventBuffer& ev) noexcept
{
    const Layer& l = mLayers[std::size_t(i)];
    mState[std::size_t(i)] = LayerState::Punctured;
    reach(i, d, t, ev);
    if (l.role == LayerRole::Air) return;
    if (!mSkinEntered) ev.push({EventType::SkinEntry, t, d, i}), mSkinEntered = true;
    if (l.role == LayerRole::Dura) ev.push({EventType::DuraPuncture, t, d, i});
}

void InsertionState::pop(int i, double d, double z, double t, EventBuffer& ev) noexcept
{
    const Layer& l = mLayers[std::size_t(i)];
    mState[std::size_t(i)] = LayerState::Punctured;
    mPopPush[std::size_t(i)] = z;
    mLastPopMm = d;
    ev.push({EventType::Pop, t, d, i});
    if (!mSkinEntered) ev.push({EventType::SkinEntry, t, d, i}), mSkinEntered = true;
    // Conci's merged "epidural_dura" row ends at the dura (§3.2); "epidural_space" does not.
    if (l.role == LayerRole::Dura || (l.role == LayerRole::Epidural && l.name.find("_dura") != std::string::npos)) {
        ev.push({EventType::DuraPuncture, t, d, i});
    }
}

void InsertionState::update(double d, double t, double shaftLengthMm, EventBuffer& ev) noexcept
{
    if (!std::isfinite(d) || mLayers.empty()) return;
    const int n = int(mLayers.size());

    // Out of the body again: a new insertion starts from intact tissue.
    if (d < mSurfaceMm && (mSkinEntered || mTouched)) {
        bool entered = mSkinEntered;
        for (int i = 0; i < n; ++i) {
            if (mState[std::size_t(i)] == LayerState::Contact) ev.push({EventType::BoneRelease, t, d, i});
        }
        reset();
        if (entered) ev.push({EventType::Withdrawn, t, d, -1});
    }
    // Deeper layers the tip has backed away from relax (tenting) or are released (bone).
    for (int i = 0; i < n; ++i) {
        LayerState& s = mState[std::size_t(i)];
        if (d >= mOrigin[std::size_t(i)]) continue;
        if (s == LayerState::Tenting)
            s = LayerState::Intact;
        else if (s == LayerState::Contact)
            s = LayerState::Intact, ev.push({EventType::BoneRelease, t, d, i});
    }

    TipState tip;
    tip.depthMm = d;
    const double shaftStart = d - std::max(0.0, shaftLengthMm);
    for (int i = 0; i < n && mLayers[std::size_t(i)].startMm <= d; ++i) {
        const Layer& l = mLayers[std::size_t(i)];
        LayerState& s = mState[std::size_t(i)];
        if (s == LayerState::Intact) {
            const double origin = std::max(l.startMm, mLastPopMm);
            if (d < origin) break; // pushed ahead by the layer before: not touched yet
            mOrigin[std::size_t(i)] = origin;
            if (l.rigid) {
                s = LayerState::Contact;
                reach(i, d, t, ev);
            } else if (l.tents) {
                s = LayerState::Tenting;
                reach(i, d, t, ev);
            } else {
                enter(i, d, t, ev);
            }
        }
        if (s == LayerState::Contact) { // §1.3: the tip stops on bone
            tip.boneLayer = i;
            tip.penetrationMm = d - mOrigin[std::size_t(i)];
            break;
        }
        if (s == LayerState::Tenting) {
            const double z = d - mOrigin[std::size_t(i)];
            if (l.elasticForceN(z) >= l.punctureForceN || z >= l.punctureDepthMm - kDepthToleranceMm) {
                pop(i, d, z, t, ev);
            } else {
                tip.pushLayer = i;
                tip.pushMm = z;
                // The pushed span counts as shaft in the layer: [LP]'s per-layer tip force
                // is read as the tip inside it (Sénac and Conci layers have no b).
                const double lo = std::max(mOrigin[std::size_t(i)], shaftStart);
                if (d > lo) tip.viscousNsPerMm += l.viscousNsPerMm2 * (d - lo);
                break;
            }
        }
        // Entered (punctured): the tip is inside; its shaft crosses the layer.
        tip.inLayer = i;
        tip.cuttingSumN += l.cuttingForceN;
        const double lo = std::max(l.startMm, shaftStart), hi = std::min(l.endMm, d);
        if (hi > lo) tip.viscousNsPerMm += l.viscousNsPerMm2 * (hi - lo);
        const double popAt = std::isfinite(l.punctureDepthMm) ? l.punctureDepthMm : mPopPush[std::size_t(i)];
        tip.plateauDepthMm = std::max(0.0, d - mOrigin[std::size_t(i)] - popAt);
    }
    tip.inBody = mSkinEntered;
    mTip = tip;
}

} // namespace voxhap::haptic
