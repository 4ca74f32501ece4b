// SPDX-License-Identifier: Apache-2.0
/// @file Foundation.h
/// @brief The tissue holding a bending needle: its Winkler modulus k [N/mm²] at
/// a point (physics.md §9.2), per label from the tissue table's
/// `foundation_modulus`, or uniform (the closed-form tests).
#pragma once

#include "core/Math.h"
#include "haptic/materials/MaterialField.h"

#include <memory>

namespace voxhap::haptic {

class Foundation {
public:
    virtual ~Foundation() = default;
    /// @brief k [N/mm²] at @p world [mm, LPS]; 0 in air and outside the volume.
    /// Never throws or allocates.
    virtual double modulusAt(const Vec3d& world) noexcept = 0;
    /// @brief At @p world: @p k = modulusAt(), and @p bevelK, the modulus a bevel
    /// cutting there presses on (§9.3): k, but 0 in rigid tissue (bone), which the
    /// needle meets as contact, not by cutting (§1.3). Never throws or allocates.
    virtual void tissueAt(const Vec3d& world, double& k, double& bevelK) noexcept { k = bevelK = modulusAt(world); }
    /// @brief An independent copy (its own grid accessors) for another model.
    virtual std::unique_ptr<Foundation> clone() const = 0;
};

/// @brief The same k everywhere.
class UniformFoundation final : public Foundation {
public:
    explicit UniformFoundation(double kNPerMm2) : mK(kNPerMm2) { }
    double modulusAt(const Vec3d&) noexcept override { return mK; }
    std::unique_ptr<Foundation> clone() const override { return std::make_unique<UniformFoundation>(mK); }

private:
    double mK;
};

/// @brief k of the tissue whose voxel holds the point (the label grid, nearest
/// voxel centre), from the field's per-label table.
/// @throw ValueError if the field has no label grid
std::unique_ptr<Foundation> makeLabelFoundation(const MaterialField& field);

} // namespace voxhap::haptic
