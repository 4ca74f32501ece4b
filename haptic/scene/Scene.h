// SPDX-License-Identifier: Apache-2.0
/// @file Scene.h
/// @brief Scene files (data/scenes/*.json): which volume or phantom, which force
/// model and terms with their parameters, the needle, the device and the
/// insertion. A term the scene does not name is off: it costs nothing per tick
/// and its material grids are not built.
#pragma once

#include "haptic/DeviceLimits.h"
#include "haptic/Needle.h"
#include "haptic/Procedure.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/materials/MaterialField.h"
#include "haptic/papers/LayerTables.h"
#include "volume/Volume.h"

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::haptic {

/// @brief Where the volume comes from: a built-in phantom or a file.
struct VolumeSource {
    std::string phantom;            ///< "lumbar", "torso", "slab", "sphere"; empty for a file
    std::string preset = "average"; ///< lumbar preset
    std::optional<double> bmi;      ///< lumbar BMI
    double spacingMm = 0.5;         ///< phantom voxel size [mm]
    std::string file;               ///< a .vdb volume
};

/// @brief A reference range of one trainee metric (a key of metrics.json), from the
/// scene's "assessment" block; `voxhap assess` (assessment/) checks the names and
/// compares sessions with it.
struct MetricRange {
    std::string metric;             ///< a metrics.json key, e.g. "speed_mean_mm_per_s"
    std::optional<double> min, max; ///< in the metric's unit; a flag (true/false) is 1/0
    std::string source;             ///< where the range comes from (a paper, or "[chosen]")
};

struct Scene {
    std::string name, description, source, origin; ///< origin: the file or "builtin:<name>"
    VolumeSource volume;
    std::optional<Vec3d> entry, target; ///< path [mm, LPS]; else the phantom's landmarks
    std::string entryLandmark = "entry", targetLandmark;
    bool fixedTable = false; ///< the paper's layer table instead of the labels
    LayerRecipe recipe;
    ForceTerms terms;
    Needle needle;
    DeviceLimits device;
    /// What success is (Procedure.h); without a "success" block, by model: kyung
    /// reach_target (5 mm), lumbar-puncture reach_csf, senac and conci dura_intact.
    SuccessCriteria success;
    double speedMmPerS = 10.0;     ///< default constant insertion speed
    double rateHz = 1000.0;        ///< servo rate of the simulation
    double approachMm = 5.0;       ///< the tip starts this far outside the entry point
    std::optional<double> depthMm; ///< insertion depth past the entry; else to the target
    /// The scene's reference ranges of the trainee metrics ("assessment" block), in file order.
    std::vector<MetricRange> assessment;
    /// Blocks the file left out and the defaults taken for them, one line each,
    /// for a command to print (docs/scenes.md lists every default).
    std::vector<std::string> defaulted;
};

/// @brief Parse a scene; errors name @p origin and the field. @throw ValueError
Scene parseScene(const std::string& json, const std::string& origin);
/// @brief A file path, or the name of a built-in scene. @throw IoError, ValueError
Scene loadScene(const std::string& nameOrPath);
/// @brief The scenes compiled in from data/scenes/.
std::vector<std::string> builtinSceneNames();

/// @brief A scene made ready to run: its volume, only the material grids its terms
/// read, the layers on its path, and the force model.
class SceneInstance {
public:
    /// @param volume the volume to use instead of the scene's (may be null)
    /// @param entry, target override the scene's path
    SceneInstance(const Scene& scene, std::shared_ptr<const volume::Volume> volume, const volume::TissueTable& table,
        std::optional<Vec3d> entry = std::nullopt, std::optional<Vec3d> target = std::nullopt);

    const Scene& scene() const { return mScene; }
    const volume::Volume& volume() const { return *mVolume; }
    const MaterialField* field() const { return mField.get(); }
    Vec3d entry() const { return mEntry; }
    Vec3d target() const { return mTarget; }
    /// @brief A fresh force model (each run or thread its own).
    /// @param guide a planned line for guidance (Guidance.h): turns the term on at
    /// the scene's parameters (defaults when the scene has no `guidance` block);
    /// without it, a scene's guidance pulls toward the scene's own path.
    std::unique_ptr<NeedleForceModel> makeModel(const std::optional<GuideLine>& guide = std::nullopt) const;
    /// @brief The skin map of the palpation term, or null.
    const SkinMap* skinMap() const { return mSkin.get(); }
    const std::vector<Layer>& layers() const { return mLayers; }

private:
    Scene mScene;
    std::shared_ptr<const volume::Volume> mVolume;
    std::unique_ptr<MaterialField> mField;
    std::shared_ptr<const SkinMap> mSkin;
    Vec3d mEntry{0, 0, 0}, mTarget{0, 0, 0};
    std::vector<Layer> mLayers;
};

/// @brief Build the volume a source names. @throw ValueError, IoError
std::shared_ptr<const volume::Volume> makeSourceVolume(const VolumeSource& s, const volume::TissueTable& table);

} // namespace voxhap::haptic
