// SPDX-License-Identifier: Apache-2.0
/// @file InsertionState.h
/// @brief Per-layer insertion state along the path: intact → tenting → punctured
/// (or contact, for rigid bone), and the events between (architecture.md "The
/// force pipeline", step 2; physics.md §1.1, §2.1, §2.3, §3.1, §4).
///
/// Depth is measured along the path from its origin. A layer the tip reaches is
/// entered at once unless it has an elastic stage; then it tents: the tip pushes
/// its surface ahead by z, measured from where the tip met it, until the elastic
/// force reaches the puncture force or z the puncture depth ("pop"). Layers
/// deeper than the tip of a tenting layer are pushed ahead and not touched. When
/// a pop lands the tip past the start of deeper layers, those are entered (or
/// start tenting) from the tip's position, so that no stored energy appears from
/// nothing [chosen, physics.md §1.1 rule]. Punctured layers stay punctured while
/// the needle is inside; pulling the tip out of the body resets every layer.
#pragma once

#include "haptic/Events.h"
#include "haptic/Layer.h"

#include <cstdint>
#include <vector>

namespace voxhap::haptic {

enum class LayerState : std::uint8_t {
    Intact,
    Tenting,
    Punctured,
    Contact
};
const char* layerStateName(LayerState s);

/// @brief Where the tip is, after an update.
struct TipState {
    double depthMm = 0;        ///< along the path [mm]
    int inLayer = -1;          ///< deepest entered layer holding the tip, -1 outside the body
    int pushLayer = -1;        ///< the tenting layer the tip pushes, -1 if none
    double pushMm = 0;         ///< z: how far it is pushed [mm]
    int boneLayer = -1;        ///< rigid layer in contact, -1 if none
    double penetrationMm = 0;  ///< depth past the bone surface [mm]
    double plateauDepthMm = 0; ///< w: depth past the tip layer's puncture depth [mm]
    double cuttingSumN = 0;    ///< Σ cutting force of the entered layers (nested boxes, §2.1) [N]
    double viscousNsPerMm = 0; ///< Σ b_i·l_i over the shaft ([LP] Eq. 3) [N·s/mm]
    bool inBody = false;       ///< the skin has been entered
    /// @brief The layer whose tip parameters apply: the one pushed, else the one entered.
    int currentLayer() const noexcept { return pushLayer >= 0 ? pushLayer : inLayer; }
};

class InsertionState {
public:
    InsertionState() = default;
    /// @brief Set the layers along the path (ordered, non-overlapping); resets the state.
    explicit InsertionState(std::vector<Layer> layers);

    /// @brief Move the tip to @p depthMm at @p timeS with the shaft @p shaftLengthMm
    /// long behind it, appending events to @p events. Never allocates or throws; a
    /// non-finite depth leaves the state as it was.
    void update(double depthMm, double timeS, double shaftLengthMm, EventBuffer& events) noexcept;
    void reset() noexcept;

    const std::vector<Layer>& layers() const { return mLayers; }
    const TipState& tip() const { return mTip; }
    LayerState state(int i) const { return mState[std::size_t(i)]; }
    bool skinEntered() const { return mSkinEntered; }
    /// @brief Depth of the first tissue's surface along the path [mm].
    double surfaceMm() const { return mSurfaceMm; }

private:
    void reach(int i, double d, double t, EventBuffer& ev) noexcept; ///< first touch: contact, LOR, bone
    void enter(int i, double d, double t, EventBuffer& ev) noexcept;
    void pop(int i, double d, double z, double t, EventBuffer& ev) noexcept;

    std::vector<Layer> mLayers;
    std::vector<LayerState> mState;
    std::vector<double> mOrigin;  ///< where the tip met each layer [mm]
    std::vector<double> mPopPush; ///< z at which each layer popped [mm]
    TipState mTip;
    double mLastPopMm = -kNoLimit;
    double mSurfaceMm = kNoLimit;
    bool mSkinEntered = false;
    bool mTouched = false;
};

} // namespace voxhap::haptic
