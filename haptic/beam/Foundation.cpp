// SPDX-License-Identifier: Apache-2.0
/// @file Foundation.cpp
/// @brief The label-grid foundation (OpenVDB stays in this file).

#include "haptic/beam/Foundation.h"

#include "core/Errors.h"
#include "haptic/materials/FieldGrids.h"

namespace voxhap::haptic {

namespace {

class LabelFoundation final : public Foundation {
public:
    explicit LabelFoundation(const MaterialField& field)
        : mField(field), mLabels(detail::labelGrid(field)), mAccessor(checked(mLabels).getConstAccessor())
    {
    }
    LabelFoundation(const LabelFoundation& o)
        : mField(o.mField), mLabels(o.mLabels), mAccessor(mLabels->getConstAccessor())
    {
    }

    double modulusAt(const Vec3d& world) noexcept override
    {
        const LabelMaterial* m = at(world);
        return m ? m->foundationNPerMm2 : 0.0;
    }
    void tissueAt(const Vec3d& world, double& k, double& bevelK) noexcept override
    {
        const LabelMaterial* m = at(world);
        k = m ? m->foundationNPerMm2 : 0.0;
        bevelK = m && !m->rigid ? k : 0.0;
    }
    std::unique_ptr<Foundation> clone() const override { return std::make_unique<LabelFoundation>(*this); }

private:
    /// The tissue whose voxel holds @p world; null in air, outside the volume, or far.
    const LabelMaterial* at(const Vec3d& world) noexcept
    {
        if (!world.allFinite()) return nullptr;
        const openvdb::Vec3d i = mLabels->transform().worldToIndex(volume::toVdb(world));
        // Beyond the int range of a coordinate the point is far outside any volume.
        constexpr double kFar = 1e9;
        if (!(std::abs(i[0]) < kFar && std::abs(i[1]) < kFar && std::abs(i[2]) < kFar)) return nullptr;
        const int label = mAccessor.getValue(openvdb::Coord::round(i));
        if (static_cast<unsigned>(label) >= static_cast<unsigned>(kMaxLabels)) return nullptr;
        return &mField.perLabel()[std::size_t(label)];
    }

    static const detail::LabelGrid& checked(const detail::LabelGrid::ConstPtr& g)
    {
        if (!g) throw ValueError("needle bending: the material field has no tissue labels to read the foundation from");
        return *g;
    }

    const MaterialField& mField;
    detail::LabelGrid::ConstPtr mLabels;
    detail::LabelGrid::ConstAccessor mAccessor;
};

} // namespace

std::unique_ptr<Foundation> makeLabelFoundation(const MaterialField& field)
{
    return std::make_unique<LabelFoundation>(field);
}

} // namespace voxhap::haptic
