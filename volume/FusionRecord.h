// SPDX-License-Identifier: Apache-2.0
/// @file FusionRecord.h
/// @brief What a fused volume remembers of how its CT and MR were brought
/// together: the registration's map and figures, and where each channel came
/// from. Written by registration/Fusion.h, saved with the volume, printed by
/// `voxhap info` (docs/reference.md "CT and MR fusion").
#pragma once

#include "core/Math.h"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace voxhap::volume {

struct FusionRecord {
    /// The registration's map from CT to MR points, LPS mm, as a homogeneous
    /// 4×4 matrix (row-major when saved): ITK's fixed → moving direction.
    Eigen::Matrix4d mrFromCt = Eigen::Matrix4d::Identity();
    std::string itkTransform;    ///< the same, as the .tfm text ITK wrote
    std::string startedFrom;     ///< how the optimiser's start was chosen
    double metricGeometry = 0;   ///< Mattes MI at the header geometry
    double metricStart = 0;      ///< at the optimiser's start
    double metricFinal = 0;      ///< at the answer
    std::int64_t iterations = 0; ///< over all stages
    std::string stopReason;      ///< the last stage's
    bool converged = true;
    std::vector<std::string> warnings;
    double overlapStart = 0;      ///< fraction of the MR body inside the CT, at the start
    double overlapFinal = 0;      ///< and at the answer
    double surfaceDistanceMm = 0; ///< the body-surface check's mean distance
    double surfaceLimitMm = 0;    ///< and its limit
    double seconds = 0;           ///< registration, resampling and grids
    /// Where each channel came from, by grid name ("hu", "t1" or "intensity", "label").
    std::map<std::string, std::string> channelSources;
    /// The MR as it was loaded, to draw it again at its header geometry
    /// (`voxhap render --fusion`): its absolute path, series and 4D volume.
    std::string mrPath;
    std::string mrSeries;
    std::int64_t mrVolume = 0;

    bool operator==(const FusionRecord&) const = default;
};

/// @brief The record as JSON (the matrix as four rows): how .vdb files keep it
/// (key "voxhap.fusion") and how `--json` prints it.
nlohmann::json toJson(const FusionRecord& r);

/// @brief The record from toJson()'s form.
/// @throw ValueError naming @p where and the field when a field is missing or of the wrong type
FusionRecord fusionRecordFromJson(const nlohmann::json& j, const std::string& where);

} // namespace voxhap::volume
