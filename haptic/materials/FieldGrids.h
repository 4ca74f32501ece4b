// SPDX-License-Identifier: Apache-2.0
/// @file FieldGrids.h
/// @brief Typed access to a MaterialField's grids (brings in OpenVDB: .cpp only).
#pragma once

#include "haptic/materials/MaterialField.h"
#include "volume/Grids.h"

namespace voxhap::haptic::detail {

using volume::FloatGrid;
using volume::LabelGrid;

inline FloatGrid::ConstPtr dampingGrid(const MaterialField& f)
{
    return openvdb::gridConstPtrCast<FloatGrid>(f.damping());
}
inline LabelGrid::ConstPtr labelGrid(const MaterialField& f)
{
    return openvdb::gridConstPtrCast<LabelGrid>(f.labels());
}
inline FloatGrid::ConstPtr stiffnessGrid(const MaterialField& f)
{
    return openvdb::gridConstPtrCast<FloatGrid>(f.boneStiffness());
}

} // namespace voxhap::haptic::detail
